//! The correction limiter of Section 4.2 ("an antiwindup algorithm and a correction limiter were
//! added to the control loop; this way, the correction vector ξ was guaranteed to be bounded"):
//! size and rate bounds per axis of ξ (eq. 7), per-axis enable, and a smooth ramp in and out.
//!
//! Order of operations on the unconstrained ξ from eq. 17: disabled axes → 0; clamp to the size
//! bound; multiply by the ramp factor (smoothstep 0 → 1 over `ramp_in_s`); during a ramp-out
//! the target is the value captured when the ramp-out began times a factor 1 → 0 over
//! `ramp_out_s` (the law's output is ignored); in *hold* the target is the captured value; finally
//! the rate bound, and the size bound again. During ramp-out and hold |ξᵢ| never grows.

/// Limits of the correction, per axis `[x, y, z, rx, ry, rz]` in base axes.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct LimiterConfig {
    /// Largest |ξᵢ|: m for the position axes, rad for the rotation axes.
    pub max_abs: [f64; 6],
    /// Largest |dξᵢ/dt|: m/s, rad/s.
    pub max_rate: [f64; 6],
    /// Axes whose correction is applied (e.g. position only: `[true, true, true, false, false, false]`).
    pub enabled: [bool; 6],
    /// Duration of the smooth ramp-in (s).
    pub ramp_in_s: f64,
    /// Duration of the smooth ramp-out (s), used at stop and on faults.
    pub ramp_out_s: f64,
}

impl Default for LimiterConfig {
    /// 8 mm and 0.5° (8.7 mrad) per axis, 20 mm/s and 2°/s, all axes on, 0.5 s ramps.
    fn default() -> Self {
        LimiterConfig {
            max_abs: [8e-3, 8e-3, 8e-3, 8.7e-3, 8.7e-3, 8.7e-3],
            max_rate: [20e-3, 20e-3, 20e-3, 0.035, 0.035, 0.035],
            enabled: [true; 6],
            ramp_in_s: 0.5,
            ramp_out_s: 0.5,
        }
    }
}

/// Where the ramp is.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum RampState {
    /// No correction is output (before start, after a completed ramp-out).
    Off,
    /// Ramping in since `t0`.
    In {
        /// Start time (s).
        t0: f64,
    },
    /// Full correction.
    On,
    /// Ramping out since `t0` from the captured correction `from`.
    Out {
        /// Start time (s).
        t0: f64,
        /// Correction when the ramp-out began.
        from: [f64; 6],
    },
    /// Holding the captured correction `value` (safe action "hold").
    Hold {
        /// The held correction.
        value: [f64; 6],
    },
}

/// Output of one limiter pass.
#[derive(Clone, Copy, Debug, PartialEq, Default)]
pub struct LimiterOutput {
    /// The applied correction ξ.
    pub xi: [f64; 6],
    /// Some axis hit its size bound.
    pub saturated_size: bool,
    /// Some axis hit its rate bound.
    pub saturated_rate: bool,
    /// A ramp is in progress.
    pub ramping: bool,
}

/// Stateful limiter (last output and ramp).
#[derive(Clone, Debug)]
pub struct Limiter {
    /// Configuration.
    pub config: LimiterConfig,
    state: RampState,
    last: [f64; 6],
}

/// Smoothstep 3u² − 2u³ on [0, 1].
#[inline]
pub fn smoothstep(u: f64) -> f64 {
    let u = u.clamp(0.0, 1.0);
    u * u * (3.0 - 2.0 * u)
}

impl Limiter {
    /// A limiter in [`RampState::Off`] with zero output.
    pub fn new(config: LimiterConfig) -> Self {
        Limiter {
            config,
            state: RampState::Off,
            last: [0.0; 6],
        }
    }

    /// Ramp state.
    pub fn state(&self) -> RampState {
        self.state
    }

    /// Last applied correction.
    pub fn output(&self) -> [f64; 6] {
        self.last
    }

    /// Begins the ramp-in at `now_s` (no effect unless off or ramping out).
    pub fn start(&mut self, now_s: f64) {
        if matches!(self.state, RampState::Off | RampState::Out { .. }) {
            self.state = RampState::In { t0: now_s };
        }
    }

    /// Begins the ramp-out to zero at `now_s` from the current output (also from a hold).
    pub fn ramp_out(&mut self, now_s: f64) {
        if !matches!(self.state, RampState::Out { .. } | RampState::Off) {
            self.state = RampState::Out {
                t0: now_s,
                from: self.last,
            };
        }
    }

    /// Freezes the output at its current value.
    pub fn hold(&mut self) {
        self.state = RampState::Hold { value: self.last };
    }

    /// True when the output is zero and no ramp is in progress.
    pub fn is_off(&self) -> bool {
        self.state == RampState::Off
    }

    /// True while the law's output drives the correction (ramping in or on).
    pub fn follows_law(&self) -> bool {
        matches!(self.state, RampState::In { .. } | RampState::On)
    }

    /// One pass: `xi_law` is the unconstrained ξ of eq. 17, `h` the time since the last pass.
    #[inline]
    pub fn apply(&mut self, xi_law: &[f64; 6], now_s: f64, h: f64) -> LimiterOutput {
        let cfg = self.config;
        let mut out = LimiterOutput::default();
        let mut target = [0.0; 6];
        match self.state {
            RampState::Off => {}
            RampState::In { t0 } => {
                let u = if cfg.ramp_in_s > 0.0 {
                    (now_s - t0) / cfg.ramp_in_s
                } else {
                    1.0
                };
                let s = smoothstep(u);
                for i in 0..6 {
                    let clamped = xi_law[i].clamp(-cfg.max_abs[i], cfg.max_abs[i]);
                    out.saturated_size |= clamped != xi_law[i];
                    target[i] = s * clamped;
                }
                out.ramping = true;
                if u >= 1.0 {
                    self.state = RampState::On;
                }
            }
            RampState::On => {
                for i in 0..6 {
                    let clamped = xi_law[i].clamp(-cfg.max_abs[i], cfg.max_abs[i]);
                    out.saturated_size |= clamped != xi_law[i];
                    target[i] = clamped;
                }
            }
            RampState::Out { t0, from } => {
                let u = if cfg.ramp_out_s > 0.0 {
                    (now_s - t0) / cfg.ramp_out_s
                } else {
                    1.0
                };
                let s = 1.0 - smoothstep(u);
                for i in 0..6 {
                    target[i] = s * from[i];
                }
                out.ramping = true;
            }
            RampState::Hold { value } => target = value,
        }
        let h = if h.is_finite() && h > 0.0 { h } else { 0.0 };
        for i in 0..6 {
            if !cfg.enabled[i] || !target[i].is_finite() {
                target[i] = 0.0;
            }
            let step = cfg.max_rate[i] * h;
            let delta = target[i] - self.last[i];
            let limited = self.last[i] + delta.clamp(-step, step);
            out.saturated_rate |= limited != target[i];
            let value = limited.clamp(-cfg.max_abs[i], cfg.max_abs[i]);
            out.xi[i] = if cfg.enabled[i] { value } else { 0.0 };
        }
        self.last = out.xi;
        if let RampState::Out { .. } = self.state
            && out.xi.iter().all(|v| *v == 0.0)
        {
            self.state = RampState::Off;
        }
        out
    }
}
