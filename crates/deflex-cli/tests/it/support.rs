//! What the tests of the binary share: running `deflex`, a fresh folder per test, free loopback
//! ports, and the robot and the sensor a `deflex run` session talks to.

use deflex_io::netft::{NetFtCalibration, NetFtSensorServer};
use deflex_io::simple_udp::SimpleUdpRobotEndpoint;
use deflex_io::{RobotSideLink, RobotState};
use deflex_model::Wrench;
use std::path::{Path, PathBuf};
use std::process::Command;
use std::sync::Arc;
use std::sync::atomic::{AtomicBool, AtomicUsize, Ordering};
use std::thread::JoinHandle;
use std::time::Duration;

/// One finished run of the `deflex` binary.
pub struct Run {
    /// It exited with status 0.
    pub ok: bool,
    /// Its exit status (`None`: ended by a signal).
    pub code: Option<i32>,
    /// Its standard output.
    pub stdout: String,
    /// Its standard error.
    pub stderr: String,
}

/// `deflex ARGS`, run to its end.
pub fn deflex(args: &[&str]) -> Run {
    let output = Command::new(env!("CARGO_BIN_EXE_deflex"))
        .args(args)
        .output()
        .expect("run deflex");
    Run {
        ok: output.status.success(),
        code: output.status.code(),
        stdout: String::from_utf8_lossy(&output.stdout).into_owned(),
        stderr: String::from_utf8_lossy(&output.stderr).into_owned(),
    }
}

/// `deflex ARGS`, which must succeed: its standard output.
pub fn succeeds(args: &[&str]) -> String {
    let run = deflex(args);
    assert!(run.ok, "deflex {args:?} failed: {}", run.stderr);
    run.stdout
}

/// `deflex cell --sim --quiet --config CONFIG`, to be given its other arguments.
pub fn cell_sim(config: &Path) -> Command {
    let mut command = Command::new(env!("CARGO_BIN_EXE_deflex"));
    command.args(["cell", "--sim", "--quiet", "--config", s(config)]);
    command
}

/// `deflex --json ARGS`, which must succeed: its standard output as JSON.
pub fn json(args: &[&str]) -> serde_json::Value {
    let mut all = vec!["--json"];
    all.extend_from_slice(args);
    let stdout = succeeds(&all);
    serde_json::from_str(&stdout).unwrap_or_else(|e| panic!("not JSON ({e}): {stdout}"))
}

/// A fresh, empty folder `deflex-cli-NAME-PID` in the temporary directory (`NAME` is the test's
/// own in this binary: its file's and its).
pub fn scratch(name: &str) -> PathBuf {
    let dir = std::env::temp_dir().join(format!("deflex-cli-{name}-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(&dir).unwrap();
    dir
}

/// The line of a command that reads the measurements `data` of `robot` (`calibrate`,
/// `validate`, `calibrate-geometry`, `predict`, `register`): `COMMAND --robot ROBOT --data DATA
/// REST…`.
pub fn with_data<'a>(
    command: &'a str,
    robot: &'a str,
    data: &'a Path,
    rest: &[&'a str],
) -> Vec<&'a str> {
    let mut args = vec![command, "--robot", robot, "--data", s(data)];
    args.extend_from_slice(rest);
    args
}

/// `p` as an argument.
pub fn s(p: &Path) -> &str {
    p.to_str().unwrap()
}

/// A TCP port of 127.0.0.1 that was free a moment ago.
pub fn free_tcp_port() -> u16 {
    std::net::TcpListener::bind("127.0.0.1:0")
        .and_then(|l| l.local_addr())
        .map(|a| a.port())
        .unwrap()
}

/// The far ends of a `deflex run` on loopback, in this process: a simple-UDP robot at the
/// TX200's forming pose and a Net F/T, each in its own thread.
pub struct RunPeers {
    stop: Arc<AtomicBool>,
    robot: JoinHandle<Vec<[f64; 6]>>,
    sensor: JoinHandle<()>,
}

impl RunPeers {
    /// Starts them. The robot sends its state to the controller's `robot_port` every 4 ms (each
    /// telegram waits up to 20 ms for its answer) while `robot_goes_on(the answers so far)`; the
    /// Net F/T on `sensor_port` sends `sensor_wrench(how many answers so far)` about every
    /// millisecond, and falls silent at its first `None`.
    pub fn start(
        robot_port: u16,
        sensor_port: u16,
        mut robot_goes_on: impl FnMut(&[[f64; 6]]) -> bool + Send + 'static,
        mut sensor_wrench: impl FnMut(usize) -> Option<Wrench> + Send + 'static,
    ) -> RunPeers {
        let stop = Arc::new(AtomicBool::new(false));
        let answered = Arc::new(AtomicUsize::new(0));
        let sensor = {
            let (stop, answered) = (stop.clone(), answered.clone());
            std::thread::spawn(move || {
                let mut s = NetFtSensorServer::bind(
                    ("127.0.0.1", sensor_port),
                    NetFtCalibration::default(),
                )
                .unwrap();
                while !stop.load(Ordering::Acquire) {
                    let Some(wrench) = sensor_wrench(answered.load(Ordering::Acquire)) else {
                        break;
                    };
                    let _ = s.poll_request(Duration::from_micros(500));
                    let _ = s.send_sample(&wrench, 0);
                    std::thread::sleep(Duration::from_millis(1));
                }
            })
        };
        let robot = {
            let stop = stop.clone();
            let q = deflex_model::TX200_FORMING_Q_DEG.map(f64::to_radians);
            std::thread::spawn(move || {
                let mut ep =
                    SimpleUdpRobotEndpoint::new("127.0.0.1:0", ([127, 0, 0, 1], robot_port).into())
                        .unwrap();
                let mut answers = Vec::new();
                while !stop.load(Ordering::Acquire) && robot_goes_on(&answers) {
                    let _ = ep.send_state(&RobotState::with_joints(&q));
                    if let Ok(Some(c)) = ep.receive_correction(Duration::from_millis(20)) {
                        answers.push(c.correction.to_array());
                        answered.store(answers.len(), Ordering::Release);
                    }
                    std::thread::sleep(Duration::from_millis(4));
                }
                answers
            })
        };
        RunPeers {
            stop,
            robot,
            sensor,
        }
    }

    /// Stops both (those still running) and waits for them; returns the corrections the robot
    /// received, in order.
    pub fn join(self) -> Vec<[f64; 6]> {
        self.stop.store(true, Ordering::Release);
        let answers = self.robot.join().unwrap();
        self.sensor.join().unwrap();
        answers
    }
}
