//! Does the log support a force–depth law as a *cause*? (issue 33)
//!
//! A log of a run where the force is set along the path (force-controlled forming, constant
//! pressure, a press fit) also shows the force changing with the depth the tool reached — but
//! there the depth changes *because* the arm gives way under the force: `u = u_c − C_t F`
//! (`u_c` the commanded depth, `C_t` the compliance along the tool axis). A law fitted to it
//! reverses cause and effect; its slope is `−1/C_t`, and the compensation's fixed point
//! `ρ = G(t·c + ρ a)/G(u_log)` then has a loop gain `|G'|·C_t ≈ 1` and does not contract.
//!
//! Three figures, on the logged run itself, over the points in contact:
//!
//! * **Held-out explanation.** The contact points are cut into [`BLOCKS`] contiguous blocks of
//!   arc length; each block's forces are predicted from the other blocks' by interpolating
//!   between their mean forces in [`BINS`] bins of the regressor, once with the **commanded depth**
//!   (the depth without the deflection-induced change: `t·c`) as regressor and once with the
//!   **path position** (arc length). `R² = 1 − Σ w (F − F̂)² / Σ w (F − F̄)²` (weights: each
//!   point's share of arc length) says how much of the force's variation each explains on data
//!   it did not see. A process whose force follows depth is predicted by the depth wherever the
//!   path passes that depth again; a force set along the path is predicted by neither across a
//!   block of its ramp (depth: not at all).
//! * **Loop gain** `max_k |G'_k| · C_t` over the law's sloped depth bins (`C_t` the median
//!   over the contact points of `tᵀ C_ff t`, the model's compliance along the tool axis):
//!   below one the compensation's fixed point contracts.
//! * **Direction**: the share of the sloped bins whose force *falls* with depth. A process
//!   that pushes back meets more force deeper; a falling law is the deflection's signature.
//!
//! The law is used ([`LawEvidence::supported`]) only when it explains the held-out force
//! ([`MIN_R2`]), at least as well as the path position does less [`MARGIN`], with a loop gain
//! below [`MAX_LOOP_GAIN`] and no falling bins beyond [`MAX_FALLING_SHARE`].

/// Contiguous blocks of arc length held out in turn.
pub const BLOCKS: usize = 8;

/// Smallest held-out `R²` of the commanded depth for the law to be used.
pub const MIN_R2: f64 = 0.5;

/// The depth's held-out `R²` may trail the path position's by at most this much.
pub const MARGIN: f64 = 0.05;

/// Largest loop gain `|G'|·C_t` accepted: one is the limit of contraction, and a law read
/// backwards from a set force has `≈ C_model/C_true ≈ 1` (1.19 measured); the margin is for the
/// model's compliance error. A spring-like process `F = k·(u − s)` has `kC/(1 + kC)` (0.35–0.43
/// on the twin's sheet), so a very stiff one (kC > 4) is left to the logged wrenches.
pub const MAX_LOOP_GAIN: f64 = 0.8;

/// Largest share of the law's sloped bins whose force falls with depth.
pub const MAX_FALLING_SHARE: f64 = 0.25;

/// Held-out points evaluated at most (a stride over the contact points).
const MAX_EVALUATED: usize = 4000;

/// The figures of the test (see the module documentation).
#[derive(Clone, Debug, PartialEq)]
pub struct LawEvidence {
    /// Blocks of arc length held out in turn.
    pub blocks: usize,
    /// Held-out points evaluated.
    pub evaluated_points: usize,
    /// Held-out `R²` of the force from the commanded depth.
    pub r2_depth: f64,
    /// Held-out `R²` of the force from the path position (arc length).
    pub r2_position: f64,
    /// Held-out RMS residual from the commanded depth (N).
    pub rms_depth_n: f64,
    /// Held-out RMS residual from the path position (N).
    pub rms_position_n: f64,
    /// Standard deviation of the axial force over the contact points (N).
    pub force_std_n: f64,
    /// Spread of the commanded depth over the contact points (max − min, m).
    pub commanded_depth_span_m: f64,
    /// Median model compliance along the tool axis over the contact points (m/N).
    pub compliance_m_per_n: f64,
    /// Steepest slope of the law (signed, N/m of actual depth).
    pub steepest_slope_n_per_m: f64,
    /// `|G'|·C_t` at the steepest slope.
    pub loop_gain: f64,
    /// Share of the sloped bins whose force falls with depth.
    pub falling_share: f64,
}

impl LawEvidence {
    /// Why the law is not supported, or `None` when it is (see the module documentation).
    pub fn rejection(&self) -> Option<String> {
        let mut why = Vec::new();
        if self.r2_depth < MIN_R2 {
            why.push(format!(
                "the commanded depth explains {:.0} % of the held-out force (at least {:.0} % needed)",
                self.r2_depth.max(-9.99) * 100.0,
                MIN_R2 * 100.0
            ));
        }
        if self.r2_depth < self.r2_position - MARGIN {
            why.push(format!(
                "the path position explains more of it ({:.0} % against {:.0} %)",
                self.r2_position.max(-9.99) * 100.0,
                self.r2_depth.max(-9.99) * 100.0
            ));
        }
        if self.loop_gain >= MAX_LOOP_GAIN {
            why.push(format!(
                "the loop gain |dF/d depth| × compliance is {:.2} (below {MAX_LOOP_GAIN} needed: the iteration would not contract)",
                self.loop_gain
            ));
        }
        if self.falling_share > MAX_FALLING_SHARE {
            why.push(format!(
                "the force falls with depth over {:.0} % of the law (the arm giving way under a set force)",
                self.falling_share * 100.0
            ));
        }
        (!why.is_empty()).then(|| why.join("; "))
    }

    /// The figures over the contact points: axial force `force` (N), commanded depth
    /// `commanded` (m), arc length `arc` (m), weights `weights`, the model's compliance along
    /// the tool axis `compliance` (m/N); `slopes` the law's sloped bins' `(G, G')` (N, N/m).
    pub fn evaluate(
        force: &[f64],
        commanded: &[f64],
        arc: &[f64],
        weights: &[f64],
        compliance: &[f64],
        slopes: &[(f64, f64)],
    ) -> LawEvidence {
        let n = force.len();
        let (s_lo, s_hi) = range_of(arc);
        let span = (s_hi - s_lo).max(1e-12);
        let block: Vec<usize> = arc
            .iter()
            .map(|s| (((s - s_lo) / span * BLOCKS as f64) as usize).min(BLOCKS - 1))
            .collect();
        let stride = n.div_ceil(MAX_EVALUATED).max(1);
        let w: Vec<f64> = weights.iter().map(|v| v.max(1e-12)).collect();
        let (r2_depth, rms_depth_n, evaluated) = held_out(commanded, force, &w, &block, stride);
        let (r2_position, rms_position_n, _) = held_out(arc, force, &w, &block, stride);
        let total: f64 = w.iter().sum();
        let mean = force.iter().zip(&w).map(|(f, w)| f * w).sum::<f64>() / total.max(1e-300);
        let var = force
            .iter()
            .zip(&w)
            .map(|(f, w)| w * (f - mean) * (f - mean))
            .sum::<f64>()
            / total.max(1e-300);
        let mut sorted: Vec<f64> = compliance.to_vec();
        sorted.sort_by(f64::total_cmp);
        let compliance_m_per_n = sorted.get(sorted.len() / 2).copied().unwrap_or(0.0);
        let steepest = slopes
            .iter()
            .map(|(_, s)| *s)
            .fold(0.0, |a: f64, s| if s.abs() > a.abs() { s } else { a });
        let falling = slopes.iter().filter(|(_, s)| *s < 0.0).count();
        let (c_lo, c_hi) = range_of(commanded);
        LawEvidence {
            blocks: BLOCKS,
            evaluated_points: evaluated,
            r2_depth: finite_or_zero(r2_depth),
            r2_position: finite_or_zero(r2_position),
            rms_depth_n: finite_or_zero(rms_depth_n),
            rms_position_n: finite_or_zero(rms_position_n),
            force_std_n: var.sqrt(),
            commanded_depth_span_m: if n > 0 { c_hi - c_lo } else { 0.0 },
            compliance_m_per_n,
            steepest_slope_n_per_m: steepest,
            loop_gain: steepest.abs() * compliance_m_per_n,
            falling_share: if slopes.is_empty() {
                0.0
            } else {
                falling as f64 / slopes.len() as f64
            },
        }
    }

    /// The law is supported by the log.
    pub fn supported(&self) -> bool {
        self.rejection().is_none()
    }
}

/// `(min, max)` of `values` (`(f64::MAX, f64::MIN)` when empty).
fn range_of(values: &[f64]) -> (f64, f64) {
    values
        .iter()
        .fold((f64::MAX, f64::MIN), |(a, b), &v| (a.min(v), b.max(v)))
}

/// `value`, or 0 when it is not finite (a held-out figure with no point to score).
fn finite_or_zero(value: f64) -> f64 {
    if value.is_finite() { value } else { 0.0 }
}

/// Bins of the regressor's range in the held-out predictions.
pub const BINS: usize = 200;

/// Held-out `(R², RMS, points)` of `y` from the regressor `x` by blocks (`block[i]` in
/// `0..BLOCKS`), `w` the weights, evaluating every `stride`-th point: each block predicted by
/// linear interpolation between the weighted means of the other blocks' points in [`BINS`]
/// equal bins of `x` (at their mean `x`), held constant beyond them.
fn held_out(x: &[f64], y: &[f64], w: &[f64], block: &[usize], stride: usize) -> (f64, f64, usize) {
    let n = x.len();
    let total: f64 = w.iter().sum();
    let mean = y.iter().zip(w).map(|(y, w)| y * w).sum::<f64>() / total;
    let (lo, hi) = range_of(x);
    let width = ((hi - lo) / BINS as f64).max(1e-300);
    let bin = |v: f64| (((v - lo) / width) as usize).min(BINS - 1);
    let (mut ssr, mut sst, mut weight, mut count) = (0.0, 0.0, 0.0, 0usize);
    for b in 0..BLOCKS {
        // (Σw, Σwx, Σwy) of the training points per bin.
        let mut sums = vec![[0.0f64; 3]; BINS];
        for i in (0..n).filter(|&i| block[i] != b) {
            let s = &mut sums[bin(x[i])];
            s[0] += w[i];
            s[1] += w[i] * x[i];
            s[2] += w[i] * y[i];
        }
        let means: Vec<(f64, f64)> = sums
            .iter()
            .filter(|s| s[0] > 0.0)
            .map(|s| (s[1] / s[0], s[2] / s[0]))
            .collect();
        if means.is_empty() {
            continue;
        }
        for i in (0..n).filter(|&i| block[i] == b).step_by(stride.max(1)) {
            let at = means.partition_point(|m| m.0 < x[i]);
            let prediction = if at == 0 {
                means[0].1
            } else if at == means.len() {
                means[at - 1].1
            } else {
                let (a, c) = (means[at - 1], means[at]);
                let f = if c.0 > a.0 {
                    (x[i] - a.0) / (c.0 - a.0)
                } else {
                    0.5
                };
                a.1 + (c.1 - a.1) * f
            };
            let e = y[i] - prediction;
            ssr += w[i] * e * e;
            sst += w[i] * (y[i] - mean) * (y[i] - mean);
            weight += w[i];
            count += 1;
        }
    }
    if count == 0 || weight <= 0.0 {
        return (f64::NAN, f64::NAN, 0);
    }
    let r2 = if sst > 0.0 { 1.0 - ssr / sst } else { 0.0 };
    (r2, (ssr / weight).sqrt(), count)
}
