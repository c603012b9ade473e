//! The correction law of eq. 17, per axis:
//!
//! ξ(t) = K_c ( ε(t) + (1/T_i) ∫₀ᵗ ε dτ + T_d dε/dt ),
//!
//! with the paper's gains K_c = 0.8, T_i = 0.048 s, T_d = 0.012 s at 100 Hz (Section 4.2).
//!
//! Discretisation (sample time h): rectangular integral, and a derivative taken on ε passed
//! through a first-order filter of time constant T_f = T_d / N ("derivative on a filtered
//! signal"): ε_f ← ε_f + a(ε − ε_f), a = h / (T_f + h), D = K_c T_d (Δε_f) / h.
//!
//! **Closing the loop of eq. 5–7 at the current sample.** The tracking error is
//! ε = s_des − ŝ_real = −ξ − δŝ (eq. 5–7), where ŝ_real = s_com + δŝ is reconstructed with the
//! set-point s_com = s_des + ξ that is being commanded *now*. In continuous time (the paper's
//! block diagram) this is an algebraic loop; evaluating it with the previous sample's ξ instead
//! adds a one-sample delay in a loop whose static gain is ≈ 1 in directions without contact, and
//! the paper's gains then oscillate at the Nyquist frequency and diverge. [`Pid::solve`] therefore
//! solves the loop exactly: the law is affine in ε, ξ = Aε + B, so with ε = −ξ − δŝ,
//! ξ = (B − A δŝ)/(1 + A). The result is well-damped for any contact stiffness (no overshoot).
//!
//! **Anti-windup** by back-calculation: after the limiter has produced the applied ξ,
//! [`Pid::commit`] adds (h/T_t)(ξ_applied − ξ_unconstrained) to the integral (T_t = T_i by
//! default) and clamps the integral to a bound; a frozen controller (fault, ramp-out) does not
//! integrate at all.

/// Gains of eq. 17 plus the discretisation parameters.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct PidGains {
    /// Proportional gain K_c (dimensionless: ξ and ε are both poses).
    pub kc: f64,
    /// Integral time T_i (s); `0` or infinite disables the integral.
    pub ti_s: f64,
    /// Derivative time T_d (s); `0` disables the derivative.
    pub td_s: f64,
    /// Derivative filter ratio N: the derivative acts on ε low-passed with T_f = T_d / N.
    pub derivative_filter_n: f64,
    /// Back-calculation tracking time T_t (s); `None` uses T_i.
    pub tracking_time_s: Option<f64>,
}

impl Default for PidGains {
    /// The paper's gains (Section 4.2, eq. 17) with N = 5.
    fn default() -> Self {
        PidGains {
            kc: 0.8,
            ti_s: 0.048,
            td_s: 0.012,
            derivative_filter_n: 5.0,
            tracking_time_s: None,
        }
    }
}

impl PidGains {
    fn integral_rate(&self) -> f64 {
        if self.ti_s > 0.0 && self.ti_s.is_finite() {
            self.kc / self.ti_s
        } else {
            0.0
        }
    }
    fn filter_alpha(&self, h: f64) -> f64 {
        let tf = if self.derivative_filter_n > 0.0 {
            self.td_s / self.derivative_filter_n
        } else {
            0.0
        };
        h / (tf + h)
    }
    fn tracking_time(&self) -> f64 {
        self.tracking_time_s.unwrap_or(self.ti_s).max(1e-6)
    }
}

/// State of one axis.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct PidAxis {
    /// Integral term, in units of ξ: K_c/T_i ∫ ε.
    pub integral: f64,
    /// Filtered error ε_f feeding the derivative.
    pub error_filtered: f64,
    /// False until the first committed sample (no derivative kick on the first sample).
    pub primed: bool,
}

/// One unconstrained solution of the loop for one axis.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct PidSolution {
    /// Unconstrained correction ξ_u.
    pub xi: f64,
    /// Tracking error ε_u = −ξ_u − δŝ (eq. 5–7).
    pub epsilon: f64,
}

/// Six independent PID axes (eq. 17), allocation-free.
#[derive(Clone, Debug)]
pub struct Pid {
    /// Gains shared by all axes.
    pub gains: PidGains,
    /// Per-axis state (`[x, y, z, rx, ry, rz]`).
    pub axes: [PidAxis; 6],
}

impl Pid {
    /// Zero state.
    pub fn new(gains: PidGains) -> Self {
        Pid {
            gains,
            axes: [PidAxis::default(); 6],
        }
    }

    /// Resets one axis (used when an axis is disabled).
    pub fn reset_axis(&mut self, axis: usize) {
        self.axes[axis] = PidAxis::default();
    }

    /// Resets all axes.
    pub fn reset(&mut self) {
        self.axes = [PidAxis::default(); 6];
    }

    /// Classic eq. 17 for a *given* error ε (no loop solving): returns ξ and commits the state.
    /// Useful for step-response checks and for callers that form ε themselves.
    pub fn step_error(&mut self, axis: usize, epsilon: f64, h: f64) -> f64 {
        let g = self.gains;
        let s = &mut self.axes[axis];
        s.integral += g.integral_rate() * h * epsilon;
        let previous = s.error_filtered;
        if s.primed {
            s.error_filtered += g.filter_alpha(h) * (epsilon - s.error_filtered);
        } else {
            s.error_filtered = epsilon;
        }
        let derivative = if s.primed && g.td_s > 0.0 {
            g.kc * g.td_s * (s.error_filtered - previous) / h
        } else {
            0.0
        };
        s.primed = true;
        g.kc * epsilon + s.integral + derivative
    }

    /// Solves ξ = PID(ε) with ε = −ξ − δŝ (eq. 5–7, 17) for one axis at sample time `h`,
    /// without changing the state.
    #[inline]
    pub fn solve(&self, axis: usize, delta_s_hat: f64, h: f64) -> PidSolution {
        let g = &self.gains;
        let s = &self.axes[axis];
        let kd = if s.primed && g.td_s > 0.0 {
            g.kc * g.td_s * g.filter_alpha(h) / h
        } else {
            0.0
        };
        let a = g.kc + g.integral_rate() * h + kd;
        let b = s.integral - kd * s.error_filtered;
        let xi = (b - a * delta_s_hat) / (1.0 + a);
        PidSolution {
            xi,
            epsilon: -xi - delta_s_hat,
        }
    }

    /// Commits one sample of one axis after limiting: integrates the unconstrained error, applies
    /// back-calculation towards `xi_applied`, clamps the integral to ±`integral_bound`, updates the
    /// derivative filter. With `frozen` the integral is left untouched (faults, ramp-out).
    #[inline]
    pub fn commit(
        &mut self,
        axis: usize,
        solution: &PidSolution,
        xi_applied: f64,
        h: f64,
        integral_bound: f64,
        frozen: bool,
    ) {
        let g = self.gains;
        let s = &mut self.axes[axis];
        if !frozen {
            s.integral += g.integral_rate() * h * solution.epsilon
                + (h / g.tracking_time()) * (xi_applied - solution.xi);
            s.integral = s.integral.clamp(-integral_bound, integral_bound);
        }
        if s.primed {
            s.error_filtered += g.filter_alpha(h) * (solution.epsilon - s.error_filtered);
        } else {
            s.error_filtered = solution.epsilon;
            s.primed = true;
        }
    }
}
