//! One Stream Motion session of deflex's controller side against a controller at an address:
//! what `scripts/check-fanuc-stream` runs against `airo-fanuc`'s fake controller (PyPI).
//!
//! ```sh
//! cargo run -p deflex-io --example fanuc_stream_session -- 127.0.0.1:60015 0,-20,20,0,30,0
//! ```
//!
//! The second argument is where the path starts (degrees, six axes); the robot may stand up to
//! 20° from it (the link approaches it first). The path moves every axis by a few degrees over
//! 2 s and back, with a small joint correction added on axis 3 (a 0.2° sine), then ends with
//! `is_last_command` and a stop packet. Prints one line of JSON: how the stream ended, the
//! commands answered, the last command and the largest step per axis (degrees). Exit status 0
//! when the stream ran to its end.

use deflex_io::RobotLink;
use deflex_io::fanuc_stream::link::{FanucStreamConfig, FanucStreamLink, StreamPhase};
use deflex_io::fanuc_stream::motion::{StreamLimits, StreamTrajectory};
use std::time::{Duration, Instant};

fn main() {
    let args: Vec<String> = std::env::args().skip(1).collect();
    let (Some(address), Some(start)) = (args.first(), args.get(1)) else {
        eprintln!("usage: fanuc_stream_session CONTROLLER_ADDRESS START_DEG(a,b,c,d,e,f)");
        std::process::exit(2);
    };
    let controller = address
        .parse()
        .expect("a socket address such as 127.0.0.1:60015");
    let start: Vec<f64> = start
        .split(',')
        .map(|v| v.trim().parse::<f64>().expect("six numbers").to_radians())
        .collect();
    assert_eq!(start.len(), 6, "six joint values");
    let start: [f64; 6] = std::array::from_fn(|i| start[i]);
    let period = 0.008;
    let limits = StreamLimits::uniform(1.0, 5.0, 100.0);
    let far: [f64; 6] = std::array::from_fn(|i| start[i] + (3.0 + i as f64).to_radians());
    let trajectory = StreamTrajectory::from_waypoints(
        period,
        0.4,
        &[(0.0, start), (2.0, far), (4.0, start)],
        &limits.scaled(0.75),
    )
    .expect("a path within the limits");
    let mut cfg = FanucStreamConfig::new(controller, period);
    cfg.limits = limits;
    // The fake controller runs in Python on a busy machine: allow its jitter.
    cfg.late_after = Duration::from_millis(250);
    cfg.lost_after = Duration::from_secs(2);
    let mut link = FanucStreamLink::bind("127.0.0.1:0", cfg, trajectory).expect("bind");
    let began = Instant::now();
    let mut k = 0u64;
    while link.phase() != StreamPhase::Done && began.elapsed() < Duration::from_secs(60) {
        match link.receive(Duration::from_millis(100)) {
            Ok(Some(_)) => {
                k += 1;
                let dq = [
                    0.0,
                    0.0,
                    0.2f64.to_radians() * (k as f64 * 0.02).sin(),
                    0.0,
                    0.0,
                    0.0,
                ];
                if let Err(e) = link.send_joint_correction(&dq) {
                    eprintln!("answer: {e}");
                }
            }
            Ok(None) => {}
            Err(e) => eprintln!("receive: {e}"),
        }
    }
    let fmt = |v: [f64; 6]| {
        v.iter()
            .map(|x| format!("{:.9}", x.to_degrees()))
            .collect::<Vec<_>>()
            .join(",")
    };
    let reason = link.stop_reason();
    println!(
        "{{\"phase\":\"{:?}\",\"stop_reason\":\"{:?}\",\"answers\":{},\"superseded\":{},\"last_command_deg\":[{}],\"largest_step_deg\":[{}]}}",
        link.phase(),
        reason,
        link.counters().answers,
        link.superseded(),
        fmt(link.commanded_rad()),
        fmt(link.largest_step_rad()),
    );
    let finished = matches!(reason, Some(r) if !r.is_fault()) && link.phase() == StreamPhase::Done;
    std::process::exit(if finished { 0 } else { 1 });
}
