//! The text line protocol of [`crate::simple_udp`] over **TCP**, for
//! controllers whose script language only has TCP client sockets — in
//! particular Universal Robots URScript (`socket_open`, `socket_send_line`,
//! `socket_read_ascii_float`), see `docs/ur/deflex_loop.script`.
//!
//! The robot connects to the PC; the PC ([`SimpleTcpLink`]) listens, by
//! default on port [`DEFAULT_PORT`] (50161). That port was chosen because it
//! collides neither with the ports a UR controller serves itself (dashboard
//! 29999, client interfaces and RTDE 30001–30004, interpreter 30020) nor
//! with the PC-side defaults of the `ur_robot_driver` (50001–50004); any
//! free port works as long as the script's `PC_PORT` matches.
//!
//! Framing: one message is one line terminated by `\n` (a preceding `\r`
//! is ignored). Lines are exactly those of [`crate::simple_udp`], parsed and
//! formatted by its pure functions:
//!
//! * robot → PC: `q <q1> … <q6>\n`, joint positions in **rad** (the
//!   tolerant parser also accepts URScript's list printing
//!   `q [0.1, -1.57, …]`);
//! * PC → robot: `(dx,dy,dz,rx,ry,rz)\n` ([`ReplyStyle::Tuple`]), the total
//!   correction — translation in **m**, rotation vector in **rad**, base
//!   axes — in the format `socket_read_ascii_float(6)` reads.
//!
//! Blank lines are skipped. A line longer than `LINE_BUFFER - 1` = 511
//! bytes (newline excluded, see [`LINE_BUFFER`]) is reported once as
//! [`LinkError::Oversize`] and then discarded up to its newline; a line
//! that does not parse is a [`LinkError::Malformed`]; in both cases the
//! connection stays open and the next call continues with the next line. Partial lines are kept
//! across reads and across calls (a timeout does not lose them).
//!
//! Connection handling on the PC side: one robot at a time. While
//! disconnected, [`RobotLink::receive`] waits for a connection within its
//! timeout; when the robot closes or resets the connection the link drops
//! it (together with any partial line) and waits for the next one, so a
//! disconnect shows up as timeouts (`Ok(None)`), like a silent UDP robot.
//! A robot that reconnects while its old connection still looks alive (a
//! half-open connection after a cable pull or a controller reboot) takes
//! over: when a receive times out, a pending new connection replaces the
//! current one. [`SimpleTcpLink::connections`] counts accepted connections.
//!
//! One client: the link serves only the robot's host: the configured address
//! ([`SimpleTcpLink::expect_peer`], IP only, as a client's source port is
//! ephemeral) or, otherwise, the host of the first connection that sent a
//! valid line, until the link is dropped. A connection from any other host
//! is closed at once and reported as [`LinkError::ForeignSender`]
//! ([`SimpleTcpLink::refused`] counts them); it never takes over.
//!
//! After construction the hot path does not allocate: lines are assembled
//! in a fixed buffer that is reused, replies are formatted into another.
//! The accepted socket has `TCP_NODELAY` set (one small line per cycle must
//! not wait for Nagle's algorithm).

use crate::error::{LinkError, Protocol};
use crate::link::{Correction, ReceivedCorrection, RobotLink, RobotSideLink, RobotState};
use crate::simple_udp::{
    LINE_BUFFER, ReplyStyle, format_correction_line, format_joints_line, parse_correction_line,
    parse_joints_line,
};
use crate::udp::trim;
use std::io::{ErrorKind, Read, Write};
use std::net::IpAddr;
use std::net::{SocketAddr, TcpListener, TcpStream, ToSocketAddrs};
use std::time::{Duration, Instant};

/// Default TCP port the PC listens on (see the module documentation).
pub const DEFAULT_PORT: u16 = 50161;

/// Default bound on a blocking write of one line (see
/// [`SimpleTcpLink::set_write_timeout`]).
pub const DEFAULT_WRITE_TIMEOUT: Duration = Duration::from_millis(50);

const P: Protocol = Protocol::SimpleLine;

/// Poll period of the listening socket while waiting for a robot.
const ACCEPT_POLL: Duration = Duration::from_millis(1);

// ------------------------------------------------------------ line buffer

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

    fn clear(&mut self) {
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
struct Conn {
    stream: TcpStream,
    /// `Some(None)`: non-blocking; `Some(Some(d))`: blocking, read timeout
    /// d; `None`: not configured yet.
    mode: Option<Option<Duration>>,
}

/// Outcome of one read.
enum Read1 {
    Data(usize),
    Timeout,
    /// Orderly close or reset by the peer.
    Closed,
}

impl Conn {
    fn new(stream: TcpStream, write_timeout: Duration) -> Result<Self, LinkError> {
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

    fn read(&mut self, buf: &mut [u8], timeout: Duration) -> Result<Read1, LinkError> {
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
    fn write_line(&mut self, data: &[u8]) -> Result<(), LinkError> {
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
fn deadline_after(timeout: Duration) -> Instant {
    let now = Instant::now();
    now.checked_add(timeout)
        .or_else(|| now.checked_add(Duration::from_secs(1 << 32)))
        .unwrap_or(now)
}

fn nonzero(d: Duration) -> Option<Duration> {
    (!d.is_zero()).then_some(d)
}

fn is_disconnect(kind: ErrorKind) -> bool {
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
fn fill_line(
    conn: &mut Conn,
    lines: &mut LineBuf,
    first: Duration,
    deadline: Instant,
) -> Result<Fill, LinkError> {
    let mut wait = first;
    loop {
        if let Some(r) = lines.take_line() {
            if trim(&lines.buf[r.clone()]).is_empty() {
                continue;
            }
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

enum Fill {
    Line(core::ops::Range<usize>),
    Timeout,
    Closed,
}

// ---------------------------------------------------------------- PC side

/// PC side: listens for the robot, receives `q` lines, answers
/// `(dx,dy,dz,rx,ry,rz)` lines on the same connection.
#[derive(Debug)]
pub struct SimpleTcpLink {
    listener: TcpListener,
    conn: Option<Conn>,
    peer: Option<SocketAddr>,
    rx: LineBuf,
    tx: [u8; LINE_BUFFER],
    write_timeout: Duration,
    count: u64,
    connections: u64,
    expected_ip: Option<IpAddr>,
    locked_ip: Option<IpAddr>,
    refused: u64,
}

impl SimpleTcpLink {
    /// Listens on `local`, e.g. `"0.0.0.0:50161"` ([`DEFAULT_PORT`]) on the
    /// robot network, or `"127.0.0.1:0"` in tests. Does not wait for the
    /// robot: the first [`RobotLink::receive`] does.
    pub fn bind(local: impl ToSocketAddrs) -> Result<Self, LinkError> {
        let listener = TcpListener::bind(local)?;
        listener.set_nonblocking(true)?;
        Ok(SimpleTcpLink {
            listener,
            conn: None,
            peer: None,
            rx: LineBuf::new(),
            tx: [0; LINE_BUFFER],
            write_timeout: DEFAULT_WRITE_TIMEOUT,
            count: 0,
            connections: 0,
            expected_ip: None,
            locked_ip: None,
            refused: 0,
        })
    }

    /// Serves only connections from `peer`'s IP (its port is ignored).
    pub fn expect_peer(&mut self, peer: SocketAddr) {
        self.expected_ip = Some(peer.ip().to_canonical());
    }

    /// Connections from other hosts closed so far.
    pub fn refused(&self) -> u64 {
        self.refused
    }

    /// The host the link serves: configured, or locked to the first robot.
    pub fn robot_host(&self) -> Option<IpAddr> {
        self.expected_ip.or(self.locked_ip)
    }

    /// Listens on all interfaces, port [`DEFAULT_PORT`].
    pub fn bind_default() -> Result<Self, LinkError> {
        Self::bind(("0.0.0.0", DEFAULT_PORT))
    }

    /// Local address the listener is bound to.
    pub fn local_addr(&self) -> Result<SocketAddr, LinkError> {
        Ok(self.listener.local_addr()?)
    }

    /// True while a robot connection is open.
    pub fn is_connected(&self) -> bool {
        self.conn.is_some()
    }

    /// Address of the connected robot.
    pub fn peer_addr(&self) -> Option<SocketAddr> {
        self.conn.as_ref().and(self.peer)
    }

    /// Number of robot connections accepted so far.
    pub fn connections(&self) -> u64 {
        self.connections
    }

    /// Bounds the time [`RobotLink::send_correction`] may block when the
    /// robot does not read (its receive window is full); zero means no
    /// bound. A write that times out closes the connection, since part of
    /// the line may have been sent. Default [`DEFAULT_WRITE_TIMEOUT`].
    pub fn set_write_timeout(&mut self, timeout: Duration) -> Result<(), LinkError> {
        self.write_timeout = timeout;
        if let Some(c) = &self.conn {
            c.stream.set_write_timeout(nonzero(timeout))?;
        }
        Ok(())
    }

    /// Closes the robot connection, if any (the listener stays open).
    pub fn disconnect(&mut self) {
        self.conn = None;
        self.peer = None;
        self.rx.clear();
    }

    /// Accepts one pending connection without waiting; true if one was. A
    /// connection from a host other than the robot's is closed and reported.
    fn try_accept(&mut self) -> Result<bool, LinkError> {
        match self.listener.accept() {
            Ok((stream, peer)) => {
                if self
                    .robot_host()
                    .is_some_and(|host| host != peer.ip().to_canonical())
                {
                    drop(stream);
                    self.refused += 1;
                    return Err(LinkError::ForeignSender {
                        protocol: P,
                        from: peer,
                    });
                }
                let conn = Conn::new(stream, self.write_timeout)?;
                self.disconnect();
                self.conn = Some(conn);
                self.peer = Some(peer);
                self.connections += 1;
                Ok(true)
            }
            Err(e)
                if matches!(
                    e.kind(),
                    ErrorKind::WouldBlock | ErrorKind::TimedOut | ErrorKind::Interrupted
                ) || is_disconnect(e.kind()) =>
            {
                Ok(false)
            }
            Err(e) => Err(e.into()),
        }
    }

    /// Waits for a robot until `deadline` (at least one attempt).
    fn accept_until(&mut self, deadline: Instant) -> Result<bool, LinkError> {
        loop {
            if self.try_accept()? {
                return Ok(true);
            }
            let left = deadline.saturating_duration_since(Instant::now());
            if left.is_zero() {
                return Ok(false);
            }
            std::thread::sleep(left.min(ACCEPT_POLL));
        }
    }
}

impl RobotLink for SimpleTcpLink {
    /// `cycle_id` is the count of valid `q` lines received since
    /// construction (it keeps counting across reconnections).
    fn receive(&mut self, timeout: Duration) -> Result<Option<RobotState>, LinkError> {
        let deadline = deadline_after(timeout);
        let mut wait = timeout;
        let mut takeover_checked = false;
        loop {
            if self.conn.is_none() {
                if !self.accept_until(deadline)? {
                    return Ok(None);
                }
                wait = deadline.saturating_duration_since(Instant::now());
            }
            let Some(conn) = self.conn.as_mut() else {
                return Ok(None);
            };
            match fill_line(conn, &mut self.rx, wait, deadline)? {
                Fill::Line(r) => {
                    let (q, joint_count) = parse_joints_line(&self.rx.buf[r])?;
                    self.count += 1;
                    if self.locked_ip.is_none() {
                        self.locked_ip = self.peer.map(|p| p.ip().to_canonical());
                    }
                    return Ok(Some(RobotState {
                        q_rad: q,
                        joint_count,
                        cycle_id: self.count,
                        ..Default::default()
                    }));
                }
                Fill::Closed => {
                    self.disconnect();
                    wait = deadline.saturating_duration_since(Instant::now());
                }
                Fill::Timeout => {
                    // A silent connection may be half-open while the robot
                    // has reconnected: let a pending connection take over.
                    if takeover_checked || !self.try_accept()? {
                        return Ok(None);
                    }
                    takeover_checked = true;
                    wait = deadline.saturating_duration_since(Instant::now());
                }
            }
        }
    }

    /// Sends `(dx,dy,dz,rx,ry,rz)\n`. [`LinkError::NoPeer`] while no robot
    /// is connected; a failed write closes the connection.
    fn send_correction(&mut self, c: &Correction) -> Result<(), LinkError> {
        let n = format_correction_line(c, ReplyStyle::Tuple, &mut self.tx)?;
        let conn = self
            .conn
            .as_mut()
            .ok_or(LinkError::NoPeer { protocol: P })?;
        if let Err(e) = conn.write_line(&self.tx[..n]) {
            self.disconnect();
            return Err(e);
        }
        Ok(())
    }

    fn protocol(&self) -> Protocol {
        P
    }
}

// ------------------------------------------------------------- robot side

/// Robot side (simulated cell, tests): connects to the PC like the
/// URScript program does, sends `q` lines and reads correction lines.
#[derive(Debug)]
pub struct SimpleTcpRobotEndpoint {
    conn: Conn,
    rx: LineBuf,
    tx: [u8; LINE_BUFFER],
    count: u64,
    closed: bool,
}

impl SimpleTcpRobotEndpoint {
    /// Connects to the PC at `pc`, waiting up to `timeout` (a zero timeout
    /// waits as long as the system does).
    pub fn connect(pc: SocketAddr, timeout: Duration) -> Result<Self, LinkError> {
        let stream = match nonzero(timeout) {
            Some(t) => TcpStream::connect_timeout(&pc, t)?,
            None => TcpStream::connect(pc)?,
        };
        Ok(SimpleTcpRobotEndpoint {
            conn: Conn::new(stream, DEFAULT_WRITE_TIMEOUT)?,
            rx: LineBuf::new(),
            tx: [0; LINE_BUFFER],
            count: 0,
            closed: false,
        })
    }

    /// Local socket address.
    pub fn local_addr(&self) -> Result<SocketAddr, LinkError> {
        Ok(self.conn.stream.local_addr()?)
    }
}

fn closed_error() -> LinkError {
    LinkError::Io(ErrorKind::UnexpectedEof.into())
}

impl RobotSideLink for SimpleTcpRobotEndpoint {
    /// Only the joints are sent (the protocol has no cycle id or pose).
    fn send_state(&mut self, s: &RobotState) -> Result<(), LinkError> {
        let n = format_joints_line(s.joints(), &mut self.tx)?;
        self.conn.write_line(&self.tx[..n])
    }

    /// `cycle_id` is the count of corrections received. Once the PC has
    /// closed the connection every call fails with
    /// [`ErrorKind::UnexpectedEof`].
    fn receive_correction(
        &mut self,
        timeout: Duration,
    ) -> Result<Option<ReceivedCorrection>, LinkError> {
        if self.closed {
            return Err(closed_error());
        }
        let deadline = deadline_after(timeout);
        match fill_line(&mut self.conn, &mut self.rx, timeout, deadline)? {
            Fill::Line(r) => {
                let correction = parse_correction_line(&self.rx.buf[r])?;
                self.count += 1;
                Ok(Some(ReceivedCorrection {
                    correction,
                    cycle_id: self.count,
                    joint_correction_rad: None,
                }))
            }
            Fill::Timeout => Ok(None),
            Fill::Closed => {
                self.closed = true;
                Err(closed_error())
            }
        }
    }
}

#[cfg(test)]
#[path = "simple_tcp_tests.rs"]
mod tests;
