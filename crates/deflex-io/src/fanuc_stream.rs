//! FANUC Stream Motion (option J519): a joint stream over UDP, where deflex is the **motion
//! source**.
//!
//! Stream Motion inverts the roles of the other robot links: the robot controller does not run
//! a path of its own that deflex corrects; its TP program enters the streaming state
//! (`IBGN start[*]`, see `docs/fanuc/`) and follows the joint targets an external device sends
//! it, one per interpolation cycle (4 or 8 ms). deflex therefore streams the whole compensated
//! path (its joint targets, time-parametrised at the program's feed) with the online correction
//! added in joint space ([`link::FanucStreamLink`]). The exchange, on UDP port
//! [`DEFAULT_PORT`] of the controller, big-endian on the wire:
//!
//! 1. the device may ask for the controller's **limit tables**: a [`ThresholdRequest`] per axis
//!    and kind (velocity °/s, acceleration °/s², jerk °/s³), answered by a [`ThresholdTable`]
//!    (20 entries without and with full payload);
//! 2. the device sends a **start packet** ([`format_start`]); the controller then sends a
//!    [`Status`] packet every cycle (sequence number, status bits, joint angles in degrees,
//!    TCP position, motor currents);
//! 3. the device answers each status packet with one [`Command`] (the status's sequence
//!    number, the joint targets in degrees, `is_last_command` on the last one, data style
//!    `0xFFFF` = joint angles);
//! 4. after its last command the device sends a **stop packet** ([`format_stop`]).
//!
//! The layouts were learnt from FANUC's Apache-2.0 ROS 2 driver (`stream_motion/packets.hpp`)
//! and from the `airo-fanuc` package's wire description; this module is deflex's own reading of
//! them, checked against `airo-fanuc`'s fake controller by `scripts/check-fanuc-stream`.
//!
//! | packet | type | bytes | direction |
//! |---|---|---|---|
//! | start | 200 | 8 | device → robot |
//! | stop | 2 | 8 | device → robot |
//! | threshold request | 3 | 16 | device → robot |
//! | threshold table | 3 | 184 | robot → device |
//! | command | 201 | 344 | device → robot |
//! | status | 202 (0 on old controllers) | 388 | robot → device |
//! | status with force data | 204 | 416 | robot → device |
//!
//! Every function here is pure (byte slices in and out, no I/O, no allocation); every received
//! packet is checked for its size, type, version and finite numbers, and a packet that fails is
//! a [`LinkError`], never a panic. Inside deflex everything is SI: the angles are converted to
//! radians by the link, not here (the codec keeps the wire's degrees so that a packet reads
//! back bit for bit).

pub mod link;
pub mod motion;
pub mod robot;

use crate::error::{LinkError, Protocol};

/// The controller's Stream Motion UDP port.
pub const DEFAULT_PORT: u16 = 60015;
/// The protocol version deflex speaks (what current controllers announce).
pub const VERSION: u32 = 3;
/// The lowest and highest version a received packet may carry.
pub const VERSIONS: core::ops::RangeInclusive<u32> = 1..=4;
/// Axes carried by every packet (robot axes first, then extended axes; unused ones are zero).
pub const MAX_AXES: usize = 9;
/// Bytes of the I/O block of a command or status packet (deflex drives no I/O: zero).
pub const IO_BYTES: usize = 256;
/// Entries of a threshold table (one per speed band).
pub const THRESHOLD_ENTRIES: usize = 20;

/// Packet type of the start packet.
pub const TYPE_START: u32 = 200;
/// Packet type of the stop packet.
pub const TYPE_STOP: u32 = 2;
/// Packet type of a threshold request and of its answer.
pub const TYPE_THRESHOLD: u32 = 3;
/// Packet type of a command packet.
pub const TYPE_COMMAND: u32 = 201;
/// Packet type of a status packet (current controllers).
pub const TYPE_STATUS: u32 = 202;
/// Packet type of a status packet of older controllers (same layout).
pub const TYPE_STATUS_LEGACY: u32 = 0;
/// Packet type of a status packet followed by force/torque data (version 4).
pub const TYPE_STATUS_FORCE: u32 = 204;

/// Bytes of a start or stop packet.
pub const CONTROL_LEN: usize = 8;
/// Bytes of a threshold request.
pub const THRESHOLD_REQUEST_LEN: usize = 16;
/// Bytes of a threshold table.
pub const THRESHOLD_TABLE_LEN: usize = 24 + 8 * THRESHOLD_ENTRIES;
/// Bytes of a command packet.
pub const COMMAND_LEN: usize = 16 + 8 * MAX_AXES + IO_BYTES;
/// Bytes of a status packet.
pub const STATUS_LEN: usize = 20 + 4 * (3 * MAX_AXES + 1) + IO_BYTES;
/// Bytes of a status packet with force/torque data.
pub const STATUS_FORCE_LEN: usize = STATUS_LEN + 4 * 7;

/// The command's data style for joint angles (the field FANUC's header calls `unused`: a zero
/// there makes the controller read the values as a Cartesian pose).
pub const DATA_STYLE_JOINT: u16 = 0xFFFF;

/// Status bit: the controller is ready to take commands.
pub const STATUS_READY: u8 = 0x01;
/// Status bit: the controller received the command of the previous cycle.
pub const STATUS_COMMAND_RECEIVED: u8 = 0x02;
/// Status bit: system ready (servos on, no alarm).
pub const STATUS_SYSRDY: u8 = 0x04;
/// Status bit: the robot is moving.
pub const STATUS_IN_MOTION: u8 = 0x08;
/// Robot-status bit: the controller is in error (an alarm is active).
pub const ROBOT_ERROR: u8 = 0x01;
/// Robot-status bit: the teach pendant is enabled.
pub const ROBOT_TP_ENABLED: u8 = 0x02;
/// Robot-status bit: emergency stop.
pub const ROBOT_ESTOP: u8 = 0x04;

const P: Protocol = Protocol::FanucStream;

fn be_u32(b: &[u8], at: usize) -> u32 {
    u32::from_be_bytes([b[at], b[at + 1], b[at + 2], b[at + 3]])
}

fn be_f32(b: &[u8], at: usize) -> f32 {
    f32::from_bits(be_u32(b, at))
}

fn be_f64(b: &[u8], at: usize) -> f64 {
    let mut x = [0u8; 8];
    x.copy_from_slice(&b[at..at + 8]);
    f64::from_be_bytes(x)
}

fn put_u32(out: &mut [u8], at: usize, v: u32) {
    out[at..at + 4].copy_from_slice(&v.to_be_bytes());
}

/// Checks that `buf` has exactly `len` bytes and returns its packet type and version.
fn header(buf: &[u8], len: usize) -> Result<(u32, u32), LinkError> {
    if buf.len() < len {
        return Err(LinkError::Truncated {
            protocol: P,
            expected: len,
            got: buf.len(),
        });
    }
    if buf.len() > len {
        return Err(LinkError::malformed(
            P,
            "packet longer than its type's layout",
        ));
    }
    let version = be_u32(buf, 4);
    if !VERSIONS.contains(&version) {
        return Err(LinkError::malformed(P, "unsupported protocol version"));
    }
    Ok((be_u32(buf, 0), version))
}

fn room(out: &[u8], len: usize) -> Result<(), LinkError> {
    if out.len() < len {
        Err(LinkError::BufferTooSmall {
            protocol: P,
            capacity: out.len(),
        })
    } else {
        Ok(())
    }
}

/// The packet type of a received datagram (its first four bytes), to dispatch it.
pub fn packet_type(buf: &[u8]) -> Result<u32, LinkError> {
    if buf.len() < 4 {
        return Err(LinkError::Truncated {
            protocol: P,
            expected: 4,
            got: buf.len(),
        });
    }
    Ok(be_u32(buf, 0))
}

/// A start or stop packet.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Control {
    /// Start streaming (type 200).
    Start {
        /// Protocol version.
        version: u32,
    },
    /// Stop streaming (type 2).
    Stop {
        /// Protocol version.
        version: u32,
    },
}

/// Writes a start packet of protocol `version` into `out`; returns its length.
pub fn format_start(version: u32, out: &mut [u8]) -> Result<usize, LinkError> {
    format_control(TYPE_START, version, out)
}

/// Writes a stop packet of protocol `version` into `out`; returns its length.
pub fn format_stop(version: u32, out: &mut [u8]) -> Result<usize, LinkError> {
    format_control(TYPE_STOP, version, out)
}

fn format_control(kind: u32, version: u32, out: &mut [u8]) -> Result<usize, LinkError> {
    room(out, CONTROL_LEN)?;
    put_u32(out, 0, kind);
    put_u32(out, 4, version);
    Ok(CONTROL_LEN)
}

/// Reads a start or stop packet.
pub fn parse_control(buf: &[u8]) -> Result<Control, LinkError> {
    let (kind, version) = header(buf, CONTROL_LEN)?;
    match kind {
        TYPE_START => Ok(Control::Start { version }),
        TYPE_STOP => Ok(Control::Stop { version }),
        _ => Err(LinkError::malformed(P, "not a start or stop packet")),
    }
}

/// One command packet: the joint targets of one cycle.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Command {
    /// Protocol version (the controller's).
    pub version: u32,
    /// The sequence number of the status packet this command answers.
    pub sequence: u32,
    /// The last command of the stream: the controller ends the motion here.
    pub is_last: bool,
    /// Joint targets in degrees (axis 1 first; unused axes zero).
    pub joints_deg: [f64; MAX_AXES],
}

/// Writes a command packet (data style joint angles, motion control on, no I/O) into `out`;
/// returns its length. A non-finite target is refused, nothing is written.
pub fn format_command(c: &Command, out: &mut [u8]) -> Result<usize, LinkError> {
    if !c.joints_deg.iter().all(|v| v.is_finite()) {
        return Err(LinkError::InvalidValue {
            protocol: P,
            reason: "non-finite joint target",
        });
    }
    room(out, COMMAND_LEN)?;
    put_u32(out, 0, TYPE_COMMAND);
    put_u32(out, 4, c.version);
    put_u32(out, 8, c.sequence);
    out[12] = u8::from(c.is_last);
    out[13] = 1;
    out[14..16].copy_from_slice(&DATA_STYLE_JOINT.to_be_bytes());
    for (i, v) in c.joints_deg.iter().enumerate() {
        out[16 + 8 * i..24 + 8 * i].copy_from_slice(&v.to_be_bytes());
    }
    out[16 + 8 * MAX_AXES..COMMAND_LEN].fill(0);
    Ok(COMMAND_LEN)
}

/// Reads a command packet (what the robot side receives): its size, type, version, data style
/// (joint angles only), motion-control flag and finite targets are checked.
pub fn parse_command(buf: &[u8]) -> Result<Command, LinkError> {
    let (kind, version) = header(buf, COMMAND_LEN)?;
    if kind != TYPE_COMMAND {
        return Err(LinkError::malformed(P, "not a command packet"));
    }
    if u16::from_be_bytes([buf[14], buf[15]]) != DATA_STYLE_JOINT {
        return Err(LinkError::malformed(
            P,
            "command data style is not joint angles (0xFFFF)",
        ));
    }
    if buf[13] != 1 {
        return Err(LinkError::malformed(P, "command without motion control"));
    }
    if buf[12] > 1 {
        return Err(LinkError::malformed(
            P,
            "is_last_command is neither 0 nor 1",
        ));
    }
    let mut joints_deg = [0.0; MAX_AXES];
    for (i, v) in joints_deg.iter_mut().enumerate() {
        *v = be_f64(buf, 16 + 8 * i);
        if !v.is_finite() {
            return Err(LinkError::malformed(P, "non-finite joint target"));
        }
    }
    Ok(Command {
        version,
        sequence: be_u32(buf, 8),
        is_last: buf[12] == 1,
        joints_deg,
    })
}

/// One status packet: what the controller reports every cycle.
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct Status {
    /// Protocol version.
    pub version: u32,
    /// Sequence number (the command answering it carries the same).
    pub sequence: u32,
    /// Status bits ([`STATUS_READY`], [`STATUS_COMMAND_RECEIVED`], [`STATUS_SYSRDY`],
    /// [`STATUS_IN_MOTION`]).
    pub status: u8,
    /// Robot-status bits ([`ROBOT_ERROR`], [`ROBOT_TP_ENABLED`], [`ROBOT_ESTOP`]).
    pub robot_status: u8,
    /// Contact-stop state (collaborative robots; 0 = none).
    pub contact_stop: u8,
    /// Controller clock (ms, wraps).
    pub time_ms: u32,
    /// TCP (or faceplate) position: X, Y, Z in mm, W, P, R in degrees, then extended axes.
    pub position: [f32; MAX_AXES],
    /// Joint angles in degrees.
    pub joints_deg: [f32; MAX_AXES],
    /// Motor currents (controller units).
    pub current: [f32; MAX_AXES],
    /// Speed scaling of the safety functions (1 = none).
    pub safety_scale: f32,
}

impl Status {
    /// The controller takes commands: ready, no error, no emergency stop. (System ready is
    /// reported but not required: a controller clears ready when it is not, and `airo-fanuc`'s
    /// fake controller never sets it.)
    pub fn accepts_commands(&self) -> bool {
        self.status & STATUS_READY != 0 && self.robot_status & (ROBOT_ERROR | ROBOT_ESTOP) == 0
    }

    /// The controller reports an error or an emergency stop.
    pub fn in_error(&self) -> bool {
        self.robot_status & (ROBOT_ERROR | ROBOT_ESTOP) != 0
    }
}

/// Writes a status packet (type 202, zero I/O) into `out`; returns its length.
pub fn format_status(s: &Status, out: &mut [u8]) -> Result<usize, LinkError> {
    let all = s.position.iter().chain(&s.joints_deg).chain(&s.current);
    if !all
        .chain(core::iter::once(&s.safety_scale))
        .all(|v| v.is_finite())
    {
        return Err(LinkError::InvalidValue {
            protocol: P,
            reason: "non-finite status value",
        });
    }
    room(out, STATUS_LEN)?;
    put_u32(out, 0, TYPE_STATUS);
    put_u32(out, 4, s.version);
    put_u32(out, 8, s.sequence);
    out[12] = s.status;
    out[13] = s.robot_status;
    out[14] = s.contact_stop;
    out[15] = 0;
    put_u32(out, 16, s.time_ms);
    let blocks = [&s.position, &s.joints_deg, &s.current];
    for (b, block) in blocks.iter().enumerate() {
        for (i, v) in block.iter().enumerate() {
            put_u32(out, 20 + 4 * (MAX_AXES * b + i), v.to_bits());
        }
    }
    put_u32(out, 20 + 4 * 3 * MAX_AXES, s.safety_scale.to_bits());
    out[STATUS_LEN - IO_BYTES..STATUS_LEN].fill(0);
    Ok(STATUS_LEN)
}

/// Reads a status packet (types 202 and 0, 388 bytes, or 204 with force data, 416 bytes; the
/// force data are not used): size, type, version and finite values are checked.
pub fn parse_status(buf: &[u8]) -> Result<Status, LinkError> {
    let kind = packet_type(buf)?;
    let len = if kind == TYPE_STATUS_FORCE {
        STATUS_FORCE_LEN
    } else {
        STATUS_LEN
    };
    let (kind, version) = header(buf, len)?;
    if !matches!(kind, TYPE_STATUS | TYPE_STATUS_LEGACY | TYPE_STATUS_FORCE) {
        return Err(LinkError::malformed(P, "not a status packet"));
    }
    let mut s = Status {
        version,
        sequence: be_u32(buf, 8),
        status: buf[12],
        robot_status: buf[13],
        contact_stop: buf[14],
        time_ms: be_u32(buf, 16),
        ..Status::default()
    };
    for (b, block) in [&mut s.position, &mut s.joints_deg, &mut s.current]
        .into_iter()
        .enumerate()
    {
        for (i, v) in block.iter_mut().enumerate() {
            *v = be_f32(buf, 20 + 4 * (MAX_AXES * b + i));
        }
    }
    s.safety_scale = be_f32(buf, 20 + 4 * 3 * MAX_AXES);
    let all = s.position.iter().chain(&s.joints_deg).chain(&s.current);
    if !all
        .chain(core::iter::once(&s.safety_scale))
        .all(|v| v.is_finite())
    {
        return Err(LinkError::malformed(P, "non-finite status value"));
    }
    Ok(s)
}

/// Which limit a threshold table gives.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum ThresholdKind {
    /// Velocity, °/s.
    Velocity,
    /// Acceleration, °/s².
    Acceleration,
    /// Jerk, °/s³.
    Jerk,
}

impl ThresholdKind {
    /// The three kinds, in the wire's order.
    pub const ALL: [ThresholdKind; 3] = [
        ThresholdKind::Velocity,
        ThresholdKind::Acceleration,
        ThresholdKind::Jerk,
    ];

    fn code(self) -> u32 {
        match self {
            ThresholdKind::Velocity => 0,
            ThresholdKind::Acceleration => 1,
            ThresholdKind::Jerk => 2,
        }
    }

    fn from_code(c: u32) -> Result<Self, LinkError> {
        match c {
            0 => Ok(ThresholdKind::Velocity),
            1 => Ok(ThresholdKind::Acceleration),
            2 => Ok(ThresholdKind::Jerk),
            _ => Err(LinkError::malformed(P, "unknown threshold type")),
        }
    }
}

/// A request for one axis's limit table.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct ThresholdRequest {
    /// Protocol version.
    pub version: u32,
    /// Axis, 1 to 9.
    pub axis: u32,
    /// Which limit.
    pub kind: ThresholdKind,
}

fn check_axis(axis: u32) -> Result<(), LinkError> {
    if (1..=MAX_AXES as u32).contains(&axis) {
        Ok(())
    } else {
        Err(LinkError::malformed(P, "threshold axis outside 1..=9"))
    }
}

/// Writes a threshold request into `out`; returns its length.
pub fn format_threshold_request(r: &ThresholdRequest, out: &mut [u8]) -> Result<usize, LinkError> {
    check_axis(r.axis).map_err(|_| LinkError::InvalidValue {
        protocol: P,
        reason: "threshold axis outside 1..=9",
    })?;
    room(out, THRESHOLD_REQUEST_LEN)?;
    put_u32(out, 0, TYPE_THRESHOLD);
    put_u32(out, 4, r.version);
    put_u32(out, 8, r.axis);
    put_u32(out, 12, r.kind.code());
    Ok(THRESHOLD_REQUEST_LEN)
}

/// Reads a threshold request.
pub fn parse_threshold_request(buf: &[u8]) -> Result<ThresholdRequest, LinkError> {
    let (kind, version) = header(buf, THRESHOLD_REQUEST_LEN)?;
    if kind != TYPE_THRESHOLD {
        return Err(LinkError::malformed(P, "not a threshold request"));
    }
    let axis = be_u32(buf, 8);
    check_axis(axis)?;
    Ok(ThresholdRequest {
        version,
        axis,
        kind: ThresholdKind::from_code(be_u32(buf, 12))?,
    })
}

/// One axis's limit table, as the controller reports it (degrees based units).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ThresholdTable {
    /// Protocol version.
    pub version: u32,
    /// Axis, 1 to 9.
    pub axis: u32,
    /// Which limit.
    pub kind: ThresholdKind,
    /// The robot's maximum Cartesian speed (mm/s).
    pub max_cartesian_speed: u32,
    /// The speed band of each entry (mm/s).
    pub interval: u32,
    /// The limit per speed band without payload.
    pub no_payload: [f32; THRESHOLD_ENTRIES],
    /// The limit per speed band with full payload.
    pub full_payload: [f32; THRESHOLD_ENTRIES],
}

impl ThresholdTable {
    /// The tightest limit of the table (every band, both payloads): what a stream must keep
    /// whatever its speed and payload.
    pub fn tightest(&self) -> f64 {
        self.no_payload
            .iter()
            .chain(&self.full_payload)
            .map(|v| f64::from(*v))
            .fold(f64::INFINITY, f64::min)
    }
}

/// Writes a threshold table into `out`; returns its length.
pub fn format_threshold_table(t: &ThresholdTable, out: &mut [u8]) -> Result<usize, LinkError> {
    let all = t.no_payload.iter().chain(&t.full_payload);
    if !all.clone().all(|v| v.is_finite() && *v > 0.0) {
        return Err(LinkError::InvalidValue {
            protocol: P,
            reason: "threshold entries must be finite and positive",
        });
    }
    room(out, THRESHOLD_TABLE_LEN)?;
    put_u32(out, 0, TYPE_THRESHOLD);
    put_u32(out, 4, t.version);
    put_u32(out, 8, t.axis);
    put_u32(out, 12, t.kind.code());
    put_u32(out, 16, t.max_cartesian_speed);
    put_u32(out, 20, t.interval);
    for (i, v) in all.enumerate() {
        put_u32(out, 24 + 4 * i, v.to_bits());
    }
    Ok(THRESHOLD_TABLE_LEN)
}

/// Reads a threshold table: every entry must be finite and positive (a zero or negative limit
/// would stop nothing).
pub fn parse_threshold_table(buf: &[u8]) -> Result<ThresholdTable, LinkError> {
    let (kind, version) = header(buf, THRESHOLD_TABLE_LEN)?;
    if kind != TYPE_THRESHOLD {
        return Err(LinkError::malformed(P, "not a threshold table"));
    }
    let axis = be_u32(buf, 8);
    check_axis(axis)?;
    let mut t = ThresholdTable {
        version,
        axis,
        kind: ThresholdKind::from_code(be_u32(buf, 12))?,
        max_cartesian_speed: be_u32(buf, 16),
        interval: be_u32(buf, 20),
        no_payload: [0.0; THRESHOLD_ENTRIES],
        full_payload: [0.0; THRESHOLD_ENTRIES],
    };
    for i in 0..THRESHOLD_ENTRIES {
        t.no_payload[i] = be_f32(buf, 24 + 4 * i);
        t.full_payload[i] = be_f32(buf, 24 + 4 * (THRESHOLD_ENTRIES + i));
    }
    let all = t.no_payload.iter().chain(&t.full_payload);
    if !all.clone().all(|v| v.is_finite() && *v > 0.0) {
        return Err(LinkError::malformed(
            P,
            "threshold entries must be finite and positive",
        ));
    }
    Ok(t)
}
