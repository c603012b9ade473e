//! The threaded runtime driving a FANUC Stream Motion link (deflex-io's `fanuc_stream`) on
//! loopback, as `deflex run` drives KUKA RSI's joint answers: the robot side plays the controller
//! (a status every 8 ms, following the commands it accepts, refusing any beyond its thresholds),
//! the Net F/T streams a contact wrench, so the control law's correction is active. The stream
//! must run the whole path with that correction added in joint space, end with
//! `is_last_command` and a stop packet, and the session end as the robot program's end.

use crate::common;

use deflex_io::fanuc_stream::link::{FanucStreamConfig, FanucStreamLink};
use deflex_io::fanuc_stream::motion::{StreamLimits, StreamTrajectory};
use deflex_io::fanuc_stream::robot::FanucStreamRobotEndpoint;
use deflex_io::{RobotSideLink, RobotState};
use deflex_runtime::WallClock;
use deflex_runtime::session::{RuntimeOptions, SessionEnd, spawn};

use std::sync::atomic::Ordering;
use std::time::{Duration, Instant};

const PERIOD_S: f64 = 0.008;

#[test]
fn the_runtime_streams_the_path_with_the_correction_added() {
    let config = common::config();
    let ctrl = common::controller(config);
    let q0 = common::q0();
    let raw = common::raw_reading(&config, &q0, [150.0, -80.0, 800.0, 0.0, 0.0, 0.0]);
    let limits = StreamLimits::uniform(1.0, 5.0, 100.0);
    let mut end = q0;
    end[0] += 0.05;
    end[2] -= 0.03;
    let trajectory = StreamTrajectory::from_waypoints(
        PERIOD_S,
        0.3,
        &[(0.0, q0), (1.5, end)],
        &limits.scaled(0.75),
    )
    .unwrap();
    let last = *trajectory.points().last().unwrap();

    let mut robot = FanucStreamRobotEndpoint::bind("127.0.0.1:0", PERIOD_S, limits).unwrap();
    let mut cfg = FanucStreamConfig::new(robot.local_addr().unwrap(), PERIOD_S);
    cfg.limits = limits;
    // A loaded 2-core machine may delay the robot thread: this test is about the runtime, the
    // late-status rule has its own tests in deflex-io.
    cfg.late_after = Duration::from_secs(1);
    cfg.lost_after = Duration::from_secs(2);
    let link = FanucStreamLink::bind("127.0.0.1:0", cfg, trajectory).unwrap();

    let (client, done, sensor) = common::sensor(raw);
    let robot = std::thread::spawn(move || {
        let start = Instant::now();
        let mut q = q0;
        let mut next = Instant::now();
        while !robot.stopped() && start.elapsed() < Duration::from_secs(20) {
            robot.send_state(&RobotState::with_joints(&q)).unwrap();
            next += Duration::from_secs_f64(PERIOD_S);
            let wait = next.saturating_duration_since(Instant::now());
            let _ = robot.receive_correction(wait.max(Duration::from_micros(200)));
            if let Some(c) = robot.commanded_rad() {
                q = c;
            }
            std::thread::sleep(next.saturating_duration_since(Instant::now()));
            robot.poll().unwrap();
        }
        (robot, q)
    });
    let options = RuntimeOptions {
        robot_cycle_s: PERIOD_S,
        realtime: false,
        startup_timeout_s: 5.0,
        idle_exit_s: Some(0.4),
        ..RuntimeOptions::default()
    };
    let telemetry = common::telemetry(&ctrl);
    let runtime = spawn(
        ctrl,
        Box::new(link),
        Box::new(client),
        WallClock::new(),
        telemetry,
        options,
    )
    .unwrap();
    let (robot, q) = robot.join().unwrap();
    let deadline = Instant::now() + Duration::from_secs(10);
    while !runtime.is_finished() && Instant::now() < deadline {
        std::thread::sleep(Duration::from_millis(20));
    }
    done.store(true, Ordering::Release);
    sensor.join().unwrap();
    runtime.request_stop();
    let summary = runtime.join();
    assert_eq!(summary.error, None, "{summary:?}");
    assert!(robot.saw_last_command(), "no is_last_command");
    assert!(robot.stopped(), "no stop packet");
    let (accepted, refused, foreign) = robot.counts();
    assert_eq!((refused, foreign), (0, 0));
    assert!(accepted > 150, "{accepted}");
    assert_eq!(summary.end, SessionEnd::RobotFinished, "{summary:?}");
    // The control law pushed against the contact wrench (a correction was streamed), and the
    // robot ended near the path's end: at most the bounded correction away from it. How much of
    // the correction is left at the very end depends on how the last cycles were scheduled (a
    // stale wrench on a busy machine ramps it out), so the end is only bounded.
    assert!(summary.max_xi_m > 1e-5, "no correction: {summary:?}");
    let offset = (0..6).map(|i| (q[i] - last[i]).abs()).fold(0.0, f64::max);
    assert!(offset < 0.02, "{offset}");
    eprintln!(
        "{accepted} commands, the path's end offset by the correction {:.3} mrad",
        offset * 1e3
    );
}
