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

pub use crate::peer::PeerLock;

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

/// Parses an ASCII decimal/float number between optional ASCII whitespace, rejecting
/// non-finite values (`inf`, `NaN`) and anything that is not UTF-8: how every number of a text
/// telegram (RSI, Net F/T, the simple line protocols) is read.
pub fn parse_f64(b: &[u8]) -> Option<f64> {
    let s = std::str::from_utf8(trim(b)).ok()?;
    // Rust accepts "inf"/"nan"; telegrams never legitimately contain them.
    let v: f64 = s.parse().ok()?;
    v.is_finite().then_some(v)
}

/// Parses an unsigned decimal integer between optional ASCII whitespace: digits only (no sign),
/// at most 20 of them, within `u64` (a telegram's counter, such as RSI's `IPOC`).
pub fn parse_u64(b: &[u8]) -> Option<u64> {
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
