//! The control thread's whole per-cycle path allocates nothing, measured **in the control
//! thread of a real session**: the clock that paces it reads that thread's allocation count
//! (the counting allocator counts per thread) every time the thread sleeps until its next
//! cycle, so the difference between two wake-ups is everything one cycle did — reading the
//! joint and wrench messages, the law (eq. 15, 17, limiter, safety, runaway guard), the joint
//! map of RSI `AK` answers, the correction command, the telemetry sample filled and published
//! (with the CSV log and a second sink subscribed) and the bookkeeping. The session runs a KUKA
//! RSI robot and a Net F/T on loopback, first in contact, then with the sensor silent (the fault
//! and the ramp to the safe value are measured too). The per-answer send shaper is measured in
//! the test's own thread.

use super::count;
use super::cycle_counter::CycleCounter;
use deflex_control::{Controller, ControllerConfig, WrenchConfig};
use deflex_model::ToolLoad;
use deflex_model::spatial::pose_from_xyz_rpy;
use deflex_model::wrench_transport::world_wrench_in_sensor;
use deflex_model::{Data, Robot, TX200_FORMING_Q_DEG, Wrench, builtin};
use deflex_record::csv_log::{Plain, spawn_writer};
use deflex_runtime::send_shaper::{LinkDirective, SendShaper, SendShaperConfig};
use deflex_runtime::session::{RuntimeOptions, spawn};
use deflex_runtime::{Clock, WallClock};
use deflex_telemetry::Flags;
use std::sync::Arc;

/// Wall time that records, at every `sleep_until` (called by the control thread only, once per
/// cycle), the allocations its caller made since the previous call (from the third call on: the
/// first two include the thread's start).
#[derive(Clone)]
struct CountingClock {
    inner: WallClock,
    counter: Arc<CycleCounter<1>>,
}

impl Clock for CountingClock {
    fn now(&self) -> f64 {
        self.inner.now()
    }
    fn sleep_until(&self, t_s: f64) {
        self.counter.cycle(0);
        self.inner.sleep_until(t_s)
    }
}

#[test]
fn control_thread_cycle_and_publish_allocate_nothing() {
    let mut config = controller_config();
    config.wrench.lowpass_hz = Some(30.0);
    config.safety.sensor_timeout_s = 0.2;
    // The fault measured is the sensor's silence: a robot held back 50 ms by a loaded machine
    // must not latch robot_link_lost first (the robot emulator is a thread of this test).
    config.safety.robot_timeout_s = 1.0;
    config.limiter.ramp_out_s = 0.2;
    let ctrl = controller(config);
    let q = q0();
    let raw = raw_reading(&config, &q, [300.0, -200.0, 900.0, 1.0, 2.0, -1.0]);
    let rsi = deflex_io::rsi::RsiConfig {
        answer: deflex_io::rsi::RsiAnswer::Joint(deflex_io::rsi::JointTag::Ak),
        ..Default::default()
    };
    // The robot and the sensor stream until told: the sensor falls silent once the session
    // has run its cycles in contact, the robot streams on until the fault is ramped out.
    let (link, client, peers) = loopback_cell(rsi, raw, q, f64::INFINITY, f64::INFINITY);
    let telemetry = telemetry(&ctrl);
    let log = spawn_writer(telemetry.subscribe(), 6, Box::new(Plain(std::io::sink()))).unwrap();
    let mut other_sink = telemetry.subscribe();
    let clock = CountingClock {
        inner: WallClock::new(),
        counter: Arc::new(CycleCounter::new(2)),
    };
    let options = RuntimeOptions {
        realtime: false,
        startup_timeout_s: 5.0,
        // Ended by a stop request once the fault is ramped out; the backstop.
        idle_exit_s: Some(0.3),
        ..RuntimeOptions::default()
    };
    let runtime = spawn(
        ctrl,
        Box::new(link),
        Box::new(client),
        clock.clone(),
        telemetry,
        options,
    )
    .unwrap();
    // 120 cycles (1.2 s) in contact, then the sensor's silence: latched, then ramped to zero.
    wait_for_status(&runtime, "120 cycles", |s| s.cycles >= 120);
    peers.silence_sensor();
    wait_for_status(&runtime, "the fault ramped out", |s| {
        s.flags.has(Flags::LATCHED) && s.xi_m == [0.0; 3] && s.xi_rot_rad == 0.0
    });
    runtime.request_stop();
    let summary = finish(runtime);
    peers.join();
    let report = log.finish(true).unwrap();
    let received = other_sink.drain(|_| {});
    let (allocations, measured) = (clock.counter.allocations(0), clock.counter.cycles(0));
    eprintln!(
        "control thread: {allocations} allocations in {measured} measured cycles of {}; log \
         {} rows; second sink {received} samples; fault {:?}",
        summary.cycles, report.written, summary.fault
    );
    assert_eq!(summary.error, None);
    // The session did the work: cycles in contact, then the sensor's silence latched and was
    // ramped out, and every cycle reached both sinks.
    assert!(measured > 100, "{measured} cycles measured");
    assert_eq!(
        summary.fault.map(|f| f.kind),
        Some(deflex_telemetry::FaultKind::SensorTimeout)
    );
    assert!(summary.max_xi_m > 1e-4, "{}", summary.max_xi_m);
    assert_eq!(report.written + report.dropped, summary.cycles);
    assert_eq!(received as u64 + other_sink.lost(), summary.cycles);
    assert_eq!(
        allocations, 0,
        "{allocations} allocations in {measured} cycles"
    );
}

#[test]
fn send_shaper_allocates_nothing() {
    let mut shaper = SendShaper::new(SendShaperConfig::new([0.02; 6], [0.008; 6], 0.004, 0.5));
    let (_, allocations) = count(|| {
        for k in 0..5000 {
            let target = [(k % 7) as f64 * 1e-3; 6];
            let directive = [
                LinkDirective::Follow,
                LinkDirective::RampOut,
                LinkDirective::Hold,
            ][k / 500 % 3];
            std::hint::black_box(shaper.next(&target, directive));
        }
    });
    assert_eq!(allocations, 0);
}

// The session's set-up, as deflex-runtime's own tests make it (their `common` module): the
// built-in TX200 at the paper's cone centre configuration, a controller with a known bias and a
// tool, raw sensor readings synthesised for a TCP wrench, a KUKA and a Net F/T on loopback.

const BIAS: [f64; 6] = [4.0, -3.0, 7.0, 0.2, -0.1, 0.05];

/// The paper's cone centre configuration (rad).
fn q0() -> [f64; 6] {
    TX200_FORMING_Q_DEG.map(f64::to_radians)
}

/// The controller's settings: a known sensor bias and a 5 kg tool on a rotated sensor mount.
fn controller_config() -> ControllerConfig {
    ControllerConfig {
        bias: Some(BIAS),
        wrench: WrenchConfig {
            sensor_in_flange: pose_from_xyz_rpy([0.0, 0.0, 0.04], [0.0, 0.0, 0.3]),
            tool_in_sensor: ToolLoad {
                mass_kg: 5.0,
                centre_of_mass_m: nalgebra::Vector3::new(0.0, 0.01, 0.12),
            },
            ..WrenchConfig::default()
        },
        ..ControllerConfig::default()
    }
}

fn robot() -> Robot {
    builtin("tx200").expect("built-in tx200")
}

fn controller(config: ControllerConfig) -> Controller {
    Controller::new(robot(), config).expect("controller")
}

/// What the sensor reads (bias + tool weight + environment wrench `w_tcp_world` at the TCP).
fn raw_reading(config: &ControllerConfig, q: &[f64], w_tcp_world: [f64; 6]) -> Wrench {
    let robot = robot();
    let mut data = Data::new();
    robot.forward_kinematics(&mut data, q).unwrap();
    let sensor = data.flange * config.wrench.sensor_in_flange;
    let env = world_wrench_in_sensor(&Wrench::from(w_tcp_world), &data.tcp_position(), &sensor);
    let g = config.wrench.gravity_world;
    let m = config.wrench.tool_in_sensor.mass_kg;
    let f =
        sensor.rotation.matrix().transpose() * nalgebra::Vector3::new(g[0] * m, g[1] * m, g[2] * m);
    let c = config.wrench.tool_in_sensor.centre_of_mass_m;
    let mg = c.cross(&f);
    let grav = [f.x, f.y, f.z, mg.x, mg.y, mg.z];
    Wrench::from_fn(|i, _| BIAS[i] + grav[i] + env[i])
}

/// The telemetry of a test session of `ctrl` (no sink unless the test subscribes one).
fn telemetry(ctrl: &Controller) -> deflex_runtime::Telemetry {
    let info = deflex_runtime::telemetry::session_info(
        ctrl,
        deflex_runtime::telemetry::Source::Runtime,
        "test",
        0.004,
    );
    deflex_runtime::Telemetry::new(info, 1024)
}

/// The far ends of a loopback cell: a KUKA (RSI robot side) sending `q` every 4 ms for
/// `robot_s` and a Net F/T streaming `raw` for `sensor_s` (wall time; `f64::INFINITY`: until
/// told), each in its own thread.
struct Peers {
    robot: std::thread::JoinHandle<u64>,
    sensor: std::thread::JoinHandle<()>,
    robot_stop: std::sync::Arc<std::sync::atomic::AtomicBool>,
    sensor_stop: std::sync::Arc<std::sync::atomic::AtomicBool>,
}

impl Peers {
    /// The sensor falls silent now.
    fn silence_sensor(&self) {
        self.sensor_stop
            .store(true, std::sync::atomic::Ordering::Release);
    }

    /// Stops both (those still running) and waits for them; returns the telegrams the robot
    /// sent.
    fn join(self) -> u64 {
        use std::sync::atomic::Ordering;
        self.robot_stop.store(true, Ordering::Release);
        self.sensor_stop.store(true, Ordering::Release);
        let sent = self.robot.join().unwrap();
        self.sensor.join().unwrap();
        sent
    }
}

/// An RSI link with `rsi`, a Net F/T client, and their peers on loopback.
fn loopback_cell(
    rsi: deflex_io::rsi::RsiConfig,
    raw: Wrench,
    q: [f64; 6],
    robot_s: f64,
    sensor_s: f64,
) -> (
    deflex_io::rsi::RsiLink,
    deflex_io::netft::NetFtClient,
    Peers,
) {
    use deflex_io::RobotSideLink;
    use deflex_io::netft::{Calibration, NetFtClient, NetFtSensorServer};
    use deflex_io::rsi::{CorrectionMode, RsiLink, RsiRobotEndpoint};
    use std::sync::Arc;
    use std::sync::atomic::{AtomicBool, Ordering};
    use std::time::{Duration, Instant};
    let link = RsiLink::bind("127.0.0.1:0", rsi).unwrap();
    let link_addr = link.local_addr().unwrap();
    let mut server = NetFtSensorServer::bind("127.0.0.1:0", Calibration::default()).unwrap();
    let sensor_addr = server.local_addr().unwrap();
    let client = NetFtClient::new("127.0.0.1:0", sensor_addr, Calibration::default()).unwrap();
    let (robot_stop, sensor_stop) = (
        Arc::new(AtomicBool::new(false)),
        Arc::new(AtomicBool::new(false)),
    );
    let sensor = {
        let stop = sensor_stop.clone();
        std::thread::spawn(move || {
            let start = Instant::now();
            while start.elapsed().as_secs_f64() < sensor_s && !stop.load(Ordering::Acquire) {
                let _ = server.poll_request(Duration::from_micros(500));
                let _ = server.send_sample(&raw, 0);
                std::thread::sleep(Duration::from_millis(1));
            }
        })
    };
    let robot = {
        let stop = robot_stop.clone();
        std::thread::spawn(move || {
            let mut ep =
                RsiRobotEndpoint::new("127.0.0.1:0", link_addr, CorrectionMode::Absolute).unwrap();
            let start = Instant::now();
            let mut sent = 0u64;
            let mut next = Instant::now();
            while start.elapsed().as_secs_f64() < robot_s && !stop.load(Ordering::Acquire) {
                let state = deflex_io::RobotState {
                    cycle_id: sent + 1,
                    ..deflex_io::RobotState::with_joints(&q)
                };
                ep.send_state(&state).unwrap();
                sent += 1;
                next += Duration::from_millis(4);
                let wait = next.saturating_duration_since(Instant::now());
                let _ = ep.receive_correction(wait.max(Duration::from_micros(100)));
                std::thread::sleep(next.saturating_duration_since(Instant::now()));
            }
            sent
        })
    };
    (
        link,
        client,
        Peers {
            robot,
            sensor,
            robot_stop,
            sensor_stop,
        },
    )
}

/// Waits (bounded, 10 s) until `done` holds for the runtime's live status.
fn wait_for_status(
    runtime: &deflex_runtime::Runtime,
    what: &str,
    done: impl Fn(&deflex_runtime::LiveStatus) -> bool,
) {
    let deadline = std::time::Instant::now() + std::time::Duration::from_secs(10);
    loop {
        let status = runtime.status();
        if done(&status) {
            return;
        }
        assert!(
            std::time::Instant::now() < deadline,
            "{what}: not within 10 s ({status:?})"
        );
        std::thread::sleep(std::time::Duration::from_millis(5));
    }
}

/// Waits (bounded) for the runtime to end by itself, then stops it and gathers the summary.
fn finish(runtime: deflex_runtime::Runtime) -> deflex_runtime::RunSummary {
    let deadline = std::time::Instant::now() + std::time::Duration::from_secs(10);
    while !runtime.is_finished() && std::time::Instant::now() < deadline {
        std::thread::sleep(std::time::Duration::from_millis(20));
    }
    runtime.request_stop();
    runtime.join()
}
