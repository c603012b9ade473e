use deflex_io::error::Protocol;
use deflex_io::peer::*;
use std::net::SocketAddr;

fn a(s: &str) -> SocketAddr {
    s.parse().unwrap()
}

#[test]
fn validate_peer_rules() {
    use PeerConfigError as E;
    let lo = a("127.0.0.1:59152");
    let any = a("0.0.0.0:59152");
    let net = a("192.168.1.10:59152");
    let robot = a("192.168.1.147:0");
    // A configured robot on a bind it can reach.
    for bind in [any, net, a("[::]:6510")] {
        assert_eq!(
            validate_peer(bind, Some(robot), false),
            Ok(PeerPolicy::Fixed(robot))
        );
    }
    assert_eq!(
        validate_peer(lo, Some(a("127.0.0.1:6000")), false),
        Ok(PeerPolicy::Fixed(a("127.0.0.1:6000")))
    );
    // Unspecified peers, with or without a port, on any bind.
    for peer in ["0.0.0.0:0", "0.0.0.0:6510", "[::]:0", "[::ffff:0.0.0.0]:0"] {
        for bind in [lo, any, net] {
            assert_eq!(
                validate_peer(bind, Some(a(peer)), false),
                Err(E::UnspecifiedPeer { peer: a(peer) }),
                "{peer} on {bind}"
            );
        }
    }
    for peer in ["255.255.255.255:0", "224.0.0.1:0", "[ff02::1]:0"] {
        assert!(matches!(
            validate_peer(a("[::]:1"), Some(a(peer)), false),
            Err(E::NotAHost { .. })
        ));
    }
    // Peers that can never reach the bind.
    for (bind, peer) in [
        (lo, robot),
        (net, a("127.0.0.1:0")),
        (any, a("[2001:db8::1]:0")),
        (a("[::1]:1"), a("127.0.0.1:0")),
        (net, a("[2001:db8::1]:0")),
    ] {
        assert!(
            matches!(
                validate_peer(bind, Some(peer), false),
                Err(E::Unreachable { .. })
            ),
            "{peer} to {bind}"
        );
    }
    // A v4-mapped peer is its IPv4 address.
    assert!(validate_peer(net, Some(a("[::ffff:192.168.1.147]:0")), false).is_ok());
    assert_eq!(
        validate_peer(any, Some(robot), true),
        Err(E::PeerAndAllowAny { peer: robot })
    );
    // No peer: loopback warns, a network bind needs allow_any_peer.
    for bind in [lo, a("127.0.0.5:1"), a("[::1]:1")] {
        for allow in [false, true] {
            let p = validate_peer(bind, None, allow).unwrap();
            assert_eq!(p, PeerPolicy::FirstLocalSender);
            assert_eq!(p.warning(), Some(PeerWarning::FirstLocalSender));
        }
    }
    for bind in [any, net, a("[::]:1")] {
        assert_eq!(
            validate_peer(bind, None, false),
            Err(E::NoPeerOnNetworkBind { bind })
        );
        let p = validate_peer(bind, None, true).unwrap();
        assert_eq!(p, PeerPolicy::FirstSender);
        assert_eq!(p.warning(), Some(PeerWarning::FirstSenderFromAnyHost));
    }
    assert_eq!(PeerPolicy::Fixed(robot).warning(), None);
    // The messages name the keys and the values.
    let m = validate_peer(any, None, false).unwrap_err().to_string();
    assert!(
        m.contains("0.0.0.0:59152") && m.contains("allow_any_peer"),
        "{m}"
    );
    let m = validate_peer(any, Some(a("0.0.0.0:0")), false)
        .unwrap_err()
        .to_string();
    assert!(m.contains("0.0.0.0:0") && m.contains("unspecified"), "{m}");
}

#[test]
fn peer_lock_first_sender_and_configured() {
    let a1 = a("10.0.0.2:6000");
    let b = a("10.0.0.3:6000");
    let a2 = a("10.0.0.2:6001");
    let mut l = PeerLock::first_sender();
    assert!(
        l.check(Protocol::Rsi, b).is_ok(),
        "anyone until the first telegram"
    );
    l.lock(a1);
    l.lock(b);
    assert_eq!(l.locked(), Some(a1));
    assert!(l.check(Protocol::Rsi, a1).is_ok());
    assert!(l.check(Protocol::Rsi, b).unwrap_err().is_foreign());
    assert!(l.check(Protocol::Rsi, a2).is_err(), "same host, other port");
    assert_eq!((l.foreign(), l.last_foreign()), (2, Some(a2)));
    let mut c = PeerLock::configured(a("10.0.0.2:0"));
    assert!(c.check(Protocol::Egm, b).is_err());
    assert!(
        c.check(Protocol::Egm, a2).is_ok(),
        "port 0: any port of the IP"
    );
    c.lock(a2);
    assert!(
        c.check(Protocol::Egm, a1).is_err(),
        "then locked to that port"
    );
    let mut d = PeerLock::configured(a1);
    assert!(d.check(Protocol::Egm, a2).is_err());
    assert!(d.check(Protocol::Egm, a1).is_ok());
}

#[test]
fn first_local_sender_refuses_network_sources() {
    let mut l = PeerLock::new(PeerPolicy::FirstLocalSender);
    assert!(l.check(Protocol::Rsi, a("192.168.1.147:6000")).is_err());
    assert!(l.check(Protocol::Rsi, a("[2001:db8::1]:6000")).is_err());
    assert!(l.check(Protocol::Rsi, a("127.0.0.1:6000")).is_ok());
    assert!(l.check(Protocol::Rsi, a("[::ffff:127.0.0.1]:6000")).is_ok());
    assert!(l.check(Protocol::Rsi, a("[::1]:6000")).is_ok());
    assert_eq!(l.foreign(), 2);
    assert!(PeerPolicy::FirstLocalSender.admits_host("127.0.0.2".parse().unwrap()));
    assert!(!PeerPolicy::FirstLocalSender.admits_host("10.0.0.1".parse().unwrap()));
    assert!(PeerPolicy::Fixed(a("10.0.0.1:7")).admits_host("10.0.0.1".parse().unwrap()));
}
