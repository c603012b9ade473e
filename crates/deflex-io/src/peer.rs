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
