//! What an elasto-geometric fit produces: the iteration table's rows, the estimates, the
//! outliers, the residuals; their error statistics are [`crate::stats::ErrorNormStats`].

use crate::geometry::fit::Step;
use crate::geometry::identify::Reduction;
use crate::geometry::params::{EgModel, Param, Unit};
use crate::geometry::protocol::GroupScore;
use crate::geometry::solve::Loss;
use crate::stats::ErrorNormStats;
use nalgebra::{DMatrix, Vector3};

/// A held-out group scored at each step.
#[derive(Clone, Debug, PartialEq)]
pub struct TestGroup {
    /// Description (e.g. `A: held-out configurations`).
    pub name: String,
    /// Position error distribution (m).
    pub stats: ErrorNormStats,
    /// Orientation error distribution (rad), when measured.
    pub orientation: Option<ErrorNormStats>,
    /// Position RMS of each registration draw (m; one entry for configurations of a fit
    /// set-up, scored with its own registration).
    pub draw_rms: Vec<f64>,
    /// Whether the group is a held-out series or session (registered by the protocol) rather
    /// than held-out configurations of a fit set-up.
    pub registered: bool,
}

impl TestGroup {
    /// A group scored by the registration protocol.
    pub fn registered(name: String, score: GroupScore) -> TestGroup {
        TestGroup {
            name,
            stats: score.position,
            orientation: score.orientation,
            draw_rms: score.draw_rms,
            registered: true,
        }
    }
}

/// The part a reading played.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Role {
    /// Fitted.
    Fit,
    /// Held out from a fit set-up (test configurations, a test file of a known set-up).
    Test,
    /// A held-out series: its own registration by the protocol, then scored.
    HeldOutSeries,
}

impl Role {
    /// Name in files.
    pub fn name(self) -> &'static str {
        match self {
            Role::Fit => "fit",
            Role::Test => "test",
            Role::HeldOutSeries => "held-out series",
        }
    }
}

/// How an opt-in step fared on held-out data.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Acceptance {
    /// Pooled held-out position RMS of the model before the step (m).
    pub before_m: f64,
    /// The same with the step (m).
    pub after_m: f64,
    /// Whether the step is kept in the written model.
    pub accepted: bool,
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
    /// Absolute readings in the fit: position error distribution.
    pub fit: ErrorNormStats,
    /// Orientation error distribution of the fitted readings (rad), when measured.
    pub fit_orientation: Option<ErrorNormStats>,
    /// Loaded readings in the fit: RMS of the displacement error (m), if any.
    pub loaded_rms: Option<f64>,
    /// Cross-validated RMS over absolute readings (m), if folds > 0.
    pub cv_rms: Option<f64>,
    /// Test groups.
    pub test: Vec<TestGroup>,
    /// Groups of the fit data left out in turn (sessions, set-ups, series) and scored by the
    /// registration protocol.
    pub cross_groups: Vec<TestGroup>,
    /// Held-out verdict of an opt-in step, when there were held-out groups to judge by.
    pub acceptance: Option<Acceptance>,
    /// Hyper-parameters of the residual model, when the step has one.
    pub residual_hyper: Option<crate::geometry::residual_model::ResidualHyper>,
    /// The joint maps' hyper-parameters, when the model has joint maps.
    pub maps_hyper: Option<crate::geometry::joint_maps::JointMapsHyper>,
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
    /// Measured − predicted (m; tracker frame for absolute readings; rad for orientations).
    pub residual: Vector3<f64>,
    /// Role.
    pub role: Role,
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
    /// Every pair of identified parameters correlated at |ρ| ≥ 0.95, the strongest first.
    pub correlations: Vec<(String, String, f64)>,
    /// Robust loss used.
    pub loss: Loss,
    /// Set-ups fitted on registration only (test set-ups).
    pub registration_only_setups: Vec<String>,
    /// Model steps kept in the written model (opt-in steps that lost on held-out data are not).
    pub kept_steps: Vec<Step>,
}
