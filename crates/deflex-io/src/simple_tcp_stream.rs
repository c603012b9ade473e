//! Stream plumbing of [`super`]: line assembly in a fixed buffer and a connected stream
//! with a cached read mode (no allocation, no syscall when nothing changes).

use super::P;
use crate::error::LinkError;
use crate::simple_udp::LINE_BUFFER;
use crate::udp::trim;
use std::io::{ErrorKind, Read, Write};
use std::net::TcpStream;
use std::time::{Duration, Instant};

impl Default for LineBuf {
    fn default() -> Self {
        Self::new()
    }
}

/// Assembles newline-terminated lines from a byte stream in a fixed buffer (the framing of
/// both ends of the TCP link; public so that it can be fuzzed on its own). Feed it with
/// [`LineBuf::space`] + [`LineBuf::commit`], take lines with [`LineBuf::take_line`] and read them
/// with [`LineBuf::line`].
#[derive(Debug)]
pub struct LineBuf {
    buf: [u8; LINE_BUFFER],
    /// Start of the unconsumed bytes.
    start: usize,
    /// End of the received bytes.
    end: usize,
    /// Dropping the rest of an overlong line, up to its newline.
    discarding: bool,
}

impl LineBuf {
    /// Empty.
    pub const fn new() -> Self {
        LineBuf {
            buf: [0; LINE_BUFFER],
            start: 0,
            end: 0,
            discarding: false,
        }
    }

    /// The bytes of a line returned by [`LineBuf::take_line`] (valid until the next
    /// [`LineBuf::space`]).
    pub fn line(&self, range: core::ops::Range<usize>) -> &[u8] {
        self.buf.get(range).unwrap_or(&[])
    }

    pub(super) fn clear(&mut self) {
        self.start = 0;
        self.end = 0;
        self.discarding = false;
    }

    /// Range of the next complete line (newline excluded) and consumes it.
    /// The bytes stay valid until the next [`LineBuf::space`].
    pub fn take_line(&mut self) -> Option<core::ops::Range<usize>> {
        loop {
            let pending = &self.buf[self.start..self.end];
            let Some(pos) = pending.iter().position(|&b| b == b'\n') else {
                if self.discarding {
                    // No newline yet: everything buffered belongs to the
                    // overlong line.
                    self.start = 0;
                    self.end = 0;
                }
                return None;
            };
            let line = self.start..self.start + pos;
            self.start += pos + 1;
            if self.discarding {
                self.discarding = false;
                continue;
            }
            return Some(line);
        }
    }

    /// True if the buffer holds `LINE_BUFFER` unconsumed bytes (no room to read more).
    pub(super) fn is_full(&self) -> bool {
        self.end - self.start == LINE_BUFFER
    }

    /// Like [`LineBuf::take_line`], skipping blank lines.
    pub(super) fn take_nonblank_line(&mut self) -> Option<core::ops::Range<usize>> {
        loop {
            let r = self.take_line()?;
            if !trim(&self.buf[r.clone()]).is_empty() {
                return Some(r);
            }
        }
    }

    /// Free space to read into, after moving unconsumed bytes to the front.
    /// Must be called only when [`LineBuf::take_line`] returned `None`; a
    /// full buffer then holds a line without newline that is too long.
    pub fn space(&mut self) -> Result<&mut [u8], LinkError> {
        if self.start > 0 {
            self.buf.copy_within(self.start..self.end, 0);
            self.end -= self.start;
            self.start = 0;
        }
        if self.end == LINE_BUFFER {
            self.end = 0;
            self.discarding = true;
            return Err(LinkError::Oversize {
                protocol: P,
                capacity: LINE_BUFFER,
            });
        }
        Ok(&mut self.buf[self.end..])
    }

    /// Marks `n` bytes of the last [`LineBuf::space`] as received.
    pub fn commit(&mut self, n: usize) {
        self.end = (self.end + n).min(LINE_BUFFER);
    }
}

// ------------------------------------------------------------- connection

/// A connected stream with cached read mode.
#[derive(Debug)]
pub(super) struct Conn {
    pub(super) stream: TcpStream,
    /// `Some(None)`: non-blocking; `Some(Some(d))`: blocking, read timeout
    /// d; `None`: not configured yet.
    mode: Option<Option<Duration>>,
}

/// Outcome of one read.
pub(super) enum Read1 {
    Data(usize),
    Timeout,
    /// Orderly close or reset by the peer.
    Closed,
}

impl Conn {
    pub(super) fn new(stream: TcpStream, write_timeout: Duration) -> Result<Self, LinkError> {
        // Accepted sockets do not inherit the listener's non-blocking flag
        // on Linux, but other systems differ: be explicit.
        stream.set_nonblocking(false)?;
        stream.set_nodelay(true)?;
        stream.set_write_timeout(nonzero(write_timeout))?;
        Ok(Conn { stream, mode: None })
    }

    fn set_read_mode(&mut self, timeout: Duration) -> Result<(), LinkError> {
        let wanted = nonzero(timeout);
        if self.mode == Some(wanted) {
            return Ok(());
        }
        match wanted {
            None => self.stream.set_nonblocking(true)?,
            Some(d) => {
                if !matches!(self.mode, Some(Some(_))) {
                    self.stream.set_nonblocking(false)?;
                }
                self.stream.set_read_timeout(Some(d))?;
            }
        }
        self.mode = Some(wanted);
        Ok(())
    }

    pub(super) fn read(&mut self, buf: &mut [u8], timeout: Duration) -> Result<Read1, LinkError> {
        self.set_read_mode(timeout)?;
        match self.stream.read(buf) {
            Ok(0) => Ok(Read1::Closed),
            Ok(n) => Ok(Read1::Data(n)),
            Err(e) if matches!(e.kind(), ErrorKind::WouldBlock | ErrorKind::TimedOut) => {
                Ok(Read1::Timeout)
            }
            Err(e) if e.kind() == ErrorKind::Interrupted => Ok(Read1::Timeout),
            Err(e) if is_disconnect(e.kind()) => Ok(Read1::Closed),
            Err(e) => Err(e.into()),
        }
    }

    /// Writes the whole line in blocking mode (bounded by the write timeout).
    pub(super) fn write_line(&mut self, data: &[u8]) -> Result<(), LinkError> {
        if self.mode == Some(None) {
            // A partial write in non-blocking mode would break the framing.
            self.stream.set_nonblocking(false)?;
            self.mode = None;
        }
        self.stream.write_all(data)?;
        Ok(())
    }
}

/// `now + timeout`, saturating far in the future for huge timeouts.
pub(super) fn deadline_after(timeout: Duration) -> Instant {
    let now = Instant::now();
    now.checked_add(timeout)
        .or_else(|| now.checked_add(Duration::from_secs(1 << 32)))
        .unwrap_or(now)
}

pub(super) fn nonzero(d: Duration) -> Option<Duration> {
    (!d.is_zero()).then_some(d)
}

pub(super) fn is_disconnect(kind: ErrorKind) -> bool {
    matches!(
        kind,
        ErrorKind::ConnectionReset
            | ErrorKind::ConnectionAborted
            | ErrorKind::BrokenPipe
            | ErrorKind::NotConnected
            | ErrorKind::UnexpectedEof
    )
}

/// Reads until `lines` yields a complete, non-blank line, a read times out
/// or the peer closes. The first read waits `first` (constant in a control
/// loop, so the cached read timeout is reused), later ones the time left
/// before `deadline`.
pub(super) fn fill_line(
    conn: &mut Conn,
    lines: &mut LineBuf,
    first: Duration,
    deadline: Instant,
) -> Result<Fill, LinkError> {
    let mut wait = first;
    loop {
        if let Some(r) = lines.take_nonblank_line() {
            return Ok(Fill::Line(r));
        }
        let space = lines.space()?;
        match conn.read(space, wait)? {
            Read1::Data(n) => lines.commit(n),
            Read1::Timeout => return Ok(Fill::Timeout),
            Read1::Closed => return Ok(Fill::Closed),
        }
        wait = deadline.saturating_duration_since(Instant::now());
    }
}

pub(super) enum Fill {
    Line(core::ops::Range<usize>),
    Timeout,
    Closed,
}
