//! Issue 18, item 10: with no `robot.peer`, the first valid sender owned the session, so a
//! local process that sent KUKA RSI telegrams before the robot got every answer and the robot
//! was refused; `bind = "0.0.0.0:…"` and `peer = "0.0.0.0:0"` passed without a word. Now
//! `validate_peer` refuses a network bind without a peer (unless `allow_any_peer`), an
//! unspecified peer and a peer that cannot reach the bind; the policy it returns keeps the early
//! local sender out and serves the robot.

use deflex_io::rsi::{RobTelegram, RsiConfig, RsiLink, format_rob, parse_sen};
use deflex_io::{
    Correction, LinkError, PeerConfigError, PeerPolicy, PeerWarning, RobotLink, validate_peer,
};
use std::net::{SocketAddr, UdpSocket};
use std::time::Duration;

const T: Duration = Duration::from_secs(5);

fn telegram(ipoc: u64) -> Vec<u8> {
    let t = RobTelegram {
        q_rad: Some([0.0, -1.57, 1.57, 0.0, 0.5, 0.0]),
        ipoc,
        ..RobTelegram::default()
    };
    let mut b = [0u8; 1024];
    let n = format_rob(&t, &mut b).unwrap();
    b[..n].to_vec()
}

/// The IPOC of every answer waiting on `sock` (the first read waits up to `first`).
fn answers(sock: &UdpSocket, first: Duration) -> Vec<u64> {
    let mut out = Vec::new();
    let mut b = [0u8; 1024];
    sock.set_read_timeout(Some(first)).unwrap();
    while let Ok(n) = sock.recv(&mut b) {
        out.push(parse_sen(&b[..n]).unwrap().ipoc);
        sock.set_read_timeout(Some(Duration::from_millis(200)))
            .unwrap();
    }
    out
}

#[test]
fn a_network_bind_needs_a_peer_and_the_early_local_sender_is_refused() {
    let bind: SocketAddr = "0.0.0.0:0".parse().unwrap();
    // The configurations the issue found passing without a word.
    assert_eq!(
        validate_peer(bind, None, false),
        Err(PeerConfigError::NoPeerOnNetworkBind { bind })
    );
    let zero: SocketAddr = "0.0.0.0:0".parse().unwrap();
    assert_eq!(
        validate_peer(bind, Some(zero), false),
        Err(PeerConfigError::UnspecifiedPeer { peer: zero })
    );
    assert!(validate_peer(bind, Some(zero), true).is_err());

    // The robot's address configured: the link bound on all interfaces serves only it.
    let robot = UdpSocket::bind("127.0.0.1:0").unwrap();
    let local = UdpSocket::bind("127.0.0.1:0").unwrap();
    let policy = validate_peer(bind, Some(robot.local_addr().unwrap()), false).unwrap();
    assert_eq!(policy.warning(), None);
    let mut pc = RsiLink::bind(bind, RsiConfig::default()).unwrap();
    pc.set_peer_policy(policy);
    let to: SocketAddr = ([127, 0, 0, 1], pc.local_addr().unwrap().port()).into();

    // The local process starts first and keeps sending; every telegram is refused.
    for k in 0..20u64 {
        local.send_to(&telegram(1000 + 4 * k), to).unwrap();
        match pc.receive(T) {
            Err(LinkError::ForeignSender { from, .. }) => {
                assert_eq!(from, local.local_addr().unwrap())
            }
            other => panic!("{other:?}"),
        }
    }
    // Then the robot: every telegram answered, to the robot, with its IPOC; the local process
    // keeps interleaving telegrams, all refused.
    for k in 0..50u64 {
        let ipoc = 500_000 + 4 * k;
        robot.send_to(&telegram(ipoc), to).unwrap();
        let s = pc.receive(T).unwrap().expect("hang guard");
        assert_eq!(s.cycle_id, ipoc);
        pc.send_correction(&Correction::ZERO).unwrap();
        local.send_to(&telegram(ipoc + 1), to).unwrap();
        assert!(pc.receive(T).unwrap_err().is_foreign());
    }
    let got = answers(&robot, T);
    assert_eq!(got, (0..50).map(|k| 500_000 + 4 * k).collect::<Vec<u64>>());
    assert!(
        answers(&local, Duration::from_millis(300)).is_empty(),
        "the local process got answers"
    );
    let c = pc.counters();
    assert_eq!((c.foreign, c.accepted, c.answers), (70, 50, 50));
}

/// Without a peer, a loopback bind starts with a warning (only local processes can reach it,
/// and the first one owns the session); a network bind starts only with `allow_any_peer`, and
/// warns that any host may take it.
#[test]
fn sessions_without_a_peer_warn() {
    let lo: SocketAddr = "127.0.0.1:59152".parse().unwrap();
    let p = validate_peer(lo, None, false).unwrap();
    assert_eq!(p, PeerPolicy::FirstLocalSender);
    let w = p.warning().unwrap();
    assert_eq!(w, PeerWarning::FirstLocalSender);
    assert!(w.to_string().contains("first local process"), "{w}");
    let net: SocketAddr = "0.0.0.0:59152".parse().unwrap();
    let p = validate_peer(net, None, true).unwrap();
    assert_eq!(p.warning(), Some(PeerWarning::FirstSenderFromAnyHost));

    // Under the loopback policy the first local sender locks the session for good.
    let mut pc = RsiLink::bind("127.0.0.1:0", RsiConfig::default()).unwrap();
    pc.set_peer_policy(PeerPolicy::FirstLocalSender);
    let first = UdpSocket::bind("127.0.0.1:0").unwrap();
    let second = UdpSocket::bind("127.0.0.1:0").unwrap();
    let to = pc.local_addr().unwrap();
    first.send_to(&telegram(8), to).unwrap();
    assert!(pc.receive(T).unwrap().is_some());
    second.send_to(&telegram(12), to).unwrap();
    assert!(pc.receive(T).unwrap_err().is_foreign());
    assert_eq!(pc.peers().locked(), Some(first.local_addr().unwrap()));
}
