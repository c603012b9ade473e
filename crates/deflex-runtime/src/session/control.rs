//! The control thread: waits for the robot and the sensor, checks the robot against the model,
//! then runs the law once per control period on the latest messages, answers through the
//! correction command and publishes one telemetry sample per cycle, until a stop (or the robot's
//! silence) has ramped the correction out.

use super::summary::{RunSummary, SessionEnd, SessionError};
use super::{RuntimeOptions, Shared};
use crate::clock::Clock;
use crate::messages::{CorrectionCommand, JointSample, LATE_UNKNOWN, WrenchAccumulation};
use crate::rt::try_realtime;
use crate::send_shaper::LinkDirective;
use crate::stats::CycleStats;
use bytemuck::Zeroable;
use deflex_control::RecordCycle;
use deflex_control::{Controller, CycleInput, CycleOutput, JointCorrectionMap, SafeAction};
use deflex_telemetry::{CycleSample, Publisher};
use deflex_telemetry::{FaultKind, Flags, Phase};
use std::sync::atomic::Ordering;
use std::time::{Duration, Instant};

/// How the wait for the equipment ended.
enum Startup {
    /// Robot and sensor heard, the robot fits the model.
    Ready,
    /// A stop was requested first.
    StoppedBeforeStart,
    /// Nothing came, or the robot does not fit the model.
    Failed(SessionError),
}

/// Checks the first telegram against the model: joint count, then joint limits (plus the
/// safety margin). The error names the joint, its value and the limit.
fn check_robot_matches_model(ctrl: &Controller, joints: &JointSample) -> Result<(), SessionError> {
    let robot = ctrl.robot();
    let n = robot.joint_count();
    let reported = joints.joint_count as usize;
    if reported != n {
        return Err(SessionError::JointCountMismatch {
            reported,
            model_joints: n,
            model: robot.name.clone(),
        });
    }
    let margin = ctrl.config().safety.joint_limit_margin_rad;
    for (i, joint) in robot.joints.iter().enumerate() {
        let qi = joints.q_rad[i];
        if let Some([lo, hi]) = joint.limits
            && (qi < lo - margin || qi > hi + margin)
        {
            return Err(SessionError::JointOutOfLimits {
                joint: i + 1,
                value_rad: qi,
                limits_rad: [lo, hi],
                margin_rad: margin,
            });
        }
    }
    check_model_pose(ctrl, joints)
}

/// Checks the TCP pose the first telegram reports, when its protocol carries one, against the
/// model's forward kinematics at its joints ([`deflex_control::model_check`]): a difference
/// above the tolerance refuses the run before the first correction.
fn check_model_pose(ctrl: &Controller, joints: &JointSample) -> Result<(), SessionError> {
    let config = ctrl.config().model_check;
    let Some(reported) = joints.tcp_pose() else {
        return Ok(());
    };
    if !config.enabled {
        return Ok(());
    }
    let robot = ctrl.robot();
    let mut data = deflex_model::Data::new();
    let Ok(mismatch) = deflex_control::tcp_pose_mismatch(
        robot,
        &mut data,
        &joints.q()[..robot.joint_count()],
        &reported,
    ) else {
        return Ok(());
    };
    if mismatch.exceeds(&config) {
        let tool = robot.tool.translation.vector;
        return Err(SessionError::ModelMismatch {
            mismatch,
            position_tolerance_m: config.position_tolerance_m,
            orientation_tolerance_rad: config.orientation_tolerance_rad,
            model: robot.name.clone(),
            tool_m: [tool.x, tool.y, tool.z],
        });
    }
    Ok(())
}

/// Waits (in wall time: this is about equipment being there) for the first robot state and
/// sensor sample, then checks the robot against the model.
fn wait_for_equipment(ctrl: &Controller, shared: &Shared, options: &RuntimeOptions) -> Startup {
    let waiting = Instant::now();
    let startup_timeout = if options.startup_timeout_s.is_finite() {
        options.startup_timeout_s.max(0.0)
    } else {
        0.0
    };
    loop {
        let (joints, joints_version) = shared.joints.read();
        let robot_heard = joints_version > 0;
        let sensor_heard = shared.wrench.version() > 0;
        if robot_heard && sensor_heard {
            return match check_robot_matches_model(ctrl, &joints) {
                Ok(()) => Startup::Ready,
                Err(e) => Startup::Failed(e),
            };
        }
        if shared.stop.load(Ordering::Acquire) {
            return Startup::StoppedBeforeStart;
        }
        let waited_s = waiting.elapsed().as_secs_f64();
        if waited_s > startup_timeout {
            return Startup::Failed(SessionError::NoData {
                waited_s,
                robot_heard,
                sensor_heard,
            });
        }
        std::thread::sleep(Duration::from_millis(1));
    }
}

/// What the robot-link thread must do given the controller's latched fault: faults of the
/// robot link ramp (or hold) in robot cycles, the rest follow the controller.
fn directive_for(ctrl: &Controller) -> LinkDirective {
    match ctrl.fault() {
        Some(f) if f.kind == FaultKind::RobotLinkLost => match ctrl.config().safety.safe_action {
            SafeAction::Zero => LinkDirective::RampOut,
            SafeAction::Hold => LinkDirective::Hold,
        },
        _ => LinkDirective::Follow,
    }
}

/// The running loop's state: everything a cycle reads and updates besides the controller.
struct Cycles {
    stats: CycleStats,
    cycles: u64,
    max_force: f64,
    max_xi: f64,
    /// The wrench accumulation at the previous cycle (the period's samples are the difference).
    previous_wrench: WrenchAccumulation,
    /// The sample being filled (reused: no allocation).
    sample: CycleSample,
    publisher: Publisher<CycleSample>,
    joint_answers: bool,
    /// Stop on the robot's silence longer than this (s).
    idle_exit_after: Option<f64>,
    stopping: bool,
    idle_exit: bool,
}

impl Cycles {
    /// One control cycle at `now` (after the clock's wake-up at `started`): the law on the
    /// latest messages, the command, the telemetry sample. Allocation-free.
    fn run_one<C: Clock>(&mut self, ctrl: &mut Controller, shared: &Shared, clock: &C) {
        let started = Instant::now();
        let now = clock.now();
        let (joints, _) = shared.joints.read();
        let (accumulation, _) = shared.wrench.read();
        let (wrench, fresh) = accumulation.mean_since(&self.previous_wrench);
        self.previous_wrench = accumulation;
        let q = joints.q();
        let input = CycleInput {
            now_s: now,
            q_rad: q,
            q_age_s: now - joints.time_s,
            wrench_sensor: wrench,
            wrench_age_s: now - accumulation.time_s,
            wrench_fresh: fresh,
            sensor_status: accumulation.status_word(),
            tcp_pose: joints.tcp_pose(),
        };
        let out = ctrl.cycle_input(&input);
        shared.command.write(&CorrectionCommand {
            xi: out.xi.into(),
            tcp_rotation: ctrl.tcp_rotation_in_base(),
            joint_map: if self.joint_answers {
                ctrl.joint_correction_map()
            } else {
                JointCorrectionMap::zeros()
            },
            directive: u64::from(directive_for(ctrl).to_u8()),
        });
        let elapsed = started.elapsed();
        self.stats.record(elapsed);
        self.cycles += 1;
        self.track_maxima(&out);
        let n = ctrl.robot().joint_count();
        self.sample
            .record_cycle(ctrl, &q[..n.min(q.len())], &wrench, &out);
        self.sample.cycle = self.cycles;
        self.sample.cycle_time_s = elapsed.as_secs_f64();
        self.sample.robot_telegrams = shared.telegrams.load(Ordering::Relaxed);
        self.sample.robot_late = shared.robot_late().unwrap_or(LATE_UNKNOWN);
        self.sample.late_answers = shared.late_answers.load(Ordering::Relaxed);
        self.sample.sensor_samples = shared.samples.load(Ordering::Relaxed);
        self.publisher.publish(&self.sample);
        self.handle_stop(ctrl, shared, now, input.q_age_s);
    }

    /// Largest tared force and position correction so far.
    fn track_maxima(&mut self, out: &CycleOutput) {
        let f = &out.wrench_tcp;
        let force = (f[0] * f[0] + f[1] * f[1] + f[2] * f[2]).sqrt();
        if !out.flags.has(Flags::TARING) {
            // Before and during the tare the reading still carries the sensor's bias.
            self.max_force = self.max_force.max(force);
        }
        let xi_p = (out.xi[0].powi(2) + out.xi[1].powi(2) + out.xi[2].powi(2)).sqrt();
        self.max_xi = self.max_xi.max(xi_p);
    }

    /// The robot's silence past the idle exit, or a stop request, starts the ramp-out.
    fn handle_stop(&mut self, ctrl: &mut Controller, shared: &Shared, now: f64, q_age_s: f64) {
        if let Some(idle) = self.idle_exit_after
            && q_age_s > idle
            && !shared.stop.load(Ordering::Acquire)
        {
            self.idle_exit = true;
            shared.stop.store(true, Ordering::Release);
        }
        if shared.stop.load(Ordering::Acquire) && !self.stopping {
            ctrl.stop(now);
            self.stopping = true;
        }
    }

    /// True once a stop has ramped the correction out (or a fault holds it settled).
    fn finished(&self, ctrl: &Controller) -> bool {
        let settled = matches!(ctrl.phase(), Phase::Stopped | Phase::Idle)
            || (ctrl.phase() == Phase::Faulted && ctrl.is_settled());
        self.stopping && settled
    }
}

/// Runs the cycles, paced by `clock` every control period, until [`Cycles::finished`].
fn run_cycles<C: Clock>(ctrl: &mut Controller, cycles: &mut Cycles, shared: &Shared, clock: &C) {
    let period = ctrl.config().period_s;
    ctrl.start(clock.now());
    let mut next = clock.now();
    loop {
        next += period;
        let now = clock.now();
        if now > next + period {
            // Overran by more than a period: count it and re-synchronise.
            cycles.stats.record_miss();
            next = now;
        }
        clock.sleep_until(next);
        cycles.run_one(ctrl, shared, clock);
        if cycles.finished(ctrl) {
            break;
        }
    }
}

/// How the session ended, the fault to report and the final silence: a `robot_link_lost`
/// latched by the robot's final silence (no telegram after it) is the end of its program, not
/// a fault (returned third, so that the summary can name what the live line showed).
fn session_end(
    ctrl: &Controller,
    shared: &Shared,
    startup: &Startup,
    idle_exit: bool,
) -> (
    SessionEnd,
    Option<deflex_control::Fault>,
    Option<deflex_control::Fault>,
) {
    let fault = ctrl.fault();
    match startup {
        Startup::Failed(_) => (SessionEnd::Failed, fault, None),
        Startup::StoppedBeforeStart => (SessionEnd::StoppedBeforeStart, fault, None),
        Startup::Ready if idle_exit => {
            let last = f64::from_bits(shared.last_telegram_s.load(Ordering::Acquire));
            let silence =
                fault.is_some_and(|f| f.kind == FaultKind::RobotLinkLost && last <= f.time_s);
            if silence {
                (SessionEnd::RobotFinished, None, fault)
            } else {
                (SessionEnd::RobotFinished, fault, None)
            }
        }
        Startup::Ready => (SessionEnd::Stopped, fault, None),
    }
}

/// The control thread's body.
pub(super) fn control_loop<C: Clock>(
    mut ctrl: Controller,
    shared: &Shared,
    clock: &C,
    publisher: Publisher<CycleSample>,
    options: RuntimeOptions,
    joint_answers: bool,
) -> RunSummary {
    let mut warnings = if options.realtime {
        try_realtime(70, options.lock_memory).warnings()
    } else {
        Vec::new()
    };
    let period = ctrl.config().period_s;
    let mut cycles = Cycles {
        stats: CycleStats::new(Duration::from_secs_f64(period.clamp(1e-6, 10.0))),
        cycles: 0,
        max_force: 0.0,
        max_xi: 0.0,
        previous_wrench: WrenchAccumulation::zeroed(),
        sample: CycleSample::default(),
        publisher,
        joint_answers,
        idle_exit_after: options.idle_exit_s,
        stopping: false,
        idle_exit: false,
    };
    let startup = wait_for_equipment(&ctrl, shared, &options);
    if matches!(startup, Startup::Ready) {
        run_cycles(&mut ctrl, &mut cycles, shared, clock);
    }
    clock.release();
    // The stream ends here: sinks see it closed once they have read it.
    cycles.publisher.close();
    warnings.dedup();
    let (end, fault, final_silence) = session_end(&ctrl, shared, &startup, cycles.idle_exit);
    RunSummary {
        control: cycles.stats.summary(),
        cycles: cycles.cycles,
        end,
        fault,
        final_silence,
        runaway_events: ctrl.runaway_events(),
        first_runaway: ctrl.first_runaway(),
        pose_mismatch_max: ctrl.pose_mismatch_max(),
        max_force_n: cycles.max_force,
        max_xi_m: cycles.max_xi,
        warnings,
        error: match startup {
            Startup::Failed(e) => Some(e),
            _ => None,
        },
        ..RunSummary::zeroed(ctrl.phase())
    }
}
