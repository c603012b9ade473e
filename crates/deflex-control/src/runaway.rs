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
//! u = ξ_p/|ξ_p|. It regresses the change of the contact force against u, ΔP = −ΔF·u, on the
//! robot's commanded motion Δx **in all three position directions** (Δx from the forward
//! kinematics of the joints the robot reports, which include the correction it applied):
//! `ΔP ≈ kᵀ Δx`, `k̂ = S_xx⁻¹ S_xp` with exponential forgetting over `window_s`, and
//! `ĝ = (uᵀ C u) (k̂·u)` with `uᵀ C u` the model's compliance along u. Regressing on the robot's
//! actual motion rather than on ξ separates cause from effect: the contact force is a function of
//! where the tool is, whoever moved it. Regressing on the full motion, not only its projection
//! on u, keeps a tangential motion from posing as excitation: a traverse along x with u tilted
//! from the contact normal moves the tool "along u" without changing the force, and a scalar
//! regression on Δx·u then reads a loop gain near zero although nothing was learnt about the
//! normal. Here such motion only informs k_x; the information along u is `1/(uᵀ S_xx⁻¹ u)`, the
//! motion along u that no other direction explains, and the estimate counts as known only when
//! `√(n_eff / uᵀ S_xx⁻¹ u) ≥ min_travel_m` (n_eff the effective sample count; for a steady
//! motion along u this is the travel within the window). Its standard error is
//! `σ̂ √(uᵀ S_xx⁻¹ u)` times the compliance, σ̂ from the fit's residuals.
//!
//! **Trip.** When the lower two-sigma bound of ĝ stays above `gain_limit` for `confirm_cycles`
//! cycles while the correction is growing along u, the guard reports `contact_runaway` and, with
//! the default action `withdraw`, **ramps the correction's component along u down to zero**
//! (smoothstep over `withdraw_s`; the other directions keep following the law); with `hold` it
//! only caps that component at its value at the trip; with `fault` it latches the fault (safe
//! action). Withdrawing rather than holding is what bounds the force by the program's own: at
//! the trip the correction has already added `k_eff ξ·u` to the force, and against a stiff
//! contact a correction along the normal buys no accuracy (the contact, not the robot, sets the
//! tool's position there).
//!
//! **Latch and release.** A hold that releases into the law's unconstrained value is a step of
//! the whole withheld correction into the contact, which is what made an earlier guard in the
//! twin's plunge release every 0.8 s (its estimate, fed by the traverse, decayed below the release
//! gain) and step the force by about 280 N each time, until the force limit tripped. The hold
//! is therefore latched until either
//! - the estimate is *confidently* low: its upper two-sigma bound below `release_gain` for
//!   `confirm_cycles` cycles, with the excitation above (a sheet that started to flow), or
//! - the law no longer pushes along u: its unconstrained ξ·u below `min_correction_m` (the
//!   contact is gone or the correction reversed),
//!
//! and then it is released **at a rate**: the cap along u rises by `release_rate_m_s` while the
//! detector keeps watching (a runaway seen again withdraws again from the cap reached, as part of
//! the same episode: one `contact_runaway` report per hold), and the hold ends once the cap
//! exceeds the law's value by `min_correction_m`. **Bound:** with `withdraw`,
//! once the ramp is done the force along u is what the program alone gives, `P₀`; before, it is at
//! most `P₀ + k_eff ξ_trip`, with ξ_trip the correction along u at the trip (what grew during
//! detection: `confirm_cycles` plus the estimator's settling, times the correction's growth per
//! cycle). `tests/runaway.rs` checks it against the real controller for contacts from 10⁵ to
//! 10⁸ N/m and ρ = 1, 1.3 with a 20 ms delay, and the twin's plunge (deflex_app::study
//! `tests/stiff_contact.rs`) at 10⁶–10⁸ N/m with a model identified from its own campaign.
//!
//! Limitations: position axes only (a rotational runaway is not watched); the guard acts along a
//! single direction u (the correction's at the trip), so a contact whose normal is far from u is
//! seen through its projection; the estimate needs motion along u (`min_travel_m` within the
//! window), and until there is some the guard cannot judge, which is why the force limit stays the
//! last line of defence. A false trip (a sheet's elastic onset long enough to look like a
//! fixture) withdraws the correction along u until the sheet is seen to flow under motion along
//! u, then gives it back at `release_rate_m_s`.

use crate::limiter::smoothstep;

mod analysis;

pub use analysis::{
    closed_loop_spectral_radius, critical_gain, force_amplification, static_loop_gain,
};

/// What the guard does when it detects a runaway.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Default)]
pub enum RunawayAction {
    /// Ramp the correction's component along the corrected direction down to zero over
    /// `withdraw_s`, report `contact_runaway` as a warning; the law keeps running in the other
    /// directions (default).
    #[default]
    Withdraw,
    /// Cap the correction's component along the corrected direction at its value at the trip,
    /// report `contact_runaway` as a warning.
    Hold,
    /// Latch a `contact_runaway` fault: the correction goes to its safe value.
    Fault,
}

impl RunawayAction {
    /// The name used in `CELL.toml` (`limits.runaway_action`).
    pub fn name(self) -> &'static str {
        match self {
            RunawayAction::Withdraw => "withdraw",
            RunawayAction::Hold => "hold",
            RunawayAction::Fault => "fault",
        }
    }
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
    /// ĝ (its upper two-sigma bound) below which a hold is released (default 0.25).
    pub release_gain: f64,
    /// Forgetting time of the estimate (s, default 0.1).
    pub window_s: f64,
    /// Motion along u within the window needed to trust the estimate (m, default 20 µm).
    pub min_travel_m: f64,
    /// Smallest |ξ_p| for which a corrected direction exists, and the law's ξ·u below which a
    /// hold is released (m, default 50 µm).
    pub min_correction_m: f64,
    /// Consecutive cycles above the limit before acting, below the release gain before
    /// releasing (default 3).
    pub confirm_cycles: u32,
    /// Duration of the withdrawal ramp (s, default 0.5).
    pub withdraw_s: f64,
    /// Rate at which a released hold gives the correction back along u (m/s, default 0.5 mm/s).
    pub release_rate_m_s: f64,
    /// Withdraw (default), hold or latch a fault.
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
            withdraw_s: 0.5,
            release_rate_m_s: 0.5e-3,
            action: RunawayAction::Withdraw,
        }
    }
}

/// Where a hold is.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum HoldPhase {
    /// The cap along u ramps from its value at the trip to zero (action `withdraw`).
    Withdrawing,
    /// The cap stays where it is (latched).
    Holding,
    /// The cap rises at `release_rate_m_s` until the law is below it.
    Releasing,
}

/// The correction along `u` limited to `cap` (m).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct RunawayHold {
    /// Unit direction (base axes) along which ξ is limited.
    pub u: [f64; 3],
    /// Largest allowed ξ·u now (m).
    pub cap: f64,
    /// ξ·u when the hold (or the latest withdrawal) began (m).
    pub cap_at_trip: f64,
    /// Force against u when the hold began (N).
    pub force_at_trip: f64,
    /// Time since the hold (or the latest withdrawal) began (s).
    pub since_trip_s: f64,
    /// Phase.
    pub phase: HoldPhase,
}

/// What one update of the guard concluded.
#[derive(Clone, Copy, Debug, PartialEq, Default)]
pub struct GuardUpdate {
    /// Estimated loop gain ĝ, NaN when unknown (no direction or too little motion).
    pub gain: f64,
    /// A runaway was detected this cycle (a hold began, or a fault is due). A runaway seen again
    /// while a hold is being released renews the hold without a new report.
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
    /// The law's unconstrained ξ·u along the held direction, from the last [`RunawayGuard::limit`].
    wanted: f64,
    hold: Option<RunawayHold>,
}

fn dot(a: &[f64; 3], b: &[f64; 3]) -> f64 {
    a[0] * b[0] + a[1] * b[1] + a[2] * b[2]
}

/// The regression's verdict along u: ĝ and its two-sigma bounds (NaN when unknown).
#[derive(Clone, Copy)]
struct Estimate {
    gain: f64,
    low: f64,
    high: f64,
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
            wanted: f64::NAN,
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

    fn forget(&mut self) {
        self.sxx = 0.0;
        self.sxp = 0.0;
        self.spp = 0.0;
        self.weight = 0.0;
        self.travel = 0.0;
        self.growth = 0.0;
        self.above = 0;
    }

    /// ĝ along u from the regression, with its two-sigma bounds.
    fn estimate(&self, compliance_u: f64) -> Estimate {
        if self.travel < self.config.min_travel_m || self.sxx <= 0.0 || self.weight <= 1.0 {
            return Estimate {
                gain: f64::NAN,
                low: f64::NAN,
                high: f64::NAN,
            };
        }
        let slope = self.sxp / self.sxx;
        let gain = compliance_u * slope;
        // Weighted residual variance over the effective number of samples minus the slope.
        let residual = (self.spp - slope * self.sxp).max(0.0) / (self.weight - 1.0).max(1.0);
        let sigma = 2.0 * compliance_u.abs() * (residual / self.sxx).sqrt();
        Estimate {
            gain,
            low: gain - sigma,
            high: gain + sigma,
        }
    }

    /// Counts the cycles a runaway is seen; true once it is confirmed.
    fn detect(&mut self, estimate: &Estimate) -> bool {
        if estimate.low > self.config.gain_limit && self.growth > 0.0 {
            self.above += 1;
        } else {
            self.above = 0;
        }
        if self.above >= self.config.confirm_cycles.max(1) {
            self.above = 0;
            true
        } else {
            false
        }
    }

    /// One cycle: `x` the TCP position the robot is at (base axes, from the reported joints),
    /// `force` the environment force on the tool (base axes), `xi_p` the applied position
    /// correction, `u` its direction ([`RunawayGuard::direction`]; a hold keeps its own) and
    /// `compliance_u` the model's compliance along the direction watched (m/N: along the held
    /// direction while a hold is active), `h` the period (s).
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
        let watched = self.hold.map(|hold| hold.u).or(u);
        let Some(u) = watched.filter(|_| finite) else {
            if self.hold.is_none() {
                // No corrected direction (or unusable inputs): no estimate, start afresh.
                self.prev = finite.then_some((*x, *force, 0.0));
                self.forget();
            }
            return out;
        };
        let along = dot(xi_p, &u);
        if let Some((px, pf, p_along)) = self.prev {
            let lambda = (-h / self.config.window_s.max(1e-6)).exp();
            let step = [x[0] - px[0], x[1] - px[1], x[2] - px[2]];
            let dx = dot(&step, &u);
            // Alignment weight: a sample informs the slope along u as much as its motion is along
            // u (cos² of the angle), so tangential motion does not pose as excitation.
            let length2 = dot(&step, &step);
            let w = if length2 > 0.0 {
                dx * dx / length2
            } else {
                0.0
            };
            // The contact pushes back against u: its force grows along −u.
            let dp = -dot(&[force[0] - pf[0], force[1] - pf[1], force[2] - pf[2]], &u);
            self.sxx = lambda * self.sxx + w * dx * dx;
            self.sxp = lambda * self.sxp + w * dx * dp;
            self.spp = lambda * self.spp + w * dp * dp;
            self.weight = lambda * self.weight + w;
            self.travel = lambda * self.travel + w * dx.abs();
            self.growth = lambda * self.growth + (along - p_along);
        }
        self.prev = Some((*x, *force, along));
        let estimate = self.estimate(compliance_u);
        out.gain = estimate.gain;
        let reaction = -dot(force, &u);
        let config = self.config;
        match self.hold {
            None => {
                if self.detect(&estimate) {
                    out.tripped = true;
                    self.below = 0;
                    let phase = match config.action {
                        RunawayAction::Withdraw => Some(HoldPhase::Withdrawing),
                        RunawayAction::Hold => Some(HoldPhase::Holding),
                        RunawayAction::Fault => None,
                    };
                    self.hold = phase.map(|phase| RunawayHold {
                        u,
                        cap: along,
                        cap_at_trip: along,
                        force_at_trip: reaction,
                        since_trip_s: 0.0,
                        phase,
                    });
                }
            }
            Some(mut hold) => {
                hold.since_trip_s += h;
                match hold.phase {
                    HoldPhase::Withdrawing => {
                        let s = smoothstep(hold.since_trip_s / config.withdraw_s.max(1e-6));
                        hold.cap = hold.cap_at_trip * (1.0 - s);
                        if s >= 1.0 {
                            hold.cap = 0.0;
                            hold.phase = HoldPhase::Holding;
                        }
                    }
                    HoldPhase::Holding => {}
                    HoldPhase::Releasing => {
                        hold.cap += config.release_rate_m_s * h;
                        if self.detect(&estimate) {
                            // The runaway is still there: withdraw (or hold) again from where it
                            // is. The same episode: no new report.
                            hold.cap_at_trip = hold.cap.min(along).max(0.0);
                            hold.cap = hold.cap_at_trip;
                            hold.since_trip_s = 0.0;
                            hold.phase = match config.action {
                                RunawayAction::Hold => HoldPhase::Holding,
                                _ => HoldPhase::Withdrawing,
                            };
                            self.below = 0;
                        }
                    }
                }
                if hold.phase != HoldPhase::Releasing {
                    // Hysteresis: release only on a confidently low estimate or when the law
                    // itself no longer pushes along u.
                    if estimate.high < config.release_gain {
                        self.below += 1;
                    } else {
                        self.below = 0;
                    }
                    if self.below >= config.confirm_cycles.max(1)
                        || self.wanted < config.min_correction_m
                    {
                        self.below = 0;
                        self.above = 0;
                        hold.phase = HoldPhase::Releasing;
                    }
                }
                let released = hold.phase == HoldPhase::Releasing
                    && hold.cap >= self.wanted + config.min_correction_m;
                self.hold = (!released).then_some(hold);
            }
        }
        out.holding = self.hold.is_some();
        out
    }

    /// Limits the position part of `xi` (the law's unconstrained correction) along the held
    /// direction, ξ·u ≤ cap, and remembers the law's ξ·u for the release test. Returns whether it
    /// changed anything.
    pub fn limit(&mut self, xi: &mut [f64; 6]) -> bool {
        let Some(hold) = self.hold else {
            self.wanted = f64::NAN;
            return false;
        };
        let p = [xi[0], xi[1], xi[2]];
        let along = dot(&p, &hold.u);
        self.wanted = along;
        let excess = along - hold.cap;
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
