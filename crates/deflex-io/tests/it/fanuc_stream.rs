//! FANUC Stream Motion: the packets against layouts written out here byte by byte (FANUC's
//! tables, not the codec's own writer), the motion planning and limiter against their limits,
//! and whole sessions of the controller side against the robot side over loopback UDP,
//! including the faults that must stop the stream safely.

#![allow(clippy::needless_range_loop)]

use deflex_io::fanuc_stream::link::{FanucStreamConfig, FanucStreamLink, StopReason, StreamPhase};
use deflex_io::fanuc_stream::motion::{
    AXES, Approach, MotionLimiter, SMOOTHING_CYCLES, StreamLimits, StreamTrajectory,
    TrajectoryError,
};
use deflex_io::fanuc_stream::robot::FanucStreamRobotEndpoint;
use deflex_io::fanuc_stream::*;
use deflex_io::{LinkError, RobotLink, RobotSideLink, RobotState};
use std::net::UdpSocket;
use std::time::Duration;

// ---------------------------------------------------------------- packets

fn be32(b: &mut Vec<u8>, v: u32) {
    b.extend_from_slice(&v.to_be_bytes());
}

/// A status packet written field by field after FANUC's table (type, version, sequence, four
/// status bytes, time stamp, 9 positions, 9 joint angles, 9 currents as floats, the safety
/// scale, 256 I/O bytes).
fn status_bytes(kind: u32, seq: u32, status: u8, robot: u8, joints: [f32; 9]) -> Vec<u8> {
    let mut b = Vec::new();
    be32(&mut b, kind);
    be32(&mut b, 3);
    be32(&mut b, seq);
    b.extend_from_slice(&[status, robot, 0, 0]);
    be32(&mut b, 1234);
    for i in 0..9 {
        be32(&mut b, (100.0f32 + i as f32).to_bits());
    }
    for j in joints {
        be32(&mut b, j.to_bits());
    }
    for i in 0..9 {
        be32(&mut b, (0.5f32 * i as f32).to_bits());
    }
    be32(&mut b, 1.0f32.to_bits());
    b.extend_from_slice(&[0u8; 256]);
    b
}

#[test]
fn packet_sizes_follow_fanucs_tables() {
    assert_eq!(CONTROL_LEN, 8);
    assert_eq!(THRESHOLD_REQUEST_LEN, 16);
    assert_eq!(THRESHOLD_TABLE_LEN, 184);
    assert_eq!(COMMAND_LEN, 344);
    assert_eq!(STATUS_LEN, 388);
    assert_eq!(STATUS_FORCE_LEN, 416);
}

#[test]
fn start_and_stop_are_type_and_version_big_endian() {
    let mut out = [0u8; 16];
    assert_eq!(format_start(3, &mut out).unwrap(), 8);
    assert_eq!(&out[..8], &[0, 0, 0, 200, 0, 0, 0, 3]);
    assert_eq!(
        parse_control(&out[..8]).unwrap(),
        Control::Start { version: 3 }
    );
    assert_eq!(format_stop(3, &mut out).unwrap(), 8);
    assert_eq!(&out[..8], &[0, 0, 0, 2, 0, 0, 0, 3]);
    assert_eq!(
        parse_control(&out[..8]).unwrap(),
        Control::Stop { version: 3 }
    );
    assert!(format_start(3, &mut out[..7]).is_err());
}

#[test]
fn command_layout_byte_by_byte() {
    let mut joints = [0.0; MAX_AXES];
    joints[0] = 12.5;
    joints[5] = -90.25;
    let c = Command {
        version: 3,
        sequence: 0x0102_0304,
        is_last: true,
        joints_deg: joints,
    };
    let mut out = [0xAAu8; 400];
    assert_eq!(format_command(&c, &mut out).unwrap(), 344);
    assert_eq!(&out[0..4], &[0, 0, 0, 201]);
    assert_eq!(&out[4..8], &[0, 0, 0, 3]);
    assert_eq!(&out[8..12], &[1, 2, 3, 4]);
    // is_last_command, do_motn_ctrl, data style 0xFFFF (joint angles).
    assert_eq!(&out[12..16], &[1, 1, 0xFF, 0xFF]);
    assert_eq!(&out[16..24], &12.5f64.to_be_bytes());
    assert_eq!(&out[56..64], &(-90.25f64).to_be_bytes());
    assert!(out[88..344].iter().all(|b| *b == 0), "I/O block zero");
    assert_eq!(parse_command(&out[..344]).unwrap(), c);
    // A zero data style would be read as a Cartesian pose by the controller: refused.
    let mut cartesian = out;
    cartesian[14] = 0;
    cartesian[15] = 0;
    assert!(parse_command(&cartesian[..344]).is_err());
    let mut nan = c;
    nan.joints_deg[2] = f64::NAN;
    assert!(matches!(
        format_command(&nan, &mut out),
        Err(LinkError::InvalidValue { .. })
    ));
}

#[test]
fn status_read_from_fanucs_layout() {
    let mut joints = [0.0f32; 9];
    joints[0] = 10.0;
    joints[1] = -20.5;
    joints[5] = 180.0;
    let b = status_bytes(202, 77, 0x0F, 0, joints);
    assert_eq!(b.len(), 388);
    let s = parse_status(&b).unwrap();
    assert_eq!(s.sequence, 77);
    assert_eq!(s.version, 3);
    assert_eq!(s.time_ms, 1234);
    assert_eq!(s.joints_deg, joints);
    assert_eq!(s.position[2], 102.0);
    assert_eq!(s.current[4], 2.0);
    assert_eq!(s.safety_scale, 1.0);
    assert!(s.accepts_commands());
    assert!(!s.in_error());
    // The codec's own writer produces the same bytes.
    let mut out = [0u8; 400];
    assert_eq!(format_status(&s, &mut out).unwrap(), 388);
    assert_eq!(&out[..388], &b[..]);
    // Old controllers' type 0, and 204 with its force block.
    assert!(parse_status(&status_bytes(0, 1, 0, 0, joints)).is_ok());
    let mut force = status_bytes(204, 1, 0, 0, joints);
    force.extend_from_slice(&[0u8; 28]);
    assert_eq!(parse_status(&force).unwrap().joints_deg, joints);
    // Error and e-stop bits.
    let e = parse_status(&status_bytes(202, 2, 0x0F, ROBOT_ERROR, joints)).unwrap();
    assert!(e.in_error() && !e.accepts_commands());
    let e = parse_status(&status_bytes(202, 2, 0x0F, ROBOT_ESTOP, joints)).unwrap();
    assert!(e.in_error());
}

#[test]
fn every_bad_status_is_an_error_not_a_panic() {
    let joints = [1.0f32; 9];
    let good = status_bytes(202, 5, 0x0F, 0, joints);
    assert!(matches!(
        parse_status(&good[..387]),
        Err(LinkError::Truncated {
            expected: 388,
            got: 387,
            ..
        })
    ));
    let mut long = good.clone();
    long.push(0);
    assert!(parse_status(&long).is_err());
    assert!(parse_status(&good[..3]).is_err());
    let mut wrong = good.clone();
    wrong[3] = 201;
    assert!(parse_status(&wrong).is_err());
    let mut version = good.clone();
    version[7] = 99;
    assert!(parse_status(&version).is_err());
    let mut nan = joints;
    nan[3] = f32::NAN;
    assert!(parse_status(&status_bytes(202, 5, 0x0F, 0, nan)).is_err());
    let mut inf = joints;
    inf[0] = f32::INFINITY;
    assert!(parse_status(&status_bytes(202, 5, 0x0F, 0, inf)).is_err());
}

#[test]
fn threshold_packets_round_trip_and_give_their_tightest_entry() {
    let r = ThresholdRequest {
        version: 3,
        axis: 4,
        kind: ThresholdKind::Jerk,
    };
    let mut out = [0u8; 200];
    assert_eq!(format_threshold_request(&r, &mut out).unwrap(), 16);
    assert_eq!(
        &out[..16],
        &[0, 0, 0, 3, 0, 0, 0, 3, 0, 0, 0, 4, 0, 0, 0, 2]
    );
    assert_eq!(parse_threshold_request(&out[..16]).unwrap(), r);
    let mut bad = out;
    bad[11] = 10;
    assert!(parse_threshold_request(&bad[..16]).is_err());
    assert!(format_threshold_request(&ThresholdRequest { axis: 0, ..r }, &mut out).is_err());
    let mut no_payload = [200.0f32; THRESHOLD_ENTRIES];
    no_payload[7] = 150.0;
    let mut full_payload = [180.0f32; THRESHOLD_ENTRIES];
    full_payload[19] = 120.0;
    let t = ThresholdTable {
        version: 3,
        axis: 2,
        kind: ThresholdKind::Velocity,
        max_cartesian_speed: 2000,
        interval: 100,
        no_payload,
        full_payload,
    };
    assert_eq!(format_threshold_table(&t, &mut out).unwrap(), 184);
    assert_eq!(&out[16..24], &[0, 0, 7, 208, 0, 0, 0, 100]);
    assert_eq!(&out[24 + 28..24 + 32], &150.0f32.to_be_bytes());
    let back = parse_threshold_table(&out[..184]).unwrap();
    assert_eq!(back, t);
    assert_eq!(back.tightest(), 120.0);
    // A zero limit would stop nothing: refused.
    out[24..28].copy_from_slice(&0.0f32.to_be_bytes());
    assert!(parse_threshold_table(&out[..184]).is_err());
}

// ---------------------------------------------------------------- motion

const T: f64 = 0.008;

fn limits() -> StreamLimits {
    StreamLimits::uniform(1.0, 5.0, 100.0)
}

/// Velocity, acceleration and jerk of a command sequence, the largest per kind over all axes,
/// as fractions of `l`.
fn peaks(q: &[[f64; AXES]], l: &StreamLimits) -> [f64; 3] {
    let mut p = [0.0f64; 3];
    for k in 1..q.len() {
        for i in 0..AXES {
            let v = (q[k][i] - q[k - 1][i]) / T;
            p[0] = p[0].max(v.abs() / l.velocity[i]);
            if k >= 2 {
                let a = (q[k][i] - 2.0 * q[k - 1][i] + q[k - 2][i]) / (T * T);
                p[1] = p[1].max(a.abs() / l.acceleration[i]);
            }
            if k >= 3 {
                let j =
                    (q[k][i] - 3.0 * q[k - 1][i] + 3.0 * q[k - 2][i] - q[k - 3][i]) / (T * T * T);
                p[2] = p[2].max(j.abs() / l.jerk[i]);
            }
        }
    }
    p
}

#[test]
fn braking_from_full_speed_keeps_every_limit_and_reaches_rest() {
    let l = limits();
    let mut m = MotionLimiter::new(T, l, [0.0; AXES]);
    // Accelerate towards a far target until at full speed on every axis.
    let mut q = vec![m.position()];
    for _ in 0..400 {
        q.push(m.step_towards(&[10.0, -10.0, 10.0, -10.0, 10.0, 10.0]));
    }
    assert!((m.velocity()[0] - 1.0).abs() < 1e-9, "{:?}", m.velocity());
    let p = peaks(&q, &l);
    assert!(p[0] <= 1.0 + 1e-9 && p[1] <= 1.0 + 1e-9, "{p:?}");
    // From full speed (the last three commands at constant velocity) to rest: every limit,
    // jerk included.
    let mut stop = q[q.len() - 3..].to_vec();
    let mut cycles = 0;
    while !m.at_rest() {
        stop.push(m.brake());
        cycles += 1;
        assert!(cycles < 1000, "never came to rest");
    }
    let p = peaks(&stop, &l);
    assert!(p.iter().all(|x| *x <= 1.0 + 1e-9), "{p:?}");
    // At least the time a jerk-limited stop from 1 rad/s needs: v/a + a/j = 0.25 s.
    assert!(cycles as f64 * T >= 0.25, "{cycles}");
    // Holds at rest.
    let held = m.brake();
    assert_eq!(held, m.brake());
}

#[test]
fn a_jump_of_the_target_is_never_followed_faster_than_the_limits() {
    let l = limits();
    let mut m = MotionLimiter::new(T, l, [0.0; AXES]);
    let mut q = vec![m.position()];
    for k in 0..300 {
        let target = if (k / 40) % 2 == 0 { 0.5 } else { -0.3 };
        q.push(m.step_towards(&[target; AXES]));
    }
    let p = peaks(&q, &l);
    assert!(p[0] <= 1.0 + 1e-9 && p[1] <= 1.0 + 1e-9, "{p:?}");
}

#[test]
fn the_approach_is_within_the_limits_and_ends_at_the_path_start() {
    let l = limits();
    let from = [0.0, 0.1, -0.2, 0.0, 0.3, 0.0];
    let to = [0.2, 0.1, 0.1, -0.1, 0.3, 0.05];
    let a = Approach::new(from, to, T, &l);
    let q: Vec<_> = (0..=a.cycles()).map(|k| a.at(k)).collect();
    assert_eq!(q[0], from);
    for i in 0..AXES {
        assert!((q.last().unwrap()[i] - to[i]).abs() < 1e-15);
    }
    let p = peaks(&q, &l);
    assert!(p.iter().all(|x| *x <= 1.0), "{p:?}");
    // Not needlessly slow: one of the three limits is nearly reached.
    assert!(p.iter().any(|x| *x > 0.8), "{p:?}");
}

#[test]
fn a_trajectory_starts_and_ends_at_rest_on_its_waypoints_path() {
    let l = limits();
    let w = [
        (0.0, [0.0, 0.0, 0.0, 0.0, 0.0, 0.0]),
        (1.0, [0.2, 0.1, 0.0, 0.0, 0.0, 0.0]),
        (2.0, [0.4, 0.18, -0.1, 0.0, 0.0, 0.0]),
    ];
    let t = StreamTrajectory::from_waypoints(T, 0.4, &w, &l).unwrap();
    let q = t.points();
    let held = 6.0 * (SMOOTHING_CYCLES / 2) as f64 * T;
    assert!(
        (t.duration_s() - 2.4 - held).abs() < T,
        "{}",
        t.duration_s()
    );
    for i in 0..AXES {
        assert!((q[0][i] - w[0].1[i]).abs() < 1e-15);
        assert!((q[q.len() - 1][i] - w[2].1[i]).abs() < 1e-15);
    }
    // At rest at both ends: the first and last steps are tiny.
    assert!((q[1][0] - q[0][0]).abs() < 1e-6);
    assert!((q[q.len() - 1][0] - q[q.len() - 2][0]).abs() < 1e-6);
    // Every sample lies on the waypoints' polyline (axes 1 and 2 move together on the first
    // segment, then axes 1, 2 and 3), except near the corner, rounded by the smoothing.
    let mut rounded = 0;
    for p in q {
        let off = if p[0] <= 0.2 {
            (p[1] - p[0] / 2.0).abs().max(p[2].abs())
        } else {
            let u = (p[0] - 0.2) / 0.2;
            (p[1] - (0.1 + 0.08 * u)).abs().max((p[2] + 0.1 * u).abs())
        };
        if off > 1e-9 {
            rounded += 1;
            assert!(
                (p[0] - 0.2).abs() < 0.03,
                "off the polyline away from the corner"
            );
            assert!(off < 2e-3, "{off}");
        }
    }
    assert!(rounded > 0 && rounded < 30, "{rounded}");
    let pk = peaks(q, &l);
    assert!(pk.iter().all(|x| *x <= 1.0), "{pk:?}");
    // A sharp corner needs more acceleration than the limit: refused.
    let corner = [
        (0.0, [0.0; AXES]),
        (0.5, [0.0, 0.3, 0.0, 0.0, 0.0, 0.0]),
        (1.0, [0.0; AXES]),
    ];
    assert!(matches!(
        StreamTrajectory::from_waypoints(T, 0.4, &corner, &l),
        Err(TrajectoryError::BeyondLimit { axis: 2, .. })
    ));
    // Too fast for the limits: refused with the axis and values.
    let fast = [(0.0, [0.0; AXES]), (0.1, [0.5, 0.0, 0.0, 0.0, 0.0, 0.0])];
    assert!(matches!(
        StreamTrajectory::from_waypoints(T, 0.05, &fast, &l),
        Err(TrajectoryError::BeyondLimit { axis: 1, .. })
    ));
    let backwards = [(1.0, [0.0; AXES]), (0.5, [0.0; AXES])];
    assert!(matches!(
        StreamTrajectory::from_waypoints(T, 0.1, &backwards, &l),
        Err(TrajectoryError::BadWaypoint { index: 1 })
    ));
}

// ---------------------------------------------------------------- sessions over loopback

const WAIT: Duration = Duration::from_secs(2);

fn path() -> StreamTrajectory {
    let w = [
        (0.0, [0.0, -0.5, 0.5, 0.0, 0.4, 0.0]),
        (1.5, [0.3, -0.4, 0.45, 0.05, 0.4, 0.1]),
    ];
    StreamTrajectory::from_waypoints(T, 0.3, &w, &limits()).unwrap()
}

struct Cell {
    link: FanucStreamLink,
    robot: FanucStreamRobotEndpoint,
    q: [f64; AXES],
    commands: Vec<[f64; AXES]>,
}

impl Cell {
    /// A link with `cfg` changes and a robot side with thresholds `robot_limits`, the robot
    /// standing at `q`.
    fn new(
        q: [f64; AXES],
        robot_limits: StreamLimits,
        tune: impl FnOnce(&mut FanucStreamConfig),
    ) -> Cell {
        let robot = FanucStreamRobotEndpoint::bind("127.0.0.1:0", T, robot_limits).unwrap();
        let mut cfg = FanucStreamConfig::new(robot.local_addr().unwrap(), T);
        cfg.limits = limits();
        // Generous (a loaded 2-core machine may hold this thread back): the tests that want a
        // late status make one on purpose.
        cfg.late_after = Duration::from_secs(1);
        cfg.lost_after = Duration::from_secs(2);
        tune(&mut cfg);
        let link = FanucStreamLink::bind("127.0.0.1:0", cfg, path()).unwrap();
        Cell {
            link,
            robot,
            q,
            commands: Vec::new(),
        }
    }

    /// Sends the start packet (the robot side takes it at its next status).
    fn start(&mut self) {
        assert!(
            self.link
                .receive(Duration::from_millis(1))
                .unwrap()
                .is_none()
        );
        assert_eq!(self.link.phase(), StreamPhase::Starting);
    }

    /// One cycle: status, the link's answer with `dq`, the robot follows what it accepted.
    /// Returns false once the robot sends no more status.
    fn cycle(&mut self, dq: [f64; AXES]) -> bool {
        self.robot
            .send_state(&RobotState::with_joints(&self.q))
            .unwrap();
        let state = loop {
            match self.link.receive(WAIT) {
                Ok(Some(s)) => break s,
                Ok(None) => return false,
                Err(e) if e.is_foreign() => continue,
                Err(e) => panic!("{e}"),
            }
        };
        for i in 0..AXES {
            assert!((state.q_rad[i] - self.q[i]).abs() < 1e-5);
        }
        self.link.send_joint_correction(&dq).unwrap();
        if self.link.phase() == StreamPhase::Done {
            return false;
        }
        let got = self.robot.receive_correction(WAIT).unwrap();
        assert!(got.is_some(), "the link answered every status");
        self.commands.push(self.link.commanded_rad());
        if let Some(c) = self.robot.commanded_rad() {
            self.q = c;
        }
        true
    }

    /// Cycles until the stream is over (bounded).
    fn run_out(&mut self, dq: [f64; AXES]) {
        for _ in 0..2000 {
            if !self.cycle(dq) {
                break;
            }
        }
        assert_eq!(self.link.phase(), StreamPhase::Done);
        self.robot.poll().unwrap();
        assert!(self.robot.stopped(), "stop packet received");
    }

    /// Runs until `k` path cycles were streamed.
    fn stream_into_path(&mut self, k: usize) {
        let mut path_cycles = 0;
        for _ in 0..2000 {
            assert!(self.cycle([0.0; AXES]));
            if self.link.phase() == StreamPhase::Path {
                path_cycles += 1;
                if path_cycles == k {
                    return;
                }
            }
        }
        panic!("never reached the path");
    }
}

fn start_pose() -> [f64; AXES] {
    path().points()[0]
}

#[test]
fn a_session_approaches_streams_the_path_and_ends_with_last_command_and_stop() {
    let mut from = start_pose();
    from[1] += 0.05;
    from[4] -= 0.03;
    let mut cell = Cell::new(from, limits(), |_| {});
    cell.start();
    cell.run_out([0.0; AXES]);
    assert_eq!(cell.link.stop_reason(), Some(StopReason::Finished));
    assert!(cell.robot.saw_last_command());
    let (accepted, refused, foreign) = cell.robot.counts();
    assert_eq!((refused, foreign), (0, 0));
    // The approach took cycles, then the whole path was streamed.
    assert!(accepted as usize > path().len() + 10, "{accepted}");
    let last = *path().points().last().unwrap();
    for i in 0..AXES {
        assert!((cell.q[i] - last[i]).abs() < 1e-9, "axis {i}");
    }
    let p = peaks(&cell.commands, &limits());
    assert!(p[0] <= 1.0 + 1e-9 && p[1] <= 1.0 + 1e-9, "{p:?}");
    let c = cell.link.counters();
    assert_eq!(c.answers, accepted);
    assert_eq!(c.foreign, 0);
}

#[test]
fn the_correction_is_added_to_the_path_in_joint_space() {
    let mut cell = Cell::new(start_pose(), limits(), |_| {});
    cell.start();
    let dq = [0.0, 0.0, 0.004, 0.0, -0.002, 0.0];
    cell.run_out(dq);
    let last = *path().points().last().unwrap();
    for i in 0..AXES {
        assert!((cell.q[i] - (last[i] + dq[i])).abs() < 1e-7, "axis {i}");
    }
    // Bounded per axis: a correction of 1 rad is cut to max_correction_rad.
    let mut cell = Cell::new(start_pose(), limits(), |c| c.max_correction_rad = 0.01);
    cell.start();
    cell.run_out([0.0, 1.0, 0.0, 0.0, 0.0, 0.0]);
    assert!((cell.q[1] - (last[1] + 0.01)).abs() < 1e-7);
    assert_eq!(cell.robot.counts().1, 0, "no command refused");
}

/// Checks what follows a fault at command `from`: every step within the velocity,
/// acceleration and jerk limits, the speed grows at most by what taking a positive
/// acceleration back at the jerk limit adds (a²/2j), the command comes to rest within the
/// time a jerk-limited stop from full speed takes (v/a + a/j, plus four cycles), the robot
/// refused nothing and saw the last command.
fn assert_braked(cell: &Cell, from: usize) {
    let l = limits();
    let q = &cell.commands;
    let p = peaks(&q[from.saturating_sub(3)..], &l);
    assert!(p.iter().all(|x| *x <= 1.0 + 1e-9), "{p:?}");
    let speed = |k: usize, i: usize| (q[k][i] - q[k - 1][i]).abs() / T;
    for i in 0..AXES {
        let at_fault = speed(from, i);
        let growth = l.acceleration[i].powi(2) / (2.0 * l.jerk[i]);
        for k in from + 1..q.len() {
            assert!(speed(k, i) <= at_fault + growth + 1e-9, "axis {i} at {k}");
        }
    }
    let bound = 1.0 / 5.0 + 5.0 / 100.0;
    let stopping = (q.len() - from) as f64 * T;
    assert!(stopping <= bound + 4.0 * T, "{stopping} s to stop");
    assert!(q.len() - from > 2, "not an instant stop");
    assert_eq!(cell.robot.counts().1, 0, "the robot refused a command");
    assert!(cell.robot.saw_last_command());
}

#[test]
fn a_late_status_stops_the_stream_within_the_limits() {
    let mut cell = Cell::new(start_pose(), limits(), |c| {
        c.late_after = Duration::from_millis(300);
    });
    cell.start();
    cell.stream_into_path(60);
    let at = cell.commands.len();
    // The next status comes late: three times the allowance.
    std::thread::sleep(Duration::from_millis(900));
    assert!(cell.cycle([0.0; AXES]));
    assert!(matches!(
        cell.link.stop_reason(),
        Some(StopReason::LateStatus { gap_s }) if gap_s >= 0.9
    ));
    assert_eq!(cell.link.phase(), StreamPhase::Stopping);
    cell.run_out([0.0; AXES]);
    assert_braked(&cell, at);
    // It stopped short of the path's end.
    let last = *path().points().last().unwrap();
    assert!((cell.q[0] - last[0]).abs() > 0.05);
}

#[test]
fn the_controllers_error_bit_stops_the_stream() {
    // The robot's thresholds are tighter than the link's: the first fast command is refused,
    // the controller latches its error bit, the link stops.
    let tight = StreamLimits::uniform(0.05, 5.0, 100.0);
    let mut cell = Cell::new(start_pose(), tight, |_| {});
    cell.start();
    for _ in 0..2000 {
        if !cell.cycle([0.0; AXES]) {
            break;
        }
    }
    assert!(matches!(
        cell.link.stop_reason(),
        Some(StopReason::ControllerError { robot_status, .. }) if robot_status & ROBOT_ERROR != 0
    ));
    let fault = cell.robot.fault().unwrap();
    assert_eq!(fault.what, "velocity");
    assert!(fault.value > 0.05);
    // The robot held its last accepted command: it stood still from the refusal on.
    assert_eq!(cell.link.phase(), StreamPhase::Done);
}

#[test]
fn the_controllers_thresholds_tighten_the_streams_limits() {
    // The same tight controller, but its tables are read first: the stream keeps them and
    // the path (too fast for them) is refused before anything moves.
    let tight = StreamLimits::uniform(0.5, 2.0, 50.0);
    let mut cell = Cell::new(start_pose(), tight, |c| c.threshold_margin = 0.9);
    // The robot side answers threshold requests when it polls: serve it from a thread.
    let robot_addr = cell.robot.local_addr().unwrap();
    let mut robot = std::mem::replace(
        &mut cell.robot,
        FanucStreamRobotEndpoint::bind("127.0.0.1:0", T, limits()).unwrap(),
    );
    let stop = std::sync::Arc::new(std::sync::atomic::AtomicBool::new(false));
    let flag = stop.clone();
    let server = std::thread::spawn(move || {
        while !flag.load(std::sync::atomic::Ordering::SeqCst) {
            robot.poll().unwrap();
            std::thread::sleep(Duration::from_millis(1));
        }
        robot
    });
    assert!(cell.link.query_thresholds(WAIT).unwrap());
    stop.store(true, std::sync::atomic::Ordering::SeqCst);
    cell.robot = server.join().unwrap();
    assert_eq!(cell.robot.local_addr().unwrap(), robot_addr);
    assert!(cell.link.thresholds_from_controller());
    let l = cell.link.limits();
    for i in 0..AXES {
        assert!((l.velocity[i] - 0.45).abs() < 1e-6, "{l:?}");
        assert!((l.acceleration[i] - 1.8).abs() < 1e-6);
        assert!((l.jerk[i] - 45.0).abs() < 1e-5);
    }
    // Streaming with these limits: the robot refuses nothing.
    cell.start();
    cell.run_out([0.0; AXES]);
    assert_eq!(cell.robot.counts().1, 0);
}

#[test]
fn a_status_from_another_host_is_refused_and_stops_the_stream() {
    let mut cell = Cell::new(start_pose(), limits(), |_| {});
    cell.start();
    cell.stream_into_path(40);
    let at = cell.commands.len();
    // Someone else sends a well-formed status telling the robot stands elsewhere.
    let intruder = UdpSocket::bind("127.0.0.1:0").unwrap();
    let fake = status_bytes(202, 100_000, 0x0F, 0, [90.0; 9]);
    intruder
        .send_to(&fake, cell.link.local_addr().unwrap())
        .unwrap();
    let err = cell.link.receive(WAIT).unwrap_err();
    assert!(err.is_foreign(), "{err}");
    assert!(matches!(
        cell.link.stop_reason(),
        Some(StopReason::ForeignStatus { from }) if from == intruder.local_addr().unwrap()
    ));
    cell.run_out([0.0; AXES]);
    assert_braked(&cell, at);
    assert_eq!(cell.link.counters().foreign, 1);
    // The intruder's joints (90°) never entered a command.
    assert!(cell.commands.iter().flatten().all(|q| q.abs() < 1.0));
}

#[test]
fn a_lost_link_sends_the_stop_packet() {
    let mut cell = Cell::new(start_pose(), limits(), |c| {
        c.lost_after = Duration::from_millis(100);
    });
    cell.start();
    cell.stream_into_path(20);
    // The controller falls silent.
    std::thread::sleep(Duration::from_millis(150));
    assert!(
        cell.link
            .receive(Duration::from_millis(20))
            .unwrap()
            .is_none()
    );
    assert!(matches!(
        cell.link.stop_reason(),
        Some(StopReason::LostLink { silent_s }) if silent_s >= 0.1
    ));
    assert_eq!(cell.link.phase(), StreamPhase::Done);
    cell.robot.poll().unwrap();
    assert!(cell.robot.stopped());
    // Nothing more is commanded.
    assert!(cell.link.send_joint_correction(&[0.0; AXES]).is_err());
}

#[test]
fn a_robot_too_far_from_the_path_start_is_held_not_moved() {
    let mut from = start_pose();
    from[2] += 0.5;
    let mut cell = Cell::new(from, limits(), |_| {});
    cell.start();
    cell.run_out([0.0; AXES]);
    assert!(matches!(
        cell.link.stop_reason(),
        Some(StopReason::StartTooFar { axis: 3, distance_rad }) if (distance_rad - 0.5).abs() < 1e-5
    ));
    assert_eq!(cell.commands.len(), 1, "one hold, the last");
    for i in 0..AXES {
        assert!((cell.q[i] - from[i]).abs() < 1e-6);
    }
}

#[test]
fn a_wild_correction_never_steps_beyond_the_limits() {
    // The robot checks velocity, acceleration and jerk against the link's own limits.
    let mut cell = Cell::new(start_pose(), limits(), |c| {
        c.max_correction_rad = 0.05;
    });
    cell.start();
    let mut sign = 1.0;
    for k in 0..3000 {
        if k % 7 == 0 {
            sign = -sign;
        }
        if !cell.cycle([sign * 0.05; AXES]) {
            break;
        }
    }
    let p = peaks(&cell.commands, &limits());
    assert!(p.iter().all(|x| *x <= 1.0 + 1e-9), "{p:?}");
    assert_eq!(cell.robot.counts().1, 0);
    assert_eq!(cell.link.stop_reason(), Some(StopReason::Finished));
    // A non-finite correction stops the stream.
    let mut cell = Cell::new(start_pose(), limits(), |_| {});
    cell.start();
    cell.stream_into_path(10);
    assert!(cell.cycle([f64::NAN; AXES]));
    assert_eq!(cell.link.stop_reason(), Some(StopReason::InvalidCorrection));
    cell.run_out([0.0; AXES]);
    assert_eq!(cell.robot.counts().1, 0);
}

#[test]
fn statuses_queued_behind_a_stall_are_answered_once_by_the_newest() {
    let mut cell = Cell::new(start_pose(), limits(), |_| {});
    cell.start();
    cell.stream_into_path(5);
    // Two statuses arrive together (the controller's first answer was delayed): only the
    // newest is answered, so no two commands leave back to back.
    let state = RobotState::with_joints(&cell.q);
    cell.robot.send_state(&state).unwrap();
    cell.robot.send_state(&state).unwrap();
    let s = cell.link.receive(WAIT).unwrap().unwrap();
    assert_eq!(cell.link.superseded(), 1);
    cell.link.send_joint_correction(&[0.0; AXES]).unwrap();
    let answer = cell.robot.receive_correction(WAIT).unwrap().unwrap();
    assert_eq!(answer.cycle_id, s.cycle_id);
    assert!(
        cell.robot
            .receive_correction(Duration::from_millis(50))
            .unwrap()
            .is_none(),
        "one command only"
    );
    assert!(matches!(
        cell.link.send_joint_correction(&[0.0; AXES]),
        Err(LinkError::InvalidValue { .. })
    ));
}

/// A controller written here from FANUC's tables (raw packets on a socket, not deflex's robot
/// side): not ready yet, then ready; a replayed status, a malformed one and a status with the
/// error bit, each from the controller's own address.
#[test]
fn a_hand_written_controller_not_ready_replayed_malformed_and_in_error() {
    let controller = UdpSocket::bind("127.0.0.1:0").unwrap();
    controller
        .set_read_timeout(Some(Duration::from_secs(2)))
        .unwrap();
    let mut cfg = FanucStreamConfig::new(controller.local_addr().unwrap(), T);
    cfg.limits = limits();
    cfg.late_after = Duration::from_secs(1);
    let mut link = FanucStreamLink::bind("127.0.0.1:0", cfg, path()).unwrap();
    let pc = link.local_addr().unwrap();
    assert!(link.receive(Duration::from_millis(1)).unwrap().is_none());
    let mut buf = [0u8; 1024];
    let (n, from) = controller.recv_from(&mut buf).unwrap();
    assert_eq!(from, pc);
    assert_eq!(&buf[..n], &[0, 0, 0, 200, 0, 0, 0, 3], "the start packet");
    let start_deg: [f32; 9] = std::array::from_fn(|i| {
        if i < AXES {
            start_pose()[i].to_degrees() as f32
        } else {
            0.0
        }
    });
    let send = |seq: u32, status: u8, robot: u8| {
        controller
            .send_to(&status_bytes(202, seq, status, robot, start_deg), pc)
            .unwrap();
    };
    let read_command = |c: &UdpSocket| {
        let mut b = [0u8; 1024];
        let (n, _) = c.recv_from(&mut b).unwrap();
        parse_command(&b[..n]).unwrap()
    };
    // Not ready (IBGN start not reached): held at the reported joints, still starting.
    send(1, STATUS_SYSRDY, 0);
    link.receive(WAIT).unwrap().unwrap();
    link.send_joint_correction(&[0.0; AXES]).unwrap();
    let hold = read_command(&controller);
    assert_eq!(hold.sequence, 1);
    assert!(!hold.is_last);
    for i in 0..AXES {
        assert!((hold.joints_deg[i] - f64::from(start_deg[i])).abs() < 1e-9);
    }
    assert_eq!(link.phase(), StreamPhase::Starting);
    // Ready: the motion begins.
    send(2, STATUS_READY | STATUS_SYSRDY, 0);
    link.receive(WAIT).unwrap().unwrap();
    link.send_joint_correction(&[0.0; AXES]).unwrap();
    assert_eq!(read_command(&controller).sequence, 2);
    assert_ne!(link.phase(), StreamPhase::Starting);
    // A replay of status 2: dropped unanswered.
    send(2, STATUS_READY | STATUS_SYSRDY, 0);
    let e = link.receive(WAIT).unwrap_err();
    assert!(e.is_dropped(), "{e}");
    // A truncated packet from the controller: a bad packet, the link stays usable.
    controller.send_to(&[0, 0, 0, 202, 0, 0], pc).unwrap();
    assert!(link.receive(WAIT).unwrap_err().is_bad_packet());
    // The error bit: the stream stops, braking, then the last command.
    send(3, STATUS_READY | STATUS_SYSRDY, ROBOT_ERROR);
    link.receive(WAIT).unwrap().unwrap();
    assert!(matches!(
        link.stop_reason(),
        Some(StopReason::ControllerError {
            robot_status: ROBOT_ERROR,
            ..
        })
    ));
    let mut seq = 3;
    loop {
        link.send_joint_correction(&[0.0; AXES]).unwrap();
        let c = read_command(&controller);
        assert_eq!(c.sequence, seq);
        if c.is_last {
            break;
        }
        seq += 1;
        assert!(seq < 100, "never ended");
        send(seq, STATUS_READY | STATUS_SYSRDY, ROBOT_ERROR);
        link.receive(WAIT).unwrap().unwrap();
    }
    // The next status brings the stop packet.
    send(seq + 1, STATUS_SYSRDY, ROBOT_ERROR);
    link.receive(WAIT).unwrap().unwrap();
    let mut b = [0u8; 64];
    let (n, _) = controller.recv_from(&mut b).unwrap();
    assert_eq!(&b[..n], &[0, 0, 0, 2, 0, 0, 0, 3], "the stop packet");
    assert_eq!(link.phase(), StreamPhase::Done);
    let c = link.counters();
    assert_eq!(c.dropped_sequence, 1);
}
