//! `deflex run` and `deflex cell` as a user runs them: every numeric flag checked, absurd
//! CELL.toml values refused with the field named, a failed run keeps an existing log, and
//! SIGTERM ends the process cleanly (before the start, and in a session, ramping the correction
//! out first).

use crate::example_cell::{example_cell_file, free_udp_port};
use crate::support::{RunPeers, scratch};
use deflex_model::Wrench;
use std::path::{Path, PathBuf};
use std::process::{Command, Stdio};
use std::sync::Arc;
use std::sync::atomic::{AtomicBool, Ordering};
use std::time::{Duration, Instant};

fn deflex() -> Command {
    Command::new(env!("CARGO_BIN_EXE_deflex"))
}

/// A cell file on free loopback ports with `extra` appended.
pub fn cell_file(dir: &Path, kind: &str, extra: &str) -> (PathBuf, u16, u16) {
    let (robot, sensor) = (free_udp_port(), free_udp_port());
    let text = format!(
        "[robot]\nkind = \"{kind}\"\nbind = \"127.0.0.1:{robot}\"\ntimeout_s = 0.2\n\
         [sensor]\nkind = \"netft\"\naddress = \"127.0.0.1:{sensor}\"\nbind = \"127.0.0.1:0\"\n\
         timeout_s = 0.2\n[model]\nfile = \"tx200\"\n[control]\nrealtime = false\n\
         lock_memory = false\n{extra}"
    );
    let path = dir.join("cell.toml");
    std::fs::write(&path, text).unwrap();
    (path, robot, sensor)
}

#[test]
fn numeric_flags_are_checked() {
    let _turn = crate::session_turn();
    let dir = scratch("run-flags");
    let (cell, ..) = cell_file(&dir, "kuka-rsi", "");
    let cell = cell.to_str().unwrap();
    for (args, flag) in [
        (
            vec!["run", "--config", cell, "--startup-timeout-s", "nan"],
            "--startup-timeout-s",
        ),
        (
            vec!["run", "--config", cell, "--duration-s", "nan"],
            "--duration-s",
        ),
        (
            vec!["run", "--config", cell, "--idle-exit-s", "1e300"],
            "--idle-exit-s",
        ),
        (
            vec!["run", "--config", cell, "--duration-s=-1"],
            "--duration-s",
        ),
        (
            vec!["cell", "--sim", "--config", cell, "--wait-s", "nan"],
            "--wait-s",
        ),
        (
            vec!["cell", "--sim", "--config", cell, "--speed", "inf"],
            "--speed",
        ),
        (
            vec!["cell", "--sim", "--config", cell, "--dwell-s", "1e9"],
            "--dwell-s",
        ),
        (
            vec!["cell", "--sim", "--config", cell, "--length-mm", "nan"],
            "--length-mm",
        ),
    ] {
        let start = Instant::now();
        let out = deflex().args(&args).output().unwrap();
        let err = String::from_utf8_lossy(&out.stderr);
        assert!(!out.status.success(), "{args:?} succeeded");
        assert!(
            err.contains(flag) && err.contains("expected a number"),
            "{args:?}: {err}"
        );
        assert!(
            start.elapsed() < Duration::from_secs(30),
            "{args:?} took long"
        );
    }
    let _ = std::fs::remove_dir_all(&dir);
}

#[test]
fn absurd_cell_values_are_refused_with_the_field() {
    let _turn = crate::session_turn();
    let dir = scratch("run-fields");
    for (extra, field) in [
        ("rate_hz = 1e-300\n", "control.rate_hz"),
        ("rate_hz = 0.001\n", "control.rate_hz"),
        ("rate_hz = 1e300\n", "control.rate_hz"),
    ] {
        let (cell, ..) = cell_file(&dir, "kuka-rsi", extra);
        let out = deflex()
            .args(["run", "--config", cell.to_str().unwrap()])
            .output()
            .unwrap();
        let err = String::from_utf8_lossy(&out.stderr);
        assert!(
            !out.status.success() && err.contains(field),
            "{extra}: {err}"
        );
    }
    let _ = std::fs::remove_dir_all(&dir);
}

/// A run that fails (nobody answers within the start-up time) leaves the previous log alone.
#[test]
fn failed_run_keeps_the_existing_log() {
    let _turn = crate::session_turn();
    let dir = scratch("run-log");
    let (cell, ..) = cell_file(&dir, "simple-udp", "[log]\npath = \"run.csv\"\n");
    std::fs::write(dir.join("run.csv"), "a previous session\n").unwrap();
    let out = deflex()
        .args([
            "run",
            "--config",
            cell.to_str().unwrap(),
            "--startup-timeout-s",
            "0.3",
        ])
        .output()
        .unwrap();
    assert!(!out.status.success());
    assert!(String::from_utf8_lossy(&out.stderr).contains("no data within"));
    assert_eq!(
        std::fs::read_to_string(dir.join("run.csv")).unwrap(),
        "a previous session\n"
    );
    let names: Vec<_> = std::fs::read_dir(&dir).unwrap().collect();
    assert_eq!(names.len(), 2, "a temporary file was left behind");
    let _ = std::fs::remove_dir_all(&dir);
}

fn sigterm(pid: u32) {
    // SAFETY: sending a signal to a child process we spawned.
    unsafe {
        libc::kill(pid as libc::pid_t, libc::SIGTERM);
    }
}

#[test]
fn sigterm_before_the_start_ends_cleanly() {
    let _turn = crate::session_turn();
    let dir = scratch("run-term0");
    let (cell, ..) = cell_file(&dir, "kuka-rsi", "");
    let mut child = deflex()
        .args(["run", "--config", cell.to_str().unwrap()])
        .stdout(Stdio::piped())
        .stderr(Stdio::piped())
        .spawn()
        .unwrap();
    // Signal once it says it is waiting (the handler is installed by then).
    let mut err = std::io::BufReader::new(child.stderr.take().unwrap());
    let mut line = String::new();
    while std::io::BufRead::read_line(&mut err, &mut line).unwrap() > 0 {
        if line.contains("waiting for the robot") {
            break;
        }
        line.clear();
    }
    assert!(line.contains("waiting for the robot"), "{line}");
    sigterm(child.id());
    let out = child.wait_with_output().unwrap();
    let text = String::from_utf8_lossy(&out.stdout);
    assert!(out.status.success(), "{text}");
    assert!(text.contains("stopped before start"), "{text}");
    let _ = std::fs::remove_dir_all(&dir);
}

/// In a session (a simple-UDP robot and a Net F/T on loopback, in this process), SIGTERM ramps
/// the correction out before the process ends: the robot's last answers come down to zero.
#[test]
fn sigterm_in_a_session_ramps_the_correction_out() {
    let _turn = crate::session_turn();
    let dir = scratch("run-term1");
    let (cell, robot_port, sensor_port) = cell_file(
        &dir,
        "simple-udp",
        "[limits]\nramp_out_s = 0.3\n[log]\npath = \"run.csv\"\n",
    );
    // The contact waits for the session to run (the robot's answers count it), whatever the
    // load on the machine delays the process's start by: out of contact for the tare (0.2 s
    // from the session's start; 250 answers are at least 1 s of robot cycles), then 800 N
    // pushing up on the tool: −z of the sensor at this tool-down pose (sensor at the flange).
    let active = Arc::new(AtomicBool::new(false));
    let peers = {
        let active = active.clone();
        RunPeers::start(
            robot_port,
            sensor_port,
            move |answers| {
                if answers.last().is_some_and(|c| c[2].abs() > 1e-4) {
                    active.store(true, Ordering::Release);
                }
                true
            },
            |answered| {
                let fz = if answered < 250 { 0.0 } else { -800.0 };
                Some(Wrench::new(0.0, 0.0, fz, 0.0, 0.0, 0.0))
            },
        )
    };
    let child = deflex()
        .args(["run", "--config", cell.to_str().unwrap(), "--quiet"])
        .stdout(Stdio::piped())
        .stderr(Stdio::piped())
        .spawn()
        .unwrap();
    // Signal once the correction is active (the session is running, the handler installed).
    let start = Instant::now();
    while !active.load(Ordering::Acquire) && start.elapsed() < Duration::from_secs(60) {
        std::thread::sleep(Duration::from_millis(10));
    }
    sigterm(child.id());
    let out = child.wait_with_output().unwrap();
    let answers = peers.join();
    let text = String::from_utf8_lossy(&out.stdout);
    assert!(
        out.status.success(),
        "{text}\n{}",
        String::from_utf8_lossy(&out.stderr)
    );
    assert!(
        text.contains("phase: stopped (correction ramped out)"),
        "{text}"
    );
    let peak = answers.iter().map(|c| c[2].abs()).fold(0.0, f64::max);
    assert!(peak > 1e-4, "the correction was active: {peak}");
    let last = answers.last().unwrap();
    assert!(
        last.iter().all(|v| v.abs() < 1e-9),
        "not ramped out: {last:?}"
    );
    // The log of the stopped session was written.
    assert!(
        std::fs::read_to_string(dir.join("run.csv"))
            .unwrap()
            .lines()
            .count()
            > 10
    );
    let _ = std::fs::remove_dir_all(&dir);
}

/// Reads a child's stderr on a thread: the live view's address (from its "open http://…"
/// line) is sent once, every line is kept.
pub fn watch_stderr(
    child: &mut std::process::Child,
) -> (
    std::sync::mpsc::Receiver<String>,
    std::thread::JoinHandle<String>,
) {
    let err = child.stderr.take().unwrap();
    let (tx, rx) = std::sync::mpsc::channel();
    let handle = std::thread::spawn(move || {
        let mut all = String::new();
        for line in std::io::BufRead::lines(std::io::BufReader::new(err)).map_while(Result::ok) {
            if let Some(url) = line.split("open ").nth(1)
                && line.starts_with("live view")
            {
                let _ = tx.send(url.trim().to_string());
            }
            all.push_str(&line);
            all.push('\n');
        }
        all
    });
    (rx, handle)
}

/// `GET /` of a live view's page.
fn get_page(url: &str) -> String {
    let host = url.trim_start_matches("http://").trim_end_matches('/');
    let mut s = std::net::TcpStream::connect(host).unwrap();
    s.set_read_timeout(Some(Duration::from_secs(10))).unwrap();
    std::io::Write::write_all(
        &mut s,
        format!("GET / HTTP/1.1\r\nHost: {host}\r\nConnection: close\r\n\r\n").as_bytes(),
    )
    .unwrap();
    let mut text = String::new();
    let _ = std::io::Read::read_to_string(&mut s, &mut text);
    text
}

/// `deflex cell --sim --view` and `deflex run --view` together from one CELL.toml: both serve
/// their page on the loopback port asked, and at the end the run's CSV log has its MCAP
/// recording beside it, the cell its ground-truth log and recording beside the run's log.
#[test]
fn cell_and_run_serve_their_pages_and_record_beside_their_logs() {
    let _turn = crate::session_turn();
    let dir = scratch("run-views");
    let cell = example_cell_file(&dir);
    let cell = cell.to_str().unwrap();
    let mut twin = deflex()
        // 30 mm: 3.1 s of forming, ≈ 160 rows of the twin's 50 Hz log (more than 100 checked).
        .args(["cell", "--sim", "--config", cell, "--length-mm", "30"])
        .args(["--view", "127.0.0.1:0", "--quiet"])
        .stdout(Stdio::piped())
        .stderr(Stdio::piped())
        .spawn()
        .unwrap();
    let (twin_url, twin_err) = watch_stderr(&mut twin);
    // The run ends 0.5 s after the twin's last telegram (the default idle exit is 2 s), as
    // the twin crate's loopback tests end theirs.
    let mut run = deflex()
        .args(["--json", "run", "--config", cell, "--view", "127.0.0.1:0"])
        .args(["--idle-exit-s", "0.5"])
        .stdout(Stdio::piped())
        .stderr(Stdio::piped())
        .spawn()
        .unwrap();
    let (run_url, run_err) = watch_stderr(&mut run);
    for url in [&twin_url, &run_url] {
        let url = url.recv_timeout(Duration::from_secs(60)).unwrap();
        assert!(url.starts_with("http://127.0.0.1:"), "{url}");
        let page = get_page(&url);
        assert!(
            page.starts_with("HTTP/1.1 200") && page.contains("deflex live view"),
            "{page}"
        );
    }
    let twin_out = twin.wait_with_output().unwrap();
    let run_out = run.wait_with_output().unwrap();
    let (twin_err, run_err) = (twin_err.join().unwrap(), run_err.join().unwrap());
    assert!(twin_out.status.success(), "{twin_err}");
    assert!(run_out.status.success(), "{run_err}");
    let v: serde_json::Value = serde_json::from_slice(&run_out.stdout).unwrap();
    assert_eq!(v["mcap"]["committed"], true, "{v}");
    assert_eq!(v["mcap"]["lost"], 0, "{v}");
    assert_eq!(v["mcap"]["cycles"], v["log_rows"], "{v}");
    assert!(v["view"]["samples"].as_u64().unwrap() > 0, "{v}");
    let twin_text = String::from_utf8_lossy(&twin_out.stdout);
    assert!(twin_text.contains("run.sim-cell.csv"), "{twin_text}");

    // The run's recording: every cycle of its CSV log.
    let rows = std::fs::read_to_string(dir.join("run.csv"))
        .unwrap()
        .lines()
        .filter(|l| !l.starts_with('#'))
        .count()
        - 1;
    let mut cycles = 0;
    let summary = deflex_record::for_each_cycle(&dir.join("run.mcap"), |_| cycles += 1).unwrap();
    assert_eq!(cycles, rows);
    assert_eq!(summary.session.unwrap().source, "runtime");
    // The cell's: the twin's own stream, a sample at each row of its ground-truth log (and at
    // the state changes before the program started).
    let log = std::fs::read_to_string(dir.join("run.sim-cell.csv")).unwrap();
    assert!(log.starts_with("# SIMULATED"));
    let twin_rows = log.lines().filter(|l| !l.starts_with('#')).count() - 1;
    let mut path_errors = 0;
    let summary = deflex_record::for_each_cycle(&dir.join("run.sim-cell.mcap"), |s| {
        path_errors += s.truth_error_m.iter().all(|v| v.is_finite()) as usize;
    })
    .unwrap();
    let session = summary.session.unwrap();
    assert_eq!(
        (session.source.as_str(), session.label.as_str()),
        ("twin-cell", "SIMULATED")
    );
    assert!(
        twin_rows > 100 && path_errors >= twin_rows,
        "{twin_rows} {path_errors}"
    );
    let _ = std::fs::remove_dir_all(&dir);
}

/// The log path is checked before any link opens (issue 18, item 4): a folder, the cell file
/// itself and a FIFO are refused at once, naming `[log] path`, and nothing is written.
#[test]
fn a_bad_log_path_is_refused_before_the_session() {
    use std::os::unix::fs::FileTypeExt;
    let dir = scratch("run-logpath");
    std::fs::create_dir_all(dir.join("logs")).unwrap();
    let fifo = dir.join("fifo.csv");
    let c = std::ffi::CString::new(fifo.to_str().unwrap()).unwrap();
    // SAFETY: mkfifo with a valid NUL-terminated path.
    assert_eq!(unsafe { libc::mkfifo(c.as_ptr(), 0o600) }, 0);
    for (log, what) in [
        ("logs", "is a folder"),
        ("cell.toml", "is also an input"),
        ("fifo.csv", "FIFO"),
    ] {
        let (cell, ..) = cell_file(&dir, "kuka-rsi", &format!("[log]\npath = \"{log}\"\n"));
        let before = std::fs::read_to_string(&cell).unwrap();
        let out = deflex()
            .args(["run", "--config", cell.to_str().unwrap(), "--quiet"])
            .output()
            .unwrap();
        let err = String::from_utf8_lossy(&out.stderr);
        assert_eq!(out.status.code(), Some(1), "{log}: {err}");
        assert!(
            err.contains("[log] path") && err.contains(what),
            "{log}: {err}"
        );
        assert!(!err.contains("waiting for the robot"), "{err}");
        assert_eq!(std::fs::read_to_string(&cell).unwrap(), before);
        assert!(
            std::fs::symlink_metadata(&fifo)
                .unwrap()
                .file_type()
                .is_fifo()
        );
    }
    let _ = std::fs::remove_dir_all(&dir);
}

/// A `deflex` built without the `ros2` feature (the default build) refuses a cell that asks for
/// ROS 2 (`[ros2]`, or a sensor on a ROS 2 topic) before any link opens, naming the cell, the
/// field and the build that has it; the log of the cell is not touched.
#[cfg(not(feature = "ros2"))]
#[test]
fn a_cell_asking_for_ros2_is_refused_by_a_build_without_it() {
    let dir = scratch("run-noros2");
    let ros2 = "[ros2]\ndomain_id = 7\n";
    let log = "[log]\npath = \"run.csv\"\n";
    for (sensor_topic, field) in [(false, "[ros2]"), (true, "sensor.kind = \"ros2\"")] {
        let (cell, ..) = cell_file(&dir, "kuka-rsi", &format!("{ros2}{log}"));
        if sensor_topic {
            let text = std::fs::read_to_string(&cell).unwrap().replace(
                "kind = \"netft\"",
                "kind = \"ros2\"\ntopic = \"/ft_sensor/wrench\"",
            );
            std::fs::write(&cell, text).unwrap();
        }
        std::fs::write(dir.join("run.csv"), "a previous session\n").unwrap();
        let out = deflex()
            .args(["run", "--config", cell.to_str().unwrap()])
            .output()
            .unwrap();
        let err = String::from_utf8_lossy(&out.stderr);
        assert_eq!(out.status.code(), Some(1), "{field}: {err}");
        assert!(
            err.contains("cell.toml")
                && err.contains(field)
                && err.contains("--features ros2")
                && !err.contains("waiting for the robot"),
            "{field}: {err}"
        );
        assert_eq!(
            std::fs::read_to_string(dir.join("run.csv")).unwrap(),
            "a previous session\n"
        );
    }
    let version = deflex().arg("--version").output().unwrap();
    let version = String::from_utf8_lossy(&version.stdout);
    assert!(
        version.contains("without ROS 2") && version.contains("--features ros2"),
        "{version}"
    );
    let _ = std::fs::remove_dir_all(&dir);
}

/// A session that latched a fault (the sensor fell silent: sensor_timeout) exits with status 3
/// and says so in its summary, so that a script can tell it from a good session (issue 18,
/// item 4). The sensor stops after the robot has had 150 answers (at least 0.6 s of a running
/// session); the robot sends 150 more telegrams (at least 0.6 s, three times the sensor
/// timeout) and falls silent: the session ends by its idle exit (0.5 s, beyond the robot's
/// 0.2 s timeout) with the fault latched, however loaded the machine.
#[test]
fn a_latched_fault_ends_the_run_with_exit_status_3() {
    let _turn = crate::session_turn();
    let dir = scratch("run-fault");
    let (cell, robot_port, sensor_port) = cell_file(&dir, "simple-udp", "");
    // The sensor streams until the robot has had 150 answers; the robot sends 150 telegrams
    // more.
    let mut after = 0;
    let peers = RunPeers::start(
        robot_port,
        sensor_port,
        move |answers| {
            if answers.len() >= 150 {
                after += 1;
            }
            after < 150
        },
        |answered| (answered < 150).then(Wrench::zeros),
    );
    let out = deflex()
        .args([
            "run",
            "--config",
            cell.to_str().unwrap(),
            "--quiet",
            "--idle-exit-s",
            "0.5",
        ])
        .output()
        .unwrap();
    peers.join();
    let text = String::from_utf8_lossy(&out.stdout);
    let err = String::from_utf8_lossy(&out.stderr);
    assert_eq!(out.status.code(), Some(3), "{text}\n{err}");
    assert!(text.contains("fault: sensor_timeout"), "{text}");
    assert!(err.contains("latched fault"), "{err}");
    let _ = std::fs::remove_dir_all(&dir);
}

/// `deflex run` against `deflex cell --sim --length-mm 20 EXTRA…` on the example cell in
/// `dir`: the run's exit code, standard output and error (the twin is ended afterwards).
fn run_against_the_twin(dir: &Path, extra: &[&str]) -> (Option<i32>, String, String) {
    let cell = dir.join("cell.toml");
    let cell = cell.to_str().unwrap();
    let mut twin = deflex()
        .args([
            "cell",
            "--sim",
            "--config",
            cell,
            "--length-mm",
            "20",
            "--quiet",
        ])
        .args(extra)
        .stdout(Stdio::null())
        .stderr(Stdio::null())
        .spawn()
        .unwrap();
    let out = deflex()
        .args(["run", "--config", cell, "--quiet", "--idle-exit-s", "0.5"])
        .output()
        .unwrap();
    // The twin waits for answers that no longer come once the run has ended.
    sigterm(twin.id());
    let _ = twin.wait();
    (
        out.status.code(),
        String::from_utf8_lossy(&out.stdout).into_owned(),
        String::from_utf8_lossy(&out.stderr).into_owned(),
    )
}

/// The model checked against the robot (issue 33): the simulated KUKA reports its TCP in
/// `RIst` (its own kinematics at the measured joints); a robot file whose tool is 60 mm too
/// long is refused before the first correction with the difference in mm, the right one runs
/// (its summary gives the largest difference), and a jump of the reported pose during the
/// session latches `model_mismatch` (exit status 3).
#[test]
fn cell_and_run_check_the_model_against_the_robot() {
    let _turn = crate::session_turn();
    let dir = scratch("run-model-check");
    example_cell_file(&dir);
    let model = dir.join("tx200_cell.toml");
    let right = std::fs::read_to_string(&model).unwrap();
    let long = right.replace("xyz = [0.0, 0.0, 0.2]", "xyz = [0.0, 0.0, 0.26]");
    assert_ne!(long, right);
    std::fs::write(&model, &long).unwrap();
    let (code, text, err) = run_against_the_twin(&dir, &[]);
    println!("{err}");
    assert_eq!(code, Some(1), "{text}\n{err}");
    assert!(
        err.contains("model_mismatch: the TCP pose the robot reports is 60.")
            && err.contains("tolerance 5.00 mm, 10.00 mrad); refusing to run")
            && err.contains("[0.0, 0.0, 260.0] mm"),
        "{text}\n{err}"
    );

    std::fs::write(&model, &right).unwrap();
    let (code, text, err) = run_against_the_twin(&dir, &[]);
    assert_eq!(code, Some(0), "{text}\n{err}");
    assert!(
        text.contains("  model check: largest difference between the robot's reported TCP and the model's at the same joints 0.")
            && text.contains("fault: none"),
        "{text}"
    );

    let (code, text, err) = run_against_the_twin(&dir, &["--pose-jump-mm", "20"]);
    println!("{text}");
    assert_eq!(code, Some(3), "{text}\n{err}");
    assert!(
        text.contains("fault: model_mismatch: TCP position reported 20."),
        "{text}"
    );
    let _ = std::fs::remove_dir_all(&dir);
}
