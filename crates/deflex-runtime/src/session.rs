//! The threads of `deflex run` (Fig. 16 of the paper, with the CompactRIO replaced by a PC):
//!
//! * **robot-link thread** (`robot`): blocks on the robot link; for every state telegram it
//!   publishes a [`JointSample`](crate::messages::JointSample) and answers at once with the
//!   latest [`CorrectionCommand`](crate::messages::CorrectionCommand) (ξ of eq. 7), passed
//!   through the [`SendShaper`](crate::send_shaper::SendShaper) so the robot never sees a step
//!   larger than the rate limit times its cycle, whatever the gap since the previous answer — no
//!   locks, no allocation, so a KUKA RSI telegram every 4 ms is answered within its cycle. Links
//!   that answer in joint space (RSI `AK`) get the correction mapped through the model's
//!   Jacobian ([`Controller::joint_correction_map`]); links whose frame follows the tool (ABB
//!   EGM) get the TCP orientation. The reply latency (receipt → reply sent) is recorded in a
//!   histogram;
//! * **sensor thread** (`sensor`): receives force/torque samples and publishes a running sum
//!   ([`WrenchAccumulation`](crate::messages::WrenchAccumulation)), so the control thread
//!   averages every sample of its period;
//! * **control thread** (`control`): paced by an injectable [`Clock`] at the control rate
//!   (100 Hz), runs [`Controller::cycle_input`] (eq. 5–7, 15, 17), publishes the correction
//!   command and one telemetry [`CycleSample`] ([`crate::telemetry`]: the CSV log, the live
//!   status and any other sink read it), and measures its cycle time and deadline misses.
//!
//! Before the correction starts, the first telegram's joint count must equal the model's and
//! every joint must lie within the model's limits (plus the margin), and where the protocol
//! reports the controller's TCP pose (KUKA RSI `RIst`, ABB EGM) it must lie within the
//! tolerance of the model's forward kinematics at the same joints
//! ([`deflex_control::model_check`]): otherwise the run is refused with a [`SessionError`]
//! naming the joint, the value and the limit (or the pose difference and its likely causes).
//! During the session the controller checks the reported pose every cycle
//! (`model_mismatch`).
//!
//! Failure: if the control thread panics, a guard marks it failed on the way out; the
//! robot-link thread then ramps what it last sent to zero in robot cycles (at most
//! [`DRAIN_S`]) and stops, and [`Runtime::join`] reports the panic as an error — the process
//! ends within a second instead of hanging with links that keep answering. A stop request
//! (operator, signal) ramps the correction out, also from a held fault, before the threads end.
//!
//! The same threads run against hardware with a [`crate::WallClock`] and against the digital
//! twin in simulated time with a driven [`crate::SimClock`] (`deflex_sim::twin::sim_time`).
//!
//! Both loop threads try SCHED_FIFO (and the process mlockall) and carry on with a warning when
//! not permitted.

mod control;
mod robot;
mod sensor;
mod shared;
mod summary;

pub use summary::{LiveStatus, RunSummary, SessionEnd, SessionError, SessionThread};

use crate::clock::Clock;
use crate::send_shaper::SendShaperConfig;
use crate::telemetry::Telemetry;
use deflex_control::Controller;
use deflex_io::{ForceSensorLink, RobotLink};
use deflex_telemetry::{Broadcast, CycleSample, SessionInfo};
use deflex_telemetry::{Flags, Phase};
use shared::Shared;
use std::sync::Arc;
use std::sync::atomic::Ordering;
use std::thread::JoinHandle;

/// Longest time the robot-link thread keeps answering after the control thread ended, to ramp
/// what it last sent to zero (s). It stops at once when the robot has been silent for longer
/// than the idle exit ([`RuntimeOptions::idle_exit_s`]): its program has ended, nobody listens.
pub const DRAIN_S: f64 = 0.8;

/// Options of the runtime.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct RuntimeOptions {
    /// Robot interpolation cycle (s): reply deadline of the robot link and the unit of the
    /// per-answer rate limit.
    pub robot_cycle_s: f64,
    /// Try SCHED_FIFO for the loop threads.
    pub realtime: bool,
    /// Try mlockall.
    pub lock_memory: bool,
    /// Give up when no robot state and sensor sample arrived within this time (s).
    pub startup_timeout_s: f64,
    /// Stop on its own when the robot has been silent this long after it started (s).
    pub idle_exit_s: Option<f64>,
}

impl Default for RuntimeOptions {
    fn default() -> Self {
        RuntimeOptions {
            robot_cycle_s: 0.004,
            realtime: true,
            lock_memory: false,
            startup_timeout_s: 30.0,
            idle_exit_s: None,
        }
    }
}

/// Handle of a running controller.
pub struct Runtime {
    shared: Arc<Shared>,
    telemetry: Arc<Broadcast<CycleSample>>,
    info: Arc<SessionInfo>,
    control: JoinHandle<RunSummary>,
    robot: JoinHandle<robot::RobotReport>,
    sensor: JoinHandle<()>,
}

/// Marks a thread's end in the shared state, also when it unwinds from a panic: a failed
/// control thread lets the links ramp out and stop; a failed link thread stops the session.
struct ExitGuard<'a> {
    shared: &'a Shared,
    control: bool,
    release: Option<&'a dyn Fn()>,
}

impl Drop for ExitGuard<'_> {
    fn drop(&mut self) {
        let panicking = std::thread::panicking();
        if self.control {
            if panicking {
                self.shared.control_failed.store(true, Ordering::Release);
            }
            if let Some(release) = self.release {
                release();
            }
            self.shared.done.store(true, Ordering::Release);
        } else if panicking {
            self.shared.link_failed.store(true, Ordering::Release);
            self.shared.stop.store(true, Ordering::Release);
        }
    }
}

fn spawn_named<T: Send + 'static>(
    name: &str,
    f: impl FnOnce() -> T + Send + 'static,
) -> std::io::Result<JoinHandle<T>> {
    std::thread::Builder::new().name(name.into()).spawn(f)
}

/// Starts the three threads. The control thread publishes one sample per cycle into
/// `telemetry` (subscribe sinks to it before calling this to see every cycle).
pub fn spawn<C: Clock + Clone + 'static>(
    controller: Controller,
    robot_link: Box<dyn RobotLink + Send>,
    sensor_link: Box<dyn ForceSensorLink + Send>,
    clock: C,
    telemetry: Telemetry,
    options: RuntimeOptions,
) -> std::io::Result<Runtime> {
    let shared = Arc::new(Shared::new());
    let joint_answers = robot_link.answers_in_joint_space();
    let limits = controller.config().limiter;
    let shaper = SendShaperConfig::new(
        limits.max_rate,
        limits.max_abs,
        options.robot_cycle_s,
        limits.ramp_out_s,
    );
    let (publisher, ring, info) = telemetry.into_parts();
    let robot = {
        let (shared, clock) = (shared.clone(), clock.clone());
        spawn_named("deflex-robot-link", move || {
            robot::robot_loop(robot_link, &shared, &clock, shaper, options)
        })?
    };
    let sensor = {
        let (shared, clock) = (shared.clone(), clock.clone());
        spawn_named("deflex-sensor", move || {
            sensor::sensor_loop(sensor_link, &shared, &clock)
        })?
    };
    let control = {
        let shared = shared.clone();
        spawn_named("deflex-control", move || {
            let release = || clock.release();
            let _guard = ExitGuard {
                shared: &shared,
                control: true,
                release: Some(&release),
            };
            control::control_loop(
                controller,
                &shared,
                &clock,
                publisher,
                options,
                joint_answers,
            )
        })?
    };
    Ok(Runtime {
        shared,
        telemetry: ring,
        info,
        control,
        robot,
        sensor,
    })
}

fn panic_message(payload: &(dyn std::any::Any + Send)) -> String {
    payload
        .downcast_ref::<&str>()
        .map(|s| s.to_string())
        .or_else(|| payload.downcast_ref::<String>().cloned())
        .unwrap_or_else(|| "no message".into())
}

impl Runtime {
    /// The telemetry stream: subscribe any number of sinks, at any time.
    pub fn telemetry(&self) -> &Arc<Broadcast<CycleSample>> {
        &self.telemetry
    }

    /// What does not change during the session.
    pub fn session_info(&self) -> &Arc<SessionInfo> {
        &self.info
    }

    /// The latest live status (from the latest telemetry sample and the link counters).
    pub fn status(&self) -> LiveStatus {
        let s = self.telemetry.latest().unwrap_or_default();
        let xi = &s.correction;
        LiveStatus {
            time_s: s.time_s,
            phase: if s.cycle == 0 { Phase::Idle } else { s.phase() },
            flags: Flags(s.flags),
            force_n: s.force_norm_n(),
            xi_m: [xi[0], xi[1], xi[2]],
            xi_rot_rad: (xi[3].powi(2) + xi[4].powi(2) + xi[5].powi(2)).sqrt(),
            cycles: s.cycle,
            telegrams: self.shared.telegrams.load(Ordering::Relaxed),
            samples: self.shared.samples.load(Ordering::Relaxed),
            robot_late: self.shared.robot_late(),
            foreign: self.shared.robot_foreign.load(Ordering::Relaxed),
        }
    }

    /// Asks for a stop: the correction ramps out, then the threads end.
    pub fn request_stop(&self) {
        self.shared.stop.store(true, Ordering::Release);
    }

    /// True once the control thread has ended (normally or not).
    pub fn is_finished(&self) -> bool {
        self.shared.done.load(Ordering::Acquire) || self.control.is_finished()
    }

    /// Waits for the threads and gathers the summary.
    pub fn join(self) -> RunSummary {
        let mut summary = match self.control.join() {
            Ok(summary) => summary,
            Err(payload) => RunSummary {
                error: Some(SessionError::ThreadPanicked {
                    thread: SessionThread::Control,
                    message: panic_message(payload.as_ref()),
                }),
                ..RunSummary::zeroed(Phase::Faulted)
            },
        };
        self.shared.done.store(true, Ordering::Release);
        match self.robot.join() {
            Ok(report) => {
                summary.reply_latency = report.latency.summary();
                summary.warnings.extend(report.warnings);
                summary.max_step_sent = report.max_step;
                summary.robot_link = report.counters;
            }
            Err(payload) => {
                summary.error.get_or_insert(SessionError::ThreadPanicked {
                    thread: SessionThread::RobotLink,
                    message: panic_message(payload.as_ref()),
                });
            }
        }
        if let Err(payload) = self.sensor.join() {
            summary.error.get_or_insert(SessionError::ThreadPanicked {
                thread: SessionThread::Sensor,
                message: panic_message(payload.as_ref()),
            });
        }
        if summary.error.is_some() {
            summary.end = SessionEnd::Failed;
        }
        self.shared.fill_counters(&mut summary);
        if summary.error.is_none() && (summary.robot_starved || summary.robot_link.robot_starved())
        {
            summary.robot_starved = true;
            summary.end = SessionEnd::RobotStarved;
        }
        summary.warnings.sort();
        summary.warnings.dedup();
        summary
    }
}
