//! The threads of `deflex run` (Fig. 16 of the paper, with the CompactRIO replaced by a PC):
//!
//! * **robot-link thread**: blocks on the robot link; for every state telegram it publishes q
//!   and answers at once with the latest ξ (eq. 7) read from a seqlock slot — no locks, no
//!   allocation, so a KUKA RSI telegram every 4 ms is answered within its cycle every time. The
//!   reply latency (receipt → reply sent) is recorded in a histogram;
//! * **sensor thread**: receives force/torque samples and publishes a running sum, so the
//!   control thread averages every sample of its period;
//! * **control thread**: paced by an injectable [`Clock`] at the control rate (100 Hz), runs
//!   [`Controller::cycle_input`] (eq. 5–7, 15, 17), publishes ξ, pushes a log record into the
//!   lock-free ring and a live status into a slot, and measures its cycle time and deadline
//!   misses.
//!
//! The same threads run against hardware with a [`crate::WallClock`] and against the digital
//! twin in simulated time with a driven [`crate::SimClock`] (the twin's links advance the time
//! one robot cycle per telegram, in lockstep with the control thread: as fast as the CPU allows;
//! see `run_runtime_in_sim_time` in deflex-cli).
//!
//! Both loop threads try SCHED_FIFO (and the process mlockall) and carry on with a warning when
//! not permitted.

use crate::clock::Clock;
use crate::controller::{Controller, CycleInput, Phase};
use crate::log::{LogRecord, LogSink};
use crate::rt::try_realtime;
use crate::safety::{Fault, Flags};
use crate::slot::SeqSlot;
use crate::stats::{CycleStats, StatsSummary};
use deflex_io::{Correction, ForceSensorLink, RobotLink};
use deflex_model::MAX_JOINTS;
use std::sync::Arc;
use std::sync::atomic::{AtomicBool, AtomicU64, Ordering};
use std::thread::JoinHandle;
use std::time::{Duration, Instant};

/// Options of the runtime.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct RuntimeOptions {
    /// Robot interpolation cycle (s): reply deadline of the robot link.
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

const Q_TIME: usize = MAX_JOINTS;
const Q_LEN: usize = MAX_JOINTS + 1;
// Wrench slot layout: running sum [0..6], count [6], last [7..13], time [13], status [14].
const W_LEN: usize = 15;
const STATUS_LEN: usize = 12;

struct Shared {
    q: SeqSlot<Q_LEN>,
    wrench: SeqSlot<W_LEN>,
    xi: SeqSlot<6>,
    status: SeqSlot<STATUS_LEN>,
    stop: AtomicBool,
    done: AtomicBool,
    telegrams: AtomicU64,
    robot_timeouts: AtomicU64,
    robot_bad_packets: AtomicU64,
    robot_errors: AtomicU64,
    samples: AtomicU64,
    sample_gaps: AtomicU64,
    sensor_faults: AtomicU64,
    sensor_errors: AtomicU64,
}

/// Live status for the operator (read any time, lock-free).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct LiveStatus {
    /// Controller time (s).
    pub time_s: f64,
    /// Phase.
    pub phase: Phase,
    /// Flags of the last cycle.
    pub flags: Flags,
    /// Force norm at the TCP (N).
    pub force_n: f64,
    /// Position correction ξ_p (m).
    pub xi_m: [f64; 3],
    /// Rotation correction norm (rad).
    pub xi_rot_rad: f64,
    /// Control cycles so far.
    pub cycles: u64,
    /// Robot telegrams answered so far.
    pub telegrams: u64,
    /// Sensor samples received so far.
    pub samples: u64,
}

const PHASES: [Phase; 6] = [
    Phase::Idle,
    Phase::Taring,
    Phase::Running,
    Phase::Stopping,
    Phase::Stopped,
    Phase::Faulted,
];

/// What a run did.
#[derive(Clone, Debug)]
pub struct RunSummary {
    /// Control cycle time statistics (deadline: the control period).
    pub control: StatsSummary,
    /// Robot-link reply latency (receipt of a telegram → reply sent; deadline: robot cycle).
    pub reply_latency: StatsSummary,
    /// Control cycles run.
    pub cycles: u64,
    /// Telegrams answered.
    pub telegrams: u64,
    /// Receive timeouts / malformed packets / other errors on the robot link.
    pub robot_timeouts: u64,
    /// Malformed robot packets.
    pub robot_bad_packets: u64,
    /// Other robot link errors (send failures…).
    pub robot_errors: u64,
    /// Sensor samples received, samples lost (sequence gaps), samples flagged faulty, errors.
    pub samples: u64,
    /// Samples lost on the network.
    pub sample_gaps: u64,
    /// Samples with a fault status.
    pub sensor_faults: u64,
    /// Sensor link errors.
    pub sensor_errors: u64,
    /// Final phase.
    pub phase: Phase,
    /// The latched fault, if any.
    pub fault: Option<Fault>,
    /// Largest force norm seen at the TCP once tared (N).
    pub max_force_n: f64,
    /// Largest |ξ_p| (m).
    pub max_xi_m: f64,
    /// Log records dropped.
    pub log_dropped: u64,
    /// Real-time warnings.
    pub warnings: Vec<String>,
    /// Set when the run could not start (no data).
    pub error: Option<String>,
}

/// Handle of a running controller.
pub struct Runtime {
    shared: Arc<Shared>,
    control: JoinHandle<RunSummary>,
    robot: JoinHandle<(CycleStats, Vec<String>)>,
    sensor: JoinHandle<()>,
}

fn spawn_named<T: Send + 'static>(
    name: &str,
    f: impl FnOnce() -> T + Send + 'static,
) -> JoinHandle<T> {
    std::thread::Builder::new()
        .name(name.into())
        .spawn(f)
        .expect("spawning a runtime thread")
}

/// Starts the three threads. `log` receives one record per control cycle.
pub fn spawn<C: Clock + Clone + 'static>(
    controller: Controller,
    mut robot_link: Box<dyn RobotLink + Send>,
    mut sensor_link: Box<dyn ForceSensorLink + Send>,
    clock: C,
    log: Option<LogSink>,
    options: RuntimeOptions,
) -> Runtime {
    let shared = Arc::new(Shared {
        q: SeqSlot::new(),
        wrench: SeqSlot::new(),
        xi: SeqSlot::new(),
        status: SeqSlot::new(),
        stop: AtomicBool::new(false),
        done: AtomicBool::new(false),
        telegrams: AtomicU64::new(0),
        robot_timeouts: AtomicU64::new(0),
        robot_bad_packets: AtomicU64::new(0),
        robot_errors: AtomicU64::new(0),
        samples: AtomicU64::new(0),
        sample_gaps: AtomicU64::new(0),
        sensor_faults: AtomicU64::new(0),
        sensor_errors: AtomicU64::new(0),
    });
    let robot = {
        let shared = shared.clone();
        let clock = clock.clone();
        spawn_named("deflex-robot-link", move || {
            let warnings = if options.realtime {
                try_realtime(80, false).warnings()
            } else {
                Vec::new()
            };
            let deadline = Duration::from_secs_f64(options.robot_cycle_s.max(1e-6));
            let mut latency = CycleStats::new(deadline);
            let mut q = [0.0; Q_LEN];
            while !shared.done.load(Ordering::Acquire) {
                match robot_link.receive(Duration::from_millis(10)) {
                    Ok(Some(state)) => {
                        let received = Instant::now();
                        let n = state.q_rad.len().min(MAX_JOINTS);
                        q[..n].copy_from_slice(&state.q_rad[..n]);
                        q[Q_TIME] = clock.now();
                        shared.q.write(&q);
                        let (xi, _) = shared.xi.read();
                        let correction = Correction::from_array(xi);
                        match robot_link.send_correction(&correction) {
                            Ok(()) => {
                                latency.record(received.elapsed());
                                shared.telegrams.fetch_add(1, Ordering::Relaxed);
                            }
                            Err(_) => {
                                shared.robot_errors.fetch_add(1, Ordering::Relaxed);
                            }
                        }
                    }
                    Ok(None) => {
                        shared.robot_timeouts.fetch_add(1, Ordering::Relaxed);
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
            (latency, warnings)
        })
    };
    let sensor = {
        let shared = shared.clone();
        let clock = clock.clone();
        spawn_named("deflex-sensor", move || {
            let mut slot = [0.0; W_LEN];
            let mut started = sensor_link.start().is_ok();
            let mut last_start = Instant::now();
            while !shared.done.load(Ordering::Acquire) {
                match sensor_link.receive(Duration::from_millis(10)) {
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
                        // Silent sensor: ask again every second (the control thread decides
                        // whether this is a fault).
                        if !started || last_start.elapsed() > Duration::from_secs(1) {
                            started = sensor_link.start().is_ok();
                            last_start = Instant::now();
                        }
                    }
                    Err(_) => {
                        shared.sensor_errors.fetch_add(1, Ordering::Relaxed);
                    }
                }
            }
            let _ = sensor_link.stop();
        })
    };
    let control = {
        let shared = shared.clone();
        spawn_named("deflex-control", move || {
            control_loop(controller, &shared, &clock, log, options)
        })
    };
    Runtime {
        shared,
        control,
        robot,
        sensor,
    }
}

fn control_loop<C: Clock>(
    mut ctrl: Controller,
    shared: &Shared,
    clock: &C,
    mut log: Option<LogSink>,
    options: RuntimeOptions,
) -> RunSummary {
    let mut warnings = if options.realtime {
        try_realtime(70, options.lock_memory).warnings()
    } else {
        Vec::new()
    };
    let period = ctrl.config().period_s;
    let n = ctrl.robot().joint_count();
    let mut stats = CycleStats::new(Duration::from_secs_f64(period));
    let mut summary_error = None;
    // Wait (in wall time: this is about equipment being there) for the first robot state and
    // sensor sample.
    let waiting = Instant::now();
    loop {
        let have_q = shared.q.read().1 > 0;
        let have_w = shared.wrench.read().1 > 0;
        if have_q && have_w {
            break;
        }
        let waited = waiting.elapsed().as_secs_f64();
        if shared.stop.load(Ordering::Acquire) || waited > options.startup_timeout_s {
            summary_error = Some(format!(
                "no data within {waited:.1} s: robot state {}, sensor samples {}",
                if have_q { "received" } else { "missing" },
                if have_w { "received" } else { "missing" }
            ));
            break;
        }
        std::thread::sleep(Duration::from_millis(1));
    }
    let mut cycles = 0u64;
    let mut max_force: f64 = 0.0;
    let mut max_xi: f64 = 0.0;
    if summary_error.is_none() {
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
            let input = CycleInput {
                now_s: now,
                q_rad: &q_slot[..n],
                q_age_s: q_age,
                wrench_sensor: &wrench,
                wrench_age_s: now - w[13],
                wrench_fresh: fresh,
                sensor_fault: w[14] != 0.0,
            };
            let out = ctrl.cycle_input(&input);
            shared.xi.write(&out.xi);
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
                    &q_slot[..n],
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
            {
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
    shared.done.store(true, Ordering::Release);
    let log_dropped = log.as_ref().map_or(0, LogSink::dropped);
    drop(log);
    warnings.dedup();
    RunSummary {
        control: stats.summary(),
        cycles,
        fault: ctrl.fault(),
        max_force_n: max_force,
        max_xi_m: max_xi,
        log_dropped,
        warnings,
        error: summary_error,
        ..RunSummary::zeroed(ctrl.phase())
    }
}

impl RunSummary {
    /// A summary in `phase` with every statistic and counter at zero, no fault, no warnings
    /// and no error. The control thread fills in what it saw; the link counters are added
    /// from the shared atomics by [`Runtime::join`].
    fn zeroed(phase: Phase) -> Self {
        RunSummary {
            control: StatsSummary::default(),
            reply_latency: StatsSummary::default(),
            cycles: 0,
            telegrams: 0,
            robot_timeouts: 0,
            robot_bad_packets: 0,
            robot_errors: 0,
            samples: 0,
            sample_gaps: 0,
            sensor_faults: 0,
            sensor_errors: 0,
            phase,
            fault: None,
            max_force_n: 0.0,
            max_xi_m: 0.0,
            log_dropped: 0,
            warnings: Vec::new(),
            error: None,
        }
    }
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
        }
    }

    /// Asks for a stop: the correction ramps out, then the threads end.
    pub fn request_stop(&self) {
        self.shared.stop.store(true, Ordering::Release);
    }

    /// True once the control thread has ended.
    pub fn is_finished(&self) -> bool {
        self.shared.done.load(Ordering::Acquire)
    }

    /// Waits for the threads and gathers the summary.
    pub fn join(self) -> RunSummary {
        let mut summary = self.control.join().unwrap_or_else(|_| RunSummary {
            error: Some("control thread panicked".into()),
            ..RunSummary::zeroed(Phase::Faulted)
        });
        self.shared.done.store(true, Ordering::Release);
        if let Ok((latency, warnings)) = self.robot.join() {
            summary.reply_latency = latency.summary();
            summary.warnings.extend(warnings);
        }
        let _ = self.sensor.join();
        let s = &self.shared;
        summary.telegrams = s.telegrams.load(Ordering::Relaxed);
        summary.robot_timeouts = s.robot_timeouts.load(Ordering::Relaxed);
        summary.robot_bad_packets = s.robot_bad_packets.load(Ordering::Relaxed);
        summary.robot_errors = s.robot_errors.load(Ordering::Relaxed);
        summary.samples = s.samples.load(Ordering::Relaxed);
        summary.sample_gaps = s.sample_gaps.load(Ordering::Relaxed);
        summary.sensor_faults = s.sensor_faults.load(Ordering::Relaxed);
        summary.sensor_errors = s.sensor_errors.load(Ordering::Relaxed);
        summary.warnings.sort();
        summary.warnings.dedup();
        summary
    }
}
