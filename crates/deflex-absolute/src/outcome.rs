//! What an elasto-geometric fit produces: the iteration table's rows, the estimates, the
//! outliers, the residuals, and the error statistics used for held-out readings.

use crate::fit::Step;
use crate::identify::Reduction;
use crate::params::{EgModel, Param, Unit};
use crate::solve::Loss;
use nalgebra::{DMatrix, Vector3};

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
