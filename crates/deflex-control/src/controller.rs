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

use crate::feedforward::{FeedForward, FeedForwardStep, TrackState};
use crate::limiter::{Limiter, LimiterConfig, LimiterOutput, RampState};
use crate::model_check::{ModelCheckConfig, PoseMismatch};
use crate::pid::{Pid, PidGains, PidSolution};
use crate::runaway::{RunawayConfig, RunawayGuard};
use crate::safety::{Fault, SafeAction, Safety, SafetyConfig};
use crate::wrench::{WrenchConfig, WrenchProcessor};
use deflex_model::{Data, MAX_JOINTS, Pose, Robot, Wrench};
use deflex_telemetry::Phase;
use deflex_telemetry::{FAULT_KINDS, FaultKind, Flags};
use nalgebra::SMatrix;

mod checks;

pub use checks::JOINT_MAP_DAMPING;

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
    /// The contact-runaway guard ([`crate::runaway`]).
    pub runaway: RunawayConfig,
    /// The robot's reported TCP pose against the model's ([`crate::model_check`]).
    pub model_check: ModelCheckConfig,
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
            runaway: RunawayConfig::default(),
            model_check: ModelCheckConfig::default(),
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
    pub wrench_sensor: Wrench,
    /// Age of the reading (s).
    pub wrench_age_s: f64,
    /// False when no new sample arrived since the previous cycle.
    pub wrench_fresh: bool,
    /// The sensor's status word (0: healthy; anything else is a `sensor_status` fault).
    pub sensor_status: u32,
    /// The TCP pose the robot reported with `q_rad` (robot base frame), when its protocol
    /// carries one (KUKA RSI `RIst`, ABB EGM): checked against the model's
    /// ([`crate::model_check`]).
    pub tcp_pose: Option<Pose>,
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
    /// Loop gain through the contact estimated by the runaway guard along the corrected
    /// direction ([`crate::runaway`]); NaN when it cannot be estimated.
    pub loop_gain: f64,
    /// The prior of [`crate::feedforward`] at the robot's place on the path (the feed-forward,
    /// or the compensated program's compensation), base axes; zero without one or off the path.
    pub feedforward: [f64; 6],
    /// Arc length of the robot's place on the feed-forward table's path (m); NaN without a
    /// table or while acquiring.
    pub path_s_m: f64,
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
    guard: RunawayGuard,
    runaway_events: u64,
    first_runaway: Option<Fault>,
    feedforward: Option<FeedForward>,
    /// The feed-forward sent with the last cycle's law (part of the limiter's output).
    feedforward_sent: [f64; 6],
    /// The largest difference between the robot's reported TCP pose and the model's so far
    /// (`None`: no pose reported, or the check is off).
    pose_mismatch_max: Option<PoseMismatch>,
}

/// Error building a controller: the setting and the value that make it unusable.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum ControlError {
    /// The control period is not a positive number of seconds.
    Period {
        /// The period given (s).
        period_s: f64,
    },
    /// The model has no joints or more than [`MAX_JOINTS`].
    JointCount {
        /// Its joints.
        joints: usize,
    },
    /// A gain of eq. 17 is negative or not finite.
    Gains {
        /// The gains given.
        gains: PidGains,
    },
    /// A size or rate limit of the limiter is negative or NaN.
    Limit {
        /// Axis (0..6: x, y, z, rx, ry, rz).
        axis: usize,
        /// Largest |ξ| given for it.
        max_abs: f64,
        /// Largest rate given for it.
        max_rate: f64,
    },
}

impl std::fmt::Display for ControlError {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            ControlError::Period { period_s } => write!(
                f,
                "invalid controller setting period_s: must be a positive number of seconds, got \
                 {period_s}"
            ),
            ControlError::JointCount { joints } => write!(
                f,
                "invalid controller setting robot: 1..={MAX_JOINTS} joints needed, the model has \
                 {joints}"
            ),
            ControlError::Gains { gains } => write!(
                f,
                "invalid controller setting gains: kc, ti_s, td_s must be finite and ≥ 0, got \
                 kc {}, ti_s {}, td_s {}",
                gains.kc, gains.ti_s, gains.td_s
            ),
            ControlError::Limit {
                axis,
                max_abs,
                max_rate,
            } => write!(
                f,
                "invalid controller setting limits: max_abs and max_rate must be ≥ 0, got {max_abs} \
                 and {max_rate} on axis {axis}"
            ),
        }
    }
}

impl std::error::Error for ControlError {}

/// The least-squares map from a correction ξ (base axes) to joint corrections: row i is joint i,
/// Δq = P ξ ([`Controller::joint_correction_map`]); rows past the joint count are zero.
pub type JointCorrectionMap = SMatrix<f64, MAX_JOINTS, 6>;

impl Controller {
    /// A controller for `robot` (the model calibrated for the cell, never the plant).
    pub fn new(robot: Robot, config: ControllerConfig) -> Result<Self, ControlError> {
        if !(config.period_s > 0.0 && config.period_s.is_finite()) {
            return Err(ControlError::Period {
                period_s: config.period_s,
            });
        }
        if robot.joint_count() == 0 || robot.joint_count() > MAX_JOINTS {
            return Err(ControlError::JointCount {
                joints: robot.joint_count(),
            });
        }
        let g = &config.gains;
        if !(g.kc.is_finite() && g.kc >= 0.0 && g.ti_s >= 0.0 && g.td_s >= 0.0) {
            return Err(ControlError::Gains { gains: *g });
        }
        let l = &config.limiter;
        let bad = |v: f64| v.is_nan() || v < 0.0;
        if let Some(axis) = (0..6).find(|&i| bad(l.max_abs[i]) || bad(l.max_rate[i])) {
            return Err(ControlError::Limit {
                axis,
                max_abs: l.max_abs[axis],
                max_rate: l.max_rate[axis],
            });
        }
        let mut wrench = WrenchProcessor::new(config.wrench);
        if let Some(bias) = config.bias {
            wrench.set_bias(Wrench::from(bias));
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
            guard: RunawayGuard::new(config.runaway),
            runaway_events: 0,
            first_runaway: None,
            feedforward: None,
            feedforward_sent: [0.0; 6],
            pose_mismatch_max: None,
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
    pub fn fault_counts(&self) -> [u64; FAULT_KINDS] {
        self.safety.counts()
    }
    /// Times the runaway guard acted (withdrew or held the correction, or latched the fault).
    pub fn runaway_events(&self) -> u64 {
        self.runaway_events
    }
    /// The first runaway the guard acted on, as a fault record (also when it only withdrew or
    /// held the correction, which is not latched).
    pub fn first_runaway(&self) -> Option<Fault> {
        self.first_runaway
    }
    /// The largest difference between the robot's reported TCP pose and the model's at the
    /// same joints so far ([`crate::model_check`]); `None` when no pose was reported or the
    /// check is off.
    pub fn pose_mismatch_max(&self) -> Option<PoseMismatch> {
        self.pose_mismatch_max
    }
    /// The runaway guard's active hold (direction, cap, phase), if any.
    pub fn runaway_hold(&self) -> Option<crate::runaway::RunawayHold> {
        self.guard.hold()
    }
    /// The last cycle's output.
    pub fn last_output(&self) -> &CycleOutput {
        &self.last
    }
    /// Current sensor bias (sensor frame, gravity excluded).
    pub fn bias(&self) -> Wrench {
        self.wrench.bias()
    }

    /// Feed-forward plus feedback ([`crate::feedforward`]): the online correction on top of an
    /// offline compensation (`None`: the correction alone). Set it before [`Controller::start`].
    pub fn set_feedforward(&mut self, feedforward: Option<FeedForward>) {
        self.feedforward = feedforward;
    }

    /// The feed-forward, when set.
    pub fn feedforward(&self) -> Option<&FeedForward> {
        self.feedforward.as_ref()
    }

    /// The feed-forward, when set, to reset its tracking for a new run of the program.
    pub fn feedforward_mut(&mut self) -> Option<&mut FeedForward> {
        self.feedforward.as_mut()
    }

    /// Starts: tare (unless a bias is configured), then ramp in. Only from `Idle` or `Stopped`.
    pub fn start(&mut self, now_s: f64) {
        if !matches!(self.phase, Phase::Idle | Phase::Stopped) {
            return;
        }
        self.pid.reset();
        self.wrench.reset_filter();
        self.guard.reset();
        if let Some(ff) = self.feedforward.as_mut() {
            ff.start(now_s);
        }
        self.phase_t0 = now_s;
        if self.config.bias.is_some() || self.config.tare_s <= 0.0 {
            self.limiter.start(now_s);
            self.phase = Phase::Running;
        } else {
            self.phase = Phase::Taring;
        }
    }

    /// Ramps the correction out; the phase becomes `Stopped` once ξ = 0. A correction held by a
    /// fault (safe action "hold") is ramped out too (the phase stays `Faulted`): a stop always
    /// leaves the robot on its programmed path.
    pub fn stop(&mut self, now_s: f64) {
        match self.phase {
            Phase::Running => {
                self.limiter.ramp_out(now_s);
                self.phase = Phase::Stopping;
            }
            Phase::Taring | Phase::Idle => self.phase = Phase::Stopped,
            Phase::Faulted => self.limiter.ramp_out(now_s),
            Phase::Stopping | Phase::Stopped => {}
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

    /// Latches a fault (detected in the cycle, or outside it by the runtime). Returns true if
    /// new.
    pub fn trip(&mut self, fault: Fault) -> bool {
        let new = self.safety.trip(fault);
        if new {
            self.enter_fault(fault.time_s);
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
    pub fn cycle(&mut self, now_s: f64, q_rad: &[f64], raw_wrench_sensor: &Wrench) -> CycleOutput {
        self.cycle_input(&CycleInput {
            now_s,
            q_rad,
            q_age_s: 0.0,
            wrench_sensor: *raw_wrench_sensor,
            wrench_age_s: 0.0,
            wrench_fresh: true,
            sensor_status: 0,
            tcp_pose: None,
        })
    }

    /// One control cycle (eq. 5–7, 15, 17). Never panics, never allocates.
    ///
    /// In order: the cycle's time step; the inputs checked and, when they can be trusted, the
    /// robot's pose, its place on a feed-forward table, the tare and the estimate
    /// (`sense`); the tare's end; the law, the runaway guard and the limiter
    /// (`apply_law`); the output with its error and status flags.
    pub fn cycle_input(&mut self, input: &CycleInput) -> CycleOutput {
        let (now, h) = self.time_step(input.now_s);
        let mut flags = Flags::default();
        let detected = self.check_inputs(input, now);
        // Inputs that cannot be trusted at all: the law does not see them.
        let data_ok = detected.is_none_or(|k| {
            !matches!(
                k,
                FaultKind::NonFinite
                    | FaultKind::SensorOverRange
                    | FaultKind::JointOutOfLimits
                    | FaultKind::JointJump
                    | FaultKind::JointCountMismatch
            )
        });
        let mut out = CycleOutput {
            time_s: now,
            loop_gain: f64::NAN,
            ..self.last
        };
        if let Some(kind) = detected {
            flags.set(kind.flag());
        }
        if !input.wrench_fresh {
            flags.set(Flags::STALE_WRENCH);
        }
        let (kinematics_ok, ff) = if data_ok {
            self.sense(input, now, h, &mut out, &mut flags)
        } else {
            (false, FeedForwardStep::none())
        };
        self.advance_tare(now, &mut flags);
        if self.feedforward.is_some() && ff.state != TrackState::OnPath {
            flags.set(Flags::FEEDFORWARD_OFF_PATH);
        }
        // The law (eq. 17 solved with eq. 5–7), only on trusted data while it drives ξ.
        let follow = self.limiter.follows_law() && self.phase == Phase::Running && data_ok;
        if follow && kinematics_ok {
            self.watch_runaway(&mut out, now, h, &mut flags);
        }
        let limited = self.apply_law(&out, &ff, follow, now, h, &mut flags);
        if self.phase == Phase::Stopping && self.limiter.is_off() {
            self.phase = Phase::Stopped;
        }
        out.xi = limited.xi;
        self.feedforward_sent = if follow { ff.sent } else { [0.0; 6] };
        out.feedforward = ff.prior;
        out.path_s_m = ff.path_s_m;
        for i in 0..6 {
            // ε = −ξ_fb − prior − δŝ with ξ_fb = ξ − sent (eq. 5–7; crate::feedforward).
            out.epsilon[i] = -(out.xi[i] - ff.sent[i]) - ff.prior[i] - out.delta_s_hat[i];
        }
        for (on, bit) in [
            (limited.saturated_size, Flags::SATURATED_SIZE),
            (limited.saturated_rate, Flags::SATURATED_RATE),
            (limited.ramping, Flags::RAMPING),
            (follow, Flags::ACTIVE),
        ] {
            if on {
                flags.set(bit);
            }
        }
        if let Some(fault) = self.safety.latched() {
            flags.set(Flags::LATCHED);
            flags.set(fault.kind.flag());
        }
        out.flags = flags;
        self.last = out;
        out
    }

    /// The cycle's time (a non-finite time continues from the last one) and its step h since
    /// the previous cycle (one period at first or when time did not advance, at most ten).
    fn time_step(&mut self, now_s: f64) -> (f64, f64) {
        let period = self.config.period_s;
        let now = if now_s.is_finite() {
            now_s
        } else {
            self.last_time.map_or(0.0, |t| t + period)
        };
        let h = match self.last_time {
            Some(t) if now - t > 0.0 => (now - t).min(10.0 * period),
            _ => period,
        };
        self.last_time = Some(now);
        (now, h)
    }

    /// On trusted inputs: forward kinematics of the reported joints, the robot's place on the
    /// feed-forward table, the tare's reading, the wrench path and the estimate (eq. 2, 15)
    /// into `out`. Returns whether the kinematics are known and the feed-forward's step.
    fn sense(
        &mut self,
        input: &CycleInput,
        now: f64,
        h: f64,
        out: &mut CycleOutput,
        flags: &mut Flags,
    ) -> (bool, FeedForwardStep) {
        let mut ff = FeedForwardStep::none();
        let q = &input.q_rad[..self.robot.joint_count()];
        let kinematics_ok = self.robot.forward_kinematics(&mut self.data, q).is_ok();
        if kinematics_ok && let Some(reported) = input.tcp_pose.as_ref() {
            self.check_model(reported, now, flags);
        }
        if kinematics_ok {
            if let Some(feedforward) = self.feedforward.as_mut() {
                // The robot's place on its program: the commanded TCP minus the correction
                // this controller sends (base axes → world).
                let xi = self.limiter.output();
                let sent = self.robot.base.rotation * nalgebra::Vector3::new(xi[0], xi[1], xi[2]);
                ff = feedforward.update(&(self.data.tcp_position() - sent), now);
            }
            if self.phase == Phase::Taring {
                let pose = self.wrench.sensor_pose(&self.data);
                self.wrench.tare_add(&input.wrench_sensor, &pose);
            }
            self.estimate(&input.wrench_sensor, h, out);
            if !self.check_estimate(out, now, flags) {
                // Never let a non-finite estimate reach ξ, ε or the log.
                out.delta_s_hat = self.last.delta_s_hat;
                out.wrench_tcp = self.last.wrench_tcp;
                out.wrench_sensor = self.last.wrench_sensor;
            }
        }
        self.q_prev[..q.len()].copy_from_slice(q);
        self.q_prev_valid = true;
        (kinematics_ok, ff)
    }

    /// While taring: flags it, and once `tare_s` has passed with readings, takes the bias and
    /// starts the ramp-in.
    fn advance_tare(&mut self, now: f64, flags: &mut Flags) {
        if self.phase == Phase::Taring {
            flags.set(Flags::TARING);
            if now - self.phase_t0 >= self.config.tare_s && self.wrench.tare_count() > 0 {
                self.wrench.tare_finish();
                self.wrench.reset_filter();
                self.limiter.start(now);
                self.phase = Phase::Running;
            }
        }
    }

    /// The law of eq. 17 per enabled axis when `follow` (with a feed-forward the PID sees
    /// δŝ + prior and the feed-forward is added to its output: derivation in
    /// crate::feedforward), the runaway guard on the feedback, the limiter, and the PID's
    /// anti-windup commit of what the limiter let through.
    fn apply_law(
        &mut self,
        out: &CycleOutput,
        ff: &FeedForwardStep,
        follow: bool,
        now: f64,
        h: f64,
        flags: &mut Flags,
    ) -> LimiterOutput {
        let mut law = [PidSolution::default(); 6];
        let mut xi_law = self.limiter.output();
        if follow {
            for (i, solution) in law.iter_mut().enumerate() {
                if self.config.limiter.enabled[i] {
                    *solution = self.pid.solve(i, out.delta_s_hat[i] + ff.prior[i], h);
                    xi_law[i] = solution.xi;
                } else {
                    self.pid.reset_axis(i);
                    xi_law[i] = 0.0;
                }
            }
            // The guard acts on the feedback, the part that can run away through the contact;
            // the feed-forward is open loop, bounded by the table (crate::feedforward).
            if self.guard.limit(&mut xi_law) {
                flags.set(Flags::RUNAWAY_HOLD);
            }
            for i in 0..6 {
                if self.config.limiter.enabled[i] {
                    xi_law[i] += ff.sent[i];
                }
            }
        }
        if self.guard.hold().is_some() {
            flags.set(Flags::RUNAWAY_HOLD);
        }
        let limited = self.limiter.apply(&xi_law, now, h);
        if follow {
            for (i, solution) in law.iter().enumerate() {
                if self.config.limiter.enabled[i] {
                    let bound = self.config.limiter.max_abs[i];
                    let applied_feedback = limited.xi[i] - ff.sent[i];
                    self.pid
                        .commit(i, solution, applied_feedback, h, bound, false);
                }
            }
        }
        limited
    }
}
