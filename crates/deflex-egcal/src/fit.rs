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
use crate::identify::{self, Reduction};
use crate::params::{EgModel, Param, Unit};
use crate::register;
use crate::solve::{self, Loss, SolveOptions};
use deflex_model::spatial::rotation_log;
use nalgebra::{DMatrix, Vector3};
use rand::seq::SliceRandom;
use rand::{Rng, SeedableRng};
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

/// Error distribution of a set of readings (norm of the 3-D error, m).
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct ErrorStats {
    /// Readings.
    pub count: usize,
    /// Root mean square.
    pub rms: f64,
    /// Mean.
    pub mean: f64,
    /// 95th percentile.
    pub p95: f64,
    /// Maximum.
    pub max: f64,
}

impl ErrorStats {
    /// Statistics of error norms.
    pub fn of(norms: &[f64]) -> ErrorStats {
        if norms.is_empty() {
            return ErrorStats::default();
        }
        let n = norms.len() as f64;
        let mut sorted = norms.to_vec();
        sorted.sort_by(f64::total_cmp);
        let rank = ((0.95 * n).ceil() as usize).clamp(1, sorted.len()) - 1;
        ErrorStats {
            count: norms.len(),
            rms: (norms.iter().map(|e| e * e).sum::<f64>() / n).sqrt(),
            mean: norms.iter().sum::<f64>() / n,
            p95: sorted[rank],
            max: sorted[sorted.len() - 1],
        }
    }
}

/// A held-out group scored at each step.
#[derive(Clone, Debug, PartialEq)]
pub struct TestGroup {
    /// Description (e.g. `A: held-out configurations`).
    pub name: String,
    /// Error distribution.
    pub stats: ErrorStats,
}

/// One row of the iteration table.
#[derive(Clone, Debug)]
pub struct StepReport {
    /// Step.
    pub step: Step,
    /// Candidate parameters.
    pub candidates: usize,
    /// Identifiable (fitted) parameters.
    pub identifiable: usize,
    /// Absolute readings in the fit: error distribution.
    pub fit: ErrorStats,
    /// Loaded readings in the fit: RMS of the displacement error (m), if any.
    pub loaded_rms: Option<f64>,
    /// Cross-validated RMS over absolute readings (m), if folds > 0.
    pub cv_rms: Option<f64>,
    /// Test groups.
    pub test: Vec<TestGroup>,
    /// LM iterations.
    pub iterations: usize,
}

/// One parameter's estimate.
#[derive(Clone, Debug)]
pub struct Estimate {
    /// Parameter.
    pub param: Param,
    /// Name.
    pub name: String,
    /// Unit.
    pub unit: Unit,
    /// Starting (nominal) value; for set-up rotations 0 (the estimate is the rotation from the
    /// registration-only fit).
    pub start: f64,
    /// Estimate.
    pub value: f64,
    /// Standard error scaled by the residual (√(χ²/dof) × formal).
    pub standard_error: f64,
    /// Bootstrap standard error, if run.
    pub bootstrap_se: Option<f64>,
}

/// A down-weighted reading.
#[derive(Clone, Debug)]
pub struct Outlier {
    /// Reading index in the campaign.
    pub index: usize,
    /// File line (absolute readings), if known.
    pub line: u64,
    /// Set-up or load case.
    pub label: String,
    /// Residual norm (m).
    pub residual: f64,
    /// Robust weight (1 = full).
    pub weight: f64,
}

/// Residual of one reading with the final model.
#[derive(Clone, Debug)]
pub struct RowResidual {
    /// Reading index.
    pub index: usize,
    /// Measured − predicted (m; tracker frame for absolute readings).
    pub residual: Vector3<f64>,
    /// Role: `fit`, `test`, `registration`.
    pub role: &'static str,
}

/// Everything a fit produces.
#[derive(Clone, Debug)]
pub struct FitResult {
    /// The iteration table.
    pub steps: Vec<StepReport>,
    /// The final model.
    pub model: EgModel,
    /// The starting model (nominal robot).
    pub start: EgModel,
    /// Reduction of the final step.
    pub reduction: Reduction,
    /// Estimates of the final step's identifiable parameters.
    pub estimates: Vec<Estimate>,
    /// Covariance of the estimates (same order), scaled by the residual.
    pub covariance: DMatrix<f64>,
    /// χ²/dof of the final fit with the stated σ (absolute and loaded readings together).
    pub chi2_per_dof: f64,
    /// Plain warning when χ²/dof ≫ 1.
    pub warning: Option<String>,
    /// Readings whose robust weight fell below 0.5, largest residual first.
    pub outliers: Vec<Outlier>,
    /// Number of readings down-weighted at all (weight < 1).
    pub downweighted: usize,
    /// Final residuals of every reading.
    pub residuals: Vec<RowResidual>,
    /// Role multiplicity used: 1 = fit, 0 = held out.
    pub fit_rows: Vec<bool>,
    /// Largest correlations |ρ| ≥ 0.95 between identified parameters.
    pub correlations: Vec<(String, String, f64)>,
    /// Robust loss used.
    pub loss: Loss,
    /// Set-ups fitted on registration only (test set-ups).
    pub registration_only_setups: Vec<String>,
}

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

/// k-fold cross-validation by configuration: refit (warm start, same identifiable set) on the
/// other folds and score each fold's absolute readings. RMS of the held-out error norms (m).
fn cross_validate(
    model: &EgModel,
    campaign: &Campaign,
    kept: &[Param],
    fit_mult: &[f64],
    fold_of: &[usize],
    folds: usize,
    options: &SolveOptions,
) -> f64 {
    let mut squares = 0.0;
    let mut count = 0usize;
    for fold in 0..folds {
        let train: Vec<f64> = (0..campaign.len())
            .map(|i| {
                if fold_of[campaign.config(i)] == fold {
                    0.0
                } else {
                    fit_mult[i]
                }
            })
            .collect();
        let held: Vec<usize> = (0..campaign.absolute.len())
            .filter(|&i| fit_mult[i] > 0.0 && fold_of[campaign.config(i)] == fold)
            .collect();
        if held.is_empty() {
            continue;
        }
        let mut trained = model.clone();
        solve::solve(&mut trained, campaign, kept, &train, options);
        for e in norms(&trained, campaign, &held) {
            squares += e * e;
            count += 1;
        }
    }
    (squares / count.max(1) as f64).sqrt()
}

/// Bootstrap by configuration: resample configurations with replacement, refit with the final
/// robust weights fixed (warm start), and return each parameter's standard deviation.
fn bootstrap_se(
    model: &EgModel,
    campaign: &Campaign,
    kept: &[Param],
    fit_mult: &[f64],
    weights: &[f64],
    replicates: usize,
    rng: &mut ChaCha8Rng,
) -> Vec<f64> {
    let configs = campaign.total_configs();
    let fitted: Vec<usize> = {
        let mut c: Vec<usize> = (0..campaign.len())
            .filter(|&i| fit_mult[i] > 0.0)
            .map(|i| campaign.config(i))
            .collect();
        c.sort_unstable();
        c.dedup();
        c
    };
    let options = SolveOptions {
        loss: Loss::Squared,
        max_iterations: 20,
        ..SolveOptions::default()
    };
    let mut sums = vec![0.0; kept.len()];
    let mut squares = vec![0.0; kept.len()];
    for _ in 0..replicates {
        let mut draws = vec![0.0; configs];
        for _ in 0..fitted.len() {
            draws[fitted[rng.gen_range(0..fitted.len())]] += 1.0;
        }
        let mult: Vec<f64> = (0..campaign.len())
            .map(|i| fit_mult[i] * draws[campaign.config(i)] * weights[i])
            .collect();
        let mut replica = model.clone();
        solve::solve(&mut replica, campaign, kept, &mult, &options);
        for (k, &param) in kept.iter().enumerate() {
            let v = relative_value(&replica, model, param);
            sums[k] += v;
            squares[k] += v * v;
        }
    }
    let n = replicates as f64;
    sums.iter()
        .zip(&squares)
        .map(|(s, q)| {
            ((q / n - (s / n).powi(2)) * n / (n - 1.0).max(1.0))
                .max(0.0)
                .sqrt()
        })
        .collect()
}
