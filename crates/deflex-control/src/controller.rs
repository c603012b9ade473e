//! The controller of Fig. 1 / Fig. 16: one call of [`Controller::cycle`] per control period
//! (100 Hz in the paper) turns the robot's reported joint values q and one raw force/torque
//! reading into the correction ξ of eq. 7, allocation-free:
//!
//! raw → [`WrenchProcessor`] → w (eq. 2, TCP, world axes) → δŝ = J K_θ⁻¹ Jᵀ w (eq. 15) →
//! ε = −ξ − δŝ (eq. 5–7) → PID (eq. 17, [`Pid::solve`]) → [`Limiter`] → ξ,
//! supervised by [`Safety`].
//!
//! Life cycle ([`Phase`]): `Idle` → [`Controller::start`] → `Taring` (out of contact, the bias is
//! the mean reading minus tool gravity; skipped when a bias is configured) → `Running` (ramp-in,
//! then the law) → [`Controller::stop`] → `Stopping` (ramp-out) → `Stopped`. Any fault latches
//! `Faulted` (see [`crate::safety`]); [`Controller::reset_faults`] returns to `Idle`.

use crate::limiter::{Limiter, LimiterConfig, RampState};
use crate::pid::{Pid, PidGains, PidSolution};
use crate::safety::{Fault, FaultKind, Flags, SafeAction, Safety, SafetyConfig};
use crate::wrench::{WrenchConfig, WrenchProcessor};
use deflex_model::{Data, MAX_JOINTS, Robot, Wrench};
use nalgebra::Vector3;

/// Everything the controller needs besides the model.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ControllerConfig {
    /// Control period h (s); 0.01 in the paper (100 Hz).
    pub period_s: f64,
    /// Gains of eq. 17.
    pub gains: PidGains,
    /// Size/rate limits, axis enables, ramps.
    pub limiter: LimiterConfig,
    /// Sensor mounting, tool, low-pass.
    pub wrench: WrenchConfig,
    /// Fault limits and safe action.
    pub safety: SafetyConfig,
    /// Duration of the tare after [`Controller::start`] (s). Ignored when `bias` is set.
    pub tare_s: f64,
    /// A known sensor bias (sensor frame, gravity excluded): no tare is taken.
    pub bias: Option<[f64; 6]>,
}

impl Default for ControllerConfig {
    fn default() -> Self {
        ControllerConfig {
            period_s: 0.01,
            gains: PidGains::default(),
            limiter: LimiterConfig::default(),
            wrench: WrenchConfig::default(),
            safety: SafetyConfig::default(),
            tare_s: 0.2,
            bias: None,
        }
    }
}

/// Life-cycle phase.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Phase {
    /// Not started: ξ = 0.
    Idle,
    /// Averaging out-of-contact readings for the bias: ξ = 0.
    Taring,
    /// Ramping in or applying the law.
    Running,
    /// Ramping out after [`Controller::stop`].
    Stopping,
    /// Stopped: ξ = 0.
    Stopped,
    /// A fault is latched: ξ goes to / stays at the safe value.
    Faulted,
}

impl Phase {
    /// Lower-case name.
    pub fn name(self) -> &'static str {
        match self {
            Phase::Idle => "idle",
            Phase::Taring => "taring",
            Phase::Running => "running",
            Phase::Stopping => "stopping",
            Phase::Stopped => "stopped",
            Phase::Faulted => "faulted",
        }
    }
}

/// One cycle's inputs with their freshness.
#[derive(Clone, Copy, Debug)]
pub struct CycleInput<'a> {
    /// Controller time (s).
    pub now_s: f64,
    /// Joint values reported by the robot (rad).
    pub q_rad: &'a [f64],
    /// Age of `q_rad` (s).
    pub q_age_s: f64,
    /// Raw force/torque reading, sensor frame (N, N·m).
    pub wrench_sensor: &'a [f64; 6],
    /// Age of the reading (s).
    pub wrench_age_s: f64,
    /// False when no new sample arrived since the previous cycle.
    pub wrench_fresh: bool,
    /// The sensor flags a fault in its status word.
    pub sensor_fault: bool,
}

/// What one cycle produced (all in base axes, SI).
#[derive(Clone, Copy, Debug, PartialEq, Default)]
pub struct CycleOutput {
    /// Controller time (s).
    pub time_s: f64,
    /// Applied correction ξ = [δp; δφ] (eq. 7): s_com = s_des + ξ.
    pub xi: [f64; 6],
    /// Estimated deflection δŝ (eq. 15).
    pub delta_s_hat: [f64; 6],
    /// Tracking error ε = −ξ − δŝ (eq. 5–7) with the applied ξ.
    pub epsilon: [f64; 6],
    /// Compensated, filtered reading in the sensor frame.
    pub wrench_sensor: [f64; 6],
    /// Environment wrench w (eq. 2) at the TCP, base axes.
    pub wrench_tcp: [f64; 6],
    /// Status bits.
    pub flags: Flags,
}

/// The correction controller. Owns a read-only [`Robot`] (the calibrated model) and its own
/// [`Data`]; [`Controller::cycle`] does not allocate.
#[derive(Clone, Debug)]
pub struct Controller {
    robot: Robot,
    data: Data,
    config: ControllerConfig,
    wrench: WrenchProcessor,
    pid: Pid,
    limiter: Limiter,
    safety: Safety,
    phase: Phase,
    phase_t0: f64,
    last_time: Option<f64>,
    q_prev: [f64; MAX_JOINTS],
    q_prev_valid: bool,
    last: CycleOutput,
}

/// Error building a controller.
#[derive(Debug, thiserror::Error, PartialEq)]
pub enum ControlError {
    /// A configuration value is unusable.
    #[error("invalid controller setting {field}: {message}")]
    Invalid {
        /// The setting.
        field: &'static str,
        /// Why.
        message: String,
    },
}

fn invalid(field: &'static str, message: impl Into<String>) -> ControlError {
    ControlError::Invalid {
        field,
        message: message.into(),
    }
}

impl Controller {
    /// A controller for `robot` (the model calibrated for the cell, never the plant).
    pub fn new(robot: Robot, config: ControllerConfig) -> Result<Self, ControlError> {
        if !(config.period_s > 0.0 && config.period_s.is_finite()) {
            return Err(invalid("period_s", "must be a positive number of seconds"));
        }
        if robot.joint_count() == 0 || robot.joint_count() > MAX_JOINTS {
            return Err(invalid("robot", format!("1..={MAX_JOINTS} joints needed")));
        }
        let g = &config.gains;
        if !(g.kc.is_finite() && g.kc >= 0.0 && g.ti_s >= 0.0 && g.td_s >= 0.0) {
            return Err(invalid("gains", "kc, ti_s, td_s must be finite and ≥ 0"));
        }
        let l = &config.limiter;
        if l.max_abs
            .iter()
            .chain(&l.max_rate)
            .any(|v| v.is_nan() || *v < 0.0)
        {
            return Err(invalid("limits", "max_abs and max_rate must be ≥ 0"));
        }
        let mut wrench = WrenchProcessor::new(config.wrench);
        if let Some(bias) = config.bias {
            wrench.set_bias(bias);
        }
        Ok(Controller {
            robot,
            data: Data::new(),
            config,
            wrench,
            pid: Pid::new(config.gains),
            limiter: Limiter::new(config.limiter),
            safety: Safety::new(config.safety),
            phase: Phase::Idle,
            phase_t0: 0.0,
            last_time: None,
            q_prev: [0.0; MAX_JOINTS],
            q_prev_valid: false,
            last: CycleOutput::default(),
        })
    }

    /// Configuration.
    pub fn config(&self) -> &ControllerConfig {
        &self.config
    }
    /// The model.
    pub fn robot(&self) -> &Robot {
        &self.robot
    }
    /// Phase.
    pub fn phase(&self) -> Phase {
        self.phase
    }
    /// Latched fault, if any.
    pub fn fault(&self) -> Option<Fault> {
        self.safety.latched()
    }
    /// Fault detection counts per kind (order of [`FaultKind::ALL`]).
    pub fn fault_counts(&self) -> [u64; 5] {
        self.safety.counts()
    }
    /// The last cycle's output.
    pub fn last_output(&self) -> &CycleOutput {
        &self.last
    }
    /// Current sensor bias.
    pub fn bias(&self) -> [f64; 6] {
        self.wrench.bias()
    }

    /// Starts: tare (unless a bias is configured), then ramp in. Only from `Idle` or `Stopped`.
    pub fn start(&mut self, now_s: f64) {
        if !matches!(self.phase, Phase::Idle | Phase::Stopped) {
            return;
        }
        self.pid.reset();
        self.wrench.reset_filter();
        self.phase_t0 = now_s;
        if self.config.bias.is_some() || self.config.tare_s <= 0.0 {
            self.limiter.start(now_s);
            self.phase = Phase::Running;
        } else {
            self.phase = Phase::Taring;
        }
    }

    /// Ramps the correction out; the phase becomes `Stopped` once ξ = 0.
    pub fn stop(&mut self, now_s: f64) {
        match self.phase {
            Phase::Running => {
                self.limiter.ramp_out(now_s);
                self.phase = Phase::Stopping;
            }
            Phase::Taring | Phase::Idle => self.phase = Phase::Stopped,
            _ => {}
        }
    }

    /// True when ξ no longer moves on its own: off, or held after a fault.
    pub fn is_settled(&self) -> bool {
        matches!(
            self.limiter.state(),
            RampState::Off | RampState::Hold { .. }
        )
    }

    /// Operator acknowledgement: clears the latch once ξ is back at zero and returns true; the
    /// controller is then `Idle` and may be started again. A held correction (safe action
    /// "hold") is first ramped out from `now_s` (returns false: call again once it is zero), so
    /// ξ never jumps.
    pub fn reset_faults(&mut self, now_s: f64) -> bool {
        if self.phase != Phase::Faulted {
            return false;
        }
        match self.limiter.state() {
            RampState::Off => {
                self.safety.reset();
                self.limiter = Limiter::new(self.config.limiter);
                self.pid.reset();
                self.phase = Phase::Idle;
                true
            }
            RampState::Hold { .. } => {
                self.limiter.ramp_out(now_s);
                false
            }
            _ => false,
        }
    }

    /// Latches a fault detected outside the cycle (e.g. by the runtime). Returns true if new.
    pub fn trip(&mut self, kind: FaultKind, now_s: f64, value: f64, limit: f64) -> bool {
        let fault = Fault {
            kind,
            time_s: now_s,
            value,
            limit,
        };
        let new = self.safety.trip(fault);
        if new {
            self.enter_fault(now_s);
        }
        new
    }

    fn enter_fault(&mut self, now_s: f64) {
        match self.config.safety.safe_action {
            SafeAction::Zero => self.limiter.ramp_out(now_s),
            SafeAction::Hold => self.limiter.hold(),
        }
        self.phase = Phase::Faulted;
    }

    /// One control cycle with fresh inputs (ages 0).
    #[inline]
    pub fn cycle(
        &mut self,
        now_s: f64,
        q_rad: &[f64],
        raw_wrench_sensor: &[f64; 6],
    ) -> CycleOutput {
        self.cycle_input(&CycleInput {
            now_s,
            q_rad,
            q_age_s: 0.0,
            wrench_sensor: raw_wrench_sensor,
            wrench_age_s: 0.0,
            wrench_fresh: true,
            sensor_fault: false,
        })
    }

    /// One control cycle (eq. 5–7, 15, 17). Never panics, never allocates.
    pub fn cycle_input(&mut self, input: &CycleInput) -> CycleOutput {
        let period = self.config.period_s;
        let now = if input.now_s.is_finite() {
            input.now_s
        } else {
            self.last_time.map_or(0.0, |t| t + period)
        };
        let h = match self.last_time {
            Some(t) if now - t > 0.0 => (now - t).min(10.0 * period),
            _ => period,
        };
        self.last_time = Some(now);
        let mut flags = Flags::default();
        let detected = self.check_inputs(input, now);
        let data_ok =
            detected.is_none_or(|k| !matches!(k, FaultKind::NonFinite | FaultKind::OutOfRange));
        let mut out = CycleOutput {
            time_s: now,
            ..self.last
        };
        if let Some(kind) = detected {
            flags.set(kind.flag());
        }
        if !input.wrench_fresh {
            flags.set(Flags::STALE_WRENCH);
        }
        if data_ok {
            let q = &input.q_rad[..self.robot.joint_count()];
            if self.robot.forward_kinematics(&mut self.data, q).is_ok() {
                if self.phase == Phase::Taring {
                    let pose = self.wrench.sensor_pose(&self.data);
                    self.wrench.tare_add(input.wrench_sensor, &pose);
                }
                self.estimate(input.wrench_sensor, h, &mut out);
                if !self.check_estimate(&out, now, &mut flags) {
                    // Never let a non-finite estimate reach ξ, ε or the log.
                    out.delta_s_hat = self.last.delta_s_hat;
                    out.wrench_tcp = self.last.wrench_tcp;
                    out.wrench_sensor = self.last.wrench_sensor;
                }
            }
            self.q_prev[..q.len()].copy_from_slice(q);
            self.q_prev_valid = true;
        }
        if self.phase == Phase::Taring {
            flags.set(Flags::TARING);
            if now - self.phase_t0 >= self.config.tare_s && self.wrench.tare_count() > 0 {
                self.wrench.tare_finish();
                self.wrench.reset_filter();
                self.limiter.start(now);
                self.phase = Phase::Running;
            }
        }
        // The law (eq. 17 solved with eq. 5–7), only on trusted data while it drives ξ.
        let follow = self.limiter.follows_law() && self.phase == Phase::Running && data_ok;
        let mut law = [PidSolution::default(); 6];
        let mut xi_law = self.limiter.output();
        if follow {
            for (i, solution) in law.iter_mut().enumerate() {
                if self.config.limiter.enabled[i] {
                    *solution = self.pid.solve(i, out.delta_s_hat[i], h);
                    xi_law[i] = solution.xi;
                } else {
                    self.pid.reset_axis(i);
                    xi_law[i] = 0.0;
                }
            }
        }
        let limited = self.limiter.apply(&xi_law, now, h);
        if follow {
            for (i, solution) in law.iter().enumerate() {
                if self.config.limiter.enabled[i] {
                    let bound = self.config.limiter.max_abs[i];
                    self.pid.commit(i, solution, limited.xi[i], h, bound, false);
                }
            }
        }
        if self.phase == Phase::Stopping && self.limiter.is_off() {
            self.phase = Phase::Stopped;
        }
        out.xi = limited.xi;
        for i in 0..6 {
            out.epsilon[i] = -out.xi[i] - out.delta_s_hat[i];
        }
        if limited.saturated_size {
            flags.set(Flags::SATURATED_SIZE);
        }
        if limited.saturated_rate {
            flags.set(Flags::SATURATED_RATE);
        }
        if limited.ramping {
            flags.set(Flags::RAMPING);
        }
        if follow {
            flags.set(Flags::ACTIVE);
        }
        if let Some(fault) = self.safety.latched() {
            flags.set(Flags::LATCHED);
            flags.set(fault.kind.flag());
        }
        out.flags = flags;
        self.last = out;
        out
    }

    /// Input checks; trips and returns the first fault kind detected this cycle.
    fn check_inputs(&mut self, input: &CycleInput, now: f64) -> Option<FaultKind> {
        let cfg = self.config.safety;
        let n = self.robot.joint_count();
        let mut found: Option<(FaultKind, f64, f64)> = None;
        let q_finite = input.q_rad.iter().all(|v| v.is_finite());
        let w_finite = input.wrench_sensor.iter().all(|v| v.is_finite());
        if !input.now_s.is_finite() || !q_finite || !w_finite {
            found = Some((FaultKind::NonFinite, f64::NAN, 0.0));
        } else if input.q_rad.len() < n {
            found = Some((FaultKind::OutOfRange, input.q_rad.len() as f64, n as f64));
        } else if let Some(i) =
            (0..6).find(|&i| input.wrench_sensor[i].abs() >= cfg.sensor_range[i])
        {
            found = Some((
                FaultKind::OutOfRange,
                input.wrench_sensor[i],
                cfg.sensor_range[i],
            ));
        } else {
            for i in 0..n {
                let qi = input.q_rad[i];
                if let Some([lo, hi]) = self.robot.joints[i].limits {
                    let m = cfg.joint_limit_margin_rad;
                    if qi < lo - m || qi > hi + m {
                        found = Some((FaultKind::OutOfRange, qi, if qi < lo { lo } else { hi }));
                        break;
                    }
                }
                if self.q_prev_valid && (qi - self.q_prev[i]).abs() > cfg.max_joint_step_rad {
                    found = Some((
                        FaultKind::OutOfRange,
                        qi - self.q_prev[i],
                        cfg.max_joint_step_rad,
                    ));
                    break;
                }
            }
        }
        if found.is_none() && (input.q_age_s.is_nan() || input.q_age_s > cfg.robot_timeout_s) {
            found = Some((FaultKind::RobotLinkLost, input.q_age_s, cfg.robot_timeout_s));
        }
        if found.is_none()
            && (input.sensor_fault
                || input.wrench_age_s.is_nan()
                || input.wrench_age_s > cfg.sensor_timeout_s)
        {
            found = Some((
                FaultKind::SensorTimeout,
                input.wrench_age_s,
                cfg.sensor_timeout_s,
            ));
        }
        let (kind, value, limit) = found?;
        self.trip(kind, now, value, limit);
        Some(kind)
    }

    /// Wrench path and deflection estimate (eq. 2, 15) into `out`, in base axes.
    #[inline]
    fn estimate(&mut self, raw: &[f64; 6], h: f64, out: &mut CycleOutput) {
        let processed = self.wrench.process(raw, &self.data, h);
        let w = Wrench::from(processed.tcp_world);
        let ds = self.robot.tcp_deflection(&self.data, &w);
        let r_t = self.robot.base.rotation.matrix().transpose();
        let to_base = |v: &[f64], at: usize| -> [f64; 3] {
            let b = r_t * Vector3::new(v[at], v[at + 1], v[at + 2]);
            [b.x, b.y, b.z]
        };
        let (f, m) = (
            to_base(&processed.tcp_world, 0),
            to_base(&processed.tcp_world, 3),
        );
        let (dp, dphi) = (to_base(ds.as_slice(), 0), to_base(ds.as_slice(), 3));
        out.wrench_sensor = processed.sensor;
        out.wrench_tcp = [f[0], f[1], f[2], m[0], m[1], m[2]];
        out.delta_s_hat = [dp[0], dp[1], dp[2], dphi[0], dphi[1], dphi[2]];
    }

    /// Checks the estimate; returns false when it is not finite.
    fn check_estimate(&mut self, out: &CycleOutput, now: f64, flags: &mut Flags) -> bool {
        let cfg = self.config.safety;
        let w = &out.wrench_tcp;
        let force = (w[0] * w[0] + w[1] * w[1] + w[2] * w[2]).sqrt();
        let torque = (w[3] * w[3] + w[4] * w[4] + w[5] * w[5]).sqrt();
        let finite = out.delta_s_hat.iter().all(|v| v.is_finite())
            && force.is_finite()
            && torque.is_finite();
        if self.phase == Phase::Taring {
            return finite;
        }
        let fault = if !finite {
            Some((FaultKind::NonFinite, f64::NAN, 0.0))
        } else if force > cfg.max_force_n {
            Some((FaultKind::ForceOverLimit, force, cfg.max_force_n))
        } else if torque > cfg.max_torque_nm {
            Some((FaultKind::ForceOverLimit, torque, cfg.max_torque_nm))
        } else {
            None
        };
        if let Some((kind, value, limit)) = fault {
            flags.set(kind.flag());
            self.trip(kind, now, value, limit);
        }
        finite
    }
}
