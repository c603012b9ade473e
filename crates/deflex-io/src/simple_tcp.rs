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
//! **One robot connection.** The PC side serves exactly one connection at a time, the
//! *holder*. While it is held:
//!
//! * any other connection — from another host or from the robot's own — is accepted by the
//!   kernel and closed at once, unanswered, and reported as [`LinkError::SecondConnection`]
//!   (counted in [`LinkCounters::refused_busy`]); it never takes over, whatever it sends.
//!   The holder's lines come first: at most one refusal is made per line delivered or per
//!   silent wait, so a flood of connections delays a robot line by one `accept` + `close` at
//!   most, and pending connections wait in the kernel's backlog (bounded by the system, 128
//!   on Linux by default), never in deflex;
//! * a refusal while the holder is not serving robot lines (it has sent no valid line yet, or
//!   none for [`STARVE_SILENCE`]) is flagged `starving` and counted in
//!   [`LinkCounters::refused_starving`]: the refused client may be the robot kept out by a
//!   squatter, and a runtime must end such a session as faulted;
//! * a holder that sends no valid line for the idle timeout ([`DEFAULT_IDLE_TIMEOUT`],
//!   [`SimpleTcpLink::set_idle_timeout`] within [`MIN_IDLE_TIMEOUT`]–[`MAX_IDLE_TIMEOUT`]) is
//!   closed ([`LinkCounters::idle_closed`]) and the next connection is served: this is how a
//!   half-open connection (a cable pull, a controller reboot) ends, and how a squatter loses
//!   the session. A robot that reconnects meanwhile is refused and must connect again.
//!
//! When the holder closes or resets the connection the link drops it (with any partial line)
//! and serves the next connection, so a disconnect shows up as timeouts (`Ok(None)`), like a
//! silent UDP robot. [`LinkCounters::connections`] counts the connections served.
//!
//! **Robot's host.** Under [`PeerPolicy::Fixed`] ([`SimpleTcpLink::expect_peer`], the IP only,
//! as a client's source port is ephemeral) only that host is served; under
//! [`PeerPolicy::FirstLocalSender`] only loopback clients; otherwise any host. Once a
//! connection has sent a valid line, its host is the session's for good. A connection from any
//! other host is closed at once and reported as [`LinkError::ForeignSender`]
//! ([`SimpleTcpLink::refused`] and [`LinkCounters::foreign`] count them).
//!
//! **Session rules.** As over UDP ([`crate::guard`]): a line whose joint count differs from the
//! session's is dropped unanswered ([`LinkError::Dropped`]); a line's optional `seq=` must
//! advance within one connection (a new connection starts a new count).
//!
//! After construction the hot path does not allocate: lines are assembled
//! in a fixed buffer that is reused, replies are formatted into another.
//! The accepted socket has `TCP_NODELAY` set (one small line per cycle must
//! not wait for Nagle's algorithm).

use crate::error::{LinkError, Protocol};
use crate::guard::{LinkCounters, SessionGuard};
use crate::link::{Correction, ReceivedCorrection, RobotLink, RobotSideLink, RobotState};
use crate::peer::PeerPolicy;
use crate::simple_udp::{
    LINE_BUFFER, ReplyStyle, format_correction_line, format_joints_line, parse_correction_line,
    parse_state_line,
};
use std::io::ErrorKind;
use std::net::{IpAddr, SocketAddr, TcpListener, TcpStream, ToSocketAddrs};
use std::time::{Duration, Instant};

#[path = "simple_tcp_stream.rs"]
mod stream;
pub use stream::LineBuf;
use stream::{Conn, Fill, Read1, deadline_after, fill_line, is_disconnect, nonzero};

/// Default TCP port the PC listens on (see the module documentation).
pub const DEFAULT_PORT: u16 = 50161;

/// Default bound on a blocking write of one line (see
/// [`SimpleTcpLink::set_write_timeout`]).
pub const DEFAULT_WRITE_TIMEOUT: Duration = Duration::from_millis(50);

/// Default idle timeout: a held connection without a valid line for this long is closed. As
/// long as the longest `robot.timeout_s` a `CELL.toml` accepts, so a session the runtime still
/// considers alive is never cut under it.
pub const DEFAULT_IDLE_TIMEOUT: Duration = Duration::from_secs(10);
/// Shortest idle timeout [`SimpleTcpLink::set_idle_timeout`] accepts.
pub const MIN_IDLE_TIMEOUT: Duration = Duration::from_millis(10);
/// Longest idle timeout [`SimpleTcpLink::set_idle_timeout`] accepts.
pub const MAX_IDLE_TIMEOUT: Duration = Duration::from_secs(600);

/// A holder without a valid line for this long is not serving robot lines: a connection
/// refused then is flagged `starving`. Ten cycles of the slowest robot cycle deflex serves
/// (KUKA RSI's 12 ms rounds to 10 ms; UR CB3 8 ms).
pub const STARVE_SILENCE: Duration = Duration::from_millis(100);

const P: Protocol = Protocol::SimpleLine;

/// Poll period of the listening socket while waiting for a robot.
const ACCEPT_POLL: Duration = Duration::from_millis(1);

// ---------------------------------------------------------------- PC side

/// The connection holding the session.
#[derive(Debug)]
struct Holder {
    conn: Conn,
    addr: SocketAddr,
    accepted: Instant,
    last_valid: Option<Instant>,
}

impl Holder {
    /// Since when it has sent no valid line.
    fn silent_since(&self) -> Instant {
        self.last_valid.unwrap_or(self.accepted)
    }
}

/// PC side: listens for the robot, receives `q` lines, answers
/// `(dx,dy,dz,rx,ry,rz)` lines on the same connection.
#[derive(Debug)]
pub struct SimpleTcpLink {
    listener: TcpListener,
    holder: Option<Holder>,
    rx: LineBuf,
    tx: [u8; LINE_BUFFER],
    write_timeout: Duration,
    idle_timeout: Duration,
    count: u64,
    policy: PeerPolicy,
    locked_ip: Option<IpAddr>,
    guard: SessionGuard,
    /// One refusal may be made: a line was delivered or a wait ended in silence since the
    /// last one.
    refusal_credit: bool,
    stats: LinkCounters,
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
            holder: None,
            rx: LineBuf::new(),
            tx: [0; LINE_BUFFER],
            write_timeout: DEFAULT_WRITE_TIMEOUT,
            idle_timeout: DEFAULT_IDLE_TIMEOUT,
            count: 0,
            policy: PeerPolicy::FirstSender,
            locked_ip: None,
            guard: SessionGuard::new(),
            refusal_credit: true,
            stats: LinkCounters::default(),
        })
    }

    /// Serves only connections from `peer`'s IP (its port is ignored).
    pub fn expect_peer(&mut self, peer: SocketAddr) {
        self.policy = PeerPolicy::Fixed(peer);
    }

    /// Sets the peer policy (see [`crate::peer::validate_peer`]; a fixed peer's port is
    /// ignored).
    pub fn set_peer_policy(&mut self, policy: PeerPolicy) {
        self.policy = policy;
    }

    /// Connections from other hosts closed so far.
    pub fn refused(&self) -> u64 {
        self.stats.foreign
    }

    /// The host the link serves: configured, or locked to the first robot.
    pub fn robot_host(&self) -> Option<IpAddr> {
        match self.policy {
            PeerPolicy::Fixed(p) => Some(p.ip().to_canonical()),
            _ => self.locked_ip,
        }
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
        self.holder.is_some()
    }

    /// Address of the connected robot.
    pub fn peer_addr(&self) -> Option<SocketAddr> {
        self.holder.as_ref().map(|h| h.addr)
    }

    /// Number of robot connections served so far.
    pub fn connections(&self) -> u64 {
        self.stats.connections
    }

    /// Bounds the time [`RobotLink::send_correction`] may block when the
    /// robot does not read (its receive window is full); zero means no
    /// bound. A write that times out closes the connection, since part of
    /// the line may have been sent. Default [`DEFAULT_WRITE_TIMEOUT`].
    pub fn set_write_timeout(&mut self, timeout: Duration) -> Result<(), LinkError> {
        self.write_timeout = timeout;
        if let Some(h) = &self.holder {
            h.conn.stream.set_write_timeout(nonzero(timeout))?;
        }
        Ok(())
    }

    /// Sets the idle timeout (see the module documentation); refused outside
    /// [`MIN_IDLE_TIMEOUT`]–[`MAX_IDLE_TIMEOUT`].
    pub fn set_idle_timeout(&mut self, timeout: Duration) -> Result<(), LinkError> {
        if !(MIN_IDLE_TIMEOUT..=MAX_IDLE_TIMEOUT).contains(&timeout) {
            return Err(LinkError::InvalidValue {
                protocol: P,
                reason: "idle timeout outside 10 ms to 600 s",
            });
        }
        self.idle_timeout = timeout;
        Ok(())
    }

    /// The idle timeout.
    pub fn idle_timeout(&self) -> Duration {
        self.idle_timeout
    }

    /// Closes the robot connection, if any (the listener stays open).
    pub fn disconnect(&mut self) {
        self.holder = None;
        self.rx.clear();
    }

    /// True if a client of host `ip` may hold the session.
    fn admits(&self, ip: IpAddr) -> bool {
        self.policy.admits_host(ip) && self.locked_ip.is_none_or(|l| l == ip.to_canonical())
    }

    /// Accepts one pending connection without waiting, if any. Without a holder it becomes
    /// the holder (`Ok(true)`); otherwise, or from a host that may not hold the session, it is
    /// closed at once and reported.
    fn try_accept(&mut self) -> Result<bool, LinkError> {
        let (stream, from) = match self.listener.accept() {
            Ok(pair) => pair,
            Err(e)
                if matches!(
                    e.kind(),
                    ErrorKind::WouldBlock | ErrorKind::TimedOut | ErrorKind::Interrupted
                ) || is_disconnect(e.kind()) =>
            {
                return Ok(false);
            }
            Err(e) => return Err(e.into()),
        };
        if !self.admits(from.ip()) {
            drop(stream);
            self.stats.foreign += 1;
            return Err(LinkError::ForeignSender { protocol: P, from });
        }
        if self.holder.is_some() && !self.holder_closed() {
            let Some(h) = &self.holder else {
                return Ok(false);
            };
            drop(stream);
            let starving = h.last_valid.is_none_or(|t| t.elapsed() >= STARVE_SILENCE);
            self.stats.refused_busy += 1;
            if starving {
                self.stats.refused_starving += 1;
            }
            return Err(LinkError::SecondConnection {
                protocol: P,
                from,
                holder: h.addr,
                starving,
            });
        }
        let conn = Conn::new(stream, self.write_timeout)?;
        self.disconnect();
        self.guard.restart_stream();
        self.holder = Some(Holder {
            conn,
            addr: from,
            accepted: Instant::now(),
            last_valid: None,
        });
        self.stats.connections += 1;
        Ok(true)
    }

    /// True if the holder has closed (or reset) its connection, checked without waiting
    /// before a newcomer is refused: a robot that closes and reconnects at once is served, not
    /// refused because its close was not read yet. Bytes read meanwhile stay in the line
    /// buffer for the next receive.
    fn holder_closed(&mut self) -> bool {
        let Some(h) = self.holder.as_mut() else {
            return true;
        };
        if self.rx.is_full() {
            return false;
        }
        let Ok(space) = self.rx.space() else {
            return false;
        };
        match h.conn.read(space, Duration::ZERO) {
            Ok(Read1::Data(n)) => {
                self.rx.commit(n);
                false
            }
            Ok(Read1::Timeout) => false,
            Ok(Read1::Closed) | Err(_) => true,
        }
    }

    /// Waits for a holder until `deadline` (at least one attempt).
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

    /// Refuses one pending connection if a refusal is due; `Err` is the refusal.
    fn refuse_one(&mut self) -> Result<(), LinkError> {
        if !self.refusal_credit {
            return Ok(());
        }
        match self.try_accept() {
            Ok(_) => Ok(()),
            Err(e) => {
                if e.is_foreign() {
                    self.refusal_credit = false;
                }
                Err(e)
            }
        }
    }

    /// Turns a complete line of the holder into the robot's state, or the error that drops it.
    fn take_state(&mut self, r: core::ops::Range<usize>) -> Result<RobotState, LinkError> {
        self.refusal_credit = true;
        let line = parse_state_line(self.rx.line(r))?;
        self.guard
            .admit(line.joint_count, line.seq, None)
            .map_err(|reason| LinkError::Dropped {
                protocol: P,
                reason,
            })?;
        self.count += 1;
        if let Some(h) = self.holder.as_mut() {
            h.last_valid = Some(Instant::now());
            if self.locked_ip.is_none() {
                self.locked_ip = Some(h.addr.ip().to_canonical());
            }
        }
        Ok(RobotState {
            q_rad: line.q_rad,
            joint_count: line.joint_count,
            cycle_id: line.seq.unwrap_or(self.count),
            ..Default::default()
        })
    }
}

impl RobotLink for SimpleTcpLink {
    /// `cycle_id` is the line's `seq=` when it carries one, otherwise the count of valid `q`
    /// lines received since construction (it keeps counting across reconnections).
    ///
    /// Order of work, so that the holder's lines always come first: a line already buffered;
    /// one refusal of a pending connection when due (see the module documentation); the idle
    /// check; then a wait for the holder's next line. Without a holder, the wait is for a
    /// connection.
    fn receive(&mut self, timeout: Duration) -> Result<Option<RobotState>, LinkError> {
        let deadline = deadline_after(timeout);
        let mut wait = timeout;
        loop {
            if self.holder.is_none() {
                if !self.accept_until(deadline)? {
                    return Ok(None);
                }
                wait = deadline.saturating_duration_since(Instant::now());
            }
            if let Some(r) = self.rx.take_nonblank_line() {
                return self.take_state(r).map(Some);
            }
            self.refuse_one()?;
            let idle = self
                .holder
                .as_ref()
                .is_some_and(|h| h.silent_since().elapsed() > self.idle_timeout);
            if idle {
                self.disconnect();
                self.stats.idle_closed += 1;
                continue;
            }
            let Some(h) = self.holder.as_mut() else {
                continue;
            };
            match fill_line(&mut h.conn, &mut self.rx, wait, deadline)? {
                Fill::Line(r) => return self.take_state(r).map(Some),
                Fill::Closed => {
                    self.disconnect();
                    wait = deadline.saturating_duration_since(Instant::now());
                }
                Fill::Timeout => {
                    // The holder was silent for the whole wait: a refusal costs it nothing.
                    self.refusal_credit = true;
                    self.refuse_one()?;
                    return Ok(None);
                }
            }
        }
    }

    /// Sends `(dx,dy,dz,rx,ry,rz)\n`. [`LinkError::NoPeer`] while no robot
    /// is connected; a failed write closes the connection.
    fn send_correction(&mut self, c: &Correction) -> Result<(), LinkError> {
        let n = format_correction_line(c, ReplyStyle::Tuple, &mut self.tx)?;
        let h = self
            .holder
            .as_mut()
            .ok_or(LinkError::NoPeer { protocol: P })?;
        if let Err(e) = h.conn.write_line(&self.tx[..n]) {
            self.disconnect();
            return Err(e);
        }
        self.stats.answers += 1;
        Ok(())
    }

    fn counters(&self) -> LinkCounters {
        let mut c = self.stats;
        self.guard.add_to(&mut c);
        c
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
                let correction = parse_correction_line(self.rx.line(r))?;
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
