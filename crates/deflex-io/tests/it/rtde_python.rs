//! Issue 34's independent check: SDU's `ur_rtde` (PyPI `ur-rtde`, a client deflex did not write)
//! reads the twin's RTDE controller ([`RtdeServer`]): it negotiates protocol version 2 and its
//! output recipe, and every value it prints equals what the server sent for that controller
//! time. Ignored by default; `scripts/check-rtde` installs `ur-rtde` in a virtual environment
//! under target/ and runs it with `DEFLEX_RTDE_PYTHON` naming that environment's python.
//!
//! `ur_rtde` always connects to port 30004, so the server binds 30004 on a loopback address of
//! its own (127.0.0.34, …: Linux routes all of 127/8 to loopback).

use deflex_io::rtde::server::OutputValues;
use deflex_io::rtde::{RtdeServer, Variable};
use std::io::Read;
use std::process::{Command, Stdio};
use std::time::{Duration, Instant};

const SAMPLES: usize = 200;

/// The values of controller cycle `k`: every field a different function of `k`.
fn values_of(k: u64, o: &mut OutputValues) {
    let x = k as f64;
    o.timestamp = x * 0.002;
    o.q = std::array::from_fn(|j| -1.5 + 0.5 * j as f64 + x * 1.3e-4 * (j + 1) as f64);
    o.tcp_pose = [
        0.7 + x * 1e-6,
        -0.1,
        0.25 - x * 2e-6,
        3.1,
        0.05 + x * 1e-7,
        -0.02,
    ];
    o.ft_raw_wrench = [1.5, -2.25, 30.0 + x * 0.01, 0.1, -0.2 + x * 1e-5, 0.03];
    o.robot_mode = 7;
    o.runtime_state = 2;
    o.output_int[36] = k as i32 * 3;
}

#[test]
#[ignore = "needs PyPI's ur-rtde: run by scripts/check-rtde"]
fn sdu_ur_rtde_reads_what_the_twin_s_controller_sends() {
    let python = std::env::var("DEFLEX_RTDE_PYTHON")
        .expect("DEFLEX_RTDE_PYTHON: the python of a virtual environment with ur-rtde");
    let script = concat!(
        env!("CARGO_MANIFEST_DIR"),
        "/tests/python/rtde_client_check.py"
    );
    let (mut server, host) = (34..60)
        .find_map(|last| {
            let host = format!("127.0.0.{last}");
            RtdeServer::bind((host.as_str(), 30004))
                .ok()
                .map(|s| (s, host))
        })
        .expect("no loopback address with port 30004 free");
    server.set_recording(true);
    let mut child = Command::new(python)
        .args([script, &host, &SAMPLES.to_string()])
        .stdout(Stdio::piped())
        .spawn()
        .unwrap();
    let start = Instant::now();
    let mut k = 0u64;
    // Serve until the client exits (hang guard 120 s), a cycle every 4 ms.
    while child.try_wait().unwrap().is_none() {
        assert!(start.elapsed() < Duration::from_secs(120), "ur_rtde hangs");
        server.poll();
        if server.streams(Variable::Timestamp) {
            k += 1;
            values_of(k, &mut server.outputs);
            server.publish();
        }
        std::thread::sleep(Duration::from_millis(4));
    }
    let status = child.wait().unwrap();
    let mut text = String::new();
    child
        .stdout
        .take()
        .unwrap()
        .read_to_string(&mut text)
        .unwrap();
    assert!(status.success(), "ur_rtde client failed: {status}\n{text}");
    let counters = server.counters();
    assert!(
        counters.clients >= 1 && counters.not_found == 0,
        "{counters:?}"
    );
    assert!(counters.output_packages >= SAMPLES as u64, "{counters:?}");
    let sent = server.take_recorded();

    let mut exact = 0;
    let lines: Vec<&str> = text.lines().collect();
    assert_eq!(lines.len(), SAMPLES, "{text}");
    for line in &lines {
        let f: Vec<&str> = line.split(' ').collect();
        assert_eq!(f.len(), 22, "{line}");
        let d: Vec<f64> = f[..19].iter().map(|v| v.parse().unwrap()).collect();
        let i: Vec<i64> = f[19..].iter().map(|v| v.parse().unwrap()).collect();
        let k = (d[0] / 0.002).round() as usize;
        assert!(k >= 1 && k <= sent.len(), "{line}");
        let o = &sent[k - 1];
        assert_eq!(d[0], o.timestamp, "{line}");
        // Each field is the value sent at this time, or (read while the next package arrived)
        // at the neighbouring one; most are all of this time.
        let field_ok = |got: &[f64], want: &dyn Fn(&OutputValues) -> &[f64]| {
            (k.saturating_sub(2)..(k + 1).min(sent.len())).any(|j| got == want(&sent[j]))
        };
        assert!(field_ok(&d[1..7], &|o| &o.q[..]), "actual_q {line}");
        assert!(
            field_ok(&d[7..13], &|o| &o.tcp_pose[..]),
            "actual_TCP_pose {line}"
        );
        assert!(
            field_ok(&d[13..19], &|o| &o.ft_raw_wrench[..]),
            "ft_raw_wrench {line}"
        );
        assert_eq!((i[0], i[1]), (7, 2), "{line}");
        if d[1..7] == o.q[..]
            && d[7..13] == o.tcp_pose[..]
            && d[13..19] == o.ft_raw_wrench[..]
            && i[2] == i64::from(o.output_int[36])
        {
            exact += 1;
        }
    }
    eprintln!(
        "ur_rtde read {} records, {exact} exactly the values sent for their controller time; \
         server: {counters:?}",
        lines.len()
    );
    assert!(
        exact * 100 >= lines.len() * 95,
        "{exact} of {}",
        lines.len()
    );
}
