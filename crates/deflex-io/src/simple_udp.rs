//! Generic text line protocol over UDP, for controllers without a dedicated
//! protocol. One datagram carries one line. URScript (Universal Robots) only
//! has TCP client sockets: it uses the same lines over TCP,
//! [`crate::simple_tcp`] (see `docs/ur/deflex_loop.script`).
//!
//! * robot → PC: `q <q1> … <qN>\n` — joint positions in **rad**, one to
//!   eight of them (a six-axis arm sends six; `run` checks the count against
//!   the model), optionally followed by ` seq=<n>`, the robot's own count of
//!   the lines it sent (an unsigned decimal integer, the last token, after a
//!   space): `q 0.1 -1.57 1.2 0 1.57 0 seq=42` ([`parse_state_line`]);
//! * PC → robot: `corr <dx> <dy> <dz> <rx> <ry> <rz>\n` — total correction,
//!   translation in **m**, rotation vector (axis × angle) in **rad**, base
//!   axes ([`ReplyStyle::Keyword`]), or the same six values as
//!   `(dx,dy,dz,rx,ry,rz)\n` ([`ReplyStyle::Tuple`]), the format URScript's
//!   `socket_read_ascii_float(6)` reads. The rotation vector is UR's own
//!   pose rotation representation.
//!
//! Parsers are tolerant: values may be separated by spaces, tabs or commas
//! and wrapped in `[...]` or `(...)` (so URScript's printing of a list,
//! `q [0.1, -1.57, ...]`, is accepted); the trailing newline (or CR LF) is
//! optional. Numbers are printed with 9 decimals (1 nm, 1 nrad).
//! `cycle_id` on the PC side is the count of valid lines received.
//!
//! [`SimpleUdpLink`] answers only the robot it is locked to: the configured
//! address or the first valid sender (see [`crate::peer`]). A line from that
//! robot is dropped unanswered ([`LinkError::Dropped`], counted in
//! [`RobotLink::counters`]) when its joint count differs from the session's;
//! when the session's first line carried `seq=`, also when a line's `seq`
//! does not advance (a duplicate or a replay) or is missing, and when it did
//! not, a line that carries one ([`crate::guard`]). Without `seq=` a
//! duplicated datagram cannot be told from the next cycle (a robot standing
//! still sends identical lines): robots that can should number their lines.
//! [`SimpleUdpRobotEndpoint`] (the simulated robot) does.

use crate::error::{LinkError, Protocol};
use crate::guard::{LinkCounters, SessionGuard};
use crate::link::{Correction, ReceivedCorrection, RobotLink, RobotSideLink, RobotState};
use crate::peer::{PeerLock, PeerPolicy};
use crate::udp::{SliceWriter, UdpEndpoint, parse_f64, parse_u64, trim};
use core::fmt::Write;
use deflex_model::MAX_JOINTS;
use std::net::{SocketAddr, ToSocketAddrs};
use std::time::Duration;

/// Line buffer size.
pub const LINE_BUFFER: usize = 512;

const P: Protocol = Protocol::SimpleLine;
const fn bad(reason: &'static str) -> LinkError {
    LinkError::malformed(P, reason)
}

/// Format of the PC's answer.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub enum ReplyStyle {
    /// `corr dx dy dz rx ry rz\n`.
    #[default]
    Keyword,
    /// `(dx,dy,dz,rx,ry,rz)\n`.
    Tuple,
}

/// Parses `min..=N` numbers after an optional keyword; `keyword` must be
/// present when `required`. Returns the values and their count.
fn parse_values<const N: usize>(
    line: &[u8],
    keyword: &str,
    required: bool,
    min: usize,
) -> Result<([f64; N], usize), LinkError> {
    let mut s = trim(line);
    if s.len() >= keyword.len() && s[..keyword.len()].eq_ignore_ascii_case(keyword.as_bytes()) {
        let rest = &s[keyword.len()..];
        if rest.first().is_some_and(|c| c.is_ascii_alphanumeric()) {
            return Err(bad("unknown keyword"));
        }
        s = trim(rest);
    } else if required {
        return Err(bad("line does not start with the expected keyword"));
    }
    if let [open, inner @ .., close] = s
        && matches!((open, close), (b'[', b']') | (b'(', b')'))
    {
        s = inner;
    }
    let mut out = [0.0; N];
    let mut n = 0;
    for tok in s.split(|c| c.is_ascii_whitespace() || *c == b',') {
        if tok.is_empty() {
            continue;
        }
        if n == N {
            return Err(bad("too many values"));
        }
        out[n] = parse_f64(tok).ok_or(bad("value is not a finite number"))?;
        n += 1;
    }
    if n < min {
        return Err(bad("too few values"));
    }
    Ok((out, n))
}

/// Parses a robot → PC line `q q1 … qN` (rad, 1 ≤ N ≤ 8) without a
/// sequence number; returns the values and N.
pub fn parse_joints_line(line: &[u8]) -> Result<([f64; MAX_JOINTS], usize), LinkError> {
    parse_values::<MAX_JOINTS>(line, "q", true, 1)
}

/// A robot → PC line: the joints and the optional sequence number.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct StateLine {
    /// Joint positions (rad), the first `joint_count` valid.
    pub q_rad: [f64; MAX_JOINTS],
    /// Number of joint values (1 to 8).
    pub joint_count: usize,
    /// The `seq=<n>` token, when present.
    pub seq: Option<u64>,
}

/// The `seq=` keyword (ASCII case-insensitive).
const SEQ_KEY: &[u8] = b"seq=";

/// Parses a robot → PC line `q q1 … qN [seq=<n>]` (rad, 1 ≤ N ≤ 8; `seq=` the
/// last token, after whitespace, an unsigned decimal integer of at most 20
/// digits).
pub fn parse_state_line(line: &[u8]) -> Result<StateLine, LinkError> {
    let s = trim(line);
    let last = s
        .iter()
        .rposition(u8::is_ascii_whitespace)
        .map_or(0, |i| i + 1);
    let tok = &s[last..];
    let (body, seq) =
        if tok.len() >= SEQ_KEY.len() && tok[..SEQ_KEY.len()].eq_ignore_ascii_case(SEQ_KEY) {
            let n = parse_u64(&tok[SEQ_KEY.len()..])
                .ok_or(bad("seq= is not an unsigned integer of at most 20 digits"))?;
            (&s[..last], Some(n))
        } else {
            (s, None)
        };
    let (q_rad, joint_count) = parse_values::<MAX_JOINTS>(body, "q", true, 1)?;
    Ok(StateLine {
        q_rad,
        joint_count,
        seq,
    })
}

/// Parses a PC → robot line, either `corr …` or `(…)`, exactly six values.
pub fn parse_correction_line(line: &[u8]) -> Result<Correction, LinkError> {
    let (v, n) = parse_values::<6>(line, "corr", false, 6)?;
    debug_assert_eq!(n, 6);
    Ok(Correction::from_array(v))
}

fn write_values(
    out: &mut [u8],
    head: &str,
    v: &[f64],
    sep: &str,
    tail: &str,
) -> Result<usize, LinkError> {
    if !v.iter().all(|x| x.is_finite()) {
        return Err(LinkError::InvalidValue {
            protocol: P,
            reason: "non-finite value",
        });
    }
    let cap = out.len();
    let mut w = SliceWriter::new(out);
    let r = (|| {
        w.write_str(head)?;
        for (i, x) in v.iter().enumerate() {
            if i > 0 {
                w.write_str(sep)?;
            }
            write!(w, "{x:.9}")?;
        }
        w.write_str(tail)
    })();
    r.map_err(|_| LinkError::BufferTooSmall {
        protocol: P,
        capacity: cap,
    })?;
    Ok(w.len())
}

/// Formats `q q1 … qN\n` (1 ≤ N ≤ 8).
pub fn format_joints_line(q: &[f64], out: &mut [u8]) -> Result<usize, LinkError> {
    format_state_line(q, None, out)
}

/// Formats `q q1 … qN seq=<n>\n` (1 ≤ N ≤ 8; without ` seq=` for `None`).
pub fn format_state_line(q: &[f64], seq: Option<u64>, out: &mut [u8]) -> Result<usize, LinkError> {
    if q.is_empty() || q.len() > MAX_JOINTS {
        return Err(LinkError::InvalidValue {
            protocol: P,
            reason: "a joints line carries 1 to 8 values",
        });
    }
    let cap = out.len();
    let n = write_values(out, "q ", q, " ", "")?;
    let mut w = SliceWriter::new(&mut out[n..]);
    let r = match seq {
        Some(s) => writeln!(w, " seq={s}"),
        None => w.write_str("\n"),
    };
    r.map_err(|_| LinkError::BufferTooSmall {
        protocol: P,
        capacity: cap,
    })?;
    Ok(n + w.len())
}

/// Formats a correction line in the given style.
pub fn format_correction_line(
    c: &Correction,
    style: ReplyStyle,
    out: &mut [u8],
) -> Result<usize, LinkError> {
    let v = c.to_array();
    match style {
        ReplyStyle::Keyword => write_values(out, "corr ", &v, " ", "\n"),
        ReplyStyle::Tuple => write_values(out, "(", &v, ",", ")\n"),
    }
}

/// PC side: receives `q` lines, answers correction lines to their sender.
#[derive(Debug)]
pub struct SimpleUdpLink {
    ep: UdpEndpoint,
    style: ReplyStyle,
    rx: [u8; LINE_BUFFER],
    tx: [u8; LINE_BUFFER],
    count: u64,
    peers: PeerLock,
    guard: SessionGuard,
    answers: u64,
}

impl SimpleUdpLink {
    /// Binds to `local`.
    pub fn bind(local: impl ToSocketAddrs, style: ReplyStyle) -> Result<Self, LinkError> {
        Ok(SimpleUdpLink {
            ep: UdpEndpoint::bind(local, P)?,
            style,
            rx: [0; LINE_BUFFER],
            tx: [0; LINE_BUFFER],
            count: 0,
            peers: PeerLock::first_sender(),
            guard: SessionGuard::new(),
            answers: 0,
        })
    }
    /// Accepts lines only from `peer` (port 0: any port of that IP).
    pub fn expect_peer(&mut self, peer: SocketAddr) {
        self.peers.set_configured(Some(peer));
    }
    /// Sets the peer policy (see [`crate::peer::validate_peer`]).
    pub fn set_peer_policy(&mut self, policy: PeerPolicy) {
        self.peers.set_policy(policy);
    }
    /// The sender lock.
    pub fn peers(&self) -> &PeerLock {
        &self.peers
    }
    /// Local socket address.
    pub fn local_addr(&self) -> Result<SocketAddr, LinkError> {
        self.ep.local_addr()
    }
}

impl RobotLink for SimpleUdpLink {
    /// `cycle_id` is the line's `seq` when it carries one, otherwise the count
    /// of lines accepted.
    fn receive(&mut self, timeout: Duration) -> Result<Option<RobotState>, LinkError> {
        let Some((n, from)) = self.ep.recv(&mut self.rx, timeout)? else {
            return Ok(None);
        };
        self.peers.check(P, from)?;
        let line = parse_state_line(&self.rx[..n])?;
        self.guard
            .admit(line.joint_count, line.seq, None)
            .map_err(|reason| LinkError::Dropped {
                protocol: P,
                reason,
            })?;
        self.peers.lock(from);
        self.ep.set_peer(from);
        self.count += 1;
        Ok(Some(RobotState {
            q_rad: line.q_rad,
            joint_count: line.joint_count,
            cycle_id: line.seq.unwrap_or(self.count),
            ..Default::default()
        }))
    }
    fn send_correction(&mut self, c: &Correction) -> Result<(), LinkError> {
        let n = format_correction_line(c, self.style, &mut self.tx)?;
        self.ep.send(&self.tx[..n])?;
        self.answers += 1;
        Ok(())
    }
    fn counters(&self) -> LinkCounters {
        let mut c = LinkCounters {
            answers: self.answers,
            foreign: self.peers.foreign(),
            ..LinkCounters::default()
        };
        self.guard.add_to(&mut c);
        c
    }
    fn protocol(&self) -> Protocol {
        P
    }
}

/// Robot side (simulated cell). It numbers its lines `seq=1, 2, …` (see
/// [`SimpleUdpRobotEndpoint::set_numbered`]).
#[derive(Debug)]
pub struct SimpleUdpRobotEndpoint {
    ep: UdpEndpoint,
    rx: [u8; LINE_BUFFER],
    tx: [u8; LINE_BUFFER],
    count: u64,
    sent: u64,
    numbered: bool,
}

impl SimpleUdpRobotEndpoint {
    /// Binds to `local` and sends to `pc`.
    pub fn new(local: impl ToSocketAddrs, pc: SocketAddr) -> Result<Self, LinkError> {
        let mut ep = UdpEndpoint::bind(local, P)?;
        ep.set_peer(pc);
        Ok(SimpleUdpRobotEndpoint {
            ep,
            rx: [0; LINE_BUFFER],
            tx: [0; LINE_BUFFER],
            count: 0,
            sent: 0,
            numbered: true,
        })
    }
    /// Local socket address.
    pub fn local_addr(&self) -> Result<SocketAddr, LinkError> {
        self.ep.local_addr()
    }
    /// With `true` (the default) every line carries ` seq=<n>`, the count of
    /// lines sent including it; with `false` plain `q …` lines.
    pub fn set_numbered(&mut self, numbered: bool) {
        self.numbered = numbered;
    }
}

impl RobotSideLink for SimpleUdpRobotEndpoint {
    /// The joints and, when numbered, the endpoint's own line count (the
    /// protocol has no pose; `cycle_id` is not sent).
    fn send_state(&mut self, s: &RobotState) -> Result<(), LinkError> {
        let seq = self.sent.wrapping_add(1);
        let n = format_state_line(s.joints(), self.numbered.then_some(seq), &mut self.tx)?;
        self.ep.send(&self.tx[..n])?;
        self.sent = seq;
        Ok(())
    }
    /// `cycle_id` is the count of corrections received.
    fn receive_correction(
        &mut self,
        timeout: Duration,
    ) -> Result<Option<ReceivedCorrection>, LinkError> {
        let Some((n, _)) = self.ep.recv(&mut self.rx, timeout)? else {
            return Ok(None);
        };
        let correction = parse_correction_line(&self.rx[..n])?;
        self.count += 1;
        Ok(Some(ReceivedCorrection {
            correction,
            cycle_id: self.count,
            joint_correction_rad: None,
        }))
    }
}
