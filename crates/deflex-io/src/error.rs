//! Error type shared by every protocol of the crate.
//!
//! Parsing never panics on network input: each malformed packet becomes a
//! [`LinkError`] whose reason is a static string, so that building an error on
//! the hot path does not allocate either.

use std::fmt;

/// Which wire protocol produced an error.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum Protocol {
    /// KUKA Robot Sensor Interface (XML over UDP).
    Rsi,
    /// ABB Externally Guided Motion (protobuf over UDP).
    Egm,
    /// The deflex binary protocol used with the Stäubli VAL3 `alter` program.
    Staubli,
    /// ATI Net F/T Raw Data Transfer (binary UDP).
    NetFt,
    /// The generic text line protocol of [`crate::simple_udp`] (UDP) and
    /// [`crate::simple_tcp`] (TCP).
    SimpleLine,
    /// The small XML scanner of [`crate::xml`].
    Xml,
    /// A ROS 2 topic over DDS (the `deflex-ros2` bridge's sensor link).
    Ros2,
    /// FANUC Stream Motion (option J519), binary UDP (port 60015).
    FanucStream,
    /// Universal Robots RTDE over TCP ([`crate::rtde`]).
    Rtde,
}

impl fmt::Display for Protocol {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        let s = match self {
            Protocol::Rsi => "KUKA RSI",
            Protocol::Egm => "ABB EGM",
            Protocol::Staubli => "deflex/Staubli",
            Protocol::NetFt => "ATI Net F/T RDT",
            Protocol::SimpleLine => "simple line",
            Protocol::Xml => "XML",
            Protocol::Ros2 => "ROS 2",
            Protocol::FanucStream => "FANUC Stream Motion",
            Protocol::Rtde => "UR RTDE",
        };
        f.write_str(s)
    }
}

/// Everything that can go wrong on a link.
#[derive(Debug, thiserror::Error)]
pub enum LinkError {
    /// Socket-level failure (other than a read timeout, which is reported as
    /// `Ok(None)` by the `receive` functions).
    #[error("I/O error: {0}")]
    Io(#[from] std::io::Error),
    /// The link's peer configuration cannot be served safely ([`crate::validate_peer`]).
    #[error("robot peer configuration: {0}")]
    PeerConfig(#[from] crate::PeerConfigError),
    /// The packet does not follow the protocol.
    #[error("malformed {protocol} packet: {reason}")]
    Malformed {
        /// Protocol whose parser rejected the packet.
        protocol: Protocol,
        /// Human-readable, static reason.
        reason: &'static str,
    },
    /// The packet is shorter than the protocol requires.
    #[error("truncated {protocol} packet: need {expected} bytes, got {got}")]
    Truncated {
        /// Protocol whose parser rejected the packet.
        protocol: Protocol,
        /// Number of bytes required.
        expected: usize,
        /// Number of bytes available.
        got: usize,
    },
    /// The packet's checksum does not match its content.
    #[error("{protocol} checksum mismatch: packet says {expected:#06x}, computed {computed:#06x}")]
    Checksum {
        /// Protocol whose parser rejected the packet.
        protocol: Protocol,
        /// Checksum carried by the packet.
        expected: u32,
        /// Checksum computed over the received bytes.
        computed: u32,
    },
    /// A received datagram (or, on a TCP line stream, a line) did not fit in
    /// the receive buffer.
    #[error("{protocol} message larger than the {capacity}-byte receive buffer")]
    Oversize {
        /// Protocol of the endpoint.
        protocol: Protocol,
        /// Receive buffer size in bytes.
        capacity: usize,
    },
    /// A formatted message did not fit in the fixed output buffer.
    #[error("{protocol} output buffer of {capacity} bytes is too small")]
    BufferTooSmall {
        /// Protocol of the formatter.
        protocol: Protocol,
        /// Output buffer size in bytes.
        capacity: usize,
    },
    /// Nobody to send to yet: the peer address is learned from the first
    /// valid packet it sends (or, for KUKA RSI, no telegram to answer yet).
    #[error("{protocol}: no peer known yet (nothing received)")]
    NoPeer {
        /// Protocol of the endpoint.
        protocol: Protocol,
    },
    /// A packet (or, on TCP, a connection) came from a host that is not the
    /// peer this link is locked to (the configured robot or sensor address,
    /// or the first valid sender of the session). It is dropped unanswered.
    #[error("{protocol}: dropped a packet from {from}, which is not the locked peer")]
    ForeignSender {
        /// Protocol of the endpoint.
        protocol: Protocol,
        /// Where the packet came from.
        from: std::net::SocketAddr,
    },
    /// A message from the locked robot that cannot be this session's next cycle (joint count
    /// changed, sequence number not advancing, robot time going back, see
    /// [`crate::guard`]): counted by reason and dropped unanswered; the link is still usable.
    #[error("{protocol}: dropped a robot message unanswered: {reason}")]
    Dropped {
        /// Protocol of the endpoint.
        protocol: Protocol,
        /// Which rule the message broke, with its values.
        reason: crate::guard::DropReason,
    },
    /// TCP: a connection arrived while another one held the session; it was closed at once,
    /// unanswered. `starving`: the holder was not serving robot lines (none yet, or none for
    /// [`crate::simple_tcp::STARVE_SILENCE`]), so the refused client may be the robot kept out.
    #[error(
        "{protocol}: refused a second connection from {from} while {holder} holds the session{}",
        if *starving { " and sends no robot lines (the robot may be starved)" } else { "" }
    )]
    SecondConnection {
        /// Protocol of the endpoint.
        protocol: Protocol,
        /// The refused client.
        from: std::net::SocketAddr,
        /// The connection holding the session.
        holder: std::net::SocketAddr,
        /// The holder was not serving robot lines.
        starving: bool,
    },
    /// The peer refused the session's set-up, or deflex refused the peer's (an RTDE recipe with
    /// a variable the controller does not know or another client holds, a controller too old):
    /// the link cannot serve this session until the cause is removed.
    #[error("{protocol}: {refusal}")]
    SetupRefused {
        /// Protocol of the endpoint.
        protocol: Protocol,
        /// What was refused, with its values.
        refusal: crate::rtde::SetupRefusal,
    },
    /// A value was rejected before sending (e.g. non-finite number, or a
    /// configuration string with forbidden characters).
    #[error("{protocol}: invalid value: {reason}")]
    InvalidValue {
        /// Protocol of the formatter.
        protocol: Protocol,
        /// Human-readable, static reason.
        reason: &'static str,
    },
}

impl LinkError {
    /// Shorthand for [`LinkError::Malformed`].
    pub const fn malformed(protocol: Protocol, reason: &'static str) -> Self {
        LinkError::Malformed { protocol, reason }
    }

    /// True for errors caused by the content of a received packet (as opposed
    /// to socket failures): the link itself is still usable. This includes a
    /// well-formed robot message dropped by the session rules
    /// ([`LinkError::Dropped`], see [`LinkError::is_dropped`]).
    pub fn is_bad_packet(&self) -> bool {
        matches!(
            self,
            LinkError::Malformed { .. }
                | LinkError::Truncated { .. }
                | LinkError::Checksum { .. }
                | LinkError::Oversize { .. }
                | LinkError::Dropped { .. }
        )
    }

    /// True for a robot message dropped unanswered by the session rules
    /// ([`LinkError::Dropped`]).
    pub fn is_dropped(&self) -> bool {
        matches!(self, LinkError::Dropped { .. })
    }

    /// True for a packet or connection from anyone but the session's robot: another host
    /// ([`LinkError::ForeignSender`]) or, over TCP, a second connection
    /// ([`LinkError::SecondConnection`]). Refused, the link is still usable.
    pub fn is_foreign(&self) -> bool {
        matches!(
            self,
            LinkError::ForeignSender { .. } | LinkError::SecondConnection { .. }
        )
    }

    /// The refused sender of a [`LinkError::ForeignSender`] or
    /// [`LinkError::SecondConnection`].
    pub fn foreign_source(&self) -> Option<std::net::SocketAddr> {
        match self {
            LinkError::ForeignSender { from, .. } | LinkError::SecondConnection { from, .. } => {
                Some(*from)
            }
            _ => None,
        }
    }

    /// True for a [`LinkError::SecondConnection`] refused while the holder was not serving
    /// robot lines: the robot may be kept out, the session must end as faulted.
    pub fn is_starving(&self) -> bool {
        matches!(self, LinkError::SecondConnection { starving: true, .. })
    }
}
