//! Every controller-side robot link answers only its robot: a datagram from another host (or,
//! over TCP, a connection from another host) is refused with `ForeignSender`, counted, and
//! never redirects the answers; a configured robot address locks the link from the start.

use deflex_io::egm::{EgmConfig, EgmLink, EgmRobotEndpoint};
use deflex_io::simple_tcp::{SimpleTcpLink, SimpleTcpRobotEndpoint};
use deflex_io::simple_udp::{ReplyStyle, SimpleUdpLink, SimpleUdpRobotEndpoint};
use deflex_io::staubli::{StaubliLink, StaubliRobotEndpoint};
use deflex_io::{Correction, RobotLink, RobotSideLink, RobotState};
use std::net::{SocketAddr, UdpSocket};
use std::time::Duration;

const T: Duration = Duration::from_secs(2);

/// The robot's first state locks the link; a copy of the same bytes from a stranger is refused
/// and the answer goes to the robot only.
fn check_udp_lock(
    pc: &mut dyn RobotLink,
    pc_addr: SocketAddr,
    robot: &mut dyn RobotSideLink,
    state_bytes: &[u8],
) {
    let state = RobotState::with_joints(&[0.1, 0.2, 0.3, 0.4, 0.5, 0.6]);
    robot.send_state(&state).unwrap();
    assert!(pc.receive(T).unwrap().is_some());
    let stranger = UdpSocket::bind("127.0.0.1:0").unwrap();
    stranger
        .set_read_timeout(Some(Duration::from_millis(200)))
        .unwrap();
    stranger.send_to(state_bytes, pc_addr).unwrap();
    let e = pc.receive(T).unwrap_err();
    assert!(e.is_foreign(), "{:?}: {e}", pc.protocol());
    pc.send_correction(&Correction::ZERO).unwrap();
    assert!(robot.receive_correction(T).unwrap().is_some());
    let mut b = [0u8; 512];
    assert!(
        stranger.recv(&mut b).is_err(),
        "{:?}: stranger answered",
        pc.protocol()
    );
}

#[test]
fn simple_udp_locks_to_its_robot() {
    let mut pc = SimpleUdpLink::bind("127.0.0.1:0", ReplyStyle::Keyword).unwrap();
    let addr = pc.local_addr().unwrap();
    let mut robot = SimpleUdpRobotEndpoint::new("127.0.0.1:0", addr).unwrap();
    check_udp_lock(&mut pc, addr, &mut robot, b"q 0 0 0 0 0 0\n");
    assert_eq!(pc.peers().foreign(), 1);
}

#[test]
fn staubli_locks_to_its_robot() {
    let mut pc = StaubliLink::bind("127.0.0.1:0").unwrap();
    let addr = pc.local_addr().unwrap();
    let mut robot =
        StaubliRobotEndpoint::new("127.0.0.1:0", addr, Duration::from_millis(100)).unwrap();
    let mut bytes = [0u8; deflex_io::staubli::STATE_LEN];
    let n = deflex_io::staubli::encode_state(&Default::default(), &mut bytes).unwrap();
    check_udp_lock(&mut pc, addr, &mut robot, &bytes[..n]);
    assert_eq!(pc.peers().foreign(), 1);
}

#[test]
fn egm_locks_to_its_robot() {
    let mut pc = EgmLink::bind("127.0.0.1:0", EgmConfig::default()).unwrap();
    let addr = pc.local_addr().unwrap();
    let mut robot = EgmRobotEndpoint::new("127.0.0.1:0", addr).unwrap();
    let mut m = deflex_io::egm::msg::EgmRobot::default();
    deflex_io::egm::fill_robot_msg(&mut m, &RobotState::with_joints(&[0.0; 6]), 1, 1, false);
    let bytes = prost::Message::encode_to_vec(&m);
    check_udp_lock(&mut pc, addr, &mut robot, &bytes);
    assert_eq!(pc.peers().foreign(), 1);
}

#[test]
fn configured_robot_address_refuses_everyone_else_from_the_start() {
    let robot_sock = UdpSocket::bind("127.0.0.1:0").unwrap();
    let mut pc = SimpleUdpLink::bind("127.0.0.1:0", ReplyStyle::Keyword).unwrap();
    pc.expect_peer(robot_sock.local_addr().unwrap());
    let stranger = UdpSocket::bind("127.0.0.1:0").unwrap();
    stranger
        .send_to(b"q 1 2 3 4 5 6\n", pc.local_addr().unwrap())
        .unwrap();
    assert!(pc.receive(T).unwrap_err().is_foreign());
    robot_sock
        .send_to(b"q 1 2 3 4 5 6\n", pc.local_addr().unwrap())
        .unwrap();
    assert_eq!(pc.receive(T).unwrap().unwrap().joint_count, 6);
}

/// TCP: one client host. A connection from a host other than the configured robot's is closed
/// at once and reported; the robot's own host connects and is served.
#[test]
fn simple_tcp_serves_only_the_robot_host() {
    let mut pc = SimpleTcpLink::bind("127.0.0.1:0").unwrap();
    let addr = pc.local_addr().unwrap();
    // The robot is configured at 127.0.0.2: a client from 127.0.0.1 is a stranger.
    pc.expect_peer("127.0.0.2:0".parse().unwrap());
    let mut stranger = SimpleTcpRobotEndpoint::connect(addr, T).unwrap();
    stranger
        .send_state(&RobotState::with_joints(&[1.0; 6]))
        .unwrap();
    let mut refused = None;
    for _ in 0..100 {
        match pc.receive(Duration::from_millis(20)) {
            Err(e) if e.is_foreign() => {
                refused = Some(e);
                break;
            }
            Ok(None) => {}
            other => panic!("{other:?}"),
        }
    }
    assert!(refused.is_some(), "the stranger was served");
    assert_eq!(pc.refused(), 1);
    assert!(!pc.is_connected());
    // The closed connection shows up on the stranger's side.
    assert!(stranger.receive_correction(T).is_err());

    // Without a configured address, the first client's host is locked: here every client is on
    // 127.0.0.1, so it is served (and a reconnect from it still takes over).
    let mut pc = SimpleTcpLink::bind("127.0.0.1:0").unwrap();
    let mut robot = SimpleTcpRobotEndpoint::connect(pc.local_addr().unwrap(), T).unwrap();
    robot
        .send_state(&RobotState::with_joints(&[2.0; 4]))
        .unwrap();
    let s = pc.receive(T).unwrap().unwrap();
    assert_eq!(s.joints(), &[2.0; 4]);
    assert_eq!(pc.robot_host(), Some("127.0.0.1".parse().unwrap()));
}
