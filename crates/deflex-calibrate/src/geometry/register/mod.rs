//! Registration of a measuring session with the robot frozen: where the tracker stands
//! (6 parameters: `R_s ← R_s exp(φ)`, `t_s ← t_s + R_s δt`) and, when asked, where a new
//! target sits on the flange (3, or 6 with its frame's rotation when orientations are measured),
//! from a handful of readings. Nothing of the robot (geometry, compliance, joint terms, residual
//! model) moves.
//!
//! **Method.** Closed-form start ([`start`]: Kabsch on the predicted world points, the target by
//! linear least squares, the target rotation by a chordal mean), then the robust LM of
//! [`crate::geometry::solve`] on the registration parameters only. Standard errors from `(JᵀWJ)⁻¹`
//! scaled by the residual's `χ²/dof` (not below 1: a handful of readings may scatter less than
//! their stated σ by chance).
//!
//! **What can go wrong** (each a [`RegistrationWarning`]): fewer readings than
//! [`RECOMMENDED_READINGS`]; readings bunched in space (the set-up's rotation is then poorly
//! known: RMS distance from their centroid below [`MIN_SPREAD_M`]); a target fitted without
//! the wrist turning (its offset trades with the set-up's translation: flange orientations
//! spread less than [`MIN_WRIST_SPREAD_RAD`]); a parameter whose Jacobian column is nearly a
//! combination of the others ([`crate::geometry::identify`] independence below
//! [`crate::geometry::identify::WEAK_THRESHOLD`]); and a residual far above the calibration's own
//! held-out error — the robot itself has changed: re-calibrate it.

pub mod start;

use crate::geometry::campaign::{Campaign, ReadingKind};
use crate::geometry::identify;
use crate::geometry::params::{EgModel, Param, Unit};
use crate::geometry::solve::{self, Loss, SolveOptions};
use crate::stats::ErrorNormStats;
use nalgebra::{DMatrix, Rotation3, Vector3};

/// Readings below which a registration is flagged (the user protocol asks for 30).
pub const RECOMMENDED_READINGS: usize = 12;
/// RMS distance of the readings from their centroid below which they are "too close" (m).
pub const MIN_SPREAD_M: f64 = 0.15;
/// RMS angle of the flange orientations from their mean below which the wrist "did not turn"
/// for a target fit (rad, ≈ 17°).
pub const MIN_WRIST_SPREAD_RAD: f64 = 0.3;

/// What to register.
#[derive(Clone, Debug)]
pub struct RegisterOptions {
    /// Set-up (index in the model) whose registration is fitted.
    pub setup: usize,
    /// Target (index in the model) whose offset is fitted too (3 parameters, 6 with measured
    /// orientations), if any.
    pub target: Option<usize>,
    /// Robust loss.
    pub loss: Loss,
    /// The residual RMS (m) above which the robot itself is deemed changed (the calibration's
    /// held-out RMS × a margin); `None`: not checked.
    pub recalibrate_above_m: Option<f64>,
    /// Start the set-up from the readings (Kabsch) rather than its current registration.
    pub restart_setup: bool,
}

/// One registered parameter.
#[derive(Clone, Debug, PartialEq)]
pub struct RegisteredParam {
    /// Parameter.
    pub param: Param,
    /// Name (`setup[B].tx`, `target[probe].rz`).
    pub name: String,
    /// Unit.
    pub unit: Unit,
    /// Value (set-up and target rotations: the rotation-vector increment from the start).
    pub value: f64,
    /// Standard error, scaled by the residual.
    pub standard_error: f64,
    /// Independent part of its scaled Jacobian column (0…1).
    pub independence: f64,
}

/// Why a registration deserves a second look.
#[derive(Clone, Debug, PartialEq)]
pub enum RegistrationWarning {
    /// Fewer readings than recommended.
    TooFewReadings {
        /// Readings used.
        readings: usize,
        /// Recommended.
        recommended: usize,
    },
    /// The readings are bunched in space.
    TooClose {
        /// RMS distance from their centroid (m).
        spread_m: f64,
        /// Bound.
        minimum_m: f64,
    },
    /// A target fitted without turning the wrist.
    NoWristRotation {
        /// RMS angle of the flange orientations from their mean (rad).
        spread_rad: f64,
        /// Bound.
        minimum_rad: f64,
    },
    /// A parameter these readings barely separate from the others.
    WeaklySeparated {
        /// Parameter name.
        name: String,
        /// Independent part (0…1).
        independence: f64,
    },
    /// Residual far above the calibration's own held-out error.
    Recalibrate {
        /// Position residual RMS (m).
        rms_m: f64,
        /// Bound (m).
        bound_m: f64,
    },
}

impl std::fmt::Display for RegistrationWarning {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            Self::TooFewReadings {
                readings,
                recommended,
            } => write!(
                f,
                "only {readings} readings (at least {recommended} recommended, 30 in the protocol): the registration's standard errors are large"
            ),
            Self::TooClose {
                spread_m,
                minimum_m,
            } => write!(
                f,
                "the readings lie within {:.0} mm RMS of their centre (< {:.0} mm): spread them over the workspace, or the set-up's rotation is poorly known",
                spread_m * 1e3,
                minimum_m * 1e3
            ),
            Self::NoWristRotation {
                spread_rad,
                minimum_rad,
            } => write!(
                f,
                "the flange turned only {:.1}° RMS (< {:.0}°) over the readings: a target offset then trades with the set-up's translation; turn the wrist between readings",
                spread_rad.to_degrees(),
                minimum_rad.to_degrees()
            ),
            Self::WeaklySeparated { name, independence } => write!(
                f,
                "{name} is barely separated by these readings (independent part {independence:.1e}): add readings in other configurations"
            ),
            Self::Recalibrate { rms_m, bound_m } => write!(
                f,
                "the registration residual is {:.3} mm RMS, above {:.3} mm: the robot itself has changed (a crash, a motor or gear swap, a loose probe?); re-calibrate it",
                rms_m * 1e3,
                bound_m * 1e3
            ),
        }
    }
}

/// What a registration produced.
#[derive(Clone, Debug)]
pub struct Registration {
    /// Registered parameters (set-up first, then target).
    pub params: Vec<RegisteredParam>,
    /// Readings used (positions).
    pub readings: usize,
    /// Position residuals of those readings (m).
    pub position: ErrorNormStats,
    /// Orientation residuals (rad), when orientations were measured and fitted.
    pub orientation: Option<ErrorNormStats>,
    /// χ²/dof with the stated σ.
    pub chi2_per_dof: f64,
    /// What deserves a second look.
    pub warnings: Vec<RegistrationWarning>,
}

/// Why a registration cannot run.
#[derive(Debug, thiserror::Error)]
pub enum RegisterError {
    /// Fewer equations than parameters.
    #[error(
        "{readings} readings give {equations} equations for {params} parameters: at least {minimum} readings are needed"
    )]
    TooFew {
        /// Readings.
        readings: usize,
        /// Equations (3 per position, 3 per orientation).
        equations: usize,
        /// Parameters.
        params: usize,
        /// Minimum number of readings.
        minimum: usize,
    },
    /// A set-up or target index outside the model.
    #[error("{what} {index} is not in the model ({count} known)")]
    Index {
        /// `set-up` or `target`.
        what: &'static str,
        /// Index given.
        index: usize,
        /// Number known.
        count: usize,
    },
}

/// The registration parameters of `options`, in priority order.
pub fn registration_params(campaign: &Campaign, options: &RegisterOptions) -> Vec<Param> {
    let s = options.setup;
    let mut params: Vec<Param> = Param::setup_pose(s).to_vec();
    if let Some(t) = options.target {
        params.extend((0..3).map(|k| Param::Target(t, k)));
        if !campaign.orientation_rows.is_empty() {
            params.extend((0..3).map(|k| Param::TargetRotation(t, k)));
        }
    }
    params
}

/// Register `options.setup` (and `options.target`) on the readings with `multiplicity > 0`
/// (positions, and orientations when the campaign has them); `model` is updated in place.
pub fn register(
    model: &mut EgModel,
    campaign: &Campaign,
    multiplicity: &[f64],
    options: &RegisterOptions,
) -> Result<Registration, RegisterError> {
    check_indices(model, options)?;
    let params = registration_params(campaign, options);
    let used: Vec<usize> = (0..campaign.len())
        .filter(|&i| multiplicity[i] > 0.0)
        .collect();
    let positions: Vec<usize> = used
        .iter()
        .copied()
        .filter(|&i| campaign.kind(i) == ReadingKind::Position)
        .collect();
    let equations = 3 * used.len();
    if equations < params.len() || positions.len() < 3 {
        return Err(RegisterError::TooFew {
            readings: positions.len(),
            equations,
            params: params.len(),
            minimum: params.len().div_ceil(3).max(3),
        });
    }
    let start = model.clone();
    if options.restart_setup || model.setups[options.setup].pose == deflex_model::Pose::identity() {
        let targets: Vec<usize> = options.target.into_iter().collect();
        start::initialise(model, campaign, &[options.setup], &targets, multiplicity, 4);
    }
    if let (Some(t), false) = (options.target, campaign.orientation_rows.is_empty()) {
        start::initialise_target_rotations(model, campaign, &[t], multiplicity);
    }
    let reference = model.clone();
    let solve_options = SolveOptions {
        loss: options.loss,
        ..SolveOptions::default()
    };
    let outcome = solve::solve(model, campaign, &params, multiplicity, &solve_options);
    let reduction = identify::reduce(model, campaign, &params, multiplicity, 0.0);
    let (a, _) = solve::normal_equations(model, campaign, &params, multiplicity, &outcome.weights);
    let residuals = solve::standardised_residuals(model, campaign, multiplicity);
    let chi2: f64 = residuals.iter().flatten().map(|r| r.norm_squared()).sum();
    let dof = (equations as f64 - params.len() as f64).max(1.0);
    let chi2_per_dof = chi2 / dof;
    let covariance = a
        .cholesky()
        .map(|c| c.inverse() * chi2_per_dof.max(1.0))
        .unwrap_or_else(|| DMatrix::from_element(params.len(), params.len(), f64::NAN));
    let registered: Vec<RegisteredParam> = params
        .iter()
        .enumerate()
        .map(|(k, &param)| RegisteredParam {
            param,
            name: model.param_name(param),
            unit: EgModel::unit(param),
            value: registered_value(model, &reference, param),
            standard_error: covariance[(k, k)].max(0.0).sqrt(),
            independence: reduction
                .kept
                .iter()
                .position(|p| *p == param)
                .map_or(0.0, |j| reduction.independence[j]),
        })
        .collect();
    let norms = |kind: ReadingKind| -> Vec<f64> {
        used.iter()
            .filter(|&&i| campaign.kind(i) == kind)
            .map(|&i| campaign.residual(model, i, &[], None).norm())
            .collect()
    };
    let position = ErrorNormStats::of(&norms(ReadingKind::Position));
    let orientation_norms = norms(ReadingKind::Orientation);
    let mut result = Registration {
        params: registered,
        readings: positions.len(),
        position,
        orientation: (!orientation_norms.is_empty())
            .then(|| ErrorNormStats::of(&orientation_norms)),
        chi2_per_dof,
        warnings: Vec::new(),
    };
    result.warnings = warnings(&start, campaign, &positions, options, &result);
    Ok(result)
}

fn check_indices(model: &EgModel, options: &RegisterOptions) -> Result<(), RegisterError> {
    if options.setup >= model.setups.len() {
        return Err(RegisterError::Index {
            what: "set-up",
            index: options.setup,
            count: model.setups.len(),
        });
    }
    match options.target {
        Some(t) if t >= model.targets.len() => Err(RegisterError::Index {
            what: "target",
            index: t,
            count: model.targets.len(),
        }),
        _ => Ok(()),
    }
}

/// Value of a registered parameter (rotations: the increment from `reference`).
fn registered_value(model: &EgModel, reference: &EgModel, param: Param) -> f64 {
    match param {
        Param::TargetRotation(t, k) => {
            let r = model.target_rotation(t) * reference.target_rotation(t).inverse();
            deflex_model::spatial::rotation_log(&r)[k]
        }
        _ => crate::geometry::fit::relative_value(model, reference, param),
    }
}

/// The warnings of a registration (module documentation).
fn warnings(
    start: &EgModel,
    campaign: &Campaign,
    positions: &[usize],
    options: &RegisterOptions,
    result: &Registration,
) -> Vec<RegistrationWarning> {
    let mut out = Vec::new();
    if positions.len() < RECOMMENDED_READINGS {
        out.push(RegistrationWarning::TooFewReadings {
            readings: positions.len(),
            recommended: RECOMMENDED_READINGS,
        });
    }
    let points: Vec<Vector3<f64>> = positions
        .iter()
        .map(|&i| Vector3::from(campaign.absolute[i].position_m))
        .collect();
    let centre = points.iter().sum::<Vector3<f64>>() / points.len() as f64;
    let spread_m = (points
        .iter()
        .map(|p| (p - centre).norm_squared())
        .sum::<f64>()
        / points.len() as f64)
        .sqrt();
    if spread_m < MIN_SPREAD_M {
        out.push(RegistrationWarning::TooClose {
            spread_m,
            minimum_m: MIN_SPREAD_M,
        });
    }
    if options.target.is_some() {
        let spread_rad = flange_spread(start, campaign, positions);
        if spread_rad < MIN_WRIST_SPREAD_RAD {
            out.push(RegistrationWarning::NoWristRotation {
                spread_rad,
                minimum_rad: MIN_WRIST_SPREAD_RAD,
            });
        }
    }
    for p in &result.params {
        if p.independence < identify::WEAK_THRESHOLD {
            out.push(RegistrationWarning::WeaklySeparated {
                name: p.name.clone(),
                independence: p.independence,
            });
        }
    }
    if let Some(bound_m) = options.recalibrate_above_m
        && result.position.rms > bound_m
    {
        out.push(RegistrationWarning::Recalibrate {
            rms_m: result.position.rms,
            bound_m,
        });
    }
    out
}

/// RMS angle of the flange orientations of `rows` from their chordal mean (rad).
fn flange_spread(model: &EgModel, campaign: &Campaign, rows: &[usize]) -> f64 {
    let rotations: Vec<Rotation3<f64>> = rows
        .iter()
        .map(|&i| {
            let row = &campaign.absolute[i];
            model
                .evaluate(
                    &row.q_rad,
                    campaign.target_of[i],
                    &campaign.conditions(model, i),
                )
                .data
                .flange
                .rotation
        })
        .collect();
    let sum = rotations
        .iter()
        .fold(nalgebra::Matrix3::zeros(), |acc, r| acc + r.matrix());
    let svd = sum.svd(true, true);
    let (Some(u), Some(v_t)) = (svd.u, svd.v_t) else {
        return 0.0;
    };
    let mut d = nalgebra::Matrix3::identity();
    if (u * v_t).determinant() < 0.0 {
        d[(2, 2)] = -1.0;
    }
    let mean = Rotation3::from_matrix_unchecked(u * d * v_t);
    (rotations
        .iter()
        .map(|r| r.angle_to(&mean).powi(2))
        .sum::<f64>()
        / rotations.len() as f64)
        .sqrt()
}
