//! Universal Robots **RTDE** (Real-Time Data Exchange), protocol version 2, over TCP port
//! [`DEFAULT_PORT`] (30004) of the robot controller.
//!
//! RTDE inverts the direction of the other robot links: the controller is the **server** and
//! deflex its **client**. deflex connects to the controller (`robot.peer` of `CELL.toml`),
//! negotiates the protocol version, reads the controller version, sets up an *output recipe*
//! (what the controller streams at its rate: 500 Hz on e-Series and UR-Series, 125 Hz on CB3)
//! and an *input recipe* (registers deflex writes), then starts the stream.
//!
//! **Wire format** (every integer and float big-endian). Each package is a header — `u16`
//! total size (header included), `u8` type — and a payload:
//!
//! | type | code | client → controller | controller → client |
//! |---|---|---|---|
//! | [`PackageType::RequestProtocolVersion`] | `V` 86 | `u16` version | `u8` accepted |
//! | [`PackageType::GetUrControlVersion`] | `v` 118 | — | `u32` major, minor, bugfix, build |
//! | [`PackageType::TextMessage`] | `M` 77 | (not sent) | `u8` length, message, `u8` length, source, `u8` level |
//! | [`PackageType::SetupOutputs`] | `O` 79 | `f64` frequency, names joined by `,` | `u8` recipe id, types joined by `,` |
//! | [`PackageType::SetupInputs`] | `I` 73 | names joined by `,` | `u8` recipe id, types joined by `,` |
//! | [`PackageType::Start`] | `S` 83 | — | `u8` accepted |
//! | [`PackageType::Pause`] | `P` 80 | — | `u8` accepted |
//! | [`PackageType::DataPackage`] | `U` 85 | `u8` recipe id, input values | `u8` recipe id, output values |
//!
//! A recipe's reply names each variable's type ([`FieldType`]), or `NOT_FOUND` (the controller
//! does not know the name, e.g. `ft_raw_wrench` on a CB3) or `IN_USE` (another RTDE client holds
//! that input register): deflex refuses both with the variable named
//! ([`SetupRefusal::NotFound`], [`SetupRefusal::InUse`]).
//!
//! This module is the codec: pure functions on byte slices, no I/O, nothing allocated (names are
//! written into the caller's buffer, values decoded into fixed arrays of [`Value`]). Every
//! package is checked: size within [`MAX_PACKAGE`], known type, the recipe id the session set
//! up, exactly the recipe's field count and size, and every double finite. The client links are
//! in [`client`] ([`RtdeLink`], [`RtdeSensor`]); the controller side the twin plays is in
//! [`server`] ([`RtdeServer`], [`RtdeRobotEndpoint`]).
//!
//! Units: UR's own are SI (m, rad, N, N·m, s): joint positions in rad, `actual_TCP_pose` as
//! `[x, y, z, rx, ry, rz]` in m and a rotation vector in rad
//! ([`deflex_model::conventions::rotation_vector`]).

use crate::error::{LinkError, Protocol};
use std::fmt;

#[path = "rtde_client.rs"]
pub mod client;
#[path = "rtde_server.rs"]
pub mod server;

pub use client::{RtdeLink, RtdeLinkConfig, RtdeSensor, RtdeStatus};
pub use server::{PathOffsetModel, RtdeRobotEndpoint, RtdeServer, RtdeServerCounters};

/// The controller's RTDE port.
pub const DEFAULT_PORT: u16 = 30004;
/// The protocol version deflex speaks.
pub const PROTOCOL_VERSION: u16 = 2;
/// Header length: `u16` size, `u8` type.
pub const HEADER_LEN: usize = 3;
/// Largest package deflex reads or writes (bytes): a recipe of [`MAX_FIELDS`] six-vectors is
/// 770 bytes, a text message at most 516.
pub const MAX_PACKAGE: usize = 2048;
/// Most fields in one recipe.
pub const MAX_FIELDS: usize = 16;
/// The input registers left to RTDE clients (24–47; 0–23 belong to fieldbuses).
pub const CLIENT_REGISTERS: std::ops::RangeInclusive<u8> = 24..=47;
/// Registers are numbered 0–47.
pub const REGISTER_COUNT: usize = 48;

const P: Protocol = Protocol::Rtde;

const fn bad(reason: &'static str) -> LinkError {
    LinkError::malformed(P, reason)
}

/// The type of a package.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum PackageType {
    /// `V`: protocol version request and its answer.
    RequestProtocolVersion,
    /// `v`: the controller's version.
    GetUrControlVersion,
    /// `M`: a text message from the controller.
    TextMessage,
    /// `U`: a data package of a recipe.
    DataPackage,
    /// `O`: output recipe set-up.
    SetupOutputs,
    /// `I`: input recipe set-up.
    SetupInputs,
    /// `S`: start the stream.
    Start,
    /// `P`: pause the stream.
    Pause,
}

impl PackageType {
    /// The type's code on the wire.
    pub const fn code(self) -> u8 {
        match self {
            PackageType::RequestProtocolVersion => b'V',
            PackageType::GetUrControlVersion => b'v',
            PackageType::TextMessage => b'M',
            PackageType::DataPackage => b'U',
            PackageType::SetupOutputs => b'O',
            PackageType::SetupInputs => b'I',
            PackageType::Start => b'S',
            PackageType::Pause => b'P',
        }
    }

    /// The type of a code, `None` for a code RTDE does not define.
    pub const fn from_code(code: u8) -> Option<PackageType> {
        Some(match code {
            b'V' => PackageType::RequestProtocolVersion,
            b'v' => PackageType::GetUrControlVersion,
            b'M' => PackageType::TextMessage,
            b'U' => PackageType::DataPackage,
            b'O' => PackageType::SetupOutputs,
            b'I' => PackageType::SetupInputs,
            b'S' => PackageType::Start,
            b'P' => PackageType::Pause,
            _ => return None,
        })
    }
}

/// The type of a recipe field, as the controller names it.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum FieldType {
    /// `BOOL`, one byte.
    Bool,
    /// `UINT8`.
    Uint8,
    /// `UINT32`.
    Uint32,
    /// `UINT64`.
    Uint64,
    /// `INT32`.
    Int32,
    /// `DOUBLE`.
    Double,
    /// `VECTOR3D`.
    Vector3d,
    /// `VECTOR6D`.
    Vector6d,
    /// `VECTOR6INT32`.
    Vector6Int32,
    /// `VECTOR6UINT32`.
    Vector6Uint32,
}

impl FieldType {
    const ALL: [FieldType; 10] = [
        FieldType::Bool,
        FieldType::Uint8,
        FieldType::Uint32,
        FieldType::Uint64,
        FieldType::Int32,
        FieldType::Double,
        FieldType::Vector3d,
        FieldType::Vector6d,
        FieldType::Vector6Int32,
        FieldType::Vector6Uint32,
    ];

    /// Bytes on the wire.
    pub const fn size(self) -> usize {
        match self {
            FieldType::Bool | FieldType::Uint8 => 1,
            FieldType::Uint32 | FieldType::Int32 => 4,
            FieldType::Uint64 | FieldType::Double => 8,
            FieldType::Vector3d => 24,
            FieldType::Vector6d => 48,
            FieldType::Vector6Int32 | FieldType::Vector6Uint32 => 24,
        }
    }

    /// The controller's name.
    pub const fn name(self) -> &'static str {
        match self {
            FieldType::Bool => "BOOL",
            FieldType::Uint8 => "UINT8",
            FieldType::Uint32 => "UINT32",
            FieldType::Uint64 => "UINT64",
            FieldType::Int32 => "INT32",
            FieldType::Double => "DOUBLE",
            FieldType::Vector3d => "VECTOR3D",
            FieldType::Vector6d => "VECTOR6D",
            FieldType::Vector6Int32 => "VECTOR6INT32",
            FieldType::Vector6Uint32 => "VECTOR6UINT32",
        }
    }

    /// The type of a name, `None` for any other text.
    pub fn from_name(name: &[u8]) -> Option<FieldType> {
        Self::ALL.into_iter().find(|t| t.name().as_bytes() == name)
    }
}

/// A variable deflex reads or writes (the subset of UR's list deflex uses and the twin serves).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Variable {
    /// `timestamp`: controller time since its start (s), `DOUBLE`.
    Timestamp,
    /// `actual_q`: joint positions (rad), `VECTOR6D`.
    ActualQ,
    /// `actual_TCP_pose`: TCP in the base frame, `[x, y, z, rx, ry, rz]` (m, rotation vector in
    /// rad), `VECTOR6D`.
    ActualTcpPose,
    /// `actual_TCP_force`: the wrench at the TCP, payload-compensated, in **base** axes
    /// (N, N·m), `VECTOR6D`.
    ActualTcpForce,
    /// `ft_raw_wrench`: the flange sensor's raw wrench, not payload-compensated (N, N·m),
    /// `VECTOR6D` (e-Series and UR-Series).
    FtRawWrench,
    /// `robot_mode` (7 = running), `INT32`.
    RobotMode,
    /// `safety_status` (1 = normal), `INT32`.
    SafetyStatus,
    /// `runtime_state` (2 = playing), `UINT32`.
    RuntimeState,
    /// `output_int_register_N`: written by the URScript program, `INT32`.
    OutputIntRegister(u8),
    /// `output_double_register_N`: written by the URScript program, `DOUBLE`.
    OutputDoubleRegister(u8),
    /// `input_double_register_N`: written by an RTDE client, `DOUBLE`.
    InputDoubleRegister(u8),
    /// `input_int_register_N`: written by an RTDE client, `INT32`.
    InputIntRegister(u8),
}

const FIXED_NAMES: [(&str, Variable); 8] = [
    ("timestamp", Variable::Timestamp),
    ("actual_q", Variable::ActualQ),
    ("actual_TCP_pose", Variable::ActualTcpPose),
    ("actual_TCP_force", Variable::ActualTcpForce),
    ("ft_raw_wrench", Variable::FtRawWrench),
    ("robot_mode", Variable::RobotMode),
    ("safety_status", Variable::SafetyStatus),
    ("runtime_state", Variable::RuntimeState),
];

const REGISTER_PREFIXES: [&str; 4] = [
    "output_int_register_",
    "output_double_register_",
    "input_double_register_",
    "input_int_register_",
];

impl Variable {
    /// The field type the controller gives it.
    pub const fn field_type(self) -> FieldType {
        match self {
            Variable::Timestamp | Variable::OutputDoubleRegister(_) => FieldType::Double,
            Variable::InputDoubleRegister(_) => FieldType::Double,
            Variable::ActualQ
            | Variable::ActualTcpPose
            | Variable::ActualTcpForce
            | Variable::FtRawWrench => FieldType::Vector6d,
            Variable::RobotMode
            | Variable::SafetyStatus
            | Variable::OutputIntRegister(_)
            | Variable::InputIntRegister(_) => FieldType::Int32,
            Variable::RuntimeState => FieldType::Uint32,
        }
    }

    /// True for what a client writes (input registers).
    pub const fn is_input(self) -> bool {
        matches!(
            self,
            Variable::InputDoubleRegister(_) | Variable::InputIntRegister(_)
        )
    }

    fn prefix_and_register(self) -> Result<&'static str, (&'static str, u8)> {
        match self {
            Variable::OutputIntRegister(n) => Err((REGISTER_PREFIXES[0], n)),
            Variable::OutputDoubleRegister(n) => Err((REGISTER_PREFIXES[1], n)),
            Variable::InputDoubleRegister(n) => Err((REGISTER_PREFIXES[2], n)),
            Variable::InputIntRegister(n) => Err((REGISTER_PREFIXES[3], n)),
            v => Ok(FIXED_NAMES
                .iter()
                .find(|(_, f)| *f == v)
                .map_or("", |(n, _)| n)),
        }
    }

    /// Writes the controller's name of the variable.
    pub fn write_name(self, w: &mut Writer<'_>) -> Result<(), LinkError> {
        match self.prefix_and_register() {
            Ok(name) => w.bytes(name.as_bytes()),
            Err((prefix, n)) => {
                w.bytes(prefix.as_bytes())?;
                if n >= 10 {
                    w.u8(b'0' + n / 10)?;
                }
                w.u8(b'0' + n % 10)
            }
        }
    }

    /// The variable of a controller name, `None` for a name deflex does not know (or a register
    /// beyond 47).
    pub fn from_name(name: &[u8]) -> Option<Variable> {
        if let Some((_, v)) = FIXED_NAMES.iter().find(|(n, _)| n.as_bytes() == name) {
            return Some(*v);
        }
        let (i, rest) = REGISTER_PREFIXES
            .iter()
            .enumerate()
            .find_map(|(i, p)| name.strip_prefix(p.as_bytes()).map(|rest| (i, rest)))?;
        if rest.is_empty() || rest.len() > 2 || (rest.len() == 2 && rest[0] == b'0') {
            return None;
        }
        let mut n: u8 = 0;
        for &d in rest {
            if !d.is_ascii_digit() {
                return None;
            }
            n = n * 10 + (d - b'0');
        }
        if usize::from(n) >= REGISTER_COUNT {
            return None;
        }
        Some(match i {
            0 => Variable::OutputIntRegister(n),
            1 => Variable::OutputDoubleRegister(n),
            2 => Variable::InputDoubleRegister(n),
            _ => Variable::InputIntRegister(n),
        })
    }
}

impl fmt::Display for Variable {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self.prefix_and_register() {
            Ok(name) => f.write_str(name),
            Err((prefix, n)) => write!(f, "{prefix}{n}"),
        }
    }
}

/// Why a controller (or deflex's own check of it) refused the session's set-up.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum SetupRefusal {
    /// The controller does not speak this protocol version.
    VersionRefused {
        /// The version asked for.
        version: u16,
    },
    /// The controller does not know a variable of a recipe.
    NotFound {
        /// The variable.
        variable: Variable,
    },
    /// Another RTDE client holds an input register of the recipe.
    InUse {
        /// The register.
        variable: Variable,
    },
    /// The controller's software is too old for what the link needs.
    ControllerTooOld {
        /// Its version, major.minor.bugfix.
        version: [u32; 3],
        /// What needs a newer one.
        needs: &'static str,
    },
    /// The controller refused to start (or pause) the stream.
    StartRefused,
    /// No answer to a set-up request within the bound.
    NoAnswer {
        /// The request.
        request: PackageType,
    },
    /// A set-up answer whose field count is not the request's.
    FieldCount {
        /// Fields asked for.
        asked: usize,
        /// Types answered.
        answered: usize,
    },
    /// A set-up answer with another type than the variable has.
    WrongType {
        /// The variable.
        variable: Variable,
        /// The type the controller names.
        answered: FieldType,
    },
}

impl fmt::Display for SetupRefusal {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            SetupRefusal::VersionRefused { version } => write!(
                f,
                "the controller refuses RTDE protocol version {version} (PolyScope 3.3 or newer \
                 speaks it)"
            ),
            SetupRefusal::NotFound { variable } => write!(
                f,
                "the controller does not know the RTDE variable {variable} (NOT_FOUND){}",
                if *variable == Variable::FtRawWrench {
                    ": a CB3 arm has no flange force/torque sensor; use an external sensor \
                     (sensor.kind = \"netft\" or \"ros2\")"
                } else {
                    ""
                }
            ),
            SetupRefusal::InUse { variable } => write!(
                f,
                "{variable} is already in use by another RTDE client (IN_USE): stop the other \
                 client (a URCap, a ROS driver, a second deflex) or choose other registers \
                 (robot.rtde_register)"
            ),
            SetupRefusal::ControllerTooOld { version, needs } => write!(
                f,
                "the controller runs software {}.{}.{}; {needs}",
                version[0], version[1], version[2]
            ),
            SetupRefusal::StartRefused => f.write_str("the controller refused to start the stream"),
            SetupRefusal::NoAnswer { request } => write!(
                f,
                "no answer to the {:?} request within the set-up bound",
                request
            ),
            SetupRefusal::FieldCount { asked, answered } => write!(
                f,
                "the recipe answer names {answered} types for {asked} variables"
            ),
            SetupRefusal::WrongType { variable, answered } => write!(
                f,
                "the controller gives {variable} the type {}, expected {}",
                answered.name(),
                variable.field_type().name()
            ),
        }
    }
}

/// A decoded field value.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Value {
    /// `BOOL`.
    Bool(bool),
    /// `UINT8`.
    U8(u8),
    /// `UINT32`.
    U32(u32),
    /// `UINT64`.
    U64(u64),
    /// `INT32`.
    I32(i32),
    /// `DOUBLE`.
    F64(f64),
    /// `VECTOR3D`.
    V3([f64; 3]),
    /// `VECTOR6D`.
    V6([f64; 6]),
    /// `VECTOR6INT32`.
    V6I([i32; 6]),
    /// `VECTOR6UINT32`.
    V6U([u32; 6]),
}

impl Default for Value {
    fn default() -> Self {
        Value::F64(0.0)
    }
}

impl Value {
    /// The type of the value.
    pub const fn field_type(&self) -> FieldType {
        match self {
            Value::Bool(_) => FieldType::Bool,
            Value::U8(_) => FieldType::Uint8,
            Value::U32(_) => FieldType::Uint32,
            Value::U64(_) => FieldType::Uint64,
            Value::I32(_) => FieldType::Int32,
            Value::F64(_) => FieldType::Double,
            Value::V3(_) => FieldType::Vector3d,
            Value::V6(_) => FieldType::Vector6d,
            Value::V6I(_) => FieldType::Vector6Int32,
            Value::V6U(_) => FieldType::Vector6Uint32,
        }
    }

    /// A double, `None` for another type.
    pub const fn as_f64(&self) -> Option<f64> {
        match self {
            Value::F64(v) => Some(*v),
            _ => None,
        }
    }

    /// A six-vector of doubles, `None` for another type.
    pub const fn as_v6(&self) -> Option<[f64; 6]> {
        match self {
            Value::V6(v) => Some(*v),
            _ => None,
        }
    }

    /// An integer of any integer type that fits i64, `None` for another type.
    pub const fn as_i64(&self) -> Option<i64> {
        match self {
            Value::Bool(b) => Some(*b as i64),
            Value::U8(v) => Some(*v as i64),
            Value::U32(v) => Some(*v as i64),
            Value::I32(v) => Some(*v as i64),
            _ => None,
        }
    }
}

/// A recipe: the variables of a set-up, in order, with the id the controller gave it.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Recipe {
    /// The id data packages of this recipe carry.
    pub id: u8,
    vars: [Variable; MAX_FIELDS],
    len: usize,
}

impl Recipe {
    /// A recipe of `vars` (at most [`MAX_FIELDS`]) with id `id`.
    pub fn new(id: u8, vars: &[Variable]) -> Result<Recipe, LinkError> {
        if vars.is_empty() || vars.len() > MAX_FIELDS {
            return Err(bad("a recipe has 1 to 16 variables"));
        }
        let mut r = Recipe {
            id,
            vars: [Variable::Timestamp; MAX_FIELDS],
            len: vars.len(),
        };
        r.vars[..vars.len()].copy_from_slice(vars);
        Ok(r)
    }

    /// The variables.
    pub fn variables(&self) -> &[Variable] {
        &self.vars[..self.len]
    }

    /// Bytes of a data package's payload: the id and the fields.
    pub fn payload_len(&self) -> usize {
        1 + self
            .variables()
            .iter()
            .map(|v| v.field_type().size())
            .sum::<usize>()
    }

    /// Index of a variable in the recipe.
    pub fn position(&self, v: Variable) -> Option<usize> {
        self.variables().iter().position(|x| *x == v)
    }
}

/// Writes into a fixed buffer (big-endian), counting the bytes.
#[derive(Debug)]
pub struct Writer<'a> {
    buf: &'a mut [u8],
    pos: usize,
}

impl<'a> Writer<'a> {
    /// A writer at the start of `buf`.
    pub fn new(buf: &'a mut [u8]) -> Self {
        Writer { buf, pos: 0 }
    }

    /// Bytes written.
    pub fn len(&self) -> usize {
        self.pos
    }

    /// True when nothing was written.
    pub fn is_empty(&self) -> bool {
        self.pos == 0
    }

    /// Appends bytes.
    pub fn bytes(&mut self, b: &[u8]) -> Result<(), LinkError> {
        let end = self.pos + b.len();
        let dst = self
            .buf
            .get_mut(self.pos..end)
            .ok_or(LinkError::BufferTooSmall {
                protocol: P,
                capacity: 0,
            })?;
        dst.copy_from_slice(b);
        self.pos = end;
        Ok(())
    }

    /// Appends a byte.
    pub fn u8(&mut self, v: u8) -> Result<(), LinkError> {
        self.bytes(&[v])
    }

    fn value(&mut self, v: &Value) -> Result<(), LinkError> {
        match *v {
            Value::Bool(b) => self.u8(u8::from(b)),
            Value::U8(x) => self.u8(x),
            Value::U32(x) => self.bytes(&x.to_be_bytes()),
            Value::U64(x) => self.bytes(&x.to_be_bytes()),
            Value::I32(x) => self.bytes(&x.to_be_bytes()),
            Value::F64(x) => self.bytes(&x.to_be_bytes()),
            Value::V3(a) => a.iter().try_for_each(|x| self.bytes(&x.to_be_bytes())),
            Value::V6(a) => a.iter().try_for_each(|x| self.bytes(&x.to_be_bytes())),
            Value::V6I(a) => a.iter().try_for_each(|x| self.bytes(&x.to_be_bytes())),
            Value::V6U(a) => a.iter().try_for_each(|x| self.bytes(&x.to_be_bytes())),
        }
    }
}

/// Writes a whole package of type `t` whose payload `payload` writes; returns its length.
pub fn encode_package(
    out: &mut [u8],
    t: PackageType,
    payload: impl FnOnce(&mut Writer<'_>) -> Result<(), LinkError>,
) -> Result<usize, LinkError> {
    let capacity = out.len().min(MAX_PACKAGE);
    let mut w = Writer::new(&mut out[..capacity]);
    w.bytes(&[0, 0, t.code()])?;
    payload(&mut w).map_err(|_| LinkError::BufferTooSmall {
        protocol: P,
        capacity,
    })?;
    let n = w.len();
    let size = u16::try_from(n).map_err(|_| LinkError::BufferTooSmall {
        protocol: P,
        capacity,
    })?;
    out[..2].copy_from_slice(&size.to_be_bytes());
    Ok(n)
}

/// The header of a package at the start of `b`: its total size and type. Checks the size
/// (at least [`HEADER_LEN`], at most [`MAX_PACKAGE`]) and the type.
pub fn decode_header(b: &[u8]) -> Result<(usize, PackageType), LinkError> {
    if b.len() < HEADER_LEN {
        return Err(LinkError::Truncated {
            protocol: P,
            expected: HEADER_LEN,
            got: b.len(),
        });
    }
    let size = usize::from(u16::from_be_bytes([b[0], b[1]]));
    if size < HEADER_LEN {
        return Err(bad("package size below the 3-byte header"));
    }
    if size > MAX_PACKAGE {
        return Err(LinkError::Oversize {
            protocol: P,
            capacity: MAX_PACKAGE,
        });
    }
    let t = PackageType::from_code(b[2]).ok_or(bad("unknown package type"))?;
    Ok((size, t))
}

/// Splits one whole package (header included) into its type and payload.
pub fn split_package(b: &[u8]) -> Result<(PackageType, &[u8]), LinkError> {
    let (size, t) = decode_header(b)?;
    if b.len() != size {
        return Err(LinkError::Truncated {
            protocol: P,
            expected: size,
            got: b.len(),
        });
    }
    Ok((t, &b[HEADER_LEN..]))
}

fn names(w: &mut Writer<'_>, vars: &[Variable]) -> Result<(), LinkError> {
    for (i, v) in vars.iter().enumerate() {
        if i > 0 {
            w.u8(b',')?;
        }
        v.write_name(w)?;
    }
    Ok(())
}

// ------------------------------------------------------------------ client → controller

/// `V`: asks for protocol `version`.
pub fn encode_request_protocol_version(out: &mut [u8], version: u16) -> Result<usize, LinkError> {
    encode_package(out, PackageType::RequestProtocolVersion, |w| {
        w.bytes(&version.to_be_bytes())
    })
}

/// A package without payload: `v` (controller version), `S` (start), `P` (pause).
pub fn encode_empty(out: &mut [u8], t: PackageType) -> Result<usize, LinkError> {
    encode_package(out, t, |_| Ok(()))
}

/// `O`: the output recipe `vars` at `frequency_hz`.
pub fn encode_setup_outputs(
    out: &mut [u8],
    frequency_hz: f64,
    vars: &[Variable],
) -> Result<usize, LinkError> {
    encode_package(out, PackageType::SetupOutputs, |w| {
        w.bytes(&frequency_hz.to_be_bytes())?;
        names(w, vars)
    })
}

/// `I`: the input recipe `vars`.
pub fn encode_setup_inputs(out: &mut [u8], vars: &[Variable]) -> Result<usize, LinkError> {
    encode_package(out, PackageType::SetupInputs, |w| names(w, vars))
}

/// `U`: a data package of `recipe` carrying `values` (one per variable, of its type; doubles
/// must be finite).
pub fn encode_data(out: &mut [u8], recipe: &Recipe, values: &[Value]) -> Result<usize, LinkError> {
    if values.len() != recipe.len {
        return Err(LinkError::InvalidValue {
            protocol: P,
            reason: "value count differs from the recipe's",
        });
    }
    for (v, var) in values.iter().zip(recipe.variables()) {
        if v.field_type() != var.field_type() {
            return Err(LinkError::InvalidValue {
                protocol: P,
                reason: "value type differs from the recipe's",
            });
        }
        if !value_finite(v) {
            return Err(LinkError::InvalidValue {
                protocol: P,
                reason: "non-finite value",
            });
        }
    }
    encode_package(out, PackageType::DataPackage, |w| {
        w.u8(recipe.id)?;
        values.iter().try_for_each(|v| w.value(v))
    })
}

fn value_finite(v: &Value) -> bool {
    match v {
        Value::F64(x) => x.is_finite(),
        Value::V3(a) => a.iter().all(|x| x.is_finite()),
        Value::V6(a) => a.iter().all(|x| x.is_finite()),
        _ => true,
    }
}

// ------------------------------------------------------------------ controller → client

/// An answer carrying one `u8` flag (`V`, `S`, `P`): accepted.
pub fn decode_accepted(payload: &[u8]) -> Result<bool, LinkError> {
    match payload {
        [a] => Ok(*a != 0),
        _ => Err(LinkError::Truncated {
            protocol: P,
            expected: 1,
            got: payload.len(),
        }),
    }
}

/// `v` answer: major, minor, bugfix, build.
pub fn decode_controller_version(payload: &[u8]) -> Result<[u32; 4], LinkError> {
    if payload.len() != 16 {
        return Err(LinkError::Truncated {
            protocol: P,
            expected: 16,
            got: payload.len(),
        });
    }
    let mut v = [0u32; 4];
    for (i, x) in v.iter_mut().enumerate() {
        *x = u32::from_be_bytes([
            payload[4 * i],
            payload[4 * i + 1],
            payload[4 * i + 2],
            payload[4 * i + 3],
        ]);
    }
    Ok(v)
}

/// A text message from the controller (protocol version 2).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct TextMessage<'a> {
    /// The message.
    pub message: &'a [u8],
    /// Its source.
    pub source: &'a [u8],
    /// 0 exception, 1 error, 2 warning, 3 info.
    pub level: u8,
}

impl TextMessage<'_> {
    /// The level's name.
    pub fn level_name(&self) -> &'static str {
        match self.level {
            0 => "exception",
            1 => "error",
            2 => "warning",
            3 => "info",
            _ => "unknown level",
        }
    }
}

/// `M` (version 2): message, source, level.
pub fn decode_text_message(payload: &[u8]) -> Result<TextMessage<'_>, LinkError> {
    let short = || bad("text message shorter than its lengths say");
    let (&ml, rest) = payload.split_first().ok_or_else(short)?;
    let message = rest.get(..usize::from(ml)).ok_or_else(short)?;
    let rest = &rest[usize::from(ml)..];
    let (&sl, rest) = rest.split_first().ok_or_else(short)?;
    let source = rest.get(..usize::from(sl)).ok_or_else(short)?;
    let rest = &rest[usize::from(sl)..];
    match rest {
        [level] => Ok(TextMessage {
            message,
            source,
            level: *level,
        }),
        _ => Err(bad("text message longer than its lengths say")),
    }
}

/// Encodes a text message (the controller side).
pub fn encode_text_message(
    out: &mut [u8],
    message: &[u8],
    source: &[u8],
    level: u8,
) -> Result<usize, LinkError> {
    let ml = message.len().min(255);
    let sl = source.len().min(255);
    encode_package(out, PackageType::TextMessage, |w| {
        w.u8(ml as u8)?;
        w.bytes(&message[..ml])?;
        w.u8(sl as u8)?;
        w.bytes(&source[..sl])?;
        w.u8(level)
    })
}

/// The answer to a recipe set-up for `asked`: the recipe with its id, or why it is refused
/// (`NOT_FOUND`, `IN_USE`, a count or type other than asked).
pub fn decode_recipe_answer(payload: &[u8], asked: &[Variable]) -> Result<Recipe, LinkError> {
    let refused = |refusal| LinkError::SetupRefused {
        protocol: P,
        refusal,
    };
    let (&id, types) = payload.split_first().ok_or(bad("empty recipe answer"))?;
    let mut answered = 0;
    for (i, t) in types.split(|&b| b == b',').enumerate() {
        answered += 1;
        let Some(&variable) = asked.get(i) else {
            continue;
        };
        match t {
            b"NOT_FOUND" => return Err(refused(SetupRefusal::NotFound { variable })),
            b"IN_USE" => return Err(refused(SetupRefusal::InUse { variable })),
            _ => {}
        }
        let ft = FieldType::from_name(t).ok_or(bad("unknown field type in a recipe answer"))?;
        if ft != variable.field_type() {
            return Err(refused(SetupRefusal::WrongType {
                variable,
                answered: ft,
            }));
        }
    }
    if answered != asked.len() {
        return Err(refused(SetupRefusal::FieldCount {
            asked: asked.len(),
            answered,
        }));
    }
    Recipe::new(id, asked)
}

/// Decodes a data package's payload of `recipe` into `out` (one value per variable): the
/// recipe id must be the recipe's, the size exactly the recipe's, every double finite.
pub fn decode_data(payload: &[u8], recipe: &Recipe, out: &mut [Value]) -> Result<(), LinkError> {
    let (&id, mut rest) = payload.split_first().ok_or(LinkError::Truncated {
        protocol: P,
        expected: recipe.payload_len(),
        got: 0,
    })?;
    if id != recipe.id {
        return Err(bad("data package of another recipe id than the session's"));
    }
    let expected = recipe.payload_len();
    if payload.len() < expected {
        return Err(LinkError::Truncated {
            protocol: P,
            expected,
            got: payload.len(),
        });
    }
    if payload.len() > expected {
        return Err(bad("data package longer than its recipe (field count)"));
    }
    if out.len() < recipe.len {
        return Err(LinkError::BufferTooSmall {
            protocol: P,
            capacity: out.len(),
        });
    }
    for (var, slot) in recipe.variables().iter().zip(out.iter_mut()) {
        let t = var.field_type();
        let (field, tail) = rest.split_at(t.size());
        rest = tail;
        *slot = read_value(t, field);
        if !value_finite(slot) {
            return Err(bad("non-finite double in a data package"));
        }
    }
    Ok(())
}

fn f64_at(b: &[u8], i: usize) -> f64 {
    let mut a = [0u8; 8];
    a.copy_from_slice(&b[8 * i..8 * i + 8]);
    f64::from_be_bytes(a)
}

fn u32_at(b: &[u8], i: usize) -> u32 {
    u32::from_be_bytes([b[4 * i], b[4 * i + 1], b[4 * i + 2], b[4 * i + 3]])
}

/// A value of type `t` from exactly `t.size()` bytes.
fn read_value(t: FieldType, b: &[u8]) -> Value {
    match t {
        FieldType::Bool => Value::Bool(b[0] != 0),
        FieldType::Uint8 => Value::U8(b[0]),
        FieldType::Uint32 => Value::U32(u32_at(b, 0)),
        FieldType::Int32 => Value::I32(u32_at(b, 0) as i32),
        FieldType::Uint64 => {
            let mut a = [0u8; 8];
            a.copy_from_slice(&b[..8]);
            Value::U64(u64::from_be_bytes(a))
        }
        FieldType::Double => Value::F64(f64_at(b, 0)),
        FieldType::Vector3d => Value::V3(std::array::from_fn(|i| f64_at(b, i))),
        FieldType::Vector6d => Value::V6(std::array::from_fn(|i| f64_at(b, i))),
        FieldType::Vector6Int32 => Value::V6I(std::array::from_fn(|i| u32_at(b, i) as i32)),
        FieldType::Vector6Uint32 => Value::V6U(std::array::from_fn(|i| u32_at(b, i))),
    }
}

// ------------------------------------------------------------------ controller side decoding

/// `V` request: the version asked for.
pub fn decode_protocol_request(payload: &[u8]) -> Result<u16, LinkError> {
    match payload {
        [a, b] => Ok(u16::from_be_bytes([*a, *b])),
        _ => Err(LinkError::Truncated {
            protocol: P,
            expected: 2,
            got: payload.len(),
        }),
    }
}

/// Splits a set-up request's names; `None` at a name deflex does not know (the controller
/// answers `NOT_FOUND` there). Calls `each` with every name's position and variable. One
/// trailing comma is allowed (SDU's `ur_rtde` ends its lists with one, and UR's controllers take
/// them).
pub fn for_each_name(
    names: &[u8],
    mut each: impl FnMut(usize, Option<Variable>) -> Result<(), LinkError>,
) -> Result<usize, LinkError> {
    let names = names.strip_suffix(b",").unwrap_or(names);
    let mut n = 0;
    for (i, name) in names.split(|&b| b == b',').enumerate() {
        if i >= MAX_FIELDS {
            return Err(bad("a recipe of more than 16 variables"));
        }
        each(i, Variable::from_name(name))?;
        n += 1;
    }
    Ok(n)
}

/// `O` request: the frequency and the names.
pub fn decode_setup_outputs(payload: &[u8]) -> Result<(f64, &[u8]), LinkError> {
    if payload.len() < 9 {
        return Err(LinkError::Truncated {
            protocol: P,
            expected: 9,
            got: payload.len(),
        });
    }
    let f = f64_at(payload, 0);
    if !(f.is_finite() && f > 0.0 && f <= 500.0) {
        return Err(bad("output frequency outside 0 to 500 Hz"));
    }
    Ok((f, &payload[8..]))
}

/// Bytes a package still needs once `have` bytes of it are buffered: `None` when it is whole
/// (or the header says it is broken: [`decode_header`] tells why).
pub fn bytes_missing(buffered: &[u8]) -> Option<usize> {
    if buffered.len() < HEADER_LEN {
        return Some(HEADER_LEN - buffered.len());
    }
    let size = usize::from(u16::from_be_bytes([buffered[0], buffered[1]]));
    (size > buffered.len()).then(|| size - buffered.len())
}
