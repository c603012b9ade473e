//! The model sequence: each step frees more parameters (or adds the residual model), is
//! reduced to the identifiable set, refitted, scored on everything held out, and — for opt-in
//! steps, when there is held-out data to judge by — kept only if it lowers the pooled
//! held-out RMS of the registered groups by [`super::options::ACCEPTANCE_GAIN`].

use super::heldout::{self, Refit};
use super::options::{ACCEPTANCE_GAIN, FitOptions, Step};
use super::roles::Roles;
use crate::geometry::campaign::Campaign;
use crate::geometry::identify::{self, Reduction};
use crate::geometry::joint_maps::{self, JointMapsHyper, MAPS_GRID};
use crate::geometry::outcome::{Acceptance, StepReport, TestGroup};
use crate::geometry::params::{EgModel, Param};
use crate::geometry::resample::cross_validate;
use crate::geometry::residual_model::{HYPER_GRID, ResidualHyper, ResidualModel};
use crate::geometry::solve::{self, SolveOptions, SolveOutcome};
use crate::stats::ErrorNormStats;
use rand::SeedableRng;
use rand_chacha::ChaCha8Rng;

/// Candidates of the steps `steps` (cumulative), in priority order.
pub fn candidates(
    model: &EgModel,
    campaign: &Campaign,
    steps: &[Step],
    elastic: &[usize],
    fit_setups: &[usize],
) -> Vec<Param> {
    let orientations = !campaign.orientation_rows.is_empty();
    let mut out: Vec<Param> = model
        .registration_params(orientations)
        .into_iter()
        .filter(|p| match p {
            Param::SetupRotation(s, _) | Param::SetupTranslation(s, _) => fit_setups.contains(s),
            _ => true,
        })
        .collect();
    let joints = model.robot.joint_count();
    for step in steps {
        match *step {
            Step::Registration | Step::ResidualModel | Step::JointMaps => {}
            Step::Geometry => out.extend(model.geometric_params()),
            Step::Compliance => out.extend(elastic.iter().map(|&e| Param::Compliance(e))),
            Step::Masses => {
                for b in 0..joints {
                    out.push(Param::Mass(b));
                    out.extend((0..3).map(|k| Param::FirstMoment(b, k)));
                }
            }
            Step::Harmonics(order) => {
                for joint in 0..joints {
                    for n in 1..=u16::from(order) {
                        out.extend(harmonic_pair(joint, n));
                    }
                }
            }
            Step::Periodic(order) => {
                for joint in 0..joints {
                    out.extend(harmonic_pair(joint, order));
                }
            }
            Step::Backlash => out.extend((0..joints).map(Param::Backlash)),
            Step::Torsion(shape) => {
                out.extend(elastic.iter().map(|&edof| Param::Torsion { edof, shape }));
            }
        }
    }
    out
}

fn harmonic_pair(joint: usize, order: u16) -> [Param; 2] {
    [false, true].map(|sine| Param::Harmonic { joint, order, sine })
}

/// The state the sequence carries from one accepted step to the next.
pub struct Accepted {
    /// The model.
    pub model: EgModel,
    /// Steps kept so far.
    pub steps: Vec<Step>,
    /// Free parameters of the last kept step.
    pub reduction: Option<Reduction>,
    /// Its solver outcome.
    pub outcome: Option<SolveOutcome>,
    /// Its residual model hyper-parameters.
    pub residual: Option<ResidualHyper>,
    /// Its joint maps' hyper-parameters.
    pub maps: Option<JointMapsHyper>,
    /// Its pooled held-out RMS (m), when there are registered held-out groups.
    pub held_out_rms: Option<f64>,
    /// Model with the held-out series registered (for the written file).
    pub with_series: EgModel,
}

/// What one step needs from the fit.
pub struct StepContext<'a> {
    /// Readings.
    pub campaign: &'a Campaign,
    /// Options.
    pub options: &'a FitOptions,
    /// Roles.
    pub roles: &'a Roles,
    /// Free eDoFs.
    pub elastic: &'a [usize],
    /// Solver settings.
    pub solve_options: SolveOptions,
    /// The robot file's compliances.
    pub nominal_compliance: &'a [f64],
}

/// Run `step` on top of `accepted`; report it and, when it is kept, update `accepted`.
pub fn run_step(step: Step, accepted: &mut Accepted, context: &StepContext) -> StepReport {
    let StepContext {
        campaign,
        options,
        roles,
        ..
    } = *context;
    let mut trial = accepted.model.clone();
    // The parametric model is reduced and solved without the maps and the residual model; both
    // are then trained on what it leaves (maps first), as every held-out refit does.
    trial.residual = None;
    trial.joint_maps = None;
    if step.elastic() && !accepted.steps.iter().any(|s| s.elastic()) {
        // Every eDoF starts at (and, when not freed, keeps) the robot file's compliance.
        trial.compliance = context.nominal_compliance.to_vec();
    }
    let mut steps = accepted.steps.clone();
    steps.push(step);
    let candidates = candidates(&trial, campaign, &steps, context.elastic, &roles.fit_setups);
    let reduced = identify::reduce(
        &trial,
        campaign,
        &candidates,
        &roles.fit_mult,
        options.tolerance,
    );
    let solved = solve::solve(
        &mut trial,
        campaign,
        &reduced.kept,
        &roles.fit_mult,
        &context.solve_options,
    );
    let mut hyper = accepted.residual;
    let mut maps = accepted.maps;
    if step == Step::JointMaps {
        maps = choose_maps(&trial, &reduced.kept, hyper, context);
    }
    if step == Step::ResidualModel {
        hyper = choose_hyper(&trial, &reduced.kept, maps, context);
    }
    if campaign.orientation_rows.is_empty() {
        // Orientations not fitted: the target frames in closed form from the fitted readings,
        // so that orientation errors can be scored.
        let targets: Vec<usize> = (0..trial.targets.len()).collect();
        crate::geometry::register::start::initialise_target_rotations(
            &mut trial,
            campaign,
            &targets,
            &roles.fit_mult,
        );
    }
    if let Some(h) = maps {
        let _ = joint_maps::train_into(&mut trial, campaign, &roles.fit_mult, h);
    }
    if let Some(h) = hyper {
        let (q, y) = heldout::residual_training_set(&trial, campaign, &roles.fit_mult);
        let mut rng = ChaCha8Rng::seed_from_u64(options.seed);
        // A failed training (fewer than 10 readings, a singular system) leaves the model without
        // a residual model, scored as it is (as a failed map training leaves the maps out).
        trial.residual = ResidualModel::train(&q, &y, h, &mut rng).ok();
    }
    let refit_with = Refit {
        kept: &reduced.kept,
        residual: hyper,
        maps,
    };
    let report = score_step(
        step,
        &trial,
        &reduced,
        &candidates,
        &solved,
        refit_with,
        context,
    );
    let held_out_rms = {
        let groups: Vec<&TestGroup> = report.0.test.iter().chain(&report.0.cross_groups).collect();
        heldout::pooled_rms(&groups)
    };
    let acceptance = match (step.opt_in(), accepted.held_out_rms, held_out_rms) {
        (true, Some(before_m), Some(after_m)) => Some(Acceptance {
            before_m,
            after_m,
            accepted: after_m < before_m * (1.0 - ACCEPTANCE_GAIN),
        }),
        _ => None,
    };
    let (mut step_report, with_series) = report;
    step_report.acceptance = acceptance;
    if acceptance.is_none_or(|a| a.accepted) {
        *accepted = Accepted {
            model: trial,
            steps,
            reduction: Some(reduced),
            outcome: Some(solved),
            residual: hyper,
            maps,
            held_out_rms,
            with_series,
        };
    }
    step_report
}

/// Score a fitted step on everything: fit, loaded, k-fold CV, held-out configurations,
/// held-out series, left-out groups.
fn score_step(
    step: Step,
    model: &EgModel,
    reduced: &Reduction,
    candidates: &[Param],
    solved: &SolveOutcome,
    refit_with: Refit,
    context: &StepContext,
) -> (StepReport, EgModel) {
    let StepContext {
        campaign,
        options,
        roles,
        ..
    } = *context;
    let errors: Vec<(f64, Option<f64>)> = roles
        .fit_rows
        .iter()
        .map(|&i| crate::geometry::protocol::row_errors(model, campaign, i))
        .collect();
    let fit = ErrorNormStats::of(&errors.iter().map(|e| e.0).collect::<Vec<_>>());
    let orientation: Vec<f64> = errors.iter().filter_map(|e| e.1).collect();
    let loaded_rms = (!roles.fit_loaded.is_empty()).then(|| {
        let norms: Vec<f64> = roles
            .fit_loaded
            .iter()
            .map(|&i| campaign.residual(model, i, &[], None).norm())
            .collect();
        ErrorNormStats::of(&norms).rms
    });
    let cv_rms = (options.folds >= 2 && refit_with.residual.is_none() && refit_with.maps.is_none())
        .then(|| {
            cross_validate(
                model,
                campaign,
                &reduced.kept,
                &roles.fit_mult,
                &roles.fold_of,
                options.folds,
                &context.solve_options,
            )
        });
    let mut test = heldout::test_groups(model, campaign, roles);
    let (series, with_series) = heldout::series_groups(model, campaign, roles, options);
    test.extend(series);
    let cross_groups = heldout::cross_groups(
        model,
        campaign,
        roles,
        options,
        refit_with,
        &context.solve_options,
    );
    (
        StepReport {
            step,
            candidates: candidates.len(),
            identifiable: reduced.kept.len(),
            fit,
            fit_orientation: (!orientation.is_empty()).then(|| ErrorNormStats::of(&orientation)),
            loaded_rms,
            cv_rms,
            test,
            cross_groups,
            acceptance: None,
            residual_hyper: refit_with.residual,
            maps_hyper: refit_with.maps,
            iterations: solved.iterations,
        },
        with_series,
    )
}

/// The residual model's hyper-parameters: the grid point with the lowest pooled RMS over the
/// left-out groups (`options.groups`) or, without groups, over the held-out series.
fn choose_hyper(
    model: &EgModel,
    kept: &[Param],
    maps: Option<JointMapsHyper>,
    context: &StepContext,
) -> Option<ResidualHyper> {
    choose_by_held_out(&HYPER_GRID, model, context, |hyper| Refit {
        kept,
        residual: Some(hyper),
        maps,
    })
}

/// The joint maps' hyper-parameters, chosen like the residual model's (the residual model, if
/// one was kept before, retrained on top of each candidate).
fn choose_maps(
    model: &EgModel,
    kept: &[Param],
    residual: Option<ResidualHyper>,
    context: &StepContext,
) -> Option<JointMapsHyper> {
    choose_by_held_out(&MAPS_GRID, model, context, |maps| Refit {
        kept,
        residual,
        maps: Some(maps),
    })
}

/// The candidate whose refit gives the lowest pooled RMS over the left-out groups
/// (`options.groups`) or, without groups, over the held-out series.
fn choose_by_held_out<'a, H: Copy>(
    grid: &[H],
    model: &EgModel,
    context: &StepContext,
    refit: impl Fn(H) -> Refit<'a>,
) -> Option<H> {
    let StepContext {
        campaign,
        options,
        roles,
        ..
    } = *context;
    let mut best: Option<(f64, H)> = None;
    for &candidate in grid {
        let refit_with = refit(candidate);
        let groups = if options.groups.is_some() {
            heldout::cross_groups(
                model,
                campaign,
                roles,
                options,
                refit_with,
                &context.solve_options,
            )
        } else {
            let trained = heldout::refit(
                model,
                campaign,
                &roles.fit_mult,
                refit_with,
                &context.solve_options,
                options.seed,
            );
            heldout::series_groups(&trained, campaign, roles, options).0
        };
        let refs: Vec<&TestGroup> = groups.iter().collect();
        if let Some(rms) = heldout::pooled_rms(&refs)
            && best.is_none_or(|(b, _)| rms < b)
        {
            best = Some((rms, candidate));
        }
    }
    best.map(|(_, h)| h)
}
