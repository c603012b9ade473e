//! What the final model's parameters are worth: covariance scaled by the residual, bootstrap,
//! strong correlations, the χ² warning, and the readings the robust loss set aside.

use super::roles::Roles;
use crate::geometry::campaign::{Campaign, ReadingKind};
use crate::geometry::identify::Reduction;
use crate::geometry::outcome::{Estimate, Outlier};
use crate::geometry::params::{EgModel, Param};
use crate::geometry::resample::bootstrap_se;
use crate::geometry::solve::{self, SolveOutcome};
use nalgebra::DMatrix;
use rand_chacha::ChaCha8Rng;

/// |ρ| from which a pair of estimates is flagged (every such pair is listed: at most p(p−1)/2
/// of the identifiable parameters).
pub const CORRELATION_LISTED: f64 = 0.95;
/// χ²/dof above which the fit warns that the model leaves a systematic error.
const CHI2_WARNING: f64 = 4.0;

/// The uncertainty of a final fit.
pub struct Uncertainty {
    /// Estimates, [`Reduction::kept`] order.
    pub estimates: Vec<Estimate>,
    /// Covariance scaled by the residual.
    pub covariance: DMatrix<f64>,
    /// χ²/dof with the stated σ.
    pub chi2_per_dof: f64,
    /// Plain warning when χ²/dof ≫ 1.
    pub warning: Option<String>,
    /// Strong correlations.
    pub correlations: Vec<(String, String, f64)>,
}

/// Covariance, estimates and correlations of the final step (`start`: the nominal model,
/// `registered_start`: after the closed-form registration).
#[allow(clippy::too_many_arguments)]
pub fn uncertainty(
    model: &EgModel,
    start: &EgModel,
    registered_start: &EgModel,
    campaign: &Campaign,
    roles: &Roles,
    reduction: &Reduction,
    outcome: &SolveOutcome,
    bootstrap: usize,
    rng: &mut ChaCha8Rng,
) -> Uncertainty {
    let kept = &reduction.kept;
    let fit_mult = &roles.fit_mult;
    let (a, _) = solve::normal_equations(model, campaign, kept, fit_mult, &outcome.weights);
    let residuals = solve::standardised_residuals(model, campaign, fit_mult);
    let equations = 3.0 * fit_mult.iter().filter(|m| **m > 0.0).count() as f64;
    let dof = (equations - kept.len() as f64).max(1.0);
    let weighted_chi2: f64 = residuals
        .iter()
        .zip(&outcome.weights)
        .filter_map(|(r, w)| r.map(|r| w * r.norm_squared()))
        .sum();
    let chi2: f64 = residuals.iter().flatten().map(|r| r.norm_squared()).sum();
    let chi2_per_dof = chi2 / dof;
    let covariance = a
        .cholesky()
        .map(|c| c.inverse() * (weighted_chi2 / dof))
        .unwrap_or_else(|| DMatrix::from_element(kept.len(), kept.len(), f64::NAN));
    let bootstrap = (bootstrap > 0).then(|| {
        bootstrap_se(
            model,
            campaign,
            kept,
            fit_mult,
            &outcome.weights,
            bootstrap,
            rng,
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
                Param::SetupRotation(..) | Param::TargetRotation(..) => 0.0,
                Param::SetupTranslation(..) | Param::Target(..) => registered_start.value(param),
                _ => start.value(param),
            },
            value: match param {
                Param::SetupRotation(..) => super::relative_value(model, registered_start, param),
                Param::TargetRotation(t, k) => deflex_model::spatial::rotation_log(
                    &(model.target_rotation(t) * registered_start.target_rotation(t).inverse()),
                )[k],
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
            if rho.abs() >= CORRELATION_LISTED {
                correlations.push((estimates[l].name.clone(), estimates[k].name.clone(), rho));
            }
        }
    }
    correlations.sort_by(|a, b| b.2.abs().total_cmp(&a.2.abs()));
    let warning = (chi2_per_dof > CHI2_WARNING).then(|| {
        format!(
            "χ²/dof = {chi2_per_dof:.1}: the residuals are {:.1}× the stated measurement noise. The model leaves a systematic error the data resolve; the standard errors are scaled by the residual, but they and the intervals describe noise-like scatter, not that model error.",
            chi2_per_dof.sqrt()
        )
    });
    Uncertainty {
        estimates,
        covariance,
        chi2_per_dof,
        warning,
        correlations,
    }
}

/// Readings whose robust weight fell below one half (largest residual first), and how many
/// were down-weighted at all.
pub fn outliers(
    model: &EgModel,
    campaign: &Campaign,
    roles: &Roles,
    outcome: &SolveOutcome,
) -> (Vec<Outlier>, usize) {
    let residuals = solve::standardised_residuals(model, campaign, &roles.fit_mult);
    let mut outliers = Vec::new();
    let mut downweighted = 0;
    for (i, w) in outcome.weights.iter().enumerate() {
        if roles.fit_mult[i] == 0.0 {
            continue;
        }
        if *w < 1.0 {
            downweighted += 1;
        }
        if *w < 0.5 {
            let (line, label) = match campaign.kind(i) {
                ReadingKind::Loaded => (
                    0,
                    campaign.loaded[i - campaign.absolute.len()]
                        .load_case
                        .clone(),
                ),
                _ => {
                    let r = campaign.absolute_row(i).unwrap_or(0);
                    (
                        campaign.absolute[r].line,
                        campaign.absolute[r].setup.clone(),
                    )
                }
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
    (outliers, downweighted)
}
