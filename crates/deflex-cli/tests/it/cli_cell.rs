//! `deflex cell --sim` before any controller answers: the robot the twin plays (`--robot`, a
//! twin file, the default) and the loopback-only rule of the CELL.toml, through the real binary.
//! (The sessions against `deflex run` are in `cli_run`.)

use crate::cli_run::cell_file;
use crate::support::{cell_sim, free_tcp_port, scratch};
use std::path::Path;
use std::process::{Command, Output, Stdio};
use std::time::{Duration, Instant};
use tungstenite::Message;
use tungstenite::stream::MaybeTlsStream;

/// `deflex cell --sim --config CONFIG --wait-s 0 EXTRA…`: no controller answers, so the twin
/// says what it plays and gives up at once.
fn cell(config: &Path, extra: &[&str]) -> Output {
    Command::new(env!("CARGO_BIN_EXE_deflex"))
        .args(["cell", "--sim", "--config", config.to_str().unwrap()])
        .args(["--wait-s", "0"])
        .args(extra)
        .output()
        .unwrap()
}

/// The twin's line "the twin plays NAME (`SPEC`), robot cycle …" of a `deflex cell` run.
fn playing(out: &Output) -> String {
    let err = String::from_utf8_lossy(&out.stderr);
    err.lines()
        .find(|l| l.contains("the twin plays"))
        .unwrap_or_else(|| panic!("no twin line: {err}"))
        .to_string()
}

/// The session of the twin's live page (its first message, the hello) while `deflex cell
/// --sim EXTRA… --view PORT` waits for a controller; the process is ended afterwards.
fn served_session(config: &Path, extra: &[&str]) -> serde_json::Value {
    let port = free_tcp_port().to_string();
    let mut child = cell_sim(config)
        .args(["--wait-s", "60", "--view", &port])
        .args(extra)
        .stdout(Stdio::null())
        .stderr(Stdio::null())
        .spawn()
        .unwrap();
    let url = format!("ws://127.0.0.1:{port}/ws");
    let start = Instant::now();
    // The page is served once the twin is set up: until then, the connection is refused.
    let connected = loop {
        match tungstenite::connect(url.as_str()) {
            Ok((ws, _)) => break Ok(ws),
            Err(_) if start.elapsed() < Duration::from_secs(30) => {
                std::thread::sleep(Duration::from_millis(50));
            }
            Err(e) => break Err(e),
        }
    };
    let hello = connected.map(|mut ws| {
        if let MaybeTlsStream::Plain(s) = ws.get_ref() {
            s.set_read_timeout(Some(Duration::from_secs(20))).unwrap();
        }
        match ws.read() {
            Ok(Message::Text(t)) => serde_json::from_str::<serde_json::Value>(t.as_str()).unwrap(),
            other => panic!("expected the hello, got {other:?}"),
        }
    });
    let _ = child.kill();
    let _ = child.wait();
    hello.expect("the twin's live page")["session"].clone()
}

/// The twin plays the robot of `--robot`, over a twin file's settings too; an unknown robot
/// is refused naming it.
#[test]
fn the_twin_plays_the_robot_of_the_flag() {
    let dir = scratch("cell-robot");
    let (config, ..) = cell_file(&dir, "kuka-rsi", "");
    let line = playing(&cell(&config, &[]));
    assert!(line.contains("(`tx200`)"), "{line}");
    let line = playing(&cell(&config, &["--robot", "ur10e"]));
    assert!(line.contains("(`ur10e`)"), "{line}");
    // The UR10e cell's robot cycle, as the twin serves it: 2 ms.
    let session = served_session(&config, &["--robot", "ur10e"]);
    assert_eq!(session["robot_cycle_s"], 0.002, "{session}");
    assert!(
        session["robot"].as_str().unwrap().contains("UR10e"),
        "{session}"
    );
    let file = dir.join("twin.toml");
    std::fs::write(
        &file,
        "[cell.part]\nrobot = \"ur10e\"\n[cell.log]\nrate_hz = 25.0\n",
    )
    .unwrap();
    let twin = file.to_str().unwrap();
    let line = playing(&cell(&config, &["--twin", twin]));
    assert!(line.contains("(`ur10e`)"), "{line}");
    let line = playing(&cell(&config, &["--robot", "tx200", "--twin", twin]));
    assert!(line.contains("(`tx200`)"), "the flag wins: {line}");
    let refused = cell(&config, &["--robot", "nosuch-robot"]);
    assert_eq!(refused.status.code(), Some(1));
    let e = String::from_utf8_lossy(&refused.stderr);
    assert!(e.contains("error: ") && e.contains("nosuch-robot"), "{e}");
    assert!(!e.contains("the twin plays"), "{e}");
    let _ = std::fs::remove_dir_all(&dir);
    // (The geometry check of the CELL.toml model: deflex-sim's twin tests.)
}

/// `deflex cell --sim` refuses anything but loopback, naming the field.
#[test]
fn cell_refuses_non_loopback_addresses() {
    let dir = scratch("cell-nonloop");
    let config = dir.join("cell.toml");
    std::fs::write(
        &config,
        "[robot]\nkind = \"kuka-rsi\"\nbind = \"10.0.0.2:59152\"\npeer = \"10.0.0.3:0\"\n\
         [sensor]\nkind = \"netft\"\naddress = \"127.0.0.1:49152\"\n[model]\nfile = \"tx200\"\n",
    )
    .unwrap();
    let out = cell_sim(&config).args(["--wait-s", "1"]).output().unwrap();
    assert_eq!(out.status.code(), Some(1));
    let e = String::from_utf8_lossy(&out.stderr);
    assert!(e.contains("loopback") && e.contains("robot.bind"), "{e}");
    let _ = std::fs::remove_dir_all(&dir);
}
