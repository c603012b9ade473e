//! The whole identification: registration, a sequence of growing models (the iteration
//! table), and for the final model its uncertainty, bootstrap, outliers and residuals.
//!
//! **Protocol.** Readings are split by *configuration* (never by row): an optional test set
//! ([`FitOptions::test_fraction`] of the configurations, and/or readings of set-ups that have
//! no fit readings, such as a second series) is never seen by the fit; k-fold
//! cross-validation, also by configuration, runs inside the fit set. A test set-up without fit
//! readings has only its registration fitted, on every other of its configurations, and is
//! scored on the rest.
//!
//! **Steps.** Each step frees more parameters than the one before, reduces them to the
//! identifiable set ([`crate::identify`]) and refits: registration only (set-ups and targets
//! on the nominal, rigid robot), + geometry (DH rows with Hayati β), + compliance (the robot's
//! eDoFs, sagging under gravity and any loads; the earlier steps are rigid), optionally
//! + lumped masses and + joint-angle harmonics.

use crate::campaign::Campaign;
use crate::identify;
use crate::params::{EgModel, Param};
use crate::register;
use crate::resample::{bootstrap_se, cross_validate};
use crate::solve::{self, Loss, SolveOptions};
use deflex_model::spatial::rotation_log;
use nalgebra::{DMatrix, Vector3};
use rand::SeedableRng;
use rand::seq::SliceRandom;
use rand_chacha::ChaCha8Rng;

/// One step of the model sequence.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Step {
    /// Set-ups and targets only, nominal rigid robot.
    Registration,
    /// + DH rows (θ, d, a, α, and β on parallel-axis rows).
    Geometry,
    /// + the robot's eDoF compliances (gravity sag, payload, loads).
    Compliance,
    /// + lumped masses and first moments of the bodies.
    Masses,
    /// + joint-angle harmonics up to this order on every joint.
    Harmonics(u8),
}

impl Step {
    /// Name in tables.
    pub fn name(self) -> String {
        match self {
            Step::Registration => "registration only".into(),
            Step::Geometry => "+ geometry (DH, Hayati β)".into(),
            Step::Compliance => "+ compliance (gravity sag, loads)".into(),
            Step::Masses => "+ lumped masses".into(),
            Step::Harmonics(n) => format!("+ joint harmonics (order ≤ {n})"),
        }
    }

    /// Whether the robot is elastic at this step.
    fn elastic(self) -> bool {
        !matches!(self, Step::Registration | Step::Geometry)
    }
}

/// Options of [`fit`].
#[derive(Clone, Debug)]
pub struct FitOptions {
    /// Model steps, in order (each adds to the previous).
    pub steps: Vec<Step>,
    /// Robust loss.
    pub loss: Loss,
    /// Cross-validation folds by configuration (0 = none).
    pub folds: usize,
    /// Bootstrap replicates by configuration (0 = none).
    pub bootstrap: usize,
    /// Fraction of the configurations of fit set-ups held out as a test set (0 = none).
    pub test_fraction: f64,
    /// Seed of the splits and the bootstrap.
    pub seed: u64,
    /// Identifiability tolerance ([`identify::DEFAULT_TOLERANCE`]).
    pub tolerance: f64,
    /// Only these eDoF compliances are free in the compliance step (labels such as `J2.z`);
    /// empty = all of the robot's eDoFs.
    pub elastic_edofs: Vec<String>,
    /// Readings (campaign indices) never fitted: a test file's readings.
    pub held_out_readings: Vec<usize>,
}

impl Default for FitOptions {
    fn default() -> Self {
        FitOptions {
            steps: vec![Step::Registration, Step::Geometry, Step::Compliance],
            loss: Loss::HUBER_DEFAULT,
            folds: 5,
            bootstrap: 0,
            test_fraction: 0.0,
            seed: 1,
            tolerance: identify::DEFAULT_TOLERANCE,
            elastic_edofs: Vec::new(),
            held_out_readings: Vec::new(),
        }
    }
}

/// Largest number of folds and bootstrap replicates.
pub const MAX_FOLDS: usize = 50;
/// Largest number of bootstrap replicates.
pub const MAX_BOOTSTRAP: usize = 2000;

/// Why a fit cannot run.
#[derive(Debug, thiserror::Error)]
pub enum FitError {
    /// Options out of range.
    #[error("{field}: {message}")]
    Option {
        /// Option concerned.
        field: &'static str,
        /// What is wrong.
        message: String,
    },
    /// Nothing to fit on.
    #[error("no readings left to fit on (all held out, or none given)")]
    NoFitData,
    /// A geometric step on a robot without a DH table.
    #[error(
        "geometric calibration needs a robot described by a DH table (standard or modified); `{0}` comes from a URDF"
    )]
    NotDh(String),
    /// An `elastic_edofs` label names no eDoF of the robot.
    #[error(
        "eDoF `{label}` is not in the robot (its eDoFs: {known}); add its stiffness to the robot file first"
    )]
    UnknownEdof {
        /// Label given.
        label: String,
        /// The robot's eDoFs.
        known: String,
    },
}

pub use crate::outcome::{
    ErrorStats, Estimate, FitResult, Outlier, RowResidual, StepReport, TestGroup,
};

/// Candidates of a step, in priority order.
fn candidates(
    model: &EgModel,
    steps: &[Step],
    upto: usize,
    elastic: &[usize],
    fit_setups: &[usize],
) -> Vec<Param> {
    let mut out: Vec<Param> = model
        .registration_params()
        .into_iter()
        .filter(|p| match p {
            Param::SetupRotation(s, _) | Param::SetupTranslation(s, _) => fit_setups.contains(s),
            _ => true,
        })
        .collect();
    for step in &steps[..=upto] {
        match *step {
            Step::Registration => {}
            Step::Geometry => out.extend(model.geometric_params()),
            Step::Compliance => out.extend(elastic.iter().map(|&e| Param::Compliance(e))),
            Step::Masses => {
                for b in 0..model.robot.joint_count() {
                    out.push(Param::Mass(b));
                    for k in 0..3 {
                        out.push(Param::FirstMoment(b, k));
                    }
                }
            }
            Step::Harmonics(order) => {
                for joint in 0..model.robot.joint_count() {
                    for n in 1..=order {
                        for sine in [false, true] {
                            out.push(Param::Harmonic {
                                joint,
                                order: n,
                                sine,
                            });
                        }
                    }
                }
            }
        }
    }
    out
}

/// Value of `param` in `model` relative to `reference` (set-up rotations: the rotation vector
/// from the reference's rotation, robot-world axes).
pub fn relative_value(model: &EgModel, reference: &EgModel, param: Param) -> f64 {
    match param {
        Param::SetupRotation(s, k) => {
            let r = reference.setups[s].pose.rotation.inverse() * model.setups[s].pose.rotation;
            rotation_log(&r)[k]
        }
        _ => model.value(param) - reference.value(param),
    }
}

/// Error norms of readings `rows` (absolute only) with `model`.
fn norms(model: &EgModel, campaign: &Campaign, rows: &[usize]) -> Vec<f64> {
    rows.iter()
        .map(|&i| campaign.residual(model, i, &[], None).norm())
        .collect()
}

/// Run the identification (module documentation).
pub fn fit(
    start: &EgModel,
    campaign: &Campaign,
    options: &FitOptions,
) -> Result<FitResult, FitError> {
    if options.folds == 1 || options.folds > MAX_FOLDS {
        return Err(FitError::Option {
            field: "folds",
            message: format!("expected 0 (none) or 2…{MAX_FOLDS}, got {}", options.folds),
        });
    }
    if options.bootstrap > MAX_BOOTSTRAP {
        return Err(FitError::Option {
            field: "bootstrap",
            message: format!(
                "at most {MAX_BOOTSTRAP} replicates, got {}",
                options.bootstrap
            ),
        });
    }
    if !(0.0..=0.9).contains(&options.test_fraction) {
        return Err(FitError::Option {
            field: "test_fraction",
            message: format!("expected 0…0.9, got {}", options.test_fraction),
        });
    }
    if options.steps.iter().any(|s| *s != Step::Registration) && start.robot.dh_convention.is_none()
    {
        return Err(FitError::NotDh(start.robot.name.clone()));
    }
    let edof_labels: Vec<String> = start.robot.edofs().map(|e| e.label()).collect();
    let elastic: Vec<usize> = if options.elastic_edofs.is_empty() {
        (0..edof_labels.len()).collect()
    } else {
        options
            .elastic_edofs
            .iter()
            .map(|label| {
                edof_labels
                    .iter()
                    .position(|l| l == label)
                    .ok_or_else(|| FitError::UnknownEdof {
                        label: label.clone(),
                        known: edof_labels.join(", "),
                    })
            })
            .collect::<Result<_, _>>()?
    };
    let mut rng = ChaCha8Rng::seed_from_u64(options.seed);
    let total = campaign.len();
    let n_abs = campaign.absolute.len();
    // Set-ups with readings: which are fit set-ups (some configurations fitted)?
    let configs = campaign.total_configs();
    // Configurations of the absolute readings that may be fitted.
    let held_out: std::collections::BTreeSet<usize> =
        options.held_out_readings.iter().copied().collect();
    let mut config_ids: Vec<usize> = (0..n_abs)
        .filter(|i| !held_out.contains(i))
        .map(|i| campaign.config_of[i])
        .collect();
    config_ids.sort_unstable();
    config_ids.dedup();
    config_ids.shuffle(&mut rng);
    let test_count = (options.test_fraction * config_ids.len() as f64).round() as usize;
    let mut is_test_config = vec![false; configs];
    for &c in config_ids.iter().take(test_count) {
        is_test_config[c] = true;
    }
    let setup_count = start.setups.len();
    // A set-up is a fit set-up if any of its readings falls outside the test configurations
    // and it was not declared a test set-up by the caller (see `fit_with_test_setups`).
    let mut fit_mult: Vec<f64> = (0..total)
        .map(|i| {
            if is_test_config[campaign.config(i)] {
                0.0
            } else {
                1.0
            }
        })
        .collect();
    for &i in &options.held_out_readings {
        if i < total {
            fit_mult[i] = 0.0;
        }
    }
    let fit_setups: Vec<usize> = (0..setup_count)
        .filter(|&s| (0..n_abs).any(|i| campaign.setup_of[i] == s && fit_mult[i] > 0.0))
        .collect();
    let registration_only: Vec<usize> = (0..setup_count)
        .filter(|s| !fit_setups.contains(s))
        .collect();
    // Readings of registration-only set-ups: alternate configurations register / score.
    let mut registration_mult = vec![0.0; total];
    let mut scored_registration_rows: Vec<usize> = Vec::new();
    for &s in &registration_only {
        let mut their_configs: Vec<usize> = (0..n_abs)
            .filter(|&i| campaign.setup_of[i] == s)
            .map(|i| campaign.config_of[i])
            .collect();
        their_configs.sort_unstable();
        their_configs.dedup();
        for i in (0..n_abs).filter(|&i| campaign.setup_of[i] == s) {
            let rank = their_configs
                .binary_search(&campaign.config_of[i])
                .unwrap_or(0);
            if rank.is_multiple_of(2) {
                registration_mult[i] = 1.0;
            } else {
                scored_registration_rows.push(i);
            }
        }
    }
    if fit_mult.iter().all(|m| *m == 0.0) {
        return Err(FitError::NoFitData);
    }
    let fit_abs_rows: Vec<usize> = (0..n_abs).filter(|&i| fit_mult[i] > 0.0).collect();
    let test_rows: Vec<usize> = (0..n_abs)
        .filter(|&i| fit_mult[i] == 0.0 && fit_setups.contains(&campaign.setup_of[i]))
        .collect();
    let fit_loaded_rows: Vec<usize> = (n_abs..total).filter(|&i| fit_mult[i] > 0.0).collect();
    // Fold of each configuration.
    let fold_of: Vec<usize> = {
        let mut ids: Vec<usize> = (0..configs).filter(|&c| !is_test_config[c]).collect();
        ids.shuffle(&mut rng);
        let mut fold = vec![usize::MAX; configs];
        for (k, c) in ids.into_iter().enumerate() {
            fold[c] = k % options.folds.max(1);
        }
        fold
    };

    let solve_options = SolveOptions {
        loss: options.loss,
        ..SolveOptions::default()
    };
    let mut model = start.clone();
    let nominal_compliance = model.compliance.clone();
    let target_ids: Vec<usize> = (0..model.targets.len()).collect();
    let unknown_setups: Vec<usize> = fit_setups
        .iter()
        .copied()
        .filter(|&s| model.setups[s].pose == deflex_model::Pose::identity())
        .collect();
    let unknown_targets: Vec<usize> = target_ids
        .iter()
        .copied()
        .filter(|&t| model.targets[t].position == Vector3::zeros())
        .collect();
    if !options.steps.first().is_some_and(|s| s.elastic()) {
        model.compliance.iter_mut().for_each(|c| *c = 0.0);
    }
    register::initialise(
        &mut model,
        campaign,
        &unknown_setups,
        &unknown_targets,
        &fit_mult,
        4,
    );
    let registered_start = model.clone();

    let mut steps = Vec::new();
    let mut reduction = None;
    let mut outcome = None;
    let mut elastic_started = false;
    for (index, &step) in options.steps.iter().enumerate() {
        if step.elastic() && !elastic_started {
            elastic_started = true;
            // Every eDoF starts at (and, when not freed, keeps) the robot file's compliance.
            model.compliance = nominal_compliance.clone();
        }
        let candidates = candidates(&model, &options.steps, index, &elastic, &fit_setups);
        let reduced = identify::reduce(&model, campaign, &candidates, &fit_mult, options.tolerance);
        let solved = solve::solve(
            &mut model,
            campaign,
            &reduced.kept,
            &fit_mult,
            &solve_options,
        );
        let fit_stats = ErrorStats::of(&norms(&model, campaign, &fit_abs_rows));
        let loaded_rms = (!fit_loaded_rows.is_empty()).then(|| {
            let n = norms(&model, campaign, &fit_loaded_rows);
            (n.iter().map(|e| e * e).sum::<f64>() / n.len() as f64).sqrt()
        });
        let cv_rms = (options.folds >= 2).then(|| {
            cross_validate(
                &model,
                campaign,
                &reduced.kept,
                &fit_mult,
                &fold_of,
                options.folds,
                &solve_options,
            )
        });
        let mut test = Vec::new();
        if !test_rows.is_empty() {
            let mut by_setup: std::collections::BTreeMap<usize, Vec<usize>> = Default::default();
            for &i in &test_rows {
                by_setup.entry(campaign.setup_of[i]).or_default().push(i);
            }
            for (s, rows) in by_setup {
                test.push(TestGroup {
                    name: format!("{}: held-out configurations", model.setups[s].name),
                    stats: ErrorStats::of(&norms(&model, campaign, &rows)),
                });
            }
        }
        for &s in &registration_only {
            let mut scored = model.clone();
            let mult: Vec<f64> = (0..total)
                .map(|i| {
                    if i < n_abs && campaign.setup_of[i] == s {
                        registration_mult[i]
                    } else {
                        0.0
                    }
                })
                .collect();
            register::initialise(&mut scored, campaign, &[s], &[], &mult, 1);
            let params: Vec<Param> = (0..3)
                .map(|k| Param::SetupRotation(s, k))
                .chain((0..3).map(|k| Param::SetupTranslation(s, k)))
                .collect();
            solve::solve(&mut scored, campaign, &params, &mult, &solve_options);
            let rows: Vec<usize> = scored_registration_rows
                .iter()
                .copied()
                .filter(|&i| campaign.setup_of[i] == s)
                .collect();
            test.push(TestGroup {
                name: format!(
                    "{}: own registration on half, scored on the rest",
                    model.setups[s].name
                ),
                stats: ErrorStats::of(&norms(&scored, campaign, &rows)),
            });
            if index + 1 == options.steps.len() {
                model.setups[s] = scored.setups[s].clone();
            }
        }
        steps.push(StepReport {
            step,
            candidates: candidates.len(),
            identifiable: reduced.kept.len(),
            fit: fit_stats,
            loaded_rms,
            cv_rms,
            test,
            iterations: solved.iterations,
        });
        reduction = Some(reduced);
        outcome = Some(solved);
    }
    let reduction = reduction.ok_or(FitError::Option {
        field: "steps",
        message: "at least one step is needed".into(),
    })?;
    let outcome = outcome.expect("set with the reduction");

    // Uncertainty of the final step.
    let kept = &reduction.kept;
    let (a, _) = solve::normal_equations(&model, campaign, kept, &fit_mult, &outcome.weights);
    let residuals = solve::standardised_residuals(&model, campaign, &fit_mult);
    let equations = 3.0 * fit_mult.iter().filter(|m| **m > 0.0).count() as f64;
    let dof = (equations - kept.len() as f64).max(1.0);
    let weighted_chi2: f64 = residuals
        .iter()
        .zip(&outcome.weights)
        .filter_map(|(r, w)| r.map(|r| w * r.norm_squared()))
        .sum();
    let chi2: f64 = residuals
        .iter()
        .filter_map(|r| r.map(|r| r.norm_squared()))
        .sum();
    let chi2_per_dof = chi2 / dof;
    let variance_scale = weighted_chi2 / dof;
    let covariance = a
        .clone()
        .cholesky()
        .map(|c| c.inverse() * variance_scale)
        .unwrap_or_else(|| DMatrix::from_element(kept.len(), kept.len(), f64::NAN));
    let bootstrap = (options.bootstrap > 0).then(|| {
        bootstrap_se(
            &model,
            campaign,
            kept,
            &fit_mult,
            &outcome.weights,
            options.bootstrap,
            &mut rng,
        )
    });
    let estimates: Vec<Estimate> = kept
        .iter()
        .enumerate()
        .map(|(k, &param)| Estimate {
            param,
            name: model.param_name(param),
            unit: EgModel::unit(param),
            start: match param {
                Param::SetupRotation(..) => 0.0,
                Param::SetupTranslation(..) | Param::Target(..) => registered_start.value(param),
                _ => start.value(param),
            },
            value: match param {
                Param::SetupRotation(..) => relative_value(&model, &registered_start, param),
                _ => model.value(param),
            },
            standard_error: covariance[(k, k)].max(0.0).sqrt(),
            bootstrap_se: bootstrap.as_ref().map(|b| b[k]),
        })
        .collect();
    let mut correlations = Vec::new();
    for k in 0..kept.len() {
        for l in 0..k {
            let rho = covariance[(k, l)] / (covariance[(k, k)] * covariance[(l, l)]).sqrt();
            if rho.abs() >= 0.95 {
                correlations.push((estimates[l].name.clone(), estimates[k].name.clone(), rho));
            }
        }
    }
    correlations.sort_by(|a, b| b.2.abs().total_cmp(&a.2.abs()));
    correlations.truncate(20);
    let warning = (chi2_per_dof > 4.0).then(|| {
        format!(
            "χ²/dof = {chi2_per_dof:.1}: the residuals are {:.1}× the stated measurement noise. The model leaves a systematic error the data resolve; the standard errors are scaled by the residual, but they and the intervals describe noise-like scatter, not that model error.",
            chi2_per_dof.sqrt()
        )
    });
    let mut outliers = Vec::new();
    let mut downweighted = 0;
    for (i, w) in outcome.weights.iter().enumerate() {
        if fit_mult[i] == 0.0 {
            continue;
        }
        if *w < 1.0 {
            downweighted += 1;
        }
        if *w < 0.5 {
            let (line, label) = if i < n_abs {
                (
                    campaign.absolute[i].line,
                    campaign.absolute[i].setup.clone(),
                )
            } else {
                (0, campaign.loaded[i - n_abs].load_case.clone())
            };
            outliers.push(Outlier {
                index: i,
                line,
                label,
                residual: residuals[i].map_or(0.0, |r| r.norm() * campaign.sigma(i)),
                weight: *w,
            });
        }
    }
    outliers.sort_by(|a, b| b.residual.total_cmp(&a.residual));
    let row_residuals = (0..total)
        .map(|i| RowResidual {
            index: i,
            residual: campaign.residual(&model, i, &[], None),
            role: if fit_mult[i] > 0.0 {
                "fit"
            } else if registration_mult[i] > 0.0 {
                "registration"
            } else {
                "test"
            },
        })
        .collect();
    Ok(FitResult {
        steps,
        start: start.clone(),
        reduction,
        estimates,
        covariance,
        chi2_per_dof,
        warning,
        outliers,
        downweighted,
        residuals: row_residuals,
        fit_rows: fit_mult.iter().map(|m| *m > 0.0).collect(),
        correlations,
        loss: options.loss,
        registration_only_setups: registration_only
            .iter()
            .map(|&s| model.setups[s].name.clone())
            .collect(),
        model,
    })
}
