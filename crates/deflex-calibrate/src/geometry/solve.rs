//! Levenberg–Marquardt with robust reweighting (IRLS), on the normal equations.
//!
//! Why our own LM on `nalgebra` rather than the `levenberg-marquardt` crate: the set-up
//! rotations live on SO(3) and are updated multiplicatively after every step (the crate
//! assumes a vector space it adds steps to); the robust loss changes the row weights at every
//! trial point (the crate minimises a fixed sum of squares); and the fit needs only the p × p
//! normal matrix, accumulated reading by reading, never the 36 000 × p Jacobian the crate
//! would hold. The algorithm is Moré's: damping `λ·diag(JᵀWJ)` (scale-invariant, so a
//! parameter in kg·m and one in rad/(N·m) are treated alike), λ ÷3 on success, ×4 on failure.
//!
//! **Robust loss.** Each reading's standardised residual `u = |r|/(σ s)` (3 components, σ its
//! standard deviation, s a robust scale: the median of `|r|/σ` over the readings of its kind
//! divided by 1.5382, the median of a χ with 3 degrees of freedom; positions, loaded
//! displacements and orientations each have their own) enters through ρ(u):
//! Huber (`u²/2` up to k, then `k u − k²/2`; weight `min(1, k/u)`) or Cauchy
//! (`k²/2 · ln(1 + (u/k)²)`; weight `1/(1 + (u/k)²)`). Each LM step is a weighted least-squares
//! step with the weights at the current point (IRLS); a step is accepted when it lowers
//! `Σ ρ`. The scale is re-estimated and the LM rerun until it settles (at most 4 passes).

use crate::geometry::campaign::Campaign;
use crate::geometry::params::{EgModel, Param};
use nalgebra::{DMatrix, DVector, Vector3};

/// Robust loss.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Loss {
    /// Plain least squares.
    Squared,
    /// Huber with threshold k (in robust standard deviations of the 3-D residual).
    Huber(f64),
    /// Cauchy with scale k.
    Cauchy(f64),
}

impl Loss {
    /// Default Huber threshold: 3 (97 % of a χ₃ lies below it).
    pub const HUBER_DEFAULT: Loss = Loss::Huber(3.0);

    fn rho(self, u: f64) -> f64 {
        match self {
            Loss::Squared => 0.5 * u * u,
            Loss::Huber(k) => {
                if u <= k {
                    0.5 * u * u
                } else {
                    k * u - 0.5 * k * k
                }
            }
            Loss::Cauchy(k) => 0.5 * k * k * (1.0 + (u / k).powi(2)).ln(),
        }
    }

    /// IRLS weight ρ'(u)/u.
    pub fn weight(self, u: f64) -> f64 {
        match self {
            Loss::Squared => 1.0,
            Loss::Huber(k) => {
                if u <= k {
                    1.0
                } else {
                    k / u
                }
            }
            Loss::Cauchy(k) => 1.0 / (1.0 + (u / k).powi(2)),
        }
    }

    /// Name for reports.
    pub fn name(self) -> String {
        match self {
            Loss::Squared => "least squares".into(),
            Loss::Huber(k) => format!("Huber (k = {k})"),
            Loss::Cauchy(k) => format!("Cauchy (k = {k})"),
        }
    }
}

/// Median of a χ distribution with 3 degrees of freedom.
pub const CHI3_MEDIAN: f64 = 1.538_172;

/// Solver settings.
#[derive(Clone, Copy, Debug)]
pub struct SolveOptions {
    /// Robust loss.
    pub loss: Loss,
    /// Largest number of LM iterations per pass.
    pub max_iterations: usize,
    /// Stop when a step lowers the cost by less than this fraction.
    pub relative_tolerance: f64,
}

impl Default for SolveOptions {
    fn default() -> Self {
        SolveOptions {
            loss: Loss::HUBER_DEFAULT,
            max_iterations: 60,
            relative_tolerance: 1e-10,
        }
    }
}

/// What the solver did.
#[derive(Clone, Debug)]
pub struct SolveOutcome {
    /// LM iterations, all passes.
    pub iterations: usize,
    /// Whether the last pass met the tolerance.
    pub converged: bool,
    /// Final robust cost Σ ρ.
    pub cost: f64,
    /// IRLS weight of every reading (0 for readings not in the fit).
    pub weights: Vec<f64>,
    /// Robust scale of position, loaded and orientation readings (1 = the stated σ).
    pub scale: [f64; 3],
}

/// Standardised residual `r/σ` of every reading in the fit (`multiplicity > 0`).
pub fn standardised_residuals(
    model: &EgModel,
    campaign: &Campaign,
    multiplicity: &[f64],
) -> Vec<Option<Vector3<f64>>> {
    (0..campaign.len())
        .map(|i| {
            (multiplicity[i] > 0.0)
                .then(|| campaign.residual(model, i, &[], None) / campaign.sigma(i))
        })
        .collect()
}

/// Robust scales of position, loaded and orientation readings from standardised residuals.
pub fn robust_scales(campaign: &Campaign, residuals: &[Option<Vector3<f64>>]) -> [f64; 3] {
    let mut out = [1.0; 3];
    for (kind, slot) in out.iter_mut().enumerate() {
        let mut norms: Vec<f64> = residuals
            .iter()
            .enumerate()
            .filter(|(i, _)| campaign.kind(*i).index() == kind)
            .filter_map(|(_, r)| r.map(|r| r.norm()))
            .collect();
        if norms.is_empty() {
            continue;
        }
        let mid = norms.len() / 2;
        let (_, median, _) = norms.select_nth_unstable_by(mid, f64::total_cmp);
        let scale = *median / CHI3_MEDIAN;
        if scale.is_finite() && scale > 1e-12 {
            *slot = scale;
        }
    }
    out
}

struct Evaluated {
    cost: f64,
    weights: Vec<f64>,
}

fn robust_cost(
    campaign: &Campaign,
    residuals: &[Option<Vector3<f64>>],
    multiplicity: &[f64],
    scale: [f64; 3],
    loss: Loss,
) -> Evaluated {
    let mut cost = 0.0;
    let mut weights = vec![0.0; residuals.len()];
    for (i, r) in residuals.iter().enumerate() {
        if let Some(r) = r {
            let s = scale[campaign.kind(i).index()];
            let u = r.norm() / s;
            cost += multiplicity[i] * s * s * loss.rho(u);
            weights[i] = loss.weight(u);
        }
    }
    Evaluated { cost, weights }
}

/// Normal equations `JᵀWJ`, `JᵀWr` over the readings in the fit, standardised by σ and
/// weighted by `multiplicity × weight`.
pub fn normal_equations(
    model: &EgModel,
    campaign: &Campaign,
    params: &[Param],
    multiplicity: &[f64],
    weights: &[f64],
) -> (DMatrix<f64>, DVector<f64>) {
    let p = params.len();
    let mut a = DMatrix::<f64>::zeros(p, p);
    let mut g = DVector::<f64>::zeros(p);
    let mut columns = Vec::with_capacity(p);
    for i in 0..campaign.len() {
        let w = multiplicity[i] * weights[i];
        if w <= 0.0 {
            continue;
        }
        let r = campaign.residual(model, i, params, Some(&mut columns));
        let scale = 1.0 / campaign.sigma(i);
        let r = r * scale;
        for c in columns.iter_mut() {
            *c *= scale;
        }
        for (k, ck) in columns.iter().enumerate() {
            g[k] += w * ck.dot(&r);
            let wck = ck * w;
            for (l, cl) in columns.iter().enumerate().skip(k) {
                a[(k, l)] += wck.dot(cl);
            }
        }
    }
    for k in 0..p {
        for l in 0..k {
            a[(k, l)] = a[(l, k)];
        }
    }
    (a, g)
}

/// Minimise the robust cost over `params` (the identifiable set), starting from `model`.
/// Readings with `multiplicity` 0 are left out (cross-validation folds, bootstrap, test sets).
pub fn solve(
    model: &mut EgModel,
    campaign: &Campaign,
    params: &[Param],
    multiplicity: &[f64],
    options: &SolveOptions,
) -> SolveOutcome {
    let mut iterations = 0;
    let mut converged = params.is_empty();
    let mut residuals = standardised_residuals(model, campaign, multiplicity);
    let mut scale = match options.loss {
        Loss::Squared => [1.0; 3],
        _ => robust_scales(campaign, &residuals),
    };
    let mut current = robust_cost(campaign, &residuals, multiplicity, scale, options.loss);
    let passes = if options.loss == Loss::Squared { 1 } else { 4 };
    for _pass in 0..passes {
        let mut lambda = 1e-3;
        converged = params.is_empty();
        for _ in 0..options.max_iterations {
            if params.is_empty() {
                break;
            }
            iterations += 1;
            let (a, g) = normal_equations(model, campaign, params, multiplicity, &current.weights);
            let diag: Vec<f64> = (0..params.len()).map(|k| a[(k, k)].max(1e-300)).collect();
            let mut accepted = false;
            let mut small_step = false;
            for _attempt in 0..12 {
                let mut damped = a.clone();
                for (k, d) in diag.iter().enumerate() {
                    damped[(k, k)] += lambda * d;
                }
                let Some(cholesky) = damped.cholesky() else {
                    lambda *= 4.0;
                    continue;
                };
                let step = cholesky.solve(&g);
                let mut trial = model.clone();
                trial.apply(params, step.as_slice());
                let trial_residuals = standardised_residuals(&trial, campaign, multiplicity);
                let evaluated = robust_cost(
                    campaign,
                    &trial_residuals,
                    multiplicity,
                    scale,
                    options.loss,
                );
                if evaluated.cost.is_finite() && evaluated.cost <= current.cost {
                    let decrease = current.cost - evaluated.cost;
                    small_step = decrease <= options.relative_tolerance * current.cost.max(1e-300);
                    *model = trial;
                    residuals = trial_residuals;
                    current = evaluated;
                    lambda = (lambda / 3.0).max(1e-12);
                    accepted = true;
                    break;
                }
                lambda *= 4.0;
            }
            if !accepted || small_step {
                converged = true;
                break;
            }
        }
        if options.loss == Loss::Squared {
            break;
        }
        let new_scale = robust_scales(campaign, &residuals);
        let settled = (0..3).all(|k| (new_scale[k] / scale[k] - 1.0).abs() < 0.01);
        scale = new_scale;
        current = robust_cost(campaign, &residuals, multiplicity, scale, options.loss);
        if settled {
            break;
        }
    }
    SolveOutcome {
        iterations,
        converged,
        cost: current.cost,
        weights: current.weights,
        scale,
    }
}
