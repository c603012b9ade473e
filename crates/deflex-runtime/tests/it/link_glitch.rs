//! A robot that falls silent for 50 ms, 300 ms and 1 s in the middle of a loaded session (three
//! sessions at once, one per pause), over every robot protocol (KUKA RSI, ABB EGM, Stäubli,
//! simple UDP, simple TCP), with the real runtime threads, links and a Net F/T stream on
//! loopback. The robot emulator answers each of
//! its states with exactly one received correction and records them; the largest change between
//! two consecutive answers it received must not exceed the rate limit × the robot cycle (plus the
//! protocol's print resolution), whatever the gap.
//!
//! Nothing here depends on timing luck: the step bound holds for any scheduling (it is enforced
//! per answer); the robot warms up until it has received a sizeable correction, and the checks
//! on the ramp after the pause apply only when the controller did latch `robot_link_lost`.
//! A session ends as soon as the outcome of its pause is known (the correction ramped out to
//! zero after the latched fault, or the controller past the pause without one): the robot asks
//! the runtime to stop and answers the stop's ramp-out, whose steps are checked too.
#![allow(clippy::needless_range_loop)] // per-axis loops over several arrays

use crate::common;

use deflex_io::egm::{EgmConfig, EgmLink, EgmRobotEndpoint};
use deflex_io::netft::{NetFtCalibration, NetFtClient, NetFtSensorServer};
use deflex_io::rsi::{CorrectionMode, RsiConfig, RsiLink, RsiRobotEndpoint};
use deflex_io::simple_tcp::{SimpleTcpLink, SimpleTcpRobotEndpoint};
use deflex_io::simple_udp::{ReplyStyle, SimpleUdpLink, SimpleUdpRobotEndpoint};
use deflex_io::staubli::{StaubliLink, StaubliRobotEndpoint};
use deflex_io::{RobotLink, RobotSideLink, RobotState};
use deflex_model::Data;
use deflex_runtime::session::{RuntimeOptions, spawn};
use deflex_runtime::{Clock, Runtime, WallClock};
use deflex_telemetry::{FaultKind, Flags};
use std::net::SocketAddr;
use std::sync::Arc;
use std::sync::atomic::{AtomicBool, Ordering};
use std::time::{Duration, Instant};

const CYCLE_S: f64 = 0.004;

#[derive(Clone, Copy, Debug, PartialEq)]
enum Kind {
    Rsi,
    Egm,
    Staubli,
    SimpleUdp,
    SimpleTcp,
}

impl Kind {
    /// Resolution of the values on the wire (m): RSI prints mm with four decimals; the line
    /// protocols print nine decimals of a metre; EGM and Stäubli carry doubles.
    fn resolution_m(self) -> f64 {
        match self {
            Kind::Rsi => 1e-7,
            Kind::SimpleUdp | Kind::SimpleTcp => 1e-9,
            Kind::Egm | Kind::Staubli => 1e-12,
        }
    }
}

/// The controller side of `kind` on loopback, and where the robot sends to.
fn controller_link(kind: Kind) -> (Box<dyn RobotLink + Send>, SocketAddr) {
    let local = "127.0.0.1:0";
    match kind {
        Kind::Rsi => {
            let l = RsiLink::bind(local, RsiConfig::default()).unwrap();
            let a = l.local_addr().unwrap();
            (Box::new(l), a)
        }
        Kind::Egm => {
            let l = EgmLink::bind(local, EgmConfig::default()).unwrap();
            let a = l.local_addr().unwrap();
            (Box::new(l), a)
        }
        Kind::Staubli => {
            let l = StaubliLink::bind(local).unwrap();
            let a = l.local_addr().unwrap();
            (Box::new(l), a)
        }
        Kind::SimpleUdp => {
            let l = SimpleUdpLink::bind(local, ReplyStyle::Keyword).unwrap();
            let a = l.local_addr().unwrap();
            (Box::new(l), a)
        }
        Kind::SimpleTcp => {
            let l = SimpleTcpLink::bind(local).unwrap();
            let a = l.local_addr().unwrap();
            (Box::new(l), a)
        }
    }
}

/// The robot side of `kind`. EGM's corrections arrive in the tool (sensor) frame; the emulator
/// rotates them back to base axes with the tool orientation at the pose (as the robot does).
fn robot_side(kind: Kind, pc: SocketAddr) -> (Box<dyn RobotSideLink + Send>, bool) {
    let local = "127.0.0.1:0";
    match kind {
        Kind::Rsi => (
            Box::new(RsiRobotEndpoint::new(local, pc, CorrectionMode::Absolute).unwrap()),
            true,
        ),
        Kind::Egm => {
            let robot = common::robot();
            let mut data = Data::new();
            robot.forward_kinematics(&mut data, &common::q0()).unwrap();
            let mut ep = EgmRobotEndpoint::new(local, pc).unwrap();
            ep.set_correction_frame(&EgmConfig::default().correction_frame(&data.tcp.rotation));
            (Box::new(ep), false)
        }
        Kind::Staubli => (
            Box::new(StaubliRobotEndpoint::new(local, pc, Duration::from_secs(5)).unwrap()),
            true,
        ),
        Kind::SimpleUdp => (
            Box::new(SimpleUdpRobotEndpoint::new(local, pc).unwrap()),
            false,
        ),
        Kind::SimpleTcp => (
            Box::new(SimpleTcpRobotEndpoint::connect(pc, Duration::from_secs(5)).unwrap()),
            false,
        ),
    }
}

struct Session {
    /// Corrections the robot received, one per state it sent, in order (the stop's ramp-out at
    /// the end included).
    received: Vec<[f64; 6]>,
    /// Index of the first answer after the pause.
    resumed_at: usize,
    /// Answers received before the robot asked for the stop.
    stopped_at: usize,
    /// Controller time (s) when the robot asked for the stop: a fault latched before it is the
    /// session's (the pause's, or a scheduling gap's); the stop's ramp-out follows it.
    stop_requested_s: f64,
    /// The controller's ξ_z just before the robot resumed.
    controller_xi_z_at_resume: f64,
    /// Wall time from the start to the pause (s): the warm-up.
    warm_up_s: f64,
    summary: deflex_runtime::session::RunSummary,
}

impl Session {
    /// The `robot_link_lost` latched while the robot was streaming (before its stop request).
    fn link_lost(&self) -> bool {
        self.summary
            .fault
            .is_some_and(|f| f.kind == FaultKind::RobotLinkLost && f.time_s < self.stop_requested_s)
    }
}

/// What the robot emulator of a session recorded.
struct RobotRecord {
    received: Vec<[f64; 6]>,
    resumed_at: usize,
    stopped_at: usize,
    stop_requested_s: f64,
    warm_up_s: f64,
}

/// Answers in the window that tells a correction is steady.
const STEADY_ANSWERS: usize = 25;

/// The last [`STEADY_ANSWERS`] answers (0.1 s) agree within 10 µm, 1 % of the ≈ 1.05 mm
/// correction: the ramp-in (0.2 s) is over and the law has settled to within 1 % (it approaches
/// its value with a time constant of about 0.1 s, so a 1 µm window would add 0.25 s to every
/// session's warm-up and change nothing checked).
fn steady(received: &[[f64; 6]]) -> bool {
    received.len() > STEADY_ANSWERS && {
        let tail = &received[received.len() - STEADY_ANSWERS..];
        tail.iter().all(|c| (c[2] - tail[0][2]).abs() < 1e-5)
    }
}

/// The robot's side of a session: warm up until a sizeable, steady correction arrives (ramp-in
/// done), fall silent for `pause`, resume until the outcome of the pause is clear (ramped out
/// to zero after a latched fault, or steady with the controller past the pause without one),
/// then ask the runtime to stop and keep answering while it ramps the correction out, until it
/// has ended.
fn robot_session(
    kind: Kind,
    pc: SocketAddr,
    pause: Duration,
    runtime: &Runtime,
    clock: &WallClock,
    paused: &AtomicBool,
) -> RobotRecord {
    let q = common::q0();
    let (mut ep, echoes) = robot_side(kind, pc);
    let mut received: Vec<[f64; 6]> = Vec::new();
    let mut cycle = 0u64;
    let (mut resumed_at, mut stopped_at) = (0, 0);
    let (mut warm_up_s, mut stop_requested_s) = (f64::NAN, f64::NAN);
    // Controller time of the first answer after the pause: that telegram's joints were
    // published before it was answered, so a control cycle that starts later no longer sees
    // the silence.
    let mut first_answer_after_s = f64::INFINITY;
    // 0: warm-up; 1: after the pause; 2: stopping (answering the stop's ramp-out).
    let mut stage = 0;
    let started = Instant::now();
    let mut stage_start = Instant::now();
    // A state every robot cycle, as a robot's interpolation clock sends them (a sleep that
    // overshoots does not delay every state after it).
    let cycle_time = Duration::from_secs_f64(CYCLE_S);
    let mut next = Instant::now();
    loop {
        cycle += 1;
        let state = RobotState {
            cycle_id: cycle,
            ..RobotState::with_joints(&q)
        };
        match ep.send_state(&state) {
            Ok(()) => {}
            // The runtime has ended (its link closed).
            Err(_) if stage == 2 => break,
            Err(e) => panic!("{kind:?}: {e}"),
        }
        // Exactly one answer per state: wait for it. Once the runtime has ended nothing
        // answers any more.
        let wait_start = Instant::now();
        let answer = loop {
            match ep.receive_correction(Duration::from_millis(20)) {
                Ok(Some(r)) if !echoes || r.cycle_id == cycle => break Some(r),
                Ok(Some(_)) => {}
                _ if stage == 2
                    && runtime.is_finished()
                    && wait_start.elapsed() > Duration::from_millis(100) =>
                {
                    break None;
                }
                _ if wait_start.elapsed() > Duration::from_secs(5) => break None,
                _ => {}
            }
        };
        let Some(answer) = answer else { break };
        received.push(answer.correction.to_array());
        let z = answer.correction.dp_m[2].abs();
        if stage == 1 && received.len() == resumed_at + 1 {
            first_answer_after_s = clock.now();
        }
        match stage {
            0 if (z > 3e-4 && steady(&received))
                || stage_start.elapsed() > Duration::from_secs(10) =>
            {
                // Steady: fall silent.
                warm_up_s = started.elapsed().as_secs_f64();
                paused.store(true, Ordering::Release);
                std::thread::sleep(pause);
                paused.store(false, Ordering::Release);
                resumed_at = received.len();
                stage = 1;
                stage_start = Instant::now();
                next = Instant::now();
            }
            // Ramped out to zero; or steady since the resume while the controller has run a
            // cycle after the first answer after the pause without a latched fault (any fault
            // of the pause is latched by then: the outcome is known, no need to wait longer);
            // 3 s at most.
            1 if z == 0.0
                || (received.len() >= resumed_at + STEADY_ANSWERS && steady(&received) && {
                    let status = runtime.status();
                    status.time_s > first_answer_after_s && !status.flags.has(Flags::LATCHED)
                })
                || stage_start.elapsed() > Duration::from_secs(3) =>
            {
                stopped_at = received.len();
                stop_requested_s = clock.now();
                runtime.request_stop();
                stage = 2;
            }
            _ => {}
        }
        next = (next + cycle_time).max(Instant::now());
        std::thread::sleep(next.saturating_duration_since(Instant::now()));
    }
    if stage < 2 {
        stopped_at = received.len();
        stop_requested_s = clock.now();
    }
    RobotRecord {
        received,
        resumed_at,
        stopped_at,
        stop_requested_s,
        warm_up_s,
    }
}

fn session(kind: Kind, pause: Duration) -> Session {
    let mut config = common::config();
    config.limiter.ramp_in_s = 0.2;
    config.limiter.ramp_out_s = 0.5;
    let ctrl = common::controller(config);
    let q = common::q0();
    let raw = common::raw_reading(&config, &q, [200.0, -100.0, 900.0, 0.0, 0.0, 0.0]);
    let (link, pc) = controller_link(kind);
    let mut server = NetFtSensorServer::bind("127.0.0.1:0", NetFtCalibration::default()).unwrap();
    let client = NetFtClient::new(
        "127.0.0.1:0",
        server.local_addr().unwrap(),
        NetFtCalibration::default(),
    )
    .unwrap();
    let done = Arc::new(AtomicBool::new(false));
    let paused = AtomicBool::new(false);
    let sensor = {
        let done = done.clone();
        std::thread::spawn(move || {
            while !done.load(Ordering::Acquire) {
                let _ = server.poll_request(Duration::from_micros(500));
                let _ = server.send_sample(&raw, 0);
                std::thread::sleep(Duration::from_millis(1));
            }
        })
    };
    let options = RuntimeOptions {
        robot_cycle_s: CYCLE_S,
        realtime: false,
        startup_timeout_s: 10.0,
        // The robot ends the session with a stop request; this is the backstop should it fail.
        // Longer than the longest pause: the session must outlive it.
        idle_exit_s: Some(1.5),
        ..RuntimeOptions::default()
    };
    let telemetry = common::telemetry(&ctrl);
    let clock = WallClock::new();
    let runtime = spawn(ctrl, link, Box::new(client), clock, telemetry, options).unwrap();
    let (record, xi_at_resume) = std::thread::scope(|scope| {
        let robot = scope.spawn(|| robot_session(kind, pc, pause, &runtime, &clock, &paused));
        // Watch the controller's own ξ while the robot is silent.
        let mut xi_at_resume = f64::NAN;
        while !robot.is_finished() {
            if paused.load(Ordering::Acquire) {
                xi_at_resume = runtime.status().xi_m[2];
            }
            std::thread::sleep(Duration::from_millis(5));
        }
        (robot.join().unwrap(), xi_at_resume)
    });
    runtime.request_stop();
    let summary = runtime.join();
    done.store(true, Ordering::Release);
    sensor.join().unwrap();
    Session {
        received: record.received,
        resumed_at: record.resumed_at,
        stopped_at: record.stopped_at,
        stop_requested_s: record.stop_requested_s,
        controller_xi_z_at_resume: xi_at_resume,
        warm_up_s: record.warm_up_s,
        summary,
    }
}

/// Sessions tried per pause until one had a sizeable correction when the robot fell silent.
const ATTEMPTS: usize = 5;

/// The three pauses of `kind`, each in its own session, the three sessions at once (each sleeps
/// most of every robot cycle).
fn check(kind: Kind) {
    std::thread::scope(|scope| {
        for pause_ms in [50u64, 300, 1000] {
            scope.spawn(move || check_pause(kind, pause_ms));
        }
    });
}

fn check_pause(kind: Kind, pause_ms: u64) {
    // On a loaded machine a scheduling gap longer than the link timeout (50 ms) can latch
    // `robot_link_lost` during the warm-up, so that the correction is already ramped out
    // when the robot pauses: such a session still has its step bound checked, and is
    // repeated to exercise a pause under an active correction.
    let mut attempt = 1;
    loop {
        let s = session(kind, Duration::from_millis(pause_ms));
        assert!(s.summary.error.is_none(), "{kind:?}: {:?}", s.summary.error);
        assert!(s.resumed_at > 0, "{kind:?}: never paused");
        check_steps(kind, pause_ms, &s);
        let before = s.received[s.resumed_at - 1];
        if before[2].abs() > 2e-4 {
            check_ramp_out(kind, pause_ms, &s);
            return;
        }
        assert!(
            attempt < ATTEMPTS,
            "{kind:?} {pause_ms} ms: in {ATTEMPTS} sessions the correction was never active \
             before the pause (last: {before:?}, fault {:?})",
            s.summary.fault
        );
        eprintln!(
            "{kind:?} {pause_ms} ms: the correction was not active before the pause (fault \
             {:?} on this loaded machine); session repeated",
            s.summary.fault.map(|f| f.to_string())
        );
        attempt += 1;
    }
}

/// The robot never received a step above the rate limit × its cycle (any session).
fn check_steps(kind: Kind, pause_ms: u64, s: &Session) {
    let limits = common::config().limiter;
    let before = s.received[s.resumed_at - 1];
    let mut largest = [0.0f64; 6];
    for w in s.received.windows(2) {
        for i in 0..6 {
            largest[i] = largest[i].max((w[1][i] - w[0][i]).abs());
        }
    }
    let step_limit = limits.max_rate[0] * CYCLE_S;
    let after_pause = s.received[s.resumed_at - 1..s.stopped_at]
        .windows(2)
        .map(|w| {
            (0..3)
                .map(|i| (w[1][i] - w[0][i]).abs())
                .fold(0.0, f64::max)
        })
        .fold(0.0, f64::max);
    let largest_p = largest[..3].iter().fold(0.0f64, |m, v| m.max(*v));
    eprintln!(
        "{kind:?}, pause {pause_ms} ms: largest step received {:.4} mm (from the pause on \
         {:.4} mm; limit {:.4} mm), \
         correction before the pause {:.4} mm, the controller's own ξz when the robot \
         resumed {:.4} mm, first answer after it {:.4} mm, {} answers ({} after the pause, \
         {} while stopping; warm-up {:.2} s), fault {}",
        largest_p * 1e3,
        after_pause * 1e3,
        step_limit * 1e3,
        before[2] * 1e3,
        s.controller_xi_z_at_resume * 1e3,
        s.received
            .get(s.resumed_at)
            .map_or(f64::NAN, |c| c[2] * 1e3),
        s.received.len(),
        s.stopped_at - s.resumed_at,
        s.received.len() - s.stopped_at,
        s.warm_up_s,
        s.summary
            .fault
            .map_or("none".to_string(), |f| f.to_string())
    );
    for i in 0..3 {
        assert!(
            largest[i] <= step_limit + kind.resolution_m() + 1e-15,
            "{kind:?} {pause_ms} ms: axis {i} stepped {} m, limit {step_limit} m",
            largest[i]
        );
    }
    for i in 3..6 {
        // RSI prints A B C with four decimals of a degree.
        let resolution = if kind == Kind::Rsi { 2e-6 } else { 1e-9 };
        assert!(
            largest[i] <= limits.max_rate[i] * CYCLE_S + resolution,
            "{kind:?} {pause_ms} ms: axis {i} stepped {} rad",
            largest[i]
        );
    }
}

/// After the pause, a controller that latched `robot_link_lost` ramps out in robot cycles.
fn check_ramp_out(kind: Kind, pause_ms: u64, s: &Session) {
    let step_limit = common::config().limiter.max_rate[0] * CYCLE_S;
    let before = s.received[s.resumed_at - 1];
    if s.link_lost() {
        // The controller ramped out on its own clock while the robot heard nothing…
        if pause_ms >= 1000 {
            assert!(
                s.controller_xi_z_at_resume.abs() < 1e-6,
                "{kind:?}: the controller had not ramped out after 1 s: {}",
                s.controller_xi_z_at_resume
            );
        }
        // …but the robot sees the ramp, in its own cycles, down to zero.
        let after = &s.received[s.resumed_at..s.stopped_at];
        assert_eq!(after.last().unwrap()[2], 0.0, "{kind:?} {pause_ms} ms");
        assert!(
            after.len() as f64 >= before[2].abs() / step_limit - 1.0,
            "{kind:?} {pause_ms} ms: ramped out in {} answers",
            after.len()
        );
    }
}

#[test]
fn kuka_rsi_pauses() {
    check(Kind::Rsi);
}

#[test]
fn abb_egm_pauses() {
    check(Kind::Egm);
}

#[test]
fn staubli_pauses() {
    check(Kind::Staubli);
}

#[test]
fn simple_udp_pauses() {
    check(Kind::SimpleUdp);
}

#[test]
fn simple_tcp_pauses() {
    check(Kind::SimpleTcp);
}
