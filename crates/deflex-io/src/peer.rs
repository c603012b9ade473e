//! Who a controller-side robot link answers: the peer policy, its validation against the local
//! address, and the lock every UDP link applies to each datagram before parsing it.
//!
//! A robot link answers exactly one robot for a whole session. Which one is a
//! [`PeerPolicy`]:
//!
//! * [`PeerPolicy::Fixed`]: the configured robot address (`robot.peer`); port 0 means any
//!   port of that IP (TCP always compares the IP only, a client's port being ephemeral);
//! * [`PeerPolicy::FirstLocalSender`]: no address configured on a **loopback** bind: only
//!   processes of this machine can reach the link, and the first one that sends a valid
//!   message owns the session (a warning, [`PeerWarning::FirstLocalSender`]);
//! * [`PeerPolicy::FirstSender`]: no address configured on a network bind, allowed only
//!   explicitly (`robot.allow_any_peer = true`): any host that sends a valid message first owns
//!   the session (a warning, [`PeerWarning::FirstSenderFromAnyHost`]).
//!
//! [`validate_peer`] turns the configuration (`bind`, `peer`, `allow_any_peer`) into a policy or
//! a [`PeerConfigError`] naming what is wrong: an unspecified (`0.0.0.0`, `::`) or non-host
//! (multicast, broadcast) peer, a peer that can never reach the bind address (a loopback bind
//! with a network peer or the reverse, IPv4 against IPv6), or a network bind without a peer
//! and without `allow_any_peer`.
//!
//! [`PeerLock`] applies the policy to every datagram: the sender is checked before the
//! packet is parsed, and the first valid sender locks the link to its exact address (IP and
//! port) until the link is dropped.

use crate::error::{LinkError, Protocol};
use std::net::{IpAddr, Ipv4Addr, SocketAddr};

/// Which robot a controller-side link accepts messages from (see the module documentation).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum PeerPolicy {
    /// Only this address (port 0: any port of that IP; TCP compares the IP only).
    Fixed(SocketAddr),
    /// The first valid sender of the session among this machine's processes (loopback
    /// sources only), locked to its address for the session.
    FirstLocalSender,
    /// The first valid sender of the session, from any host, locked to its address for the
    /// session: the configuration allowed it explicitly (`allow_any_peer`).
    FirstSender,
}

impl PeerPolicy {
    /// The warning a session started with this policy must print (`None` for a configured
    /// peer).
    pub fn warning(&self) -> Option<PeerWarning> {
        match self {
            PeerPolicy::Fixed(_) => None,
            PeerPolicy::FirstLocalSender => Some(PeerWarning::FirstLocalSender),
            PeerPolicy::FirstSender => Some(PeerWarning::FirstSenderFromAnyHost),
        }
    }

    /// True if a message from `from` may be accepted under this policy, before any lock.
    /// (The locked address, once there is one, is checked by [`PeerLock`].)
    pub fn admits(&self, from: SocketAddr) -> bool {
        match self {
            PeerPolicy::Fixed(p) => {
                p.ip().to_canonical() == from.ip().to_canonical()
                    && (p.port() == 0 || p.port() == from.port())
            }
            PeerPolicy::FirstLocalSender => from.ip().to_canonical().is_loopback(),
            PeerPolicy::FirstSender => true,
        }
    }

    /// Like [`PeerPolicy::admits`] for a TCP client: the IP only.
    pub fn admits_host(&self, from: IpAddr) -> bool {
        match self {
            PeerPolicy::Fixed(p) => p.ip().to_canonical() == from.to_canonical(),
            PeerPolicy::FirstLocalSender => from.to_canonical().is_loopback(),
            PeerPolicy::FirstSender => true,
        }
    }
}

/// What a session without a configured peer must tell its user at start.
#[derive(Debug, Clone, Copy, PartialEq, Eq, thiserror::Error)]
pub enum PeerWarning {
    /// Loopback bind without `peer`.
    #[error(
        "no robot peer configured: the first local process that sends a valid message owns \
         the session (set `peer` to the robot's address to lock it)"
    )]
    FirstLocalSender,
    /// Network bind without `peer`, with `allow_any_peer = true`.
    #[error(
        "no robot peer configured and allow_any_peer = true: the first host on the network that \
         sends a valid message owns the session (set `peer` to the robot's address to lock it)"
    )]
    FirstSenderFromAnyHost,
}

/// A peer configuration that cannot be served safely (see [`validate_peer`]).
#[derive(Debug, Clone, Copy, PartialEq, Eq, thiserror::Error)]
pub enum PeerConfigError {
    /// `peer` is `0.0.0.0` or `::`: no robot sends from there.
    #[error(
        "peer {peer} is an unspecified address, not a robot's: give the robot controller's own \
         address (port 0 = any port of that IP)"
    )]
    UnspecifiedPeer {
        /// The configured peer.
        peer: SocketAddr,
    },
    /// `peer` is a multicast or broadcast address.
    #[error("peer {peer} is a multicast or broadcast address, not a robot's")]
    NotAHost {
        /// The configured peer.
        peer: SocketAddr,
    },
    /// `peer` can never reach `bind` (loopback against network, IPv4 against IPv6).
    #[error(
        "peer {peer} can never reach a link bound to {bind} ({why}): bind to an address on \
         the robot's network, or to 0.0.0.0"
    )]
    Unreachable {
        /// The local address.
        bind: SocketAddr,
        /// The configured peer.
        peer: SocketAddr,
        /// Which mismatch.
        why: &'static str,
    },
    /// A network bind without `peer`: any host could take the session.
    #[error(
        "bind {bind} is reachable from the network and no peer is configured: set `peer` to \
         the robot controller's address, or allow_any_peer = true to let the first host that \
         sends a valid message own the session"
    )]
    NoPeerOnNetworkBind {
        /// The local address.
        bind: SocketAddr,
    },
    /// Both `peer` and `allow_any_peer = true`: the second has no meaning.
    #[error(
        "peer {peer} is configured and allow_any_peer = true: the link answers only the peer; \
         remove allow_any_peer"
    )]
    PeerAndAllowAny {
        /// The configured peer.
        peer: SocketAddr,
    },
}

/// The peer policy of a link bound to `bind`, from the configured `peer` and
/// `allow_any_peer` (the `[robot]` keys of the same names):
///
/// | `peer` | `bind` | `allow_any_peer` | result |
/// |---|---|---|---|
/// | a host that can reach `bind` | any | false | [`PeerPolicy::Fixed`] |
/// | unspecified (`0.0.0.0`, `::`) | any | any | [`PeerConfigError::UnspecifiedPeer`] |
/// | multicast or broadcast | any | any | [`PeerConfigError::NotAHost`] |
/// | loopback vs network, IPv4 vs IPv6 | | any | [`PeerConfigError::Unreachable`] |
/// | a host | any | true | [`PeerConfigError::PeerAndAllowAny`] |
/// | none | loopback | any | [`PeerPolicy::FirstLocalSender`] (warning) |
/// | none | network or unspecified | true | [`PeerPolicy::FirstSender`] (warning) |
/// | none | network or unspecified | false | [`PeerConfigError::NoPeerOnNetworkBind`] |
///
/// The warning of an accepted policy is [`PeerPolicy::warning`].
pub fn validate_peer(
    bind: SocketAddr,
    peer: Option<SocketAddr>,
    allow_any_peer: bool,
) -> Result<PeerPolicy, PeerConfigError> {
    let Some(peer) = peer else {
        return if bind.ip().to_canonical().is_loopback() {
            Ok(PeerPolicy::FirstLocalSender)
        } else if allow_any_peer {
            Ok(PeerPolicy::FirstSender)
        } else {
            Err(PeerConfigError::NoPeerOnNetworkBind { bind })
        };
    };
    let ip = peer.ip().to_canonical();
    if ip.is_unspecified() {
        return Err(PeerConfigError::UnspecifiedPeer { peer });
    }
    if ip.is_multicast() || ip == IpAddr::V4(Ipv4Addr::BROADCAST) {
        return Err(PeerConfigError::NotAHost { peer });
    }
    if let Some(why) = unreachable_because(bind.ip(), ip) {
        return Err(PeerConfigError::Unreachable { bind, peer, why });
    }
    if allow_any_peer {
        return Err(PeerConfigError::PeerAndAllowAny { peer });
    }
    Ok(PeerPolicy::Fixed(peer))
}

/// Why datagrams from `peer` (canonical) can never arrive at a socket bound to `bind`, if so.
fn unreachable_because(bind: IpAddr, peer: IpAddr) -> Option<&'static str> {
    if bind.is_unspecified() {
        // 0.0.0.0 takes IPv4 only; :: takes both (IPv4 as mapped addresses, dual stack).
        return (bind.is_ipv4() && peer.is_ipv6()).then_some("an IPv6 peer on an IPv4 bind");
    }
    let bind = bind.to_canonical();
    if bind.is_ipv4() != peer.is_ipv4() {
        return Some("IPv4 and IPv6");
    }
    match (bind.is_loopback(), peer.is_loopback()) {
        (true, false) => Some("a network peer on a loopback bind"),
        (false, true) => Some("a loopback peer on a network bind"),
        _ => None,
    }
}

/// Which host a controller-side UDP link accepts datagrams from, under its [`PeerPolicy`].
///
/// Until the first valid message the policy alone decides; from then on the link is locked to
/// that sender's exact address (IP and port) until the link is dropped, i.e. for the whole
/// session. Datagrams from other hosts are counted and refused with
/// [`LinkError::ForeignSender`] before they are parsed, so a stray datagram can neither
/// redirect the answers nor be taken for robot state.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct PeerLock {
    policy: PeerPolicy,
    locked: Option<SocketAddr>,
    foreign: u64,
    last_foreign: Option<SocketAddr>,
}

impl Default for PeerLock {
    fn default() -> Self {
        Self::first_sender()
    }
}

impl PeerLock {
    /// Under `policy`.
    pub const fn new(policy: PeerPolicy) -> Self {
        PeerLock {
            policy,
            locked: None,
            foreign: 0,
            last_foreign: None,
        }
    }

    /// Locks to the first valid sender, from any host ([`PeerPolicy::FirstSender`]).
    pub const fn first_sender() -> Self {
        Self::new(PeerPolicy::FirstSender)
    }

    /// Locks to `peer` from the start (port 0: any port of that IP).
    pub const fn configured(peer: SocketAddr) -> Self {
        Self::new(PeerPolicy::Fixed(peer))
    }

    /// Sets (or, with `None`, clears to [`PeerPolicy::FirstSender`]) the configured peer.
    pub fn set_configured(&mut self, peer: Option<SocketAddr>) {
        self.policy = peer.map_or(PeerPolicy::FirstSender, PeerPolicy::Fixed);
    }

    /// Sets the policy (before the session starts: an existing lock stays).
    pub fn set_policy(&mut self, policy: PeerPolicy) {
        self.policy = policy;
    }

    /// The policy.
    pub fn policy(&self) -> PeerPolicy {
        self.policy
    }

    fn matches(&self, from: SocketAddr) -> bool {
        self.policy.admits(from) && self.locked.is_none_or(|l| l == from)
    }

    /// Checks a packet's sender before parsing; a foreign sender is counted
    /// and refused.
    pub fn check(&mut self, protocol: Protocol, from: SocketAddr) -> Result<(), LinkError> {
        if self.matches(from) {
            Ok(())
        } else {
            self.foreign += 1;
            self.last_foreign = Some(from);
            Err(LinkError::ForeignSender { protocol, from })
        }
    }

    /// Locks to `from` after its packet was accepted (no effect once locked).
    pub fn lock(&mut self, from: SocketAddr) {
        if self.locked.is_none() {
            self.locked = Some(from);
        }
    }

    /// The address the link is locked to, if any.
    pub fn locked(&self) -> Option<SocketAddr> {
        self.locked
    }

    /// Packets refused so far.
    pub fn foreign(&self) -> u64 {
        self.foreign
    }

    /// The last refused sender.
    pub fn last_foreign(&self) -> Option<SocketAddr> {
        self.last_foreign
    }
}

#[cfg(test)]
mod tests {
    use super::*;

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
}
