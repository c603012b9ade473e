//! Checks that the controller-side hot path (`receive` / `send_correction`,
//! and the force sensor's `receive`) does not allocate after construction.

use deflex_io::egm::{EgmConfig, EgmLink, EgmRobotEndpoint};
use deflex_io::netft::{Calibration, NetFtClient, NetFtSensorServer};
use deflex_io::rsi::{CorrectionMode, RsiConfig, RsiLink, RsiRobotEndpoint};
use deflex_io::simple_tcp::{SimpleTcpLink, SimpleTcpRobotEndpoint};
use deflex_io::simple_udp::{ReplyStyle, SimpleUdpLink, SimpleUdpRobotEndpoint};
use deflex_io::staubli::{StaubliLink, StaubliRobotEndpoint};
use deflex_io::{Correction, ForceSensorLink, Pose6, RobotLink, RobotSideLink, RobotState};
use std::time::Duration;

fn allocs() -> u64 {
    deflex_alloc_count::allocations()
}

const T: Duration = Duration::from_secs(2);

fn state(k: u64) -> RobotState {
    let mut s = RobotState::with_joints(&[0.1, -1.2, 1.3, 0.0, 0.7, k as f64 * 1e-3]);
    s.tcp_pose = Some(Pose6 {
        position_m: [1.0, 0.2, 0.5],
        zyx_rad: [0.1, 0.2, 3.0],
    });
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
    let mut sensor = NetFtSensorServer::bind("127.0.0.1:0", Calibration::default()).unwrap();
    let mut client = NetFtClient::new(
        "127.0.0.1:0",
        sensor.local_addr().unwrap(),
        Calibration::default(),
    )
    .unwrap();
    client.start().unwrap();
    sensor.poll_request(T).unwrap().unwrap();
    let mut total = 0;
    for k in 0..50 {
        sensor
            .send_sample(&[1.0, 2.0, 3.0, 0.1, 0.2, k as f64], 0)
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
