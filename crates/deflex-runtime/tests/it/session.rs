//! The runtime against a hand-written robot on loopback: a control thread that panics ends the
//! session (links ramp out and stop, an error is reported); a model whose joint count or limits
//! do not match the robot's telegrams is refused; ABB EGM corrections for a tool-down pose, decoded
//! by hand from the bytes, have the right sign in the tool frame; KUKA RSI joint answers (`AK`)
//! move the TCP by the Cartesian correction.

use crate::common;

use deflex_control::Controller;
use deflex_io::egm::{EgmConfig, EgmLink};
use deflex_io::rsi::{JointTag, RsiAnswer, RsiConfig, RsiLink};
use deflex_io::{RobotLink, RobotState};
use deflex_model::Data;
use deflex_runtime::session::{
    Runtime, RuntimeOptions, SessionEnd, SessionError, SessionThread, spawn,
};
use deflex_runtime::{Clock, WallClock};
use deflex_telemetry::FaultKind;
use std::net::{SocketAddr, UdpSocket};
use std::sync::atomic::{AtomicBool, AtomicU64, Ordering};
use std::sync::{Arc, Mutex};
use std::time::{Duration, Instant};

/// A wall clock whose `sleep_until` panics after `limit` calls: a control thread that fails.
#[derive(Clone)]
struct FailingClock {
    inner: WallClock,
    calls: Arc<AtomicU64>,
    limit: u64,
}

impl Clock for FailingClock {
    fn now(&self) -> f64 {
        self.inner.now()
    }
    fn sleep_until(&self, t: f64) {
        if self.calls.fetch_add(1, Ordering::SeqCst) >= self.limit {
            panic!("injected control-thread failure");
        }
        self.inner.sleep_until(t)
    }
}

fn options() -> RuntimeOptions {
    RuntimeOptions {
        realtime: false,
        startup_timeout_s: 5.0,
        idle_exit_s: Some(0.5),
        ..RuntimeOptions::default()
    }
}

/// A KUKA emulator (raw socket, hand-written telegrams) sending `q` (degrees) every 4 ms until
/// stopped, keeping the answers' text. The 4 ms are a period, as a robot's interpolation clock
/// keeps it: a sleep that overshoots does not delay every telegram after it (so a ramp-out
/// counted in robot cycles ends in its time on a loaded machine too).
struct Kuka {
    run: Arc<AtomicBool>,
    answers: Arc<Mutex<Vec<String>>>,
    thread: std::thread::JoinHandle<()>,
}

impl Kuka {
    /// The latest answer so far.
    fn last_answer(&self) -> Option<String> {
        self.answers.lock().unwrap().last().cloned()
    }

    /// Stops sending; returns every answer.
    fn stop(self) -> Vec<String> {
        self.run.store(false, Ordering::Release);
        self.thread.join().unwrap();
        std::mem::take(&mut *self.answers.lock().unwrap())
    }
}

fn kuka(to: SocketAddr, q_deg: Vec<f64>) -> Kuka {
    let run = Arc::new(AtomicBool::new(true));
    let answers = Arc::new(Mutex::new(Vec::new()));
    let thread = {
        let (run, answers) = (run.clone(), answers.clone());
        std::thread::spawn(move || {
            let sock = UdpSocket::bind("127.0.0.1:0").unwrap();
            sock.set_read_timeout(Some(Duration::from_millis(20)))
                .unwrap();
            let mut buf = [0u8; 2048];
            let mut ipoc = 0u64;
            let mut next = Instant::now();
            while run.load(Ordering::Acquire) {
                ipoc += 4;
                let axes: String = q_deg
                    .iter()
                    .enumerate()
                    .map(|(i, v)| format!(" A{}=\"{v:.4}\"", i + 1))
                    .collect();
                let t = format!(
                    "<Rob Type=\"KUKA\"><AIPos{axes}/><Delay D=\"0\"/><IPOC>{ipoc}</IPOC></Rob>"
                );
                sock.send_to(t.as_bytes(), to).unwrap();
                if let Ok(n) = sock.recv(&mut buf) {
                    let answer = String::from_utf8_lossy(&buf[..n]).into_owned();
                    answers.lock().unwrap().push(answer);
                }
                next = (next + Duration::from_millis(4)).max(Instant::now());
                std::thread::sleep(next.saturating_duration_since(Instant::now()));
            }
        })
    };
    Kuka {
        run,
        answers,
        thread,
    }
}

fn wait(runtime: &Runtime, limit: Duration) -> Duration {
    let start = Instant::now();
    while !runtime.is_finished() && start.elapsed() < limit {
        std::thread::sleep(Duration::from_millis(2));
    }
    start.elapsed()
}

/// The control thread panics mid-session: the session ends (the links stop answering after
/// ramping the correction out), the summary carries the panic as an error.
#[test]
fn panicking_control_thread_ends_the_session_with_an_error() {
    let config = common::config();
    let q = common::q0();
    let raw = common::raw_reading(&config, &q, [0.0, 0.0, 900.0, 0.0, 0.0, 0.0]);
    let (client, sensor_done, sensor) = common::sensor(raw);
    let link = RsiLink::bind("127.0.0.1:0", RsiConfig::default()).unwrap();
    let to = link.local_addr().unwrap();
    let robot = kuka(to, q.iter().map(|v| v.to_degrees()).collect());
    // Fails 40 cycles (0.4 s) in: the correction is most of the way ramped in (0.5 s), so the
    // links have one to ramp out.
    let clock = FailingClock {
        inner: WallClock::new(),
        calls: Arc::new(AtomicU64::new(0)),
        limit: 40,
    };
    let ctrl = common::controller(config);
    let telemetry = common::telemetry(&ctrl);
    let runtime = spawn(
        ctrl,
        Box::new(link),
        Box::new(client),
        clock,
        telemetry,
        options(),
    )
    .unwrap();
    // The runtime reports the end by itself, while the robot still sends.
    let waited = wait(&runtime, Duration::from_secs(30));
    assert!(runtime.is_finished(), "did not end after {waited:?}");
    let joined = Instant::now();
    let summary = runtime.join();
    let drain = joined.elapsed();
    let answers = robot.stop();
    sensor_done.store(true, Ordering::Release);
    sensor.join().unwrap();
    eprintln!(
        "control panic: joined in {:.0} ms (links draining), {} answers, error {:?}",
        drain.as_secs_f64() * 1e3,
        answers.len(),
        summary.error
    );
    let error = summary.error.clone().unwrap();
    assert!(
        matches!(&error, SessionError::ThreadPanicked { thread: SessionThread::Control, message } if message.contains("injected")),
        "{error:?}"
    );
    let e = error.to_string();
    assert!(
        e.contains("control thread panicked") && e.contains("injected"),
        "{e}"
    );
    assert_eq!(summary.end, SessionEnd::Failed);
    // The drain is bounded (the design bound, not a timing assertion on this machine: the
    // robot-link thread stops after at most DRAIN_S plus one receive timeout).
    assert!(drain < Duration::from_secs(5), "{drain:?}");
    // The correction was active, and the last answer the robot heard is it ramped to zero.
    assert!(
        answers.iter().any(|a| !a.contains(r#"Z="0.0000""#)),
        "the correction was never active"
    );
    let last = answers.last().unwrap();
    assert!(last.contains(r#"Z="0.0000""#), "{last}");
}

/// A 1-joint model against a 6-joint robot is refused with a clear error, and so is a robot
/// whose joints lie outside the model's limits.
#[test]
fn model_that_does_not_fit_the_robot_is_refused() {
    let config = common::config();
    let q = common::q0();
    let raw = common::raw_reading(&config, &q, [0.0; 6]);
    let mut one_joint = common::robot();
    one_joint.joints.truncate(1);
    let mut limits = common::robot();
    limits.joints[2].limits = Some([-0.1, 0.1]);
    for (robot, expect, kind) in [
        (
            one_joint,
            "carry 6 joint values but the model",
            FaultKind::JointCountMismatch,
        ),
        (
            limits,
            "joint_out_of_limits: joint 3 reported at",
            FaultKind::JointOutOfLimits,
        ),
    ] {
        let (client, done, sensor) = common::sensor(raw);
        let link = RsiLink::bind("127.0.0.1:0", RsiConfig::default()).unwrap();
        let to = link.local_addr().unwrap();
        let kuka = kuka(to, q.iter().map(|v| v.to_degrees()).collect());
        let ctrl = Controller::new(robot, config).unwrap();
        let telemetry = common::telemetry(&ctrl);
        let runtime = spawn(
            ctrl,
            Box::new(link),
            Box::new(client),
            WallClock::new(),
            telemetry,
            options(),
        )
        .unwrap();
        wait(&runtime, Duration::from_secs(30));
        let summary = runtime.join();
        let answers = kuka.stop();
        done.store(true, Ordering::Release);
        sensor.join().unwrap();
        let error = summary.error.expect("refused");
        // Typed, with the values: the count or the joint, value and limits.
        assert_eq!(error.fault_kind(), Some(kind), "{error:?}");
        match &error {
            SessionError::JointCountMismatch {
                reported,
                model_joints,
                ..
            } => assert_eq!((*reported, *model_joints), (6, 1)),
            SessionError::JointOutOfLimits {
                joint, limits_rad, ..
            } => assert_eq!((*joint, *limits_rad), (3, [-0.1, 0.1])),
            other => panic!("{other:?}"),
        }
        let e = error.to_string();
        assert!(e.contains(expect), "{e}");
        assert_eq!(summary.cycles, 0);
        // Nothing but zero was ever sent.
        assert!(
            answers
                .iter()
                .all(|a| a.contains(r#"X="0.0000" Y="0.0000" Z="0.0000""#))
        );
    }
}

/// The model checked against the robot: a KUKA reporting its TCP in `RIst` (its own TX200 with
/// the 0.2 m tool of the test set-up's robot) against a model whose tool is 60 mm longer is
/// refused before the first correction, typed, with the difference in mm; the right model runs
/// with the largest difference in its summary.
#[test]
fn a_model_with_another_tool_is_refused_before_the_first_correction() {
    let config = common::config();
    let q = common::q0();
    let raw = common::raw_reading(&config, &q, [0.0; 6]);
    let mut long_tool = common::robot();
    long_tool.tool *= nalgebra::Translation3::new(0.0, 0.0, 0.06);
    for (robot, refused) in [(long_tool, true), (common::robot(), false)] {
        let (link, client, peers) =
            common::loopback_cell(RsiConfig::default(), raw, q, f64::INFINITY, f64::INFINITY);
        let ctrl = Controller::new(robot, config).unwrap();
        let telemetry = common::telemetry(&ctrl);
        let runtime = spawn(
            ctrl,
            Box::new(link),
            Box::new(client),
            WallClock::new(),
            telemetry,
            options(),
        )
        .unwrap();
        if refused {
            wait(&runtime, Duration::from_secs(30));
        } else {
            let started = Instant::now();
            while runtime.status().cycles < 20 && started.elapsed() < Duration::from_secs(30) {
                std::thread::sleep(Duration::from_millis(5));
            }
            runtime.request_stop();
            wait(&runtime, Duration::from_secs(30));
        }
        let summary = runtime.join();
        peers.join();
        if !refused {
            assert!(summary.error.is_none(), "{:?}", summary.error);
            let m = summary.pose_mismatch_max.expect("checked");
            // RSI carries 4 decimals of mm and degrees.
            assert!(m.position_m < 1e-5 && m.orientation_rad < 1e-5, "{m:?}");
            continue;
        }
        let error = summary.error.expect("refused");
        assert_eq!(error.fault_kind(), Some(FaultKind::ModelMismatch));
        let SessionError::ModelMismatch { mismatch, .. } = &error else {
            panic!("{error:?}");
        };
        assert!((mismatch.position_m - 0.06).abs() < 1e-5, "{mismatch:?}");
        let e = error.to_string();
        assert!(
            e.starts_with("model_mismatch: the TCP pose the robot reports is 60.00 mm and"),
            "{e}"
        );
        assert_eq!(summary.cycles, 0);
        assert!(summary.pose_mismatch_max.is_none());
    }
}

/// Hand decoding of `EgmSensorPathCorr.pathCorr.pos` from the official egm.proto field numbers
/// (message field 2 → field 1 → doubles 1, 2, 3), written here independently of deflex.
fn egm_pos(b: &[u8]) -> [f64; 3] {
    fn varint(b: &[u8], i: &mut usize) -> u64 {
        let mut v = 0u64;
        for shift in (0..64).step_by(7) {
            let byte = b[*i];
            *i += 1;
            v |= u64::from(byte & 0x7f) << shift;
            if byte & 0x80 == 0 {
                break;
            }
        }
        v
    }
    fn sub(b: &[u8], want: u64) -> &[u8] {
        let mut i = 0;
        loop {
            let key = varint(b, &mut i);
            match key & 7 {
                0 => {
                    varint(b, &mut i);
                }
                1 => i += 8,
                2 => {
                    let n = varint(b, &mut i) as usize;
                    if key >> 3 == want {
                        return &b[i..i + n];
                    }
                    i += n;
                }
                _ => i += 4,
            }
        }
    }
    let pos = sub(sub(b, 2), 1);
    // Three (key, fixed64) pairs: fields 1, 2, 3 in order.
    std::array::from_fn(|k| {
        let at = k * 9 + 1;
        f64::from_le_bytes(pos[at..at + 8].try_into().unwrap())
    })
}

/// The TX200 at the forming pose holds the tool pointing down. A 900 N upward contact force
/// deflects it up; the correction pushes down (ξ_z < 0 in base axes), which in the tool frame,
/// whose z points down, is +z: the bytes the robot receives say so.
#[test]
fn egm_tool_down_correction_has_the_right_sign_on_the_wire() {
    let config = common::config();
    let q = common::q0();
    let robot = common::robot();
    let mut data = Data::new();
    robot.forward_kinematics(&mut data, &q).unwrap();
    let tool_z = data.tcp.rotation * nalgebra::Vector3::z();
    assert!(
        tool_z.z < -0.99,
        "the forming pose holds the tool down: {tool_z}"
    );
    let raw = common::raw_reading(&config, &q, [0.0, 0.0, 900.0, 0.0, 0.0, 0.0]);
    let (client, done, sensor) = common::sensor(raw);
    let link = EgmLink::bind("127.0.0.1:0", EgmConfig::default()).unwrap();
    let to = link.local_addr().unwrap();
    let ctrl = common::controller(config);
    let telemetry = common::telemetry(&ctrl);
    let runtime = spawn(
        ctrl,
        Box::new(link),
        Box::new(client),
        WallClock::new(),
        telemetry,
        options(),
    )
    .unwrap();
    let sock = UdpSocket::bind("127.0.0.1:0").unwrap();
    sock.set_read_timeout(Some(Duration::from_millis(100)))
        .unwrap();
    let mut m = deflex_io::egm::msg::EgmRobot::default();
    let mut last = [0.0; 3];
    let mut buf = [0u8; 512];
    let start = Instant::now();
    let mut seq = 0;
    while start.elapsed() < Duration::from_secs(20) {
        seq += 1;
        deflex_io::egm::fill_robot_msg(&mut m, &RobotState::with_joints(&q), seq, 4 * seq, false);
        sock.send_to(&prost::Message::encode_to_vec(&m), to)
            .unwrap();
        if let Ok(n) = sock.recv(&mut buf) {
            last = egm_pos(&buf[..n]);
        }
        if last[2] > 0.5 && seq > 200 {
            break;
        }
        std::thread::sleep(Duration::from_millis(4));
    }
    // Stopped while the robot still streams: the correction ramps out as the robot hears it
    // and the session ends once a telegram goes unanswered (a robot that fell silent first
    // would leave the link waiting to send its last answer).
    runtime.request_stop();
    let stopping = Instant::now();
    while stopping.elapsed() < Duration::from_secs(10) {
        seq += 1;
        deflex_io::egm::fill_robot_msg(&mut m, &RobotState::with_joints(&q), seq, 4 * seq, false);
        sock.send_to(&prost::Message::encode_to_vec(&m), to)
            .unwrap();
        if sock.recv(&mut buf).is_err() && runtime.is_finished() {
            break;
        }
        std::thread::sleep(Duration::from_millis(4));
    }
    wait(&runtime, Duration::from_secs(10));
    let _ = runtime.join();
    done.store(true, Ordering::Release);
    sensor.join().unwrap();
    // Positive along the tool's z (down), in mm; the base-z correction is about −1 mm here.
    assert!(last[2] > 0.5 && last[2] < 3.0, "pathCorr.pos = {last:?} mm");
}

/// KUKA RSI with joint answers: the `AK` values (degrees, parsed by hand) move the TCP, through
/// the model's own forward kinematics, by the correction the Cartesian law computes at steady
/// state (the same controller run in-process to convergence).
#[test]
fn rsi_joint_answers_move_the_tcp_by_the_correction() {
    let config = common::config();
    let q = common::q0();
    let raw = common::raw_reading(&config, &q, [150.0, -80.0, 900.0, 0.0, 0.0, 0.0]);
    // The steady correction, in-process.
    let mut reference = common::controller(config);
    reference.start(0.0);
    let t = common::run_steady(&mut reference, &raw, &q, 0.0, 5.0);
    let xi = reference.cycle(t + 0.01, &q, &raw).xi;
    let (client, done, sensor) = common::sensor(raw);
    let cfg = RsiConfig {
        answer: RsiAnswer::Joint(JointTag::Ak),
        ..RsiConfig::default()
    };
    let link = RsiLink::bind("127.0.0.1:0", cfg).unwrap();
    assert!(link.answers_in_joint_space());
    let to = link.local_addr().unwrap();
    let robot = kuka(to, q.iter().map(|v| v.to_degrees()).collect());
    let ctrl = common::controller(config);
    let telemetry = common::telemetry(&ctrl);
    let runtime = spawn(
        ctrl,
        Box::new(link),
        Box::new(client),
        WallClock::new(),
        telemetry,
        options(),
    )
    .unwrap();
    // Until the session's correction is the steady one (however slowly a loaded machine runs
    // the cycles), then a few more answers to the robot.
    let start = Instant::now();
    while start.elapsed() < Duration::from_secs(30) {
        let now = runtime.status().xi_m;
        if (0..3).all(|i| (now[i] - xi[i]).abs() < 1e-7) {
            break;
        }
        std::thread::sleep(Duration::from_millis(10));
    }
    std::thread::sleep(Duration::from_millis(200));
    let last = robot.last_answer().expect("answers");
    // Stopped while the robot still streams: the correction ramps out as the robot hears it and
    // the session ends (a silent robot would leave the link draining its last answer).
    runtime.request_stop();
    wait(&runtime, Duration::from_secs(10));
    let _ = runtime.join();
    robot.stop();
    done.store(true, Ordering::Release);
    sensor.join().unwrap();
    // The last answer at the steady correction, parsed by hand.
    assert!(last.contains("<AK ") && !last.contains("RKorr"), "{last}");
    let dq: Vec<f64> = (1..=6)
        .map(|i| {
            let key = format!(" A{i}=\"");
            let at = last.find(&key).unwrap() + key.len();
            let end = last[at..].find('"').unwrap();
            last[at..at + end].parse::<f64>().unwrap().to_radians()
        })
        .collect();
    let robot = common::robot();
    let (mut a, mut b) = (Data::new(), Data::new());
    robot.forward_kinematics(&mut a, &q).unwrap();
    let moved: Vec<f64> = q.iter().zip(&dq).map(|(x, d)| x + d).collect();
    robot.forward_kinematics(&mut b, &moved).unwrap();
    let dp = b.tcp_position() - a.tcp_position();
    for i in 0..3 {
        // Within the print resolution of AK (10⁻⁴ °, ≈ 4 µm at 2 m) and second-order terms.
        assert!(
            (dp[i] - xi[i]).abs() < 10e-6,
            "axis {i}: TCP moved {} m, correction {} m",
            dp[i],
            xi[i]
        );
    }
    assert!(xi[2].abs() > 5e-4, "a sizeable correction: {xi:?}");
}
