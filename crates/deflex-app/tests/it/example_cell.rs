//! The documented `CELL.toml` (docs/cell.example.toml, the twin's TX200 cell) as a test session
//! runs it: free loopback ports, no real-time privileges, the log `run.csv`, and link timeouts
//! a loaded test machine meets (0.5 s: the real cell's 50 ms latch a fault when the machine
//! holds a process back that long), with its model beside it.
//!
//! One definition for every test binary that runs the example cell: this package's sessions,
//! deflex-cli's `deflex run`/`deflex cell --sim` processes and the facade's live-view cost
//! compile this file by `#[path]`; it uses nothing but the standard library.
#![allow(dead_code)]

use std::path::{Path, PathBuf};

/// A UDP port of 127.0.0.1 that was free a moment ago.
pub fn free_udp_port() -> u16 {
    std::net::UdpSocket::bind("127.0.0.1:0")
        .and_then(|s| s.local_addr())
        .map(|a| a.port())
        .unwrap()
}

/// The example cell (`cell.toml`) and its model (`tx200_cell.toml`) in `dir`; the path of the
/// cell file.
pub fn example_cell_file(dir: &Path) -> PathBuf {
    let docs = Path::new(env!("CARGO_MANIFEST_DIR")).join("../../docs");
    let text = std::fs::read_to_string(docs.join("cell.example.toml"))
        .unwrap()
        .replace("127.0.0.1:59152", &format!("127.0.0.1:{}", free_udp_port()))
        .replace("127.0.0.1:49152", &format!("127.0.0.1:{}", free_udp_port()))
        .replace("realtime = true", "realtime = false")
        .replace("lock_memory = true", "lock_memory = false")
        .replace("path = \"deflex-run.csv\"", "path = \"run.csv\"")
        .replace("timeout_s = 0.05", "timeout_s = 0.5");
    assert!(text.contains("path = \"run.csv\"") && !text.contains("timeout_s = 0.05"));
    std::fs::copy(docs.join("tx200_cell.toml"), dir.join("tx200_cell.toml")).unwrap();
    let path = dir.join("cell.toml");
    std::fs::write(&path, text).unwrap();
    path
}
