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
    /// to socket failures): the link itself is still usable.
    pub fn is_bad_packet(&self) -> bool {
        matches!(
            self,
            LinkError::Malformed { .. }
                | LinkError::Truncated { .. }
                | LinkError::Checksum { .. }
                | LinkError::Oversize { .. }
        )
    }

    /// True for a packet or connection from a host other than the locked
    /// peer ([`LinkError::ForeignSender`]): dropped, the link is still usable.
    pub fn is_foreign(&self) -> bool {
        matches!(self, LinkError::ForeignSender { .. })
    }
}
