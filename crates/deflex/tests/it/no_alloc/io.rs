//! No allocation on deflex-io's per-cycle path: the controller-side hot path (`receive` /
//! `send_correction`, and the force sensor's `receive`) does not allocate after construction,
//! counted on this thread by this binary's counting allocator.

use deflex_io::egm::{EgmConfig, EgmLink, EgmRobotEndpoint};
use deflex_io::netft::{NetFtCalibration, NetFtClient, NetFtSensorServer};
use deflex_io::rsi::{CorrectionMode, RsiConfig, RsiLink, RsiRobotEndpoint};
use deflex_io::simple_tcp::{SimpleTcpLink, SimpleTcpRobotEndpoint};
use deflex_io::simple_udp::{ReplyStyle, SimpleUdpLink, SimpleUdpRobotEndpoint};
use deflex_io::staubli::{StaubliLink, StaubliRobotEndpoint};
use deflex_io::{Correction, ForceSensorLink, RobotLink, RobotSideLink, RobotState};
use deflex_model::conventions::rotation_from_kuka_abc_rad;
use deflex_model::{Pose, Wrench};
use nalgebra::Translation3;
use std::time::Duration;

fn allocs() -> u64 {
    super::allocations()
}

const T: Duration = Duration::from_secs(2);

fn state(k: u64) -> RobotState {
    let mut s = RobotState::with_joints(&[0.1, -1.2, 1.3, 0.0, 0.7, k as f64 * 1e-3]);
    s.tcp_pose = Some(Pose::from_parts(
        Translation3::new(1.0, 0.2, 0.5),
        rotation_from_kuka_abc_rad([0.1, 0.2, 3.0]),
    ));
    s.cycle_id = k;
    s.robot_time_s = Some(k as f64 * 0.004);
    s
}

/// Runs 50 cycles; counts allocations of the PC side only (after a warm-up).
fn run(pc: &mut dyn RobotLink, robot: &mut dyn RobotSideLink) -> u64 {
    let mut total = 0;
    for k in 0..50u64 {
        robot.send_state(&state(k)).unwrap();
        let c = Correction {
            dp_m: [1e-4 * k as f64, 0.0, 1e-5],
            dphi_rad: [1e-5, 0.0, 0.0],
        };
        let before = allocs();
        let s = pc.receive(T).unwrap().unwrap();
        pc.send_correction(&c).unwrap();
        let after = allocs();
        if k > 0 {
            total += after - before;
        }
        assert!((s.q_rad[0] - 0.1).abs() < 1e-6);
        robot.receive_correction(T).unwrap().unwrap();
    }
    total
}

#[test]
fn robot_links_do_not_allocate_on_the_hot_path() {
    let mut pc = RsiLink::bind(
        "127.0.0.1:0",
        RsiConfig {
            mode: CorrectionMode::Relative,
            ..Default::default()
        },
    )
    .unwrap();
    let mut robot = RsiRobotEndpoint::new(
        "127.0.0.1:0",
        pc.local_addr().unwrap(),
        CorrectionMode::Relative,
    )
    .unwrap();
    assert_eq!(run(&mut pc, &mut robot), 0, "RSI");

    let mut pc = EgmLink::bind("127.0.0.1:0", EgmConfig::default()).unwrap();
    let mut robot = EgmRobotEndpoint::new("127.0.0.1:0", pc.local_addr().unwrap()).unwrap();
    assert_eq!(run(&mut pc, &mut robot), 0, "EGM");

    let mut pc = StaubliLink::bind("127.0.0.1:0").unwrap();
    let mut robot = StaubliRobotEndpoint::new("127.0.0.1:0", pc.local_addr().unwrap(), T).unwrap();
    assert_eq!(run(&mut pc, &mut robot), 0, "Staubli");

    let mut pc = SimpleUdpLink::bind("127.0.0.1:0", ReplyStyle::Keyword).unwrap();
    let mut robot = SimpleUdpRobotEndpoint::new("127.0.0.1:0", pc.local_addr().unwrap()).unwrap();
    assert_eq!(run(&mut pc, &mut robot), 0, "simple line");

    let mut pc = SimpleTcpLink::bind("127.0.0.1:0").unwrap();
    let mut robot = SimpleTcpRobotEndpoint::connect(pc.local_addr().unwrap(), T).unwrap();
    assert_eq!(run(&mut pc, &mut robot), 0, "simple line over TCP");
}

#[test]
fn the_counter_sees_allocations() {
    let before = allocs();
    let v = std::hint::black_box(vec![1u8; 16]);
    assert!(allocs() > before);
    drop(v);
}

#[test]
fn netft_receive_does_not_allocate() {
    let mut sensor = NetFtSensorServer::bind("127.0.0.1:0", NetFtCalibration::default()).unwrap();
    let mut client = NetFtClient::new(
        "127.0.0.1:0",
        sensor.local_addr().unwrap(),
        NetFtCalibration::default(),
    )
    .unwrap();
    client.start().unwrap();
    sensor.poll_request(T).unwrap().unwrap();
    let mut total = 0;
    for k in 0..50 {
        sensor
            .send_sample(&Wrench::new(1.0, 2.0, 3.0, 0.1, 0.2, k as f64), 0)
            .unwrap();
        let before = allocs();
        let s = client.receive(T).unwrap().unwrap();
        if k > 0 {
            total += allocs() - before;
        }
        assert_eq!(s.wrench[0], 1.0);
    }
    assert_eq!(total, 0);
}

/// The drop paths allocate nothing either: a duplicate of the message just answered (EGM
/// `seqno`, RSI `IPOC`, Stäubli `seq`, simple UDP `seq=`), a joint count that changed, and,
/// over TCP, a second connection refused while the robot holds the session.
#[test]
fn drop_paths_do_not_allocate() {
    use deflex_io::LinkError;
    use std::net::UdpSocket;

    /// Sends message k, then its duplicate, then a message of k with another joint count
    /// (`None`: the protocol's joint count is fixed); counts the PC side's allocations.
    fn run_drops(
        pc: &mut dyn RobotLink,
        to: std::net::SocketAddr,
        message: &dyn Fn(u64, usize) -> Option<Vec<u8>>,
        joints: usize,
    ) -> (u64, u64) {
        let robot = UdpSocket::bind("127.0.0.1:0").unwrap();
        robot.set_read_timeout(Some(T)).unwrap();
        let mut b = [0u8; 2048];
        let (mut total, mut dropped) = (0, 0);
        for k in 1..=30u64 {
            let mut sends = vec![message(k, joints).unwrap(), message(k, joints).unwrap()];
            sends.extend(message(k + 1, joints - 1));
            for (i, bytes) in sends.iter().enumerate() {
                robot.send_to(bytes, to).unwrap();
                let before = allocs();
                let r = pc.receive(T);
                let ok = matches!(r, Ok(Some(_)));
                if ok {
                    pc.send_correction(&Correction::ZERO).unwrap();
                }
                let after = allocs();
                if k > 1 {
                    total += after - before;
                }
                match (i, r) {
                    (0, Ok(Some(_))) => {
                        robot.recv(&mut b).unwrap();
                    }
                    (_, Err(LinkError::Dropped { .. })) => dropped += 1,
                    (_, other) => panic!("message {i} of cycle {k}: {other:?}"),
                }
            }
        }
        (total, dropped)
    }
    let mut pc = EgmLink::bind("127.0.0.1:0", EgmConfig::default()).unwrap();
    let to = pc.local_addr().unwrap();
    let egm = |k: u64, n: usize| {
        let mut m = deflex_io::egm::msg::EgmRobot::default();
        let q = [0.1; 6];
        deflex_io::egm::fill_robot_msg(
            &mut m,
            &RobotState::with_joints(&q[..n]),
            k as u32,
            4 * k as u32,
            false,
        );
        Some(prost::Message::encode_to_vec(&m))
    };
    assert_eq!(run_drops(&mut pc, to, &egm, 6), (0, 60), "EGM");

    let mut pc = RsiLink::bind("127.0.0.1:0", RsiConfig::default()).unwrap();
    let to = pc.local_addr().unwrap();
    let rsi = |k: u64, n: usize| {
        (n == 6).then(|| {
            let t = deflex_io::rsi::RobTelegram {
                q_rad: Some([0.1; 6]),
                ipoc: 4 * k,
                ..Default::default()
            };
            let mut b = [0u8; 1024];
            let len = deflex_io::rsi::format_rob(&t, &mut b).unwrap();
            b[..len].to_vec()
        })
    };
    assert_eq!(run_drops(&mut pc, to, &rsi, 6), (0, 30), "RSI");

    let mut pc = StaubliLink::bind("127.0.0.1:0").unwrap();
    let to = pc.local_addr().unwrap();
    let staubli = |k: u64, n: usize| {
        (n == 6).then(|| {
            let m = deflex_io::staubli::StateMsg {
                header: deflex_io::staubli::StaubliHeader {
                    seq: k as u32,
                    timestamp_s: k as f64 * 0.004,
                    ..Default::default()
                },
                q_rad: [0.1; 6],
                status: 0,
            };
            let mut b = [0u8; deflex_io::staubli::STATE_LEN];
            deflex_io::staubli::encode_state(&m, &mut b).unwrap();
            b.to_vec()
        })
    };
    assert_eq!(run_drops(&mut pc, to, &staubli, 6), (0, 30), "Staubli");

    let mut pc = SimpleUdpLink::bind("127.0.0.1:0", ReplyStyle::Keyword).unwrap();
    let to = pc.local_addr().unwrap();
    let line = |k: u64, n: usize| {
        let mut b = [0u8; 512];
        let len =
            deflex_io::simple_udp::format_state_line(&[0.1; 6][..n], Some(k), &mut b).unwrap();
        Some(b[..len].to_vec())
    };
    assert_eq!(run_drops(&mut pc, to, &line, 6), (0, 60), "simple UDP");

    // TCP: a second connection refused while the robot holds the session.
    let mut pc = SimpleTcpLink::bind("127.0.0.1:0").unwrap();
    let mut robot = SimpleTcpRobotEndpoint::connect(pc.local_addr().unwrap(), T).unwrap();
    let mut total = 0;
    let mut strangers = Vec::new();
    for k in 0..30u64 {
        robot.send_state(&state(k)).unwrap();
        let before = allocs();
        assert!(pc.receive(T).unwrap().is_some());
        pc.send_correction(&Correction::ZERO).unwrap();
        total += allocs() - before;
        robot.receive_correction(T).unwrap().unwrap();
        strangers.push(std::net::TcpStream::connect(pc.local_addr().unwrap()).unwrap());
        // The refusal comes within a few silent polls (the connection may still be on its way
        // into the backlog); each poll is counted.
        let mut refused = false;
        for _ in 0..1000 {
            let before = allocs();
            let r = pc.receive(Duration::from_millis(1));
            total += allocs() - before;
            match r {
                Err(LinkError::SecondConnection { .. }) => {
                    refused = true;
                    break;
                }
                Ok(None) => {}
                other => panic!("{other:?}"),
            }
        }
        assert!(refused, "cycle {k}");
    }
    assert_eq!(total, 0, "simple TCP with refusals");
    assert_eq!(pc.counters().refused_busy, 30);
}

/// FANUC Stream Motion: the link's receive and joint answer (approach, path with a changing
/// correction, the filter and limiter) allocate nothing after construction.
#[test]
fn fanuc_stream_link_does_not_allocate_while_streaming() {
    use deflex_io::fanuc_stream::link::{FanucStreamConfig, FanucStreamLink, StreamPhase};
    use deflex_io::fanuc_stream::motion::{StreamLimits, StreamTrajectory};
    use deflex_io::fanuc_stream::robot::FanucStreamRobotEndpoint;
    let period = 0.008;
    let limits = StreamLimits::uniform(1.0, 5.0, 100.0);
    let start = [0.0, -0.5, 0.5, 0.0, 0.4, 0.0];
    let end = [0.2, -0.4, 0.45, 0.05, 0.4, 0.1];
    let trajectory =
        StreamTrajectory::from_waypoints(period, 0.3, &[(0.0, start), (1.0, end)], &limits)
            .unwrap();
    let mut robot = FanucStreamRobotEndpoint::bind("127.0.0.1:0", period, limits).unwrap();
    let mut cfg = FanucStreamConfig::new(robot.local_addr().unwrap(), period);
    cfg.limits = limits;
    cfg.late_after = Duration::from_secs(1);
    cfg.lost_after = Duration::from_secs(2);
    let mut pc = FanucStreamLink::bind("127.0.0.1:0", cfg, trajectory).unwrap();
    let mut q = start;
    q[1] += 0.02;
    assert!(pc.receive(Duration::from_millis(1)).unwrap().is_none());
    let mut total = 0;
    let mut path_cycles = 0;
    for k in 0..400u64 {
        robot.send_state(&RobotState::with_joints(&q)).unwrap();
        let dq = [0.0, 0.0, 1e-4 * (k % 50) as f64, 0.0, 0.0, 0.0];
        let before = allocs();
        let s = pc.receive(T).unwrap().unwrap();
        pc.send_joint_correction(&dq).unwrap();
        let after = allocs();
        if k > 0 {
            total += after - before;
        }
        assert!((s.q_rad[1] - q[1]).abs() < 1e-5);
        robot.receive_correction(T).unwrap().unwrap();
        q = robot.commanded_rad().unwrap();
        if pc.phase() == StreamPhase::Path {
            path_cycles += 1;
        }
    }
    assert!(path_cycles > 50, "{path_cycles}");
    assert_eq!(robot.counts().1, 0);
    assert_eq!(total, 0);
}

/// UR RTDE: the robot link's `receive` / `send_correction` and the flange sensor's `receive`
/// allocate nothing once connected (the twin's controller runs in a thread of its own, whose
/// allocations this thread's counter does not see).
#[test]
fn rtde_links_do_not_allocate_on_the_hot_path() {
    use deflex_io::rtde::{
        PathOffsetModel, RtdeLink, RtdeLinkConfig, RtdeRobotEndpoint, RtdeSensor,
    };
    use std::sync::Arc;
    use std::sync::atomic::{AtomicBool, Ordering};
    let mut controller =
        RtdeRobotEndpoint::bind("127.0.0.1:0", 24, PathOffsetModel::new(1.0, 1.0, 1.0, 100))
            .unwrap();
    let addr = controller.server().local_addr().unwrap();
    let stop = Arc::new(AtomicBool::new(false));
    let flag = stop.clone();
    let thread = std::thread::spawn(move || {
        let mut k = 0u64;
        while !flag.load(Ordering::SeqCst) {
            k += 1;
            controller.set_flange_wrench(&Wrench::new(1.0, 2.0, 3.0, 0.1, 0.2, k as f64));
            controller.send_state(&state(k)).unwrap();
            let _ = controller.receive_correction(Duration::from_millis(5));
        }
    });
    let mut link = RtdeLink::connect(
        addr,
        RtdeLinkConfig {
            register: 24,
            connect_wait: T,
        },
    )
    .unwrap();
    let mut sensor = RtdeSensor::connect(addr, T).unwrap();
    let (mut total, mut states, mut samples) = (0, 0, 0);
    for k in 0..200u64 {
        let before = allocs();
        let s = link.receive(Duration::from_millis(20)).unwrap();
        if s.is_some() {
            link.send_correction(&Correction {
                dp_m: [1e-5 * k as f64, 0.0, 0.0],
                dphi_rad: [0.0; 3],
            })
            .unwrap();
        }
        let w = sensor.receive(Duration::from_millis(20)).unwrap();
        let after = allocs();
        if k > 0 {
            total += after - before;
        }
        states += u64::from(s.is_some());
        samples += u64::from(w.is_some());
    }
    stop.store(true, Ordering::SeqCst);
    thread.join().unwrap();
    assert!(states > 50 && samples > 50, "{states} {samples}");
    assert_eq!(total, 0, "RTDE");
}
