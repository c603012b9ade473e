//! The threaded runtime over real protocols on loopback (KUKA RSI robot side and ATI Net F/T
//! sensor side from deflex-io): every telegram is answered, and a sensor that goes silent or a
//! robot that stops talking latches the right fault while the correction the robot receives
//! stays bounded and ramps to zero.

use crate::common;

#[allow(unused_imports)]
use deflex_io::RobotLink as _;
use deflex_io::netft::{NetFtCalibration, NetFtClient, NetFtSensorServer};
use deflex_io::rsi::{CorrectionMode, RsiConfig, RsiLink, RsiRobotEndpoint};
use deflex_io::{RobotSideLink, RobotState};
use deflex_runtime::WallClock;
use deflex_runtime::session::{RuntimeOptions, spawn};
use deflex_telemetry::FaultKind;
use std::sync::Arc;
use std::sync::atomic::{AtomicBool, Ordering};
use std::time::{Duration, Instant};

struct Outcome {
    summary: deflex_runtime::session::RunSummary,
    corrections: Vec<[f64; 6]>,
    answered: u64,
    sent: u64,
}

/// How the session's far ends behave.
#[derive(Clone, Copy, Debug)]
enum Script {
    /// The sensor falls silent once the robot has sent 250 telegrams (1 s) and heard an active
    /// correction (0.5 mm); the robot streams on until it has heard the correction at zero for
    /// 25 answers in a row (10 s at most).
    SensorGoesSilent,
    /// The robot streams for `robot_s` (wall time), then falls silent for good; the sensor
    /// streams until the session has ended.
    RobotEnds { robot_s: f64 },
}

/// All six components of a correction below 1 µm (µrad).
fn is_zero(c: &[f64; 6]) -> bool {
    c.iter().all(|v| v.abs() < 1e-6)
}

fn run(script: Script) -> Outcome {
    let mut config = common::config();
    config.safety.robot_timeout_s = 0.2;
    config.safety.sensor_timeout_s = 0.2;
    config.limiter.ramp_in_s = 0.2;
    config.limiter.ramp_out_s = 0.2;
    let ctrl = common::controller(config);
    let q = common::q0();
    let raw = common::raw_reading(&config, &q, [200.0, -100.0, 900.0, 0.0, 0.0, 0.0]);

    let link = RsiLink::bind("127.0.0.1:0", RsiConfig::default()).unwrap();
    let link_addr = link.local_addr().unwrap();
    let mut server = NetFtSensorServer::bind("127.0.0.1:0", NetFtCalibration::default()).unwrap();
    let sensor_addr = server.local_addr().unwrap();
    let client = NetFtClient::new("127.0.0.1:0", sensor_addr, NetFtCalibration::default()).unwrap();

    // Set by the robot (its script) or once the session has ended.
    let silence_sensor = Arc::new(AtomicBool::new(false));
    let sensor = {
        let silence = silence_sensor.clone();
        std::thread::spawn(move || {
            while !silence.load(Ordering::Acquire) {
                let _ = server.poll_request(Duration::from_micros(500));
                let _ = server.send_sample(&raw, 0);
                std::thread::sleep(Duration::from_millis(1));
            }
        })
    };
    let robot = {
        let silence = silence_sensor.clone();
        std::thread::spawn(move || {
            let mut ep =
                RsiRobotEndpoint::new("127.0.0.1:0", link_addr, CorrectionMode::Absolute).unwrap();
            let start = Instant::now();
            let (mut sent, mut answered) = (0u64, 0u64);
            let mut corrections: Vec<[f64; 6]> = Vec::new();
            let mut next = Instant::now();
            let mut zeros_after_silence = 0;
            loop {
                let elapsed = start.elapsed().as_secs_f64();
                let go_on = match script {
                    Script::SensorGoesSilent => zeros_after_silence < 25 && elapsed < 10.0,
                    Script::RobotEnds { robot_s } => elapsed < robot_s,
                };
                if !go_on {
                    break;
                }
                let state = RobotState {
                    cycle_id: sent + 1,
                    ..RobotState::with_joints(&q)
                };
                ep.send_state(&state).unwrap();
                sent += 1;
                next += Duration::from_millis(4);
                let wait = next.saturating_duration_since(Instant::now());
                if let Ok(Some(reply)) = ep.receive_correction(wait.max(Duration::from_micros(100)))
                {
                    answered += 1;
                    let c = reply.correction.to_array();
                    corrections.push(c);
                    if let Script::SensorGoesSilent = script {
                        if silence.load(Ordering::Acquire) {
                            zeros_after_silence = if is_zero(&c) {
                                zeros_after_silence + 1
                            } else {
                                0
                            };
                        } else if sent >= 250 && c[2].abs() > 5e-4 {
                            silence.store(true, Ordering::Release);
                        }
                    }
                }
                std::thread::sleep(next.saturating_duration_since(Instant::now()));
            }
            (corrections, sent, answered)
        })
    };
    let options = RuntimeOptions {
        realtime: false,
        startup_timeout_s: 5.0,
        idle_exit_s: Some(0.4),
        ..RuntimeOptions::default()
    };
    let telemetry = common::telemetry(&ctrl);
    let runtime = spawn(
        ctrl,
        Box::new(link),
        Box::new(client),
        WallClock::new(),
        telemetry,
        options,
    )
    .unwrap();
    let (corrections, sent, answered) = robot.join().unwrap();
    if let Script::SensorGoesSilent = script {
        // The fault is latched and ramped out: how the session ends is not checked here.
        runtime.request_stop();
    }
    let deadline = Instant::now() + Duration::from_secs(10);
    while !runtime.is_finished() && Instant::now() < deadline {
        std::thread::sleep(Duration::from_millis(20));
    }
    silence_sensor.store(true, Ordering::Release);
    sensor.join().unwrap();
    runtime.request_stop();
    Outcome {
        summary: runtime.join(),
        corrections,
        answered,
        sent,
    }
}

fn check_bounded(corrections: &[[f64; 6]]) {
    let max_abs = deflex_control::LimiterConfig::default().max_abs;
    for c in corrections {
        for i in 0..6 {
            assert!(c[i].is_finite() && c[i].abs() <= max_abs[i] + 1e-6, "{c:?}");
        }
    }
}

#[test]
fn sensor_goes_silent() {
    let o = run(Script::SensorGoesSilent);
    let s = &o.summary;
    assert_eq!(s.error, None);
    assert_eq!(
        s.fault.map(|f| f.kind),
        Some(FaultKind::SensorTimeout),
        "{s:?}"
    );
    check_bounded(&o.corrections);
    // The correction was active, then ramped to zero while the robot was still listening.
    let peak = o.corrections.iter().map(|c| c[2].abs()).fold(0.0, f64::max);
    assert!(peak > 1e-4, "correction never became active: {peak}");
    let last = o.corrections.last().unwrap();
    assert!(
        last.iter().all(|v| v.abs() < 1e-6),
        "not ramped to zero: {last:?}"
    );
    // Nearly every telegram answered (a loaded 2-core box may lose a few).
    assert!(
        o.answered as f64 >= 0.95 * o.sent as f64,
        "{} of {}",
        o.answered,
        o.sent
    );
    assert!(s.reply_latency.count > 0 && s.reply_latency.p50_us > 0.0);
    eprintln!(
        "{} of {} telegrams answered; reply latency: {}",
        o.answered, o.sent, s.reply_latency
    );
    eprintln!("control cycle: {}", s.control);
}

/// The robot stops sending for good: the end of its program, reported as an end (not a
/// `robot_link_lost` fault), and the correction it last heard was bounded.
#[test]
fn robot_program_end_is_an_end_not_a_fault() {
    let o = run(Script::RobotEnds { robot_s: 0.6 });
    let s = &o.summary;
    assert_eq!(s.error, None);
    assert_eq!(
        s.end,
        deflex_runtime::session::SessionEnd::RobotFinished,
        "{s:?}"
    );
    assert_eq!(s.fault, None, "{s:?}");
    assert_eq!(s.phase_text(), "ended (robot program finished)");
    assert_eq!(s.robot_joints, 6);
    check_bounded(&o.corrections);
    assert!(s.cycles > 50);
}
