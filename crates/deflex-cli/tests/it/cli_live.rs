//! What `deflex run`, `deflex cell --sim` and `deflex sim isf` share to watch and record a
//! session, through the real binary: the `--view [ADDR]` value and the MCAP recording's name
//! beside the CSV log.

use crate::cli_run::cell_file;
use crate::support::{cell_sim, scratch};
use std::path::Path;
use std::process::{Command, Output};

/// `deflex cell --sim --config CONFIG --quiet --wait-s 0 EXTRA…`, expected to fail: its stderr.
fn cell_error(config: &Path, extra: &[&str]) -> String {
    let out: Output = cell_sim(config)
        .args(["--wait-s", "0"])
        .args(extra)
        .output()
        .unwrap();
    let err = String::from_utf8_lossy(&out.stderr).into_owned();
    assert_eq!(out.status.code(), Some(1), "{extra:?}: {err}");
    err
}

/// `--view` takes `HOST:PORT` (an IP address or `localhost`) or a bare port on 127.0.0.1, and
/// names anything else; the recording is the log's name with `.mcap`, and a log already named
/// `.mcap` is refused naming the field. The address a `--view` value gives is what the view
/// tries to listen on: the port is held here, so the error names it and no page is served.
#[test]
fn view_addresses_and_recording_names() {
    let dir = scratch("live-names");
    let (config, ..) = cell_file(&dir, "kuka-rsi", "");
    let held = std::net::TcpListener::bind("127.0.0.1:0").unwrap();
    let port = held.local_addr().unwrap().port();
    for (view, address) in [
        (port.to_string(), format!("127.0.0.1:{port}")),
        (format!("localhost:{port}"), format!("127.0.0.1:{port}")),
        (format!("0.0.0.0:{port}"), format!("0.0.0.0:{port}")),
    ] {
        let e = cell_error(&config, &["--view", &view]);
        assert!(
            e.contains(&format!("live view: cannot listen on {address}:")),
            "{view}: {e}"
        );
    }
    drop(held);
    let e = cell_error(&config, &["--view", "example.com:80"]);
    assert!(e.contains("--view") && e.contains("example.com"), "{e}");
    let e = cell_error(&config, &["--view", "70000"]);
    assert!(e.contains("error: --view"), "{e}");
    // The recording beside the log: in a folder that does not exist, its start fails naming it.
    let absent = dir.join("absent");
    for (log, mcap) in [("deflex-run.csv", "deflex-run.mcap"), ("run", "run.mcap")] {
        let e = cell_error(&config, &["--log", absent.join(log).to_str().unwrap()]);
        let named = format!(
            "{}: cannot start the recording",
            absent.join(mcap).display()
        );
        assert!(e.contains(&named), "{log}: {e}");
    }
    // A log named `.mcap`: `deflex run` names `log.path` (its `[log] path`), `cell` its `--log`.
    let (config, ..) = cell_file(&dir, "kuka-rsi", "[log]\npath = \"run.mcap\"\n");
    let out = Command::new(env!("CARGO_BIN_EXE_deflex"))
        .args(["run", "--quiet", "--config", config.to_str().unwrap()])
        .output()
        .unwrap();
    let e = String::from_utf8_lossy(&out.stderr);
    assert_eq!(out.status.code(), Some(1), "{e}");
    assert!(e.contains("log.path") && e.contains("run.mcap"), "{e}");
    let e = cell_error(&config, &["--log", dir.join("run.mcap").to_str().unwrap()]);
    assert!(e.contains("--log") && e.contains("run.mcap"), "{e}");
    assert!(!dir.join("run.mcap").exists());
    let _ = std::fs::remove_dir_all(&dir);
}
