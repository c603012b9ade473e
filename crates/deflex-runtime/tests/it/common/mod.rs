//! Shared set-up of the sessions: deflex-control's controller set-up (compiled here from that
//! package's tests, not copied: the built-in TX200 at the paper's cone centre configuration, a
//! controller with a known bias and a tool, the raw sensor readings for a TCP wrench); a KUKA
//! and a Net F/T on loopback; the telemetry of a session.
//!
//! The facade's no-allocation tests of a session (crates/deflex/tests/it/no_alloc) compile this
//! file too, by `#[path]`: it uses nothing of this binary beyond these files.
#![allow(dead_code)]

#[path = "../../../../deflex-control/tests/it/common/mod.rs"]
mod controller;

pub use controller::*;

use deflex_control::Controller;
use deflex_io::RobotSideLink;
use deflex_io::netft::{NetFtCalibration, NetFtClient, NetFtSensorServer};
use deflex_io::rsi::{CorrectionMode, RsiConfig, RsiLink, RsiRobotEndpoint};
use deflex_model::Wrench;
use std::net::SocketAddr;
use std::sync::Arc;
use std::sync::atomic::{AtomicBool, Ordering};
use std::time::{Duration, Instant};

/// The telemetry of a test session of `ctrl` (no sink unless the test subscribes one).
pub fn telemetry(ctrl: &Controller) -> deflex_runtime::Telemetry {
    let info = deflex_runtime::telemetry::session_info(
        ctrl,
        deflex_runtime::telemetry::StreamSource::Runtime,
        "test",
        0.004,
    );
    deflex_runtime::Telemetry::new(info, 1024)
}

/// A peer thread of a loopback cell: it runs until its time is up or it is told to stop.
pub struct Peer<T> {
    handle: std::thread::JoinHandle<T>,
    stop: Arc<AtomicBool>,
}

impl<T> Peer<T> {
    /// Tells it to stop (it ends within one of its periods).
    pub fn stop(&self) {
        self.stop.store(true, Ordering::Release);
    }

    /// Stops it and waits for it; returns what it returned.
    pub fn join(self) -> T {
        self.stop();
        self.handle.join().unwrap()
    }
}

/// A KUKA (RSI robot side, absolute corrections) sending `q` to the link at `link` every 4 ms,
/// with its TCP pose in `RIst` (the built-in TX200's own kinematics at `q`, robot base frame,
/// as the controller computes it), and reading its answers, for `seconds` of wall time
/// (`f64::INFINITY`: until stopped); returns the telegrams it sent.
pub fn kuka_robot(link: SocketAddr, q: [f64; 6], seconds: f64) -> Peer<u64> {
    let tx200 = robot();
    let pose = tx200.base.inverse() * tx200.tcp_pose(&q).unwrap();
    let stop = Arc::new(AtomicBool::new(false));
    let stopped = stop.clone();
    let handle = std::thread::spawn(move || {
        let mut ep = RsiRobotEndpoint::new("127.0.0.1:0", link, CorrectionMode::Absolute).unwrap();
        let start = Instant::now();
        let mut sent = 0u64;
        let mut next = Instant::now();
        while start.elapsed().as_secs_f64() < seconds && !stopped.load(Ordering::Acquire) {
            let state = deflex_io::RobotState {
                cycle_id: sent + 1,
                tcp_pose: Some(pose),
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
    });
    Peer { handle, stop }
}

/// A Net F/T (sensor side) streaming `raw` from `server` about every millisecond, for `seconds`
/// of wall time (`f64::INFINITY`: until stopped).
pub fn netft_sensor(mut server: NetFtSensorServer, raw: Wrench, seconds: f64) -> Peer<()> {
    let stop = Arc::new(AtomicBool::new(false));
    let stopped = stop.clone();
    let handle = std::thread::spawn(move || {
        let start = Instant::now();
        while start.elapsed().as_secs_f64() < seconds && !stopped.load(Ordering::Acquire) {
            let _ = server.poll_request(Duration::from_micros(500));
            let _ = server.send_sample(&raw, 0);
            std::thread::sleep(Duration::from_millis(1));
        }
    });
    Peer { handle, stop }
}

/// The far ends of a loopback cell: a KUKA ([`kuka_robot`]) and a Net F/T ([`netft_sensor`]),
/// each in its own thread.
pub struct Peers {
    robot: Peer<u64>,
    sensor: Peer<()>,
}

impl Peers {
    /// The sensor falls silent now.
    pub fn silence_sensor(&self) {
        self.sensor.stop();
    }

    /// Stops both (those still running) and waits for them; returns the telegrams the robot
    /// sent.
    pub fn join(self) -> u64 {
        self.robot.stop();
        self.sensor.stop();
        let sent = self.robot.join();
        self.sensor.join();
        sent
    }
}

/// An RSI link with `rsi`, a Net F/T client, and their peers on loopback: the KUKA sends `q`
/// for `robot_s`, the Net F/T streams `raw` for `sensor_s` (wall time; `f64::INFINITY`: until
/// told).
pub fn loopback_cell(
    rsi: RsiConfig,
    raw: Wrench,
    q: [f64; 6],
    robot_s: f64,
    sensor_s: f64,
) -> (RsiLink, NetFtClient, Peers) {
    let link = RsiLink::bind("127.0.0.1:0", rsi).unwrap();
    let server = NetFtSensorServer::bind("127.0.0.1:0", NetFtCalibration::default()).unwrap();
    let sensor_addr = server.local_addr().unwrap();
    let client = NetFtClient::new("127.0.0.1:0", sensor_addr, NetFtCalibration::default()).unwrap();
    let peers = Peers {
        sensor: netft_sensor(server, raw, sensor_s),
        robot: kuka_robot(link.local_addr().unwrap(), q, robot_s),
    };
    (link, client, peers)
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

/// A Net F/T streaming `raw` until the returned flag is set.
pub fn sensor(
    raw: deflex_model::Wrench,
) -> (NetFtClient, Arc<AtomicBool>, std::thread::JoinHandle<()>) {
    let mut server = NetFtSensorServer::bind("127.0.0.1:0", NetFtCalibration::default()).unwrap();
    let client = NetFtClient::new(
        "127.0.0.1:0",
        server.local_addr().unwrap(),
        NetFtCalibration::default(),
    )
    .unwrap();
    let done = Arc::new(AtomicBool::new(false));
    let handle = {
        let done = done.clone();
        std::thread::spawn(move || {
            while !done.load(Ordering::Acquire) {
                let _ = server.poll_request(Duration::from_micros(500));
                let _ = server.send_sample(&raw, 0);
                std::thread::sleep(Duration::from_millis(1));
            }
        })
    };
    (client, done, handle)
}
