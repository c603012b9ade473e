//! deflex binary UDP protocol for Stäubli controllers (VAL3 `alter`).
//!
//! Stäubli offers no standard streaming-correction protocol, so deflex
//! defines this one (full specification in `docs/staubli/PROTOCOL.md`, VAL3
//! counterpart in `docs/staubli/deflex_alter.val3`). All fields are
//! **little-endian**; every datagram is one message:
//!
//! | offset | size | field |
//! |---|---|---|
//! | 0 | 4 | magic `"DFLX"` |
//! | 4 | 1 | version ([`VERSION`]) |
//! | 5 | 1 | type: 1 = correction (PC → robot), 2 = state (robot → PC) |
//! | 6 | 2 | flags (u16) |
//! | 8 | 4 | sequence number of the sender (u32) |
//! | 12 | 4 | ack: last sequence number received from the peer (u32) |
//! | 16 | 8 | sender timestamp, seconds (f64) |
//! | 24 | … | payload |
//! | end−2 | 2 | Fletcher-16 checksum of all preceding bytes (u16) |
//!
//! * correction payload (48 bytes, total [`CORRECTION_LEN`]): `dx dy dz` in
//!   **m**, `rx ry rz` in **rad** as Stäubli XYZ Euler angles
//!   (`R = Rx(rx)·Ry(ry)·Rz(rz)`, the VAL3 `trsf` convention), f64 each;
//!   the total correction of the path in the `alterBegin` frame. Flag bit 0
//!   ([`FLAG_ACTIVE`]) set means "apply"; clear means "go back to zero".
//! * state payload (56 bytes, total [`STATE_LEN`]): six joint positions in
//!   **rad** (f64), status word (u32, [`STATUS_ALTER_ACTIVE`]…), reserved u32.
//!
//! [`StaubliLink`] answers only its robot ([`crate::peer`]) and drops unanswered
//! ([`LinkError::Dropped`], counted in [`RobotLink::counters`]) a state whose `seq` does not
//! advance over the last accepted one (a duplicate or a replay) or whose timestamp goes back
//! ([`crate::guard`]). Its own `seq` counts the corrections actually sent (no gaps), and its
//! `ack` is the `seq` of the last accepted state.

use crate::error::{LinkError, Protocol};
use crate::guard::{LinkCounters, SessionGuard, Stamp};
use crate::link::{Correction, ReceivedCorrection, RobotLink, RobotSideLink, RobotState};
use crate::peer::{PeerLock, PeerPolicy};
use crate::udp::UdpEndpoint;
use deflex_model::conventions::{
    rotation_from_rotation_vector, rotation_from_staubli_rxryrz_rad, rotation_vector,
    staubli_rxryrz_rad,
};
use std::net::{SocketAddr, ToSocketAddrs};
use std::time::{Duration, Instant};

/// Magic bytes.
pub const MAGIC: [u8; 4] = *b"DFLX";
/// Protocol version.
pub const VERSION: u8 = 1;
/// Suggested UDP port (both sides).
pub const DEFAULT_PORT: u16 = 50160;
/// Header length.
pub const HEADER_LEN: usize = 24;
/// Total length of a correction message.
pub const CORRECTION_LEN: usize = HEADER_LEN + 48 + 2;
/// Total length of a state message.
pub const STATE_LEN: usize = HEADER_LEN + 56 + 2;
/// Message type of a correction.
pub const TYPE_CORRECTION: u8 = 1;
/// Message type of a state.
pub const TYPE_STATE: u8 = 2;
/// Correction flag: apply the correction (clear: return to zero).
pub const FLAG_ACTIVE: u16 = 1;
/// Status bit: `alter` mode is running.
pub const STATUS_ALTER_ACTIVE: u32 = 1;
/// Status bit: the VAL3 watchdog zeroed the correction (messages stopped).
pub const STATUS_WATCHDOG: u32 = 2;
/// Status bit: the robot clamped the correction to its limits.
pub const STATUS_LIMITED: u32 = 4;
/// Status bit: `alter()` returned an error.
pub const STATUS_ALTER_ERROR: u32 = 8;

const P: Protocol = Protocol::Staubli;
const fn bad(reason: &'static str) -> LinkError {
    LinkError::malformed(P, reason)
}

/// Fletcher-16 checksum (sums modulo 255; `sum2 << 8 | sum1`).
pub fn fletcher16(data: &[u8]) -> u16 {
    let (mut s1, mut s2) = (0u32, 0u32);
    for &b in data {
        s1 = (s1 + u32::from(b)) % 255;
        s2 = (s2 + s1) % 255;
    }
    ((s2 << 8) | s1) as u16
}

/// Common header fields.
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct StaubliHeader {
    /// Flags.
    pub flags: u16,
    /// Sender sequence number.
    pub seq: u32,
    /// Last sequence number received from the peer.
    pub ack: u32,
    /// Sender timestamp (s).
    pub timestamp_s: f64,
}

/// A correction message (PC → robot).
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct CorrectionMsg {
    /// Header.
    pub header: StaubliHeader,
    /// `[dx, dy, dz]` m, `[rx, ry, rz]` rad, Stäubli X-Y'-Z'' angles
    /// ([`deflex_model::conventions::staubli_rxryrz_rad`]).
    pub values: [f64; 6],
}

/// A state message (robot → PC).
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct StateMsg {
    /// Header.
    pub header: StaubliHeader,
    /// Joint positions (rad).
    pub q_rad: [f64; 6],
    /// Status word.
    pub status: u32,
}

/// SI correction → wire values: the translation, then the Stäubli angles of the correction's
/// rotation vector.
pub fn correction_to_wire(c: &Correction) -> [f64; 6] {
    let e = staubli_rxryrz_rad(&rotation_from_rotation_vector(c.dphi_rad), None);
    [c.dp_m[0], c.dp_m[1], c.dp_m[2], e[0], e[1], e[2]]
}

/// Wire values → SI correction.
pub fn wire_to_correction(v: &[f64; 6]) -> Correction {
    Correction {
        dp_m: [v[0], v[1], v[2]],
        dphi_rad: rotation_vector(&rotation_from_staubli_rxryrz_rad([v[3], v[4], v[5]]), None),
    }
}

fn put_header(out: &mut [u8], ty: u8, h: &StaubliHeader) {
    out[0..4].copy_from_slice(&MAGIC);
    out[4] = VERSION;
    out[5] = ty;
    out[6..8].copy_from_slice(&h.flags.to_le_bytes());
    out[8..12].copy_from_slice(&h.seq.to_le_bytes());
    out[12..16].copy_from_slice(&h.ack.to_le_bytes());
    out[16..24].copy_from_slice(&h.timestamp_s.to_le_bytes());
}

fn put_f64s(out: &mut [u8], v: &[f64]) -> Result<(), LinkError> {
    for (i, x) in v.iter().enumerate() {
        if !x.is_finite() {
            return Err(LinkError::InvalidValue {
                protocol: P,
                reason: "non-finite value",
            });
        }
        out[i * 8..i * 8 + 8].copy_from_slice(&x.to_le_bytes());
    }
    Ok(())
}

fn seal(out: &mut [u8]) {
    let n = out.len();
    let c = fletcher16(&out[..n - 2]);
    out[n - 2..].copy_from_slice(&c.to_le_bytes());
}

fn check_out(out: &[u8], n: usize) -> Result<(), LinkError> {
    if out.len() < n {
        Err(LinkError::BufferTooSmall {
            protocol: P,
            capacity: out.len(),
        })
    } else {
        Ok(())
    }
}

/// Encodes a correction message into `out`; returns [`CORRECTION_LEN`].
pub fn encode_correction(m: &CorrectionMsg, out: &mut [u8]) -> Result<usize, LinkError> {
    check_out(out, CORRECTION_LEN)?;
    let out = &mut out[..CORRECTION_LEN];
    put_header(out, TYPE_CORRECTION, &m.header);
    put_f64s(&mut out[HEADER_LEN..HEADER_LEN + 48], &m.values)?;
    seal(out);
    Ok(CORRECTION_LEN)
}

/// Encodes a state message into `out`; returns [`STATE_LEN`].
pub fn encode_state(m: &StateMsg, out: &mut [u8]) -> Result<usize, LinkError> {
    check_out(out, STATE_LEN)?;
    let out = &mut out[..STATE_LEN];
    put_header(out, TYPE_STATE, &m.header);
    put_f64s(&mut out[HEADER_LEN..HEADER_LEN + 48], &m.q_rad)?;
    out[HEADER_LEN + 48..HEADER_LEN + 52].copy_from_slice(&m.status.to_le_bytes());
    out[HEADER_LEN + 52..HEADER_LEN + 56].copy_from_slice(&[0; 4]);
    seal(out);
    Ok(STATE_LEN)
}

fn u32_at(b: &[u8], i: usize) -> u32 {
    u32::from_le_bytes([b[i], b[i + 1], b[i + 2], b[i + 3]])
}

fn f64_at(b: &[u8], i: usize) -> f64 {
    let mut a = [0u8; 8];
    a.copy_from_slice(&b[i..i + 8]);
    f64::from_le_bytes(a)
}

fn check(buf: &[u8], ty: u8, len: usize) -> Result<StaubliHeader, LinkError> {
    if buf.len() < len {
        return Err(LinkError::Truncated {
            protocol: P,
            expected: len,
            got: buf.len(),
        });
    }
    if buf[0..4] != MAGIC {
        return Err(bad("bad magic"));
    }
    if buf[4] != VERSION {
        return Err(bad("unsupported version"));
    }
    if buf[5] != ty {
        return Err(bad("unexpected message type"));
    }
    if buf.len() != len {
        return Err(bad("wrong length for message type"));
    }
    let expected = u16::from_le_bytes([buf[len - 2], buf[len - 1]]);
    let computed = fletcher16(&buf[..len - 2]);
    if expected != computed {
        return Err(LinkError::Checksum {
            protocol: P,
            expected: expected.into(),
            computed: computed.into(),
        });
    }
    let h = StaubliHeader {
        flags: u16::from_le_bytes([buf[6], buf[7]]),
        seq: u32_at(buf, 8),
        ack: u32_at(buf, 12),
        timestamp_s: f64_at(buf, 16),
    };
    if !h.timestamp_s.is_finite() {
        return Err(bad("non-finite timestamp"));
    }
    Ok(h)
}

fn f64s<const N: usize>(buf: &[u8]) -> Result<[f64; N], LinkError> {
    let mut v = [0.0; N];
    for (i, x) in v.iter_mut().enumerate() {
        *x = f64_at(buf, HEADER_LEN + 8 * i);
        if !x.is_finite() {
            return Err(bad("non-finite value"));
        }
    }
    Ok(v)
}

/// Decodes and verifies a correction message.
pub fn decode_correction(buf: &[u8]) -> Result<CorrectionMsg, LinkError> {
    let header = check(buf, TYPE_CORRECTION, CORRECTION_LEN)?;
    Ok(CorrectionMsg {
        header,
        values: f64s(buf)?,
    })
}

/// Decodes and verifies a state message.
pub fn decode_state(buf: &[u8]) -> Result<StateMsg, LinkError> {
    let header = check(buf, TYPE_STATE, STATE_LEN)?;
    Ok(StateMsg {
        header,
        q_rad: f64s(buf)?,
        status: u32_at(buf, HEADER_LEN + 48),
    })
}

/// PC side: receives states, sends corrections to the state's sender.
#[derive(Debug)]
pub struct StaubliLink {
    ep: UdpEndpoint,
    rx: [u8; 256],
    tx: [u8; CORRECTION_LEN],
    seq: u32,
    last_state_seq: u32,
    epoch: Instant,
    peers: PeerLock,
    guard: SessionGuard,
    answers: u64,
}

impl StaubliLink {
    /// Binds to `local`.
    pub fn bind(local: impl ToSocketAddrs) -> Result<Self, LinkError> {
        Ok(StaubliLink {
            ep: UdpEndpoint::bind(local, P)?,
            rx: [0; 256],
            tx: [0; CORRECTION_LEN],
            seq: 0,
            last_state_seq: 0,
            epoch: Instant::now(),
            peers: PeerLock::first_sender(),
            guard: SessionGuard::new(),
            answers: 0,
        })
    }
    /// Accepts states only from `peer` (port 0: any port of that IP).
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
    /// Sends a correction with [`FLAG_ACTIVE`] cleared: the robot returns to
    /// the nominal path.
    pub fn send_inactive(&mut self) -> Result<(), LinkError> {
        self.send(&Correction::ZERO, 0)
    }
    fn send(&mut self, c: &Correction, flags: u16) -> Result<(), LinkError> {
        if self.ep.peer().is_none() {
            return Err(LinkError::NoPeer { protocol: P });
        }
        let seq = self.seq.wrapping_add(1);
        let m = CorrectionMsg {
            header: StaubliHeader {
                flags,
                seq,
                ack: self.last_state_seq,
                timestamp_s: self.epoch.elapsed().as_secs_f64(),
            },
            values: correction_to_wire(c),
        };
        let n = encode_correction(&m, &mut self.tx)?;
        self.ep.send(&self.tx[..n])?;
        self.seq = seq;
        self.answers += 1;
        Ok(())
    }
}

impl RobotLink for StaubliLink {
    fn receive(&mut self, timeout: Duration) -> Result<Option<RobotState>, LinkError> {
        let Some((n, from)) = self.ep.recv(&mut self.rx, timeout)? else {
            return Ok(None);
        };
        self.peers.check(P, from)?;
        let m = decode_state(&self.rx[..n])?;
        self.guard
            .admit(
                m.q_rad.len(),
                Some(u64::from(m.header.seq)),
                Some(Stamp::Seconds(m.header.timestamp_s)),
            )
            .map_err(|reason| LinkError::Dropped {
                protocol: P,
                reason,
            })?;
        self.peers.lock(from);
        self.ep.set_peer(from);
        self.last_state_seq = m.header.seq;
        let mut state = RobotState::with_joints(&m.q_rad);
        state.cycle_id = u64::from(m.header.seq);
        state.robot_time_s = Some(m.header.timestamp_s);
        state.status = m.status;
        Ok(Some(state))
    }
    fn send_correction(&mut self, c: &Correction) -> Result<(), LinkError> {
        self.send(c, FLAG_ACTIVE)
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

/// Robot side (simulated cell), with the same watchdog as the VAL3 program.
#[derive(Debug)]
pub struct StaubliRobotEndpoint {
    ep: UdpEndpoint,
    rx: [u8; 256],
    tx: [u8; STATE_LEN],
    last_corr_seq: u32,
    last: Option<(Instant, Correction)>,
    /// Time without a valid active correction after which
    /// [`Self::current_correction`] returns zero.
    pub watchdog: Duration,
}

impl StaubliRobotEndpoint {
    /// Binds to `local` and sends to `pc`.
    pub fn new(
        local: impl ToSocketAddrs,
        pc: SocketAddr,
        watchdog: Duration,
    ) -> Result<Self, LinkError> {
        let mut ep = UdpEndpoint::bind(local, P)?;
        ep.set_peer(pc);
        Ok(StaubliRobotEndpoint {
            ep,
            rx: [0; 256],
            tx: [0; STATE_LEN],
            last_corr_seq: 0,
            last: None,
            watchdog,
        })
    }
    /// Local socket address.
    pub fn local_addr(&self) -> Result<SocketAddr, LinkError> {
        self.ep.local_addr()
    }
    /// Correction to apply at `now`: the last active one, or zero when the
    /// watchdog expired or the PC asked for inactivity.
    pub fn current_correction(&self, now: Instant) -> Correction {
        match self.last {
            Some((t, c)) if now.saturating_duration_since(t) <= self.watchdog => c,
            _ => Correction::ZERO,
        }
    }
}

impl RobotSideLink for StaubliRobotEndpoint {
    /// `cycle_id` → sequence (32 bits), `status` → status word; the first six
    /// joint values (the protocol carries six).
    fn send_state(&mut self, s: &RobotState) -> Result<(), LinkError> {
        let mut q_rad = [0.0; 6];
        let n = s.joint_count.min(6);
        q_rad[..n].copy_from_slice(&s.q_rad[..n]);
        let m = StateMsg {
            header: StaubliHeader {
                flags: 0,
                seq: s.cycle_id as u32,
                ack: self.last_corr_seq,
                timestamp_s: s.robot_time_s.unwrap_or(0.0),
            },
            q_rad,
            status: s.status,
        };
        let n = encode_state(&m, &mut self.tx)?;
        self.ep.send(&self.tx[..n])
    }
    /// `cycle_id` of the result is the acknowledged state sequence number.
    fn receive_correction(
        &mut self,
        timeout: Duration,
    ) -> Result<Option<ReceivedCorrection>, LinkError> {
        let Some((n, _)) = self.ep.recv(&mut self.rx, timeout)? else {
            return Ok(None);
        };
        let m = decode_correction(&self.rx[..n])?;
        self.last_corr_seq = m.header.seq;
        let correction = if m.header.flags & FLAG_ACTIVE != 0 {
            wire_to_correction(&m.values)
        } else {
            Correction::ZERO
        };
        self.last = Some((Instant::now(), correction));
        Ok(Some(ReceivedCorrection {
            correction,
            cycle_id: u64::from(m.header.ack),
            joint_correction_rad: None,
        }))
    }
}
