//! Shared set-up (as in deflex-control's tests): the built-in TX200 at the paper's cone centre
//! configuration, a controller with a known bias and a tool, and raw sensor readings synthesised
//! for a TCP wrench; plus a KUKA and a Net F/T on loopback, and the telemetry of a session.
#![allow(dead_code)]

use deflex_control::{Controller, ControllerConfig, WrenchConfig};
use deflex_model::ToolLoad;
use deflex_model::spatial::pose_from_xyz_rpy;
use deflex_model::wrench_transport::world_wrench_in_sensor;
use deflex_model::{Data, Robot, TX200_FORMING_Q_DEG, Wrench, builtin};

pub const BIAS: [f64; 6] = [4.0, -3.0, 7.0, 0.2, -0.1, 0.05];

pub fn q0() -> [f64; 6] {
    TX200_FORMING_Q_DEG.map(f64::to_radians)
}

pub fn config() -> ControllerConfig {
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

pub fn robot() -> Robot {
    builtin("tx200").expect("built-in tx200")
}

pub fn controller(config: ControllerConfig) -> Controller {
    Controller::new(robot(), config).expect("controller")
}

/// What the sensor reads (bias + tool weight + environment wrench `w_tcp_world` at the TCP).
pub fn raw_reading(config: &ControllerConfig, q: &[f64], w_tcp_world: [f64; 6]) -> Wrench {
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

/// Runs `seconds` of the law against a rigid-environment-free plant (constant wrench), returns
/// the controller time reached.
pub fn run_steady(ctrl: &mut Controller, raw: &Wrench, q: &[f64], t0: f64, seconds: f64) -> f64 {
    let mut t = t0;
    let steps = (seconds / 0.01).round() as usize;
    for _ in 0..steps {
        t += 0.01;
        ctrl.cycle(t, q, raw);
    }
    t
}

/// The telemetry of a test session of `ctrl` (no sink unless the test subscribes one).
pub fn telemetry(ctrl: &Controller) -> deflex_runtime::Telemetry {
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
pub struct Peers {
    robot: std::thread::JoinHandle<u64>,
    sensor: std::thread::JoinHandle<()>,
    robot_stop: std::sync::Arc<std::sync::atomic::AtomicBool>,
    sensor_stop: std::sync::Arc<std::sync::atomic::AtomicBool>,
}

impl Peers {
    /// The sensor falls silent now.
    pub fn silence_sensor(&self) {
        self.sensor_stop
            .store(true, std::sync::atomic::Ordering::Release);
    }

    /// Stops both (those still running) and waits for them; returns the telegrams the robot
    /// sent.
    pub fn join(self) -> u64 {
        use std::sync::atomic::Ordering;
        self.robot_stop.store(true, Ordering::Release);
        self.sensor_stop.store(true, Ordering::Release);
        let sent = self.robot.join().unwrap();
        self.sensor.join().unwrap();
        sent
    }
}

/// An RSI link with `rsi`, a Net F/T client, and their peers on loopback.
pub fn loopback_cell(
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

/// Waits (bounded) for the runtime to end by itself, then stops it and gathers the summary.
pub fn finish(runtime: deflex_runtime::Runtime) -> deflex_runtime::RunSummary {
    let deadline = std::time::Instant::now() + std::time::Duration::from_secs(10);
    while !runtime.is_finished() && std::time::Instant::now() < deadline {
        std::thread::sleep(std::time::Duration::from_millis(20));
    }
    runtime.request_stop();
    runtime.join()
}

/// An in-memory file for a log writer: every clone writes into the same bytes.
#[derive(Clone, Default)]
pub struct SharedBuffer(std::sync::Arc<std::sync::Mutex<Vec<u8>>>);

impl SharedBuffer {
    /// What was written so far, as text.
    pub fn text(&self) -> String {
        String::from_utf8(self.0.lock().unwrap().clone()).unwrap()
    }
}

impl std::io::Write for SharedBuffer {
    fn write(&mut self, b: &[u8]) -> std::io::Result<usize> {
        self.0.lock().unwrap().extend_from_slice(b);
        Ok(b.len())
    }
    fn flush(&mut self) -> std::io::Result<()> {
        Ok(())
    }
}
