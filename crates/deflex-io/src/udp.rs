//! Thin wrapper around [`std::net::UdpSocket`] shared by every endpoint.
//!
//! It caches the read timeout so that a receive loop with a constant timeout
//! does not issue a `setsockopt` per call, treats a zero timeout as a
//! non-blocking poll, maps timeouts to `Ok(None)` and refuses datagrams that
//! fill the whole receive buffer (they may have been truncated by the kernel).

use crate::error::{LinkError, Protocol};
use std::io::ErrorKind;
use std::net::{SocketAddr, ToSocketAddrs, UdpSocket};
use std::time::Duration;

/// A UDP socket with timeout caching and an optional remembered peer.
#[derive(Debug)]
pub struct UdpEndpoint {
    socket: UdpSocket,
    protocol: Protocol,
    /// `Some(None)`: non-blocking; `Some(Some(d))`: blocking with timeout d;
    /// `None`: not configured yet.
    mode: Option<Option<Duration>>,
    peer: Option<SocketAddr>,
}

impl UdpEndpoint {
    /// Binds a socket to `local` (e.g. `"0.0.0.0:59152"` or `"127.0.0.1:0"`).
    pub fn bind(local: impl ToSocketAddrs, protocol: Protocol) -> Result<Self, LinkError> {
        Ok(UdpEndpoint {
            socket: UdpSocket::bind(local)?,
            protocol,
            mode: None,
            peer: None,
        })
    }

    /// Local address the socket is bound to.
    pub fn local_addr(&self) -> Result<SocketAddr, LinkError> {
        Ok(self.socket.local_addr()?)
    }

    /// The peer packets are sent to, if known.
    pub fn peer(&self) -> Option<SocketAddr> {
        self.peer
    }

    /// Sets the peer packets are sent to.
    pub fn set_peer(&mut self, peer: SocketAddr) {
        self.peer = Some(peer);
    }

    /// Underlying socket (e.g. to tune buffer sizes or priorities).
    pub fn socket(&self) -> &UdpSocket {
        &self.socket
    }

    fn set_timeout(&mut self, timeout: Duration) -> Result<(), LinkError> {
        let wanted = if timeout.is_zero() {
            None
        } else {
            Some(timeout)
        };
        if self.mode == Some(wanted) {
            return Ok(());
        }
        match wanted {
            None => self.socket.set_nonblocking(true)?,
            Some(d) => {
                if self.mode == Some(None) || self.mode.is_none() {
                    self.socket.set_nonblocking(false)?;
                }
                self.socket.set_read_timeout(Some(d))?;
            }
        }
        self.mode = Some(wanted);
        Ok(())
    }

    /// Receives one datagram into `buf`, waiting up to `timeout`.
    /// Returns the length and source; `Ok(None)` on timeout.
    pub fn recv(
        &mut self,
        buf: &mut [u8],
        timeout: Duration,
    ) -> Result<Option<(usize, SocketAddr)>, LinkError> {
        self.set_timeout(timeout)?;
        match self.socket.recv_from(buf) {
            Ok((n, from)) => {
                if n >= buf.len() {
                    Err(LinkError::Oversize {
                        protocol: self.protocol,
                        capacity: buf.len(),
                    })
                } else {
                    Ok(Some((n, from)))
                }
            }
            Err(e) if matches!(e.kind(), ErrorKind::WouldBlock | ErrorKind::TimedOut) => Ok(None),
            Err(e) => Err(e.into()),
        }
    }

    /// Sends `data` to the remembered peer.
    pub fn send(&mut self, data: &[u8]) -> Result<(), LinkError> {
        let peer = self.peer.ok_or(LinkError::NoPeer {
            protocol: self.protocol,
        })?;
        self.send_to(data, peer)
    }

    /// Sends `data` to `to`.
    pub fn send_to(&mut self, data: &[u8], to: SocketAddr) -> Result<(), LinkError> {
        self.socket.send_to(data, to)?;
        Ok(())
    }
}

/// Which host a controller-side link accepts packets from.
///
/// Until the first valid telegram the link accepts any sender (unless a peer
/// is configured); from then on it is locked to that sender's address (IP
/// and port) until the link is dropped, i.e. for the whole session. A
/// configured peer locks from the start; its port 0 means "any port of that
/// IP" (for controllers whose source port is not fixed). Packets from other
/// hosts are counted and refused with [`LinkError::ForeignSender`] before
/// they are parsed, so a stray datagram can neither redirect the answers nor
/// be taken for robot state.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub struct PeerLock {
    configured: Option<SocketAddr>,
    locked: Option<SocketAddr>,
    foreign: u64,
    last_foreign: Option<SocketAddr>,
}

impl PeerLock {
    /// Locks to the first valid sender.
    pub const fn first_sender() -> Self {
        PeerLock {
            configured: None,
            locked: None,
            foreign: 0,
            last_foreign: None,
        }
    }

    /// Locks to `peer` from the start (port 0: any port of that IP).
    pub const fn configured(peer: SocketAddr) -> Self {
        PeerLock {
            configured: Some(peer),
            locked: None,
            foreign: 0,
            last_foreign: None,
        }
    }

    /// Sets (or clears) the configured peer.
    pub fn set_configured(&mut self, peer: Option<SocketAddr>) {
        self.configured = peer;
    }

    fn matches(&self, from: SocketAddr) -> bool {
        if let Some(p) = self.configured {
            let ip_ok = p.ip() == from.ip() || (p.ip().to_canonical() == from.ip().to_canonical());
            if !ip_ok || (p.port() != 0 && p.port() != from.port()) {
                return false;
            }
        }
        self.locked.is_none_or(|l| l == from)
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

    /// Locks to `from` after its packet parsed (no effect once locked).
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

/// A fixed-capacity byte buffer implementing [`core::fmt::Write`], used to
/// format text telegrams without allocating.
#[derive(Debug)]
pub struct FixedBuf<const N: usize> {
    data: [u8; N],
    len: usize,
    overflow: bool,
}

impl<const N: usize> Default for FixedBuf<N> {
    fn default() -> Self {
        Self::new()
    }
}

impl<const N: usize> FixedBuf<N> {
    /// An empty buffer.
    pub const fn new() -> Self {
        FixedBuf {
            data: [0; N],
            len: 0,
            overflow: false,
        }
    }

    /// Empties the buffer.
    pub fn clear(&mut self) {
        self.len = 0;
        self.overflow = false;
    }

    /// Formatted bytes so far.
    pub fn as_bytes(&self) -> &[u8] {
        &self.data[..self.len]
    }

    /// True if a write did not fit (the content is then incomplete).
    pub fn overflowed(&self) -> bool {
        self.overflow
    }

    /// Appends raw bytes; returns false (and marks overflow) if they do not fit.
    pub fn push_bytes(&mut self, b: &[u8]) -> bool {
        if self.len + b.len() > N {
            self.overflow = true;
            return false;
        }
        self.data[self.len..self.len + b.len()].copy_from_slice(b);
        self.len += b.len();
        true
    }
}

impl<const N: usize> core::fmt::Write for FixedBuf<N> {
    fn write_str(&mut self, s: &str) -> core::fmt::Result {
        if self.push_bytes(s.as_bytes()) {
            Ok(())
        } else {
            Err(core::fmt::Error)
        }
    }
}

/// A [`core::fmt::Write`] adapter over a caller-provided byte slice: the
/// pure formatters of this crate write into `&mut [u8]` through it.
#[derive(Debug)]
pub struct SliceWriter<'a> {
    buf: &'a mut [u8],
    len: usize,
}

impl<'a> SliceWriter<'a> {
    /// Writes into `buf` from its start.
    pub fn new(buf: &'a mut [u8]) -> Self {
        SliceWriter { buf, len: 0 }
    }

    /// Number of bytes written.
    pub fn len(&self) -> usize {
        self.len
    }

    /// True if nothing was written.
    pub fn is_empty(&self) -> bool {
        self.len == 0
    }

    /// Appends raw bytes, failing if they do not fit.
    pub fn push_bytes(&mut self, b: &[u8]) -> core::fmt::Result {
        let end = self.len + b.len();
        if end > self.buf.len() {
            return Err(core::fmt::Error);
        }
        self.buf[self.len..end].copy_from_slice(b);
        self.len = end;
        Ok(())
    }
}

impl core::fmt::Write for SliceWriter<'_> {
    fn write_str(&mut self, s: &str) -> core::fmt::Result {
        self.push_bytes(s.as_bytes())
    }
}

/// Parses an ASCII decimal/float number, rejecting non-finite values.
pub(crate) fn parse_f64(b: &[u8]) -> Option<f64> {
    let s = std::str::from_utf8(trim(b)).ok()?;
    // Rust accepts "inf"/"nan"; telegrams never legitimately contain them.
    let v: f64 = s.parse().ok()?;
    v.is_finite().then_some(v)
}

/// Parses an unsigned decimal integer.
pub(crate) fn parse_u64(b: &[u8]) -> Option<u64> {
    let b = trim(b);
    if b.is_empty() || b.len() > 20 || !b.iter().all(u8::is_ascii_digit) {
        return None;
    }
    std::str::from_utf8(b).ok()?.parse().ok()
}

/// Strips ASCII whitespace on both ends.
pub(crate) fn trim(mut b: &[u8]) -> &[u8] {
    while let [first, rest @ ..] = b {
        if first.is_ascii_whitespace() {
            b = rest;
        } else {
            break;
        }
    }
    while let [rest @ .., last] = b {
        if last.is_ascii_whitespace() {
            b = rest;
        } else {
            break;
        }
    }
    b
}

#[cfg(test)]
mod tests {
    use super::*;
    use core::fmt::Write;

    #[test]
    fn fixed_buf_overflow() {
        let mut b = FixedBuf::<4>::new();
        assert!(write!(b, "abc").is_ok());
        assert!(write!(b, "de").is_err());
        assert!(b.overflowed());
        b.clear();
        assert!(!b.overflowed());
        assert_eq!(b.as_bytes(), b"");
    }

    #[test]
    fn numbers() {
        assert_eq!(parse_f64(b" 1.5 "), Some(1.5));
        assert_eq!(parse_f64(b"-2e3"), Some(-2000.0));
        assert_eq!(parse_f64(b"inf"), None);
        assert_eq!(parse_f64(b"NaN"), None);
        assert_eq!(parse_f64(b""), None);
        assert_eq!(parse_f64(&[0xff, 0x31]), None);
        assert_eq!(parse_u64(b"123"), Some(123));
        assert_eq!(parse_u64(b"+1"), None);
        assert_eq!(parse_u64(b"99999999999999999999999"), None);
    }

    #[test]
    fn peer_lock_first_sender_and_configured() {
        let a: SocketAddr = "10.0.0.2:6000".parse().unwrap();
        let b: SocketAddr = "10.0.0.3:6000".parse().unwrap();
        let a2: SocketAddr = "10.0.0.2:6001".parse().unwrap();
        let mut l = PeerLock::first_sender();
        assert!(
            l.check(Protocol::Rsi, b).is_ok(),
            "anyone until the first telegram"
        );
        l.lock(a);
        l.lock(b);
        assert_eq!(l.locked(), Some(a));
        assert!(l.check(Protocol::Rsi, a).is_ok());
        assert!(l.check(Protocol::Rsi, b).unwrap_err().is_foreign());
        assert!(l.check(Protocol::Rsi, a2).is_err(), "same host, other port");
        assert_eq!((l.foreign(), l.last_foreign()), (2, Some(a2)));
        let mut c = PeerLock::configured("10.0.0.2:0".parse().unwrap());
        assert!(c.check(Protocol::Egm, b).is_err());
        assert!(
            c.check(Protocol::Egm, a2).is_ok(),
            "port 0: any port of the IP"
        );
        c.lock(a2);
        assert!(
            c.check(Protocol::Egm, a).is_err(),
            "then locked to that port"
        );
        let mut d = PeerLock::configured(a);
        assert!(d.check(Protocol::Egm, a2).is_err());
        assert!(d.check(Protocol::Egm, a).is_ok());
    }

    #[test]
    fn zero_timeout_is_a_poll() {
        let mut e = UdpEndpoint::bind("127.0.0.1:0", Protocol::Rsi).unwrap();
        let mut buf = [0u8; 16];
        assert!(e.recv(&mut buf, Duration::ZERO).unwrap().is_none());
        assert!(
            e.recv(&mut buf, Duration::from_millis(1))
                .unwrap()
                .is_none()
        );
        assert!(matches!(e.send(b"x"), Err(LinkError::NoPeer { .. })));
    }
}
