//! The threads of `deflex run` (Fig. 16 of the paper, with the CompactRIO replaced by a PC):
//!
//! * **robot-link thread**: blocks on the robot link; for every state telegram it publishes q
//!   and answers at once with the latest ξ (eq. 7) read from a seqlock slot, passed through the
//!   [`SendShaper`] so the robot never sees a step larger than the rate limit times its cycle,
//!   whatever the gap since the previous answer — no locks, no allocation, so a KUKA RSI telegram
//!   every 4 ms is answered within its cycle. Links that answer in joint space (RSI `AK`) get
//!   the correction mapped through the model's Jacobian ([`Controller::joint_correction_map`]);
//!   links whose frame follows the tool (ABB EGM) get the TCP orientation. The reply latency
//!   (receipt → reply sent) is recorded in a histogram;
//! * **sensor thread**: receives force/torque samples and publishes a running sum, so the
//!   control thread averages every sample of its period;
//! * **control thread**: paced by an injectable [`Clock`] at the control rate (100 Hz), runs
//!   [`Controller::cycle_input`] (eq. 5–7, 15, 17), publishes ξ, pushes a log record into the
//!   lock-free ring and a live status into a slot, and measures its cycle time and deadline
//!   misses.
//!
//! Before the correction starts, the first telegram's joint count must equal the model's and
//! every joint must lie within the model's limits (plus the margin): otherwise the run is
//! refused with an error naming the joint, the value and the limit.
//!
//! Failure: if the control thread panics, a guard marks it failed on the way out; the
//! robot-link thread then ramps what it last sent to zero in robot cycles (at most
//! [`DRAIN_S`]) and stops, and [`Runtime::join`] reports the panic as an error — the process
//! ends within a second instead of hanging with links that keep answering. A stop request
//! (operator, signal) ramps the correction out, also from a held fault, before the threads end.
//!
//! The same threads run against hardware with a [`crate::WallClock`] and against the digital
//! twin in simulated time with a driven [`crate::SimClock`] (see `run_runtime_in_sim_time` in
//! deflex-cli).
//!
//! Both loop threads try SCHED_FIFO (and the process mlockall) and carry on with a warning when
//! not permitted.

mod summary;

pub use summary::{LiveStatus, RunSummary, SessionEnd};

use crate::clock::Clock;
use crate::controller::{Controller, CycleInput, Phase};
use crate::log::{LogRecord, LogSink};
use crate::rt::try_realtime;
use crate::safety::{FaultKind, Flags, SafeAction};
use crate::send_shaper::{LinkDirective, SendShaper, SendShaperConfig};
use crate::slot::SeqSlot;
use crate::stats::CycleStats;
use deflex_io::{Correction, ForceSensorLink, RobotLink};
use deflex_model::MAX_JOINTS;
use std::net::SocketAddr;
use std::sync::atomic::{AtomicBool, AtomicU8, AtomicU64, Ordering};
use std::sync::{Arc, Mutex};
use std::thread::JoinHandle;
use std::time::{Duration, Instant};

const _: () = assert!(deflex_io::MAX_JOINTS == MAX_JOINTS);

/// Longest time the robot-link thread keeps answering after the control thread ended, to ramp
/// what it last sent to zero (s).
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

// Joint slot layout: q [0..MAX_JOINTS], time, joint count, robot late counter (−1: none).
const Q_TIME: usize = MAX_JOINTS;
const Q_COUNT: usize = MAX_JOINTS + 1;
const Q_LATE: usize = MAX_JOINTS + 2;
const Q_LEN: usize = MAX_JOINTS + 3;
// Wrench slot layout: running sum [0..6], count [6], last [7..13], time [13], status [14].
const W_LEN: usize = 15;
const STATUS_LEN: usize = 12;
const MAP_LEN: usize = MAX_JOINTS * 6;
const NO_LATE: u64 = u64::MAX;

struct Shared {
    q: SeqSlot<Q_LEN>,
    wrench: SeqSlot<W_LEN>,
    xi: SeqSlot<6>,
    tcp_rotation: SeqSlot<9>,
    joint_map: SeqSlot<MAP_LEN>,
    directive: AtomicU8,
    status: SeqSlot<STATUS_LEN>,
    stop: AtomicBool,
    done: AtomicBool,
    control_failed: AtomicBool,
    link_failed: AtomicBool,
    telegrams: AtomicU64,
    last_telegram_s: AtomicU64,
    robot_timeouts: AtomicU64,
    robot_bad_packets: AtomicU64,
    robot_errors: AtomicU64,
    robot_foreign: AtomicU64,
    last_foreign: Mutex<Option<SocketAddr>>,
    first_late: AtomicU64,
    last_late: AtomicU64,
    samples: AtomicU64,
    sample_gaps: AtomicU64,
    sensor_faults: AtomicU64,
    sensor_errors: AtomicU64,
    sensor_foreign: AtomicU64,
}

impl Shared {
    fn new() -> Self {
        Shared {
            q: SeqSlot::new(),
            wrench: SeqSlot::new(),
            xi: SeqSlot::new(),
            tcp_rotation: SeqSlot::new(),
            joint_map: SeqSlot::new(),
            directive: AtomicU8::new(LinkDirective::Follow.to_u8()),
            status: SeqSlot::new(),
            stop: AtomicBool::new(false),
            done: AtomicBool::new(false),
            control_failed: AtomicBool::new(false),
            link_failed: AtomicBool::new(false),
            telegrams: AtomicU64::new(0),
            last_telegram_s: AtomicU64::new(f64::NEG_INFINITY.to_bits()),
            robot_timeouts: AtomicU64::new(0),
            robot_bad_packets: AtomicU64::new(0),
            robot_errors: AtomicU64::new(0),
            robot_foreign: AtomicU64::new(0),
            last_foreign: Mutex::new(None),
            first_late: AtomicU64::new(NO_LATE),
            last_late: AtomicU64::new(NO_LATE),
            samples: AtomicU64::new(0),
            sample_gaps: AtomicU64::new(0),
            sensor_faults: AtomicU64::new(0),
            sensor_errors: AtomicU64::new(0),
            sensor_foreign: AtomicU64::new(0),
        }
    }

    fn robot_late(&self) -> Option<u64> {
        let (first, last) = (
            self.first_late.load(Ordering::Relaxed),
            self.last_late.load(Ordering::Relaxed),
        );
        (first != NO_LATE && last != NO_LATE).then(|| last.saturating_sub(first))
    }
}

const PHASES: [Phase; 6] = [
    Phase::Idle,
    Phase::Taring,
    Phase::Running,
    Phase::Stopping,
    Phase::Stopped,
    Phase::Faulted,
];

/// What the robot-link thread reports at its end.
struct RobotReport {
    latency: CycleStats,
    warnings: Vec<String>,
    max_step: [f64; 6],
}

/// Handle of a running controller.
pub struct Runtime {
    shared: Arc<Shared>,
    control: JoinHandle<RunSummary>,
    robot: JoinHandle<RobotReport>,
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

/// Starts the three threads. `log` receives one record per control cycle.
pub fn spawn<C: Clock + Clone + 'static>(
    controller: Controller,
    robot_link: Box<dyn RobotLink + Send>,
    sensor_link: Box<dyn ForceSensorLink + Send>,
    clock: C,
    log: Option<LogSink>,
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
    let robot = {
        let (shared, clock) = (shared.clone(), clock.clone());
        spawn_named("deflex-robot-link", move || {
            robot_loop(robot_link, &shared, &clock, shaper, options)
        })?
    };
    let sensor = {
        let (shared, clock) = (shared.clone(), clock.clone());
        spawn_named("deflex-sensor", move || {
            sensor_loop(sensor_link, &shared, &clock)
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
            control_loop(controller, &shared, &clock, log, options, joint_answers)
        })?
    };
    Ok(Runtime {
        shared,
        control,
        robot,
        sensor,
    })
}

fn robot_loop<C: Clock>(
    mut link: Box<dyn RobotLink + Send>,
    shared: &Shared,
    clock: &C,
    shaper: SendShaperConfig,
    options: RuntimeOptions,
) -> RobotReport {
    let _guard = ExitGuard {
        shared,
        control: false,
        release: None,
    };
    let warnings = if options.realtime {
        try_realtime(80, false).warnings()
    } else {
        Vec::new()
    };
    let deadline = Duration::from_secs_f64(options.robot_cycle_s.clamp(1e-6, 10.0));
    let mut latency = CycleStats::new(deadline);
    let mut shaper = SendShaper::new(shaper);
    let mut max_step = [0.0f64; 6];
    let mut q = [0.0; Q_LEN];
    let mut dq = [0.0; MAX_JOINTS];
    let mut ended_at: Option<Instant> = None;
    loop {
        if shared.done.load(Ordering::Acquire) {
            // The control thread has ended: keep answering until what was sent is zero
            // (bounded), ramping it out in robot cycles if the control thread failed.
            let since = *ended_at.get_or_insert_with(Instant::now);
            if shaper.is_zero() || since.elapsed().as_secs_f64() > DRAIN_S {
                break;
            }
        }
        match link.receive(Duration::from_millis(10)) {
            Ok(Some(state)) => {
                let received = Instant::now();
                let n = state.joint_count.min(MAX_JOINTS);
                q[..MAX_JOINTS].copy_from_slice(&state.q_rad);
                q[Q_TIME] = clock.now();
                q[Q_COUNT] = n as f64;
                q[Q_LATE] = state.late_answers.map_or(-1.0, f64::from);
                shared.q.write(&q);
                shared
                    .last_telegram_s
                    .store(q[Q_TIME].to_bits(), Ordering::Release);
                if let Some(late) = state.late_answers {
                    let late = u64::from(late);
                    let _ = shared.first_late.compare_exchange(
                        NO_LATE,
                        late,
                        Ordering::Relaxed,
                        Ordering::Relaxed,
                    );
                    shared.last_late.store(late, Ordering::Relaxed);
                }
                let directive = if shared.control_failed.load(Ordering::Acquire) {
                    LinkDirective::RampOut
                } else {
                    LinkDirective::from_u8(shared.directive.load(Ordering::Acquire))
                };
                let (target, _) = shared.xi.read();
                let before = shaper.last();
                let sent = shaper.next(&target, directive);
                let result = if link.answers_in_joint_space() {
                    let (map, _) = shared.joint_map.read();
                    for (i, d) in dq.iter_mut().enumerate() {
                        *d = (0..6).map(|j| map[i * 6 + j] * sent[j]).sum();
                    }
                    link.send_joint_correction(&dq[..n.max(1)])
                } else {
                    let (r, _) = shared.tcp_rotation.read();
                    link.set_tcp_rotation(&[
                        [r[0], r[1], r[2]],
                        [r[3], r[4], r[5]],
                        [r[6], r[7], r[8]],
                    ]);
                    link.send_correction(&Correction::from_array(sent))
                };
                match result {
                    Ok(()) => {
                        latency.record(received.elapsed());
                        shared.telegrams.fetch_add(1, Ordering::Relaxed);
                        for i in 0..6 {
                            max_step[i] = max_step[i].max((sent[i] - before[i]).abs());
                        }
                    }
                    Err(_) => {
                        shared.robot_errors.fetch_add(1, Ordering::Relaxed);
                    }
                }
            }
            Ok(None) => {
                shared.robot_timeouts.fetch_add(1, Ordering::Relaxed);
            }
            Err(deflex_io::LinkError::ForeignSender { from, .. }) => {
                shared.robot_foreign.fetch_add(1, Ordering::Relaxed);
                if let Ok(mut last) = shared.last_foreign.lock() {
                    *last = Some(from);
                }
            }
            Err(e) if e.is_bad_packet() => {
                shared.robot_bad_packets.fetch_add(1, Ordering::Relaxed);
            }
            Err(_) => {
                shared.robot_errors.fetch_add(1, Ordering::Relaxed);
                std::thread::sleep(Duration::from_millis(1));
            }
        }
    }
    RobotReport {
        latency,
        warnings,
        max_step,
    }
}

fn sensor_loop<C: Clock>(mut link: Box<dyn ForceSensorLink + Send>, shared: &Shared, clock: &C) {
    let _guard = ExitGuard {
        shared,
        control: false,
        release: None,
    };
    let mut slot = [0.0; W_LEN];
    let mut started = link.start().is_ok();
    let mut last_start = Instant::now();
    while !shared.done.load(Ordering::Acquire) {
        match link.receive(Duration::from_millis(10)) {
            Ok(Some(sample)) => {
                for (sum, w) in slot[..6].iter_mut().zip(sample.wrench) {
                    *sum += w;
                }
                slot[7..13].copy_from_slice(&sample.wrench);
                slot[6] += 1.0;
                slot[13] = clock.now();
                slot[14] = f64::from(sample.status);
                shared.wrench.write(&slot);
                shared.samples.fetch_add(1, Ordering::Relaxed);
                shared
                    .sample_gaps
                    .fetch_add(u64::from(sample.gap), Ordering::Relaxed);
                if sample.is_fault() {
                    shared.sensor_faults.fetch_add(1, Ordering::Relaxed);
                }
            }
            Ok(None) => {
                // Silent sensor: ask again every second (the control thread decides whether
                // this is a fault).
                if !started || last_start.elapsed() > Duration::from_secs(1) {
                    started = link.start().is_ok();
                    last_start = Instant::now();
                }
            }
            Err(e) if e.is_foreign() => {
                shared.sensor_foreign.fetch_add(1, Ordering::Relaxed);
            }
            Err(_) => {
                shared.sensor_errors.fetch_add(1, Ordering::Relaxed);
            }
        }
    }
    let _ = link.stop();
}

/// Checks the first telegram against the model: joint count, then joint limits (plus the
/// safety margin). The error names the joint, its value and the limit.
fn check_robot_matches_model(ctrl: &Controller, q_slot: &[f64; Q_LEN]) -> Result<(), String> {
    let robot = ctrl.robot();
    let n = robot.joint_count();
    let reported = q_slot[Q_COUNT] as usize;
    if reported != n {
        return Err(format!(
            "joint_count_mismatch: the robot's telegrams carry {reported} joint values but the \
             model \"{}\" has {n} joints; refusing to run (use the model of this robot)",
            robot.name
        ));
    }
    let margin = ctrl.config().safety.joint_limit_margin_rad;
    for (i, joint) in robot.joints.iter().enumerate() {
        let qi = q_slot[i];
        if let Some([lo, hi]) = joint.limits
            && (qi < lo - margin || qi > hi + margin)
        {
            return Err(format!(
                "joint_out_of_limits: joint {} reported at {:.4} rad ({:.2}°), outside the \
                 model's limits [{:.4}, {:.4}] rad ([{:.2}°, {:.2}°]) plus the {:.3} rad margin; \
                 refusing to run (wrong model, or the robot is not where its program starts)",
                i + 1,
                qi,
                qi.to_degrees(),
                lo,
                hi,
                lo.to_degrees(),
                hi.to_degrees(),
                margin
            ));
        }
    }
    Ok(())
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

fn control_loop<C: Clock>(
    mut ctrl: Controller,
    shared: &Shared,
    clock: &C,
    mut log: Option<LogSink>,
    options: RuntimeOptions,
    joint_answers: bool,
) -> RunSummary {
    let mut warnings = if options.realtime {
        try_realtime(70, options.lock_memory).warnings()
    } else {
        Vec::new()
    };
    let period = ctrl.config().period_s;
    let n = ctrl.robot().joint_count();
    let mut stats = CycleStats::new(Duration::from_secs_f64(period.clamp(1e-6, 10.0)));
    let mut summary_error = None;
    let mut stopped_before_start = false;
    // Wait (in wall time: this is about equipment being there) for the first robot state and
    // sensor sample.
    let waiting = Instant::now();
    let startup_timeout = if options.startup_timeout_s.is_finite() {
        options.startup_timeout_s.max(0.0)
    } else {
        0.0
    };
    loop {
        let (q_slot, q_version) = shared.q.read();
        let have_w = shared.wrench.read().1 > 0;
        if q_version > 0 && have_w {
            if let Err(e) = check_robot_matches_model(&ctrl, &q_slot) {
                summary_error = Some(e);
            }
            break;
        }
        if shared.stop.load(Ordering::Acquire) {
            stopped_before_start = true;
            break;
        }
        let waited = waiting.elapsed().as_secs_f64();
        if waited > startup_timeout {
            summary_error = Some(format!(
                "no data within {waited:.1} s: robot state {}, sensor samples {}",
                if q_version > 0 { "received" } else { "missing" },
                if have_w { "received" } else { "missing" }
            ));
            break;
        }
        std::thread::sleep(Duration::from_millis(1));
    }
    let mut cycles = 0u64;
    let mut max_force: f64 = 0.0;
    let mut max_xi: f64 = 0.0;
    let mut idle_exit = false;
    if summary_error.is_none() && !stopped_before_start {
        ctrl.start(clock.now());
        let mut next = clock.now();
        let (mut prev_sum, mut prev_count) = ([0.0; 6], 0.0);
        let mut stopping = false;
        loop {
            next += period;
            let now = clock.now();
            if now > next + period {
                // Overran by more than a period: count it and re-synchronise.
                stats.record_miss();
                next = now;
            }
            clock.sleep_until(next);
            let started = Instant::now();
            let now = clock.now();
            let (q_slot, _) = shared.q.read();
            let (w, _) = shared.wrench.read();
            let count = w[6];
            let fresh = count > prev_count;
            let mut wrench = [0.0; 6];
            for i in 0..6 {
                wrench[i] = if fresh {
                    (w[i] - prev_sum[i]) / (count - prev_count)
                } else {
                    w[7 + i]
                };
                prev_sum[i] = w[i];
            }
            prev_count = count;
            let q_age = now - q_slot[Q_TIME];
            let reported = (q_slot[Q_COUNT] as usize).min(MAX_JOINTS);
            let input = CycleInput {
                now_s: now,
                q_rad: &q_slot[..reported],
                q_age_s: q_age,
                wrench_sensor: &wrench,
                wrench_age_s: now - w[13],
                wrench_fresh: fresh,
                sensor_status: w[14] as u32,
            };
            let out = ctrl.cycle_input(&input);
            shared.xi.write(&out.xi);
            shared
                .directive
                .store(directive_for(&ctrl).to_u8(), Ordering::Release);
            let r = ctrl.tcp_rotation_in_base();
            shared.tcp_rotation.write(&[
                r[0][0], r[0][1], r[0][2], r[1][0], r[1][1], r[1][2], r[2][0], r[2][1], r[2][2],
            ]);
            if joint_answers {
                let map = ctrl.joint_correction_map();
                let mut flat = [0.0; MAP_LEN];
                for (i, row) in map.iter().enumerate() {
                    flat[i * 6..i * 6 + 6].copy_from_slice(row);
                }
                shared.joint_map.write(&flat);
            }
            let elapsed = started.elapsed();
            stats.record(elapsed);
            cycles += 1;
            let f = &out.wrench_tcp;
            let force = (f[0] * f[0] + f[1] * f[1] + f[2] * f[2]).sqrt();
            if !out.flags.has(Flags::TARING) {
                // Before and during the tare the reading still carries the sensor's bias.
                max_force = max_force.max(force);
            }
            let xi_p = (out.xi[0].powi(2) + out.xi[1].powi(2) + out.xi[2].powi(2)).sqrt();
            max_xi = max_xi.max(xi_p);
            if let Some(sink) = log.as_mut() {
                sink.push(LogRecord::new(
                    &q_slot[..n.min(reported)],
                    &wrench,
                    &out,
                    elapsed.as_secs_f64() * 1e6,
                ));
            }
            let phase_index = PHASES.iter().position(|p| *p == ctrl.phase()).unwrap_or(0);
            let xi_rot = (out.xi[3].powi(2) + out.xi[4].powi(2) + out.xi[5].powi(2)).sqrt();
            shared.status.write(&[
                now,
                phase_index as f64,
                f64::from(out.flags.0),
                force,
                out.xi[0],
                out.xi[1],
                out.xi[2],
                xi_rot,
                cycles as f64,
                0.0,
                0.0,
                0.0,
            ]);
            if let Some(idle) = options.idle_exit_s
                && q_age > idle
                && !shared.stop.load(Ordering::Acquire)
            {
                idle_exit = true;
                shared.stop.store(true, Ordering::Release);
            }
            if shared.stop.load(Ordering::Acquire) && !stopping {
                ctrl.stop(now);
                stopping = true;
            }
            let settled = matches!(ctrl.phase(), Phase::Stopped | Phase::Idle)
                || (ctrl.phase() == Phase::Faulted && ctrl.is_settled());
            if stopping && settled {
                break;
            }
        }
    }
    clock.release();
    let log_dropped = log.as_ref().map_or(0, LogSink::dropped);
    drop(log);
    warnings.dedup();
    let mut fault = ctrl.fault();
    let end = if summary_error.is_some() {
        SessionEnd::Failed
    } else if stopped_before_start {
        SessionEnd::StoppedBeforeStart
    } else if idle_exit {
        // The robot went silent and stayed silent: the end of its program. A robot_link_lost
        // latched by that silence (no telegram after it) is the end, not a fault.
        let last = f64::from_bits(shared.last_telegram_s.load(Ordering::Acquire));
        if fault.is_some_and(|f| f.kind == FaultKind::RobotLinkLost && last <= f.time_s) {
            fault = None;
        }
        SessionEnd::RobotFinished
    } else {
        SessionEnd::Stopped
    };
    RunSummary {
        control: stats.summary(),
        cycles,
        end,
        fault,
        runaway_events: ctrl.runaway_events(),
        first_runaway: ctrl.first_runaway(),
        max_force_n: max_force,
        max_xi_m: max_xi,
        log_dropped,
        warnings,
        error: summary_error,
        ..RunSummary::zeroed(ctrl.phase())
    }
}

fn panic_message(payload: &(dyn std::any::Any + Send)) -> String {
    payload
        .downcast_ref::<&str>()
        .map(|s| s.to_string())
        .or_else(|| payload.downcast_ref::<String>().cloned())
        .unwrap_or_else(|| "no message".into())
}

impl Runtime {
    /// The latest live status.
    pub fn status(&self) -> LiveStatus {
        let (s, _) = self.shared.status.read();
        LiveStatus {
            time_s: s[0],
            phase: PHASES[(s[1] as usize).min(PHASES.len() - 1)],
            flags: Flags(s[2] as u32),
            force_n: s[3],
            xi_m: [s[4], s[5], s[6]],
            xi_rot_rad: s[7],
            cycles: s[8] as u64,
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
                error: Some(format!(
                    "control thread panicked ({}); the links ramped the correction out and \
                     stopped",
                    panic_message(payload.as_ref())
                )),
                ..RunSummary::zeroed(Phase::Faulted)
            },
        };
        self.shared.done.store(true, Ordering::Release);
        match self.robot.join() {
            Ok(report) => {
                summary.reply_latency = report.latency.summary();
                summary.warnings.extend(report.warnings);
                summary.max_step_sent = report.max_step;
            }
            Err(payload) => {
                summary.error.get_or_insert(format!(
                    "robot link thread panicked ({})",
                    panic_message(payload.as_ref())
                ));
            }
        }
        if let Err(payload) = self.sensor.join() {
            summary.error.get_or_insert(format!(
                "sensor thread panicked ({})",
                panic_message(payload.as_ref())
            ));
        }
        if summary.error.is_some() {
            summary.end = SessionEnd::Failed;
        }
        let s = &self.shared;
        summary.telegrams = s.telegrams.load(Ordering::Relaxed);
        summary.robot_joints = s.q.read().0[Q_COUNT] as usize;
        summary.robot_timeouts = s.robot_timeouts.load(Ordering::Relaxed);
        summary.robot_bad_packets = s.robot_bad_packets.load(Ordering::Relaxed);
        summary.robot_errors = s.robot_errors.load(Ordering::Relaxed);
        summary.robot_foreign = s.robot_foreign.load(Ordering::Relaxed);
        summary.last_foreign = s.last_foreign.lock().ok().and_then(|g| *g);
        summary.robot_late = s.robot_late();
        summary.samples = s.samples.load(Ordering::Relaxed);
        summary.sample_gaps = s.sample_gaps.load(Ordering::Relaxed);
        summary.sensor_faults = s.sensor_faults.load(Ordering::Relaxed);
        summary.sensor_errors = s.sensor_errors.load(Ordering::Relaxed);
        summary.sensor_foreign = s.sensor_foreign.load(Ordering::Relaxed);
        summary.warnings.sort();
        summary.warnings.dedup();
        summary
    }
}
