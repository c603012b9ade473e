//! Stiff contact turns the paper's correction into positive feedback; this module states when,
//! and guards against it online.
//!
//! # The loop through a compliant contact
//!
//! Along the corrected direction u (a scalar study), let the robot's true compliance be `c_r`
//! (m/N), the model's estimate `ĉ = ρ c_r` (ρ: model-to-true compliance ratio), and let the tool
//! press on a contact of stiffness `k_c` (compliance `c_c = 1/k_c`) in series with the robot.
//! The robot is commanded to `s_com = s_des + ξ` (eq. 7); the contact force `P` (pushing back
//! along −u) deflects the robot by `c_r P`, so the tool sits at `s_com − c_r P` and
//!
//! ```text
//! P = k_c (d₀ + ξ − c_r P)   ⇒   P = k_eff (d₀ + ξ),   k_eff = 1 / (c_r + c_c),
//! ```
//!
//! with `d₀` the programmed penetration. The controller estimates `δŝ = ĉ P` (eq. 15) and drives
//! ε = −ξ − δŝ to zero (eq. 5–7), i.e. ξ → ĉ P along u. Each metre of correction therefore
//! raises the force by `k_eff` newtons, which the model turns into `ĉ k_eff` metres of further
//! correction: the **static loop gain** through the contact is
//!
//! ```text
//! g = ĉ k_eff = ĉ / (c_r + c_c) = ρ / (1 + c_c / c_r) = ρ k_c c_r / (1 + k_c c_r).
//! ```
//!
//! At equilibrium ξ = ĉ P and P = k_eff (d₀ + ĉ P), so `P = P₀ / (1 − g)` with `P₀ = k_eff d₀` the
//! force the program alone would give: the correction **multiplies the force by 1/(1 − g)**
//! and, for `g ≥ 1`, runs away until a limit stops it. The static condition is
//!
//! ```text
//! g < 1   ⇔   ĉ < c_r + c_c   ⇔   ρ < 1 + 1 / (k_c c_r).
//! ```
//!
//! A forming contact is soft along u once the sheet flows (dF/dz of a few N/mm: `c_c ≫ c_r`, g of
//! a few percent), which is why the paper's scheme works there. Against a rigid fixture
//! (`c_c → 0`) an exact model (ρ = 1) is marginal and any model too soft (ρ > 1) runs away: with
//! the built-in TX200 model at the forming pose (c ≈ 1.09 µm/N along z), k_c = 10⁵ N/m gives
//! g ≈ 0.10 ρ, 10⁶ N/m g ≈ 0.52 ρ, 10⁷ N/m g ≈ 0.92 ρ and 10⁸ N/m g ≈ 0.99 ρ.
//!
//! # With the discrete law of [`crate::pid`] and a delay
//!
//! [`crate::pid::Pid::solve`] closes ε = −ξ − δŝ within the sample, so per axis the law is
//! `ξ = Q(z) ε` with (h the period, a_i = K_c h/T_i, α = h/(T_f + h) the derivative filter,
//! k_d = K_c T_d α/h, A = K_c + a_i + k_d)
//!
//! ```text
//! Q(z) = a_i/(z − 1) + A − k_d α/(z − 1 + α).
//! ```
//!
//! The contact answers a correction after `d` control periods (robot cycle, transport delay,
//! servo filter, sensor averaging): `δŝ_k = s₀ − g ξ_{k−d}`. Then `ξ (1 + Q) = g Q z^{−d} ξ`, and
//! with `Q = N_Q / D_Q`, `D_Q = (z − 1)(z − 1 + α)`,
//! `N_Q = a_i (z − 1 + α) + A (z − 1)(z − 1 + α) − k_d α (z − 1)`, the closed loop's
//! characteristic polynomial is
//!
//! ```text
//! χ(z) = z^d (D_Q + N_Q) − g N_Q.
//! ```
//!
//! At z = 1, `D_Q = 0` and `N_Q = a_i α`, so `χ(1) = a_i α (1 − g)`: a real root crosses the
//! unit circle at z = 1 exactly when g = 1, whatever the delay (the integral action makes the
//! static gain of T = Q/(1 + Q) one). No other root crosses before: on the unit circle
//! `Re 1/(z − 1) = −1/2` and `|α/(z − 1 + α)| ≤ 1`, so `Re Q ≥ K_c + a_i/2 ≥ 0` and `|T| ≤ 1`;
//! for 0 ≤ g < 1, `|g T(z)| < 1 = |z^d|` on the circle and the roots of `z^d = g T(z)` stay
//! inside it (argument principle). Solving the algebraic loop within the sample (rather than
//! with the previous ξ) is what makes the law this robust: **for any non-negative gains and
//! any delay, the loop through a contact is stable if and only if g < 1.** [`critical_gain`]
//! confirms it numerically (1.000 for the paper's gains K_c = 0.8, T_i = 0.048 s,
//! T_d = 0.012 s, N = 5 at h = 0.01 s with d = 1…5, and for much hotter gains; tested against
//! a simulation of [`crate::pid::Pid`]). The divergence is monotonic (a real root through
//! z = 1), which is what the online guard below looks for. **Stability condition:**
//! `ĉ / (c_r + 1/k_c) < 1`, and in practice well below it, since the force is amplified by
//! 1/(1 − g) long before.
//!
//! # The guard
//!
//! [`RunawayGuard`] estimates, online, the local loop gain along the corrected direction
//! u = ξ_p/|ξ_p|: the force's rise per metre of the robot's commanded motion along u,
//! `k̂ = Σ Δx ΔP / Σ Δx²` (exponential forgetting over `window_s`; Δx from the forward
//! kinematics of the joints the robot reports, which include the correction it applied; ΔP the
//! change of the contact force's component against u), times the model's compliance along u,
//! `ĝ = (uᵀ C u) k̂`. Regressing on the robot's actual motion rather than on ξ is what separates
//! cause from effect: the contact force is a function of where the tool is, whoever moved it, so
//! the slope is the contact's stiffness in series with the robot's whether the program or the
//! correction moves the tool; a forming force set by the material's flow (a few N/mm) gives a
//! ĝ of a few percent. When ĝ stays significantly above `gain_limit` (its lower two-sigma
//! bound, from the residuals of the fit, so that sensor noise on small motions does not count)
//! for `confirm_cycles` cycles while the correction is growing along u, the guard **stops the correction growing along u** (its
//! component along u is capped at its value then; the other directions keep following the law)
//! and reports `contact_runaway`; with `action = fault` it latches the fault instead (safe
//! action). The hold is released when the estimate falls below `release_gain` with enough
//! motion to trust it, or when the force against u falls below a quarter of its value at the
//! trip (the contact is gone). Bound: the force then stays below `P₀/(1 − gain_limit)` plus what
//! the correction added during detection (`confirm_cycles` cycles at most at the rate limit,
//! times k_eff). `tests/runaway.rs` checks it against the real controller for contacts from
//! 10⁵ to 10⁸ N/m and ρ = 1, 1.3 with a 20 ms delay: without the guard the force reaches
//! 1.7–10.3 kN from 800 N (the correction at its 8 mm limit from 10⁷ N/m up); with it the force
//! stays below 2.5 × 800 N (measured: at most 936 N).
//!
//! Limitations: position axes only (a rotational runaway is not watched); a single direction u
//! (the correction's), so a contact whose normal is far from u is seen through its projection;
//! the estimate needs motion along u (`min_travel_m` within the window), and until there is some
//! the guard cannot judge, which is why the force limit stays the last line of defence.

use crate::pid::PidGains;

/// What the guard does when it detects a runaway.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Default)]
pub enum RunawayAction {
    /// Stop the correction growing along the corrected direction and report `contact_runaway`
    /// as a warning; the law keeps running in the other directions (default).
    #[default]
    Hold,
    /// Latch a `contact_runaway` fault: the correction goes to its safe value.
    Fault,
}

/// Settings of the guard (`[limits]` of `CELL.toml`: `runaway_guard`, `runaway_gain_limit`, …;
/// documented in `docs/cell.example.toml`).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct RunawayConfig {
    /// Watch for runaways at all.
    pub enabled: bool,
    /// Estimated loop gain ĝ above which the guard acts (default 0.5: the correction would at
    /// least double the force the program alone gives).
    pub gain_limit: f64,
    /// ĝ below which a hold is released (default 0.25).
    pub release_gain: f64,
    /// Forgetting time of the estimate (s, default 0.1).
    pub window_s: f64,
    /// Motion along u within the window needed to trust the estimate (m, default 20 µm).
    pub min_travel_m: f64,
    /// Smallest |ξ_p| for which a corrected direction exists (m, default 50 µm).
    pub min_correction_m: f64,
    /// Consecutive cycles above the limit before acting (default 3).
    pub confirm_cycles: u32,
    /// Hold the growth (default) or latch a fault.
    pub action: RunawayAction,
}

impl Default for RunawayConfig {
    fn default() -> Self {
        RunawayConfig {
            enabled: true,
            gain_limit: 0.5,
            release_gain: 0.25,
            window_s: 0.1,
            min_travel_m: 20e-6,
            min_correction_m: 50e-6,
            confirm_cycles: 3,
            action: RunawayAction::Hold,
        }
    }
}

/// The correction's growth held along `u` at `cap` (m).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct RunawayHold {
    /// Unit direction (base axes) along which ξ may not grow.
    pub u: [f64; 3],
    /// Largest allowed ξ·u (m).
    pub cap: f64,
    /// Force against u when the hold began (N).
    pub force_at_trip: f64,
}

/// What one update of the guard concluded.
#[derive(Clone, Copy, Debug, PartialEq, Default)]
pub struct GuardUpdate {
    /// Estimated loop gain ĝ, NaN when unknown (no direction or too little motion).
    pub gain: f64,
    /// A runaway was detected this cycle (the hold began, or a fault is due).
    pub tripped: bool,
    /// A hold is active after this update.
    pub holding: bool,
}

/// Online runaway detector (see the module documentation). Allocation-free.
#[derive(Clone, Debug)]
pub struct RunawayGuard {
    config: RunawayConfig,
    prev: Option<([f64; 3], [f64; 3], f64)>,
    sxx: f64,
    sxp: f64,
    spp: f64,
    weight: f64,
    travel: f64,
    growth: f64,
    above: u32,
    below: u32,
    hold: Option<RunawayHold>,
}

fn dot(a: &[f64; 3], b: &[f64; 3]) -> f64 {
    a[0] * b[0] + a[1] * b[1] + a[2] * b[2]
}

impl RunawayGuard {
    /// A guard with no history.
    pub fn new(config: RunawayConfig) -> Self {
        RunawayGuard {
            config,
            prev: None,
            sxx: 0.0,
            sxp: 0.0,
            spp: 0.0,
            weight: 0.0,
            travel: 0.0,
            growth: 0.0,
            above: 0,
            below: 0,
            hold: None,
        }
    }

    /// Settings.
    pub fn config(&self) -> &RunawayConfig {
        &self.config
    }

    /// The active hold, if any.
    pub fn hold(&self) -> Option<RunawayHold> {
        self.hold
    }

    /// Forgets the estimate and any hold (start, reset).
    pub fn reset(&mut self) {
        *self = RunawayGuard::new(self.config);
    }

    /// The corrected direction of `xi_p` (base axes), if |ξ_p| is large enough.
    pub fn direction(&self, xi_p: &[f64; 3]) -> Option<[f64; 3]> {
        let n = dot(xi_p, xi_p).sqrt();
        (n >= self.config.min_correction_m && n.is_finite()).then(|| xi_p.map(|v| v / n))
    }

    /// One cycle: `x` the TCP position the robot is at (base axes, from the reported joints),
    /// `force` the environment force on the tool (base axes), `xi_p` the applied position
    /// correction, `u` its direction ([`RunawayGuard::direction`]) and `compliance_u` the model's
    /// compliance along u (m/N), `h` the period (s).
    pub fn update(
        &mut self,
        x: &[f64; 3],
        force: &[f64; 3],
        xi_p: &[f64; 3],
        u: Option<[f64; 3]>,
        compliance_u: f64,
        h: f64,
    ) -> GuardUpdate {
        let mut out = GuardUpdate {
            gain: f64::NAN,
            tripped: false,
            holding: self.hold.is_some(),
        };
        if !self.config.enabled {
            return out;
        }
        let finite = x.iter().chain(force).chain(xi_p).all(|v| v.is_finite())
            && compliance_u.is_finite()
            && h.is_finite()
            && h > 0.0;
        let Some(u) = u.filter(|_| finite) else {
            // No corrected direction (or unusable inputs): no estimate, start afresh.
            self.prev = finite.then_some((*x, *force, 0.0));
            self.sxx = 0.0;
            self.sxp = 0.0;
            self.spp = 0.0;
            self.weight = 0.0;
            self.travel = 0.0;
            self.growth = 0.0;
            self.above = 0;
            return out;
        };
        let along = dot(xi_p, &u);
        if let Some((px, pf, p_along)) = self.prev {
            let lambda = (-h / self.config.window_s.max(1e-6)).exp();
            let dx = dot(&[x[0] - px[0], x[1] - px[1], x[2] - px[2]], &u);
            // The contact pushes back against u: its force grows along −u.
            let dp = -dot(&[force[0] - pf[0], force[1] - pf[1], force[2] - pf[2]], &u);
            self.sxx = lambda * self.sxx + dx * dx;
            self.sxp = lambda * self.sxp + dx * dp;
            self.spp = lambda * self.spp + dp * dp;
            self.weight = lambda * self.weight + 1.0;
            self.travel = lambda * self.travel + dx.abs();
            self.growth = lambda * self.growth + (along - p_along);
        }
        self.prev = Some((*x, *force, along));
        // Least-squares slope and its standard error (weighted residual variance over the
        // effective number of samples, minus the fitted parameter).
        let mut gain_low = f64::NAN;
        if self.travel >= self.config.min_travel_m && self.sxx > 0.0 {
            let slope = self.sxp / self.sxx;
            out.gain = compliance_u * slope;
            let residual = (self.spp - slope * self.sxp).max(0.0) / (self.weight - 1.0).max(1.0);
            gain_low = out.gain - 2.0 * compliance_u.abs() * (residual / self.sxx).sqrt();
        }
        let reaction = -dot(force, &u);
        match self.hold {
            None => {
                if gain_low > self.config.gain_limit && self.growth > 0.0 {
                    self.above += 1;
                } else {
                    self.above = 0;
                }
                if self.above >= self.config.confirm_cycles.max(1) {
                    out.tripped = true;
                    self.above = 0;
                    self.below = 0;
                    if self.config.action == RunawayAction::Hold {
                        self.hold = Some(RunawayHold {
                            u,
                            cap: along,
                            force_at_trip: reaction,
                        });
                    }
                }
            }
            Some(hold) => {
                if out.gain < self.config.release_gain {
                    self.below += 1;
                } else {
                    self.below = 0;
                }
                if self.below >= self.config.confirm_cycles.max(1)
                    || reaction < 0.25 * hold.force_at_trip
                {
                    self.hold = None;
                    self.below = 0;
                }
            }
        }
        out.holding = self.hold.is_some();
        out
    }

    /// Caps the position part of `xi` along the held direction: ξ·u ≤ cap. Returns whether it
    /// changed anything.
    pub fn limit(&self, xi: &mut [f64; 6]) -> bool {
        let Some(hold) = self.hold else {
            return false;
        };
        let p = [xi[0], xi[1], xi[2]];
        let excess = dot(&p, &hold.u) - hold.cap;
        if excess > 0.0 {
            for i in 0..3 {
                xi[i] -= excess * hold.u[i];
            }
            true
        } else {
            false
        }
    }
}

/// Static loop gain g = ĉ/(c_r + 1/k_c) of the correction through a contact of stiffness
/// `contact_stiffness_n_m` in series with a robot of true compliance `robot_compliance_m_n`,
/// with the model's compliance `model_compliance_m_n` (all along the corrected direction).
pub fn static_loop_gain(
    model_compliance_m_n: f64,
    robot_compliance_m_n: f64,
    contact_stiffness_n_m: f64,
) -> f64 {
    model_compliance_m_n / (robot_compliance_m_n + 1.0 / contact_stiffness_n_m)
}

/// Factor 1/(1 − g) by which the correction multiplies the contact force at equilibrium;
/// infinite for g ≥ 1 (no equilibrium: runaway).
pub fn force_amplification(loop_gain: f64) -> f64 {
    if loop_gain < 1.0 {
        1.0 / (1.0 - loop_gain)
    } else {
        f64::INFINITY
    }
}

/// Coefficients (ascending powers of z) of the characteristic polynomial χ(z) of the module
/// documentation.
fn characteristic_polynomial(g: f64, gains: &PidGains, h: f64, delay: usize) -> Vec<f64> {
    let kc = gains.kc;
    let ai = if gains.ti_s > 0.0 && gains.ti_s.is_finite() {
        kc * h / gains.ti_s
    } else {
        0.0
    };
    let tf = if gains.derivative_filter_n > 0.0 {
        gains.td_s / gains.derivative_filter_n
    } else {
        0.0
    };
    let alpha = h / (tf + h);
    let kd = if gains.td_s > 0.0 {
        kc * gains.td_s * alpha / h
    } else {
        0.0
    };
    let a = kc + ai + kd;
    // Polynomials in z, ascending: (z − 1) = [−1, 1], (z − 1 + α) = [α − 1, 1].
    let mul = |p: &[f64], q: &[f64]| -> Vec<f64> {
        let mut r = vec![0.0; p.len() + q.len() - 1];
        for (i, x) in p.iter().enumerate() {
            for (j, y) in q.iter().enumerate() {
                r[i + j] += x * y;
            }
        }
        r
    };
    let add = |p: &[f64], q: &[f64], s: f64| -> Vec<f64> {
        let mut r = vec![0.0; p.len().max(q.len())];
        for (i, x) in p.iter().enumerate() {
            r[i] += x;
        }
        for (i, y) in q.iter().enumerate() {
            r[i] += s * y;
        }
        r
    };
    let zm1 = [-1.0, 1.0];
    let zma = [alpha - 1.0, 1.0];
    let dq = mul(&zm1, &zma);
    let nq = add(
        &add(
            &zma.map(|c| ai * c),
            &dq.iter().map(|c| a * c).collect::<Vec<_>>(),
            1.0,
        ),
        &zm1.map(|c| kd * alpha * c),
        -1.0,
    );
    let mut zd = vec![0.0; delay + 1];
    zd[delay] = 1.0;
    add(&mul(&zd, &add(&dq, &nq, 1.0)), &nq, -g)
}

/// Largest modulus of the closed-loop poles of the discrete law of [`crate::pid`] (gains
/// `gains`, period `h`) against a contact of static loop gain `g` answering after `delay`
/// periods: the loop is stable when it is below 1.
pub fn closed_loop_spectral_radius(g: f64, gains: &PidGains, h: f64, delay: usize) -> f64 {
    let mut p = characteristic_polynomial(g, gains, h, delay);
    while p.len() > 1 && p.last().is_some_and(|c| c.abs() < 1e-300) {
        p.pop();
    }
    let n = p.len() - 1;
    if n == 0 {
        return 0.0;
    }
    let lead = p[n];
    let companion = nalgebra::DMatrix::from_fn(n, n, |r, c| {
        if r == 0 {
            -p[n - 1 - c] / lead
        } else if r == c + 1 {
            1.0
        } else {
            0.0
        }
    });
    companion
        .complex_eigenvalues()
        .iter()
        .map(|z| z.norm())
        .fold(0.0, f64::max)
}

/// The static loop gain at which the closed loop of [`closed_loop_spectral_radius`] first
/// becomes unstable (bisection on g in [0, 4]; 4 if it never does there).
pub fn critical_gain(gains: &PidGains, h: f64, delay: usize) -> f64 {
    let stable = |g: f64| closed_loop_spectral_radius(g, gains, h, delay) < 1.0 - 1e-12;
    if stable(4.0) {
        return 4.0;
    }
    let (mut lo, mut hi) = (0.0, 4.0);
    // The first crossing: scan coarsely, then bisect.
    let mut g = 0.0;
    while g < 4.0 {
        if !stable(g + 0.01) {
            hi = g + 0.01;
            lo = g;
            break;
        }
        g += 0.01;
    }
    for _ in 0..60 {
        let mid = 0.5 * (lo + hi);
        if stable(mid) {
            lo = mid;
        } else {
            hi = mid;
        }
    }
    0.5 * (lo + hi)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::pid::Pid;

    /// The scalar discrete loop simulated with the real [`Pid`] (solve + commit): δŝ_k =
    /// s₀ − g ξ_{k−d}. Returns the largest |ξ| over the last quarter relative to the first
    /// quarter's, i.e. growth > 1 means divergence.
    fn simulate(g: f64, delay: usize, steps: usize) -> f64 {
        let gains = PidGains::default();
        let mut pid = Pid::new(gains);
        let h = 0.01;
        let mut history = vec![0.0; delay + 1];
        let mut xs = Vec::with_capacity(steps);
        for k in 0..steps {
            let delayed = history[(k + history.len() - delay) % history.len()];
            let ds = 1e-4 - g * delayed;
            let sol = pid.solve(0, ds, h);
            pid.commit(0, &sol, sol.xi, h, 1e9, false);
            let slot = k % history.len();
            history[slot] = sol.xi;
            xs.push(sol.xi);
        }
        // Distance from the equilibrium −s₀/(1−g) (or growth when there is none).
        let eq = if g < 1.0 { -1e-4 / (1.0 - g) } else { 0.0 };
        let dev = |s: &[f64]| s.iter().map(|x| (x - eq).abs()).fold(0.0, f64::max);
        dev(&xs[3 * steps / 4..]) / dev(&xs[steps / 4..steps / 2]).max(1e-300)
    }

    #[test]
    fn characteristic_polynomial_predicts_the_simulated_loop() {
        let gains = PidGains::default();
        for delay in [1usize, 2, 3] {
            let g_star = critical_gain(&gains, 0.01, delay);
            eprintln!("paper gains, h = 10 ms, delay {delay}: critical loop gain {g_star:.4}");
            assert!((g_star - 1.0).abs() < 1e-3, "delay {delay}: {g_star}");
            for (g, stable) in [(0.9 * g_star, true), (1.05 * g_star, false)] {
                let rho = closed_loop_spectral_radius(g, &gains, 0.01, delay);
                assert_eq!(rho < 1.0, stable, "delay {delay} g {g}: radius {rho}");
                let growth = simulate(g, delay, 4000);
                assert_eq!(growth < 1.0, stable, "delay {delay} g {g}: growth {growth}");
            }
        }
        // Hotter gains and longer delays: still g* = 1 (|T| ≤ 1 on the unit circle).
        for (kc, ti_s, td_s) in [(8.0, 0.048, 0.012), (0.8, 0.002, 0.0), (3.0, 0.01, 0.05)] {
            let hot = PidGains {
                kc,
                ti_s,
                td_s,
                ..PidGains::default()
            };
            for delay in [1usize, 5] {
                let g_star = critical_gain(&hot, 0.01, delay);
                assert!(
                    (g_star - 1.0).abs() < 1e-3,
                    "{kc} {ti_s} {td_s} d {delay}: {g_star}"
                );
            }
        }
    }

    #[test]
    fn static_gain_and_amplification() {
        // Exact model against a contact taking 20 % of the deflection: g = 0.8, force × 5.
        let c_r = 3e-6;
        let g = static_loop_gain(c_r, c_r, 1.0 / (0.25 * c_r));
        assert!((g - 0.8).abs() < 1e-12);
        assert!((force_amplification(g) - 5.0).abs() < 1e-9);
        // A model 1.3× too soft against a rigid fixture: no equilibrium.
        assert!(force_amplification(static_loop_gain(1.3 * c_r, c_r, 1e12)).is_infinite());
    }

    #[test]
    fn guard_caps_growth_only_along_the_held_direction() {
        let mut guard = RunawayGuard::new(RunawayConfig::default());
        guard.hold = Some(RunawayHold {
            u: [0.0, 0.0, -1.0],
            cap: 1e-3,
            force_at_trip: 100.0,
        });
        let mut xi = [2e-4, 0.0, -3e-3, 0.0, 0.0, 0.0];
        assert!(guard.limit(&mut xi));
        assert_eq!(xi, [2e-4, 0.0, -1e-3, 0.0, 0.0, 0.0]);
        let mut smaller = [0.0, 5e-4, -5e-4, 0.0, 0.0, 0.0];
        assert!(!guard.limit(&mut smaller));
    }
}
