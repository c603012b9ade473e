//! The RTDE client links of deflex: [`RtdeLink`] (the robot: joints, TCP pose, controller time;
//! the correction written to input registers) and [`RtdeSensor`] (the flange sensor's
//! `ft_raw_wrench` on a connection of its own).
//!
//! **Registers** (`robot.rtde_register` = N, 24 by default, within the client range 24–47):
//! the correction goes to `input_double_register_N … N+5` as `[dx, dy, dz, rx, ry, rz]` (m and
//! a rotation vector in rad, base axes: URScript's `path_offset_set(…, 1)`), and a sequence
//! number that advances with every correction to `input_int_register_N`: the URScript program
//! (`docs/ur/deflex_rtde.script`) watches it and ramps the offset out when it stops advancing.
//! The program's own heartbeat is read from `output_int_register_N`.
//!
//! **Connection.** [`RtdeLink::connect`] connects to the controller (retrying a refused
//! connection for the configured wait) and sets the session up: protocol version 2, controller
//! version (path_offset needs PolyScope 5.6 or newer: a CB3 or an older e-Series is refused with
//! the text-loop fallback named), the output recipe at the controller's rate (500 Hz, 125 Hz on
//! CB3) and the input recipe (`IN_USE`: another client holds the registers). A set-up refusal
//! is a [`LinkError::SetupRefused`] naming the variable. A lost connection shows as timeouts;
//! the link reconnects at most once per [`RECONNECT_PERIOD`].
//!
//! **Checks.** Every package is bounded ([`super::MAX_PACKAGE`]); a size the stream cannot
//! carry closes the connection (the framing is lost); an unknown type, a data package of
//! another recipe id, of another size or with a non-finite double is a bad packet
//! ([`LinkError::is_bad_packet`]) and the connection stays. Text messages are written to the
//! standard error and counted ([`RtdeStatus`]). After connection nothing allocates: packages
//! are assembled in a fixed buffer, values decoded into fixed arrays.

use super::{
    HEADER_LEN, MAX_FIELDS, MAX_PACKAGE, P, PROTOCOL_VERSION, PackageType, Recipe, SetupRefusal,
    Value, Variable, decode_accepted, decode_controller_version, decode_data, decode_header,
    decode_recipe_answer, decode_text_message, encode_data, encode_empty,
    encode_request_protocol_version, encode_setup_inputs, encode_setup_outputs,
};
use crate::error::LinkError;
use crate::guard::{LinkCounters, SessionGuard, Stamp};
use crate::link::{Correction, ForceSensorLink, RobotLink, RobotState, WrenchSample};
use deflex_model::conventions::rotation_from_rotation_vector;
use deflex_model::{Pose, Wrench};
use nalgebra::{Translation3, Vector3};
use std::io::{ErrorKind, Read, Write};
use std::net::{SocketAddr, TcpStream};
use std::time::{Duration, Instant};

/// Bound on each set-up answer.
pub const SETUP_TIMEOUT: Duration = Duration::from_secs(2);
/// Least time between two reconnection attempts after a lost connection.
pub const RECONNECT_PERIOD: Duration = Duration::from_secs(1);
/// Bound on a blocking write of one package.
pub const WRITE_TIMEOUT: Duration = Duration::from_millis(50);

/// Assembles RTDE packages from a byte stream in a fixed buffer.
#[derive(Debug)]
pub struct PackageBuf {
    buf: [u8; MAX_PACKAGE],
    len: usize,
}

impl Default for PackageBuf {
    fn default() -> Self {
        Self::new()
    }
}

/// What [`PackageBuf::next_package`] found.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Next {
    /// A whole package of this type and total length is at the front ([`PackageBuf::package`]);
    /// [`PackageBuf::consume`] it once read.
    Package(PackageType, usize),
    /// A whole package of a type RTDE does not define was dropped.
    UnknownType(u8),
    /// More bytes are needed.
    Incomplete,
}

impl PackageBuf {
    /// Empty.
    pub const fn new() -> Self {
        PackageBuf {
            buf: [0; MAX_PACKAGE],
            len: 0,
        }
    }

    /// Forgets everything buffered.
    pub fn clear(&mut self) {
        self.len = 0;
    }

    /// Free space to read into (never empty while no whole package waits).
    pub fn space(&mut self) -> &mut [u8] {
        &mut self.buf[self.len..]
    }

    /// Marks `n` bytes of [`PackageBuf::space`] as received.
    pub fn commit(&mut self, n: usize) {
        self.len = (self.len + n).min(MAX_PACKAGE);
    }

    /// The next package. `Err`: the header's size is below 3 or above [`MAX_PACKAGE`]: the
    /// framing is lost and the stream must be closed.
    pub fn next_package(&mut self) -> Result<Next, LinkError> {
        if self.len < HEADER_LEN {
            return Ok(Next::Incomplete);
        }
        match decode_header(&self.buf[..self.len]) {
            Ok((size, t)) if size <= self.len => Ok(Next::Package(t, size)),
            Ok(_) => Ok(Next::Incomplete),
            Err(LinkError::Malformed {
                reason: "unknown package type",
                ..
            }) => {
                let size = usize::from(u16::from_be_bytes([self.buf[0], self.buf[1]]));
                if size <= self.len {
                    let code = self.buf[2];
                    self.consume(size);
                    Ok(Next::UnknownType(code))
                } else {
                    Ok(Next::Incomplete)
                }
            }
            Err(e) => Err(e),
        }
    }

    /// The whole package of length `size` at the front.
    pub fn package(&self, size: usize) -> &[u8] {
        &self.buf[..size.min(self.len)]
    }

    /// Drops the package of length `size` at the front.
    pub fn consume(&mut self, size: usize) {
        let size = size.min(self.len);
        self.buf.copy_within(size..self.len, 0);
        self.len -= size;
    }
}

/// Reads into `rx` once, waiting up to `wait` (zero: do not wait). `Ok(false)` on timeout;
/// an orderly close or a reset is an `UnexpectedEof` error.
pub(super) fn read_once(
    stream: &mut TcpStream,
    rx: &mut PackageBuf,
    wait: Duration,
    cached: &mut Option<Option<Duration>>,
) -> Result<bool, LinkError> {
    let wanted = (!wait.is_zero()).then_some(wait);
    if *cached != Some(wanted) {
        match wanted {
            None => stream.set_nonblocking(true)?,
            Some(d) => {
                stream.set_nonblocking(false)?;
                stream.set_read_timeout(Some(d))?;
            }
        }
        *cached = Some(wanted);
    }
    match stream.read(rx.space()) {
        Ok(0) => Err(LinkError::Io(ErrorKind::UnexpectedEof.into())),
        Ok(n) => {
            rx.commit(n);
            Ok(true)
        }
        Err(e)
            if matches!(
                e.kind(),
                ErrorKind::WouldBlock | ErrorKind::TimedOut | ErrorKind::Interrupted
            ) =>
        {
            Ok(false)
        }
        Err(e) => Err(e.into()),
    }
}

/// What the controller last reported about itself.
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct RtdeStatus {
    /// Controller software version: major, minor, bugfix, build.
    pub controller_version: [u32; 4],
    /// `robot_mode` (7 = running).
    pub robot_mode: i32,
    /// `safety_status` (1 = normal).
    pub safety_status: i32,
    /// `runtime_state` (2 = playing).
    pub runtime_state: u32,
    /// The URScript program's heartbeat (`output_int_register_N`).
    pub script_heartbeat: i32,
    /// Text messages received from the controller.
    pub text_messages: u64,
    /// Packages dropped as bad (unknown type, other recipe id, size, non-finite).
    pub bad_packages: u64,
    /// Data packages whose controller time did not advance by one period (packages missed).
    pub gaps: u64,
}

/// What a connection sets up.
#[derive(Debug, Clone, Copy)]
struct Spec<'a> {
    outputs: &'a [Variable],
    inputs: &'a [Variable],
    /// The link needs `path_offset` (PolyScope 5.6 or newer).
    needs_path_offset: bool,
}

/// One RTDE session with the controller: set up and started.
#[derive(Debug)]
struct Session {
    stream: TcpStream,
    rx: PackageBuf,
    tx: [u8; 512],
    read_mode: Option<Option<Duration>>,
    outputs: Recipe,
    inputs: Option<Recipe>,
    values: [Value; MAX_FIELDS],
    answer: [u8; MAX_PACKAGE],
    version: [u32; 4],
    period_s: f64,
}

/// What [`Session::next_data`] found.
enum Data {
    /// A data package of the output recipe, decoded into `values`.
    Fresh,
    /// Nothing within the wait.
    Timeout,
}

impl Session {
    /// Connects and sets up `spec` (see the module documentation).
    fn open(controller: SocketAddr, spec: Spec<'_>, timeout: Duration) -> Result<Self, LinkError> {
        let stream =
            TcpStream::connect_timeout(&controller, timeout.max(Duration::from_millis(1)))?;
        stream.set_nodelay(true)?;
        stream.set_write_timeout(Some(WRITE_TIMEOUT))?;
        let mut s = Session {
            stream,
            rx: PackageBuf::new(),
            tx: [0; 512],
            read_mode: None,
            outputs: Recipe::new(0, spec.outputs)?,
            inputs: None,
            values: [Value::default(); MAX_FIELDS],
            answer: [0; MAX_PACKAGE],
            version: [0; 4],
            period_s: 0.002,
        };
        let refused = |refusal| LinkError::SetupRefused {
            protocol: P,
            refusal,
        };
        let n = encode_request_protocol_version(&mut s.tx, PROTOCOL_VERSION)?;
        let answer = s.request(n, PackageType::RequestProtocolVersion)?;
        if !decode_accepted(answer)? {
            return Err(refused(SetupRefusal::VersionRefused {
                version: PROTOCOL_VERSION,
            }));
        }
        let n = encode_empty(&mut s.tx, PackageType::GetUrControlVersion)?;
        s.version = decode_controller_version(s.request(n, PackageType::GetUrControlVersion)?)?;
        let [major, minor, bugfix, _] = s.version;
        if spec.needs_path_offset && (major < 5 || (major == 5 && minor < 6)) {
            return Err(refused(SetupRefusal::ControllerTooOld {
                version: [major, minor, bugfix],
                needs: "path_offset needs PolyScope 5.6 or newer: keep the text loop \
                        (robot.kind = \"simple-tcp\", docs/ur/deflex_loop.script) on this controller",
            }));
        }
        // e-Series and UR-Series stream at 500 Hz, CB3 (software 3.x) at 125 Hz.
        let frequency = if major >= 5 { 500.0 } else { 125.0 };
        s.period_s = 1.0 / frequency;
        let n = encode_setup_outputs(&mut s.tx, frequency, spec.outputs)?;
        s.outputs = decode_recipe_answer(s.request(n, PackageType::SetupOutputs)?, spec.outputs)?;
        if !spec.inputs.is_empty() {
            let n = encode_setup_inputs(&mut s.tx, spec.inputs)?;
            s.inputs = Some(decode_recipe_answer(
                s.request(n, PackageType::SetupInputs)?,
                spec.inputs,
            )?);
        }
        let n = encode_empty(&mut s.tx, PackageType::Start)?;
        if !decode_accepted(s.request(n, PackageType::Start)?)? {
            return Err(refused(SetupRefusal::StartRefused));
        }
        Ok(s)
    }

    /// Sends the first `n` bytes of `tx` and waits for the answer of type `t` (text messages
    /// are logged on the way); its payload, copied aside.
    fn request(&mut self, n: usize, t: PackageType) -> Result<&[u8], LinkError> {
        self.stream.write_all(&self.tx[..n])?;
        let deadline = Instant::now() + SETUP_TIMEOUT;
        loop {
            match self.rx.next_package()? {
                Next::Package(got, size) if got == t => {
                    let payload = &self.rx.package(size)[HEADER_LEN..];
                    let len = payload.len();
                    self.answer[..len].copy_from_slice(payload);
                    self.rx.consume(size);
                    return Ok(&self.answer[..len]);
                }
                Next::Package(PackageType::TextMessage, size) => {
                    log_text(self.rx.package(size));
                    self.rx.consume(size);
                }
                Next::Package(_, size) => self.rx.consume(size),
                Next::UnknownType(_) => {}
                Next::Incomplete => {
                    let wait = deadline.saturating_duration_since(Instant::now());
                    if wait.is_zero() {
                        return Err(LinkError::SetupRefused {
                            protocol: P,
                            refusal: SetupRefusal::NoAnswer { request: t },
                        });
                    }
                    read_once(&mut self.stream, &mut self.rx, wait, &mut self.read_mode)?;
                }
            }
        }
    }

    /// Waits up to `timeout` for the next data package of the output recipe, decoded into
    /// `values`. Text messages are logged and counted; `Err` with [`LinkError::is_bad_packet`]
    /// for a bad package (the session stays), any other `Err` when the session is lost.
    fn next_data(&mut self, timeout: Duration, status: &mut RtdeStatus) -> Result<Data, LinkError> {
        let deadline = Instant::now() + timeout;
        let mut wait = timeout;
        loop {
            match self.rx.next_package()? {
                Next::Package(PackageType::DataPackage, size) => {
                    let result = decode_data(
                        &self.rx.package(size)[HEADER_LEN..],
                        &self.outputs,
                        &mut self.values,
                    );
                    self.rx.consume(size);
                    if let Err(e) = result {
                        status.bad_packages += 1;
                        return Err(e);
                    }
                    return Ok(Data::Fresh);
                }
                Next::Package(PackageType::TextMessage, size) => {
                    status.text_messages += 1;
                    log_text(self.rx.package(size));
                    self.rx.consume(size);
                }
                Next::Package(PackageType::Start | PackageType::Pause, size) => {
                    // The answer to a start or pause deflex sent.
                    self.rx.consume(size);
                }
                Next::Package(_, size) => {
                    // Answers to nothing deflex asked for during the stream.
                    self.rx.consume(size);
                    status.bad_packages += 1;
                    return Err(super::bad("unexpected package type during the stream"));
                }
                Next::UnknownType(_) => {
                    status.bad_packages += 1;
                    return Err(super::bad("unknown package type"));
                }
                Next::Incomplete => {
                    if !read_once(&mut self.stream, &mut self.rx, wait, &mut self.read_mode)? {
                        return Ok(Data::Timeout);
                    }
                    // Later reads of the same package wait only what is left (none: no wait).
                    wait = deadline.saturating_duration_since(Instant::now());
                }
            }
        }
    }

    /// Writes a data package of the input recipe.
    fn send_inputs(&mut self, values: &[Value]) -> Result<(), LinkError> {
        let recipe = self
            .inputs
            .as_ref()
            .ok_or(LinkError::NoPeer { protocol: P })?;
        let n = encode_data(&mut self.tx, recipe, values)?;
        self.stream.write_all(&self.tx[..n])?;
        Ok(())
    }

    /// Pauses the stream (no answer awaited: the session ends next).
    fn pause(&mut self) {
        if let Ok(n) = encode_empty(&mut self.tx, PackageType::Pause) {
            let _ = self.stream.write_all(&self.tx[..n]);
        }
    }
}

/// Writes a controller's text message to the standard error.
fn log_text(package: &[u8]) {
    if let Some(payload) = package.get(HEADER_LEN..)
        && let Ok(m) = decode_text_message(payload)
    {
        eprintln!(
            "deflex: UR controller {} from {}: {}",
            m.level_name(),
            String::from_utf8_lossy(m.source),
            String::from_utf8_lossy(m.message)
        );
    }
}

/// Connects with retries of a refused or failed TCP connection until `wait` has passed; a
/// set-up refusal ends at once.
fn open_with_retry(
    controller: SocketAddr,
    spec: Spec<'_>,
    wait: Duration,
) -> Result<Session, LinkError> {
    let start = Instant::now();
    loop {
        match Session::open(controller, spec, SETUP_TIMEOUT) {
            Ok(s) => return Ok(s),
            // Refused or reset: the controller (or the twin) is not listening yet.
            Err(LinkError::Io(_)) if start.elapsed() < wait => {
                std::thread::sleep(Duration::from_millis(50));
            }
            Err(e) => return Err(e),
        }
    }
}

// ---------------------------------------------------------------- robot link

/// Settings of [`RtdeLink`].
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct RtdeLinkConfig {
    /// First register (`robot.rtde_register`, 24–42): doubles N … N+5, int N in, int N out.
    pub register: u8,
    /// How long [`RtdeLink::connect`] retries a refused connection.
    pub connect_wait: Duration,
}

impl Default for RtdeLinkConfig {
    fn default() -> Self {
        RtdeLinkConfig {
            register: 24,
            connect_wait: Duration::from_secs(10),
        }
    }
}

impl RtdeLinkConfig {
    /// The output recipe of the robot link.
    pub fn outputs(&self) -> [Variable; 7] {
        [
            Variable::Timestamp,
            Variable::ActualQ,
            Variable::ActualTcpPose,
            Variable::RobotMode,
            Variable::SafetyStatus,
            Variable::RuntimeState,
            Variable::OutputIntRegister(self.register),
        ]
    }

    /// The input recipe: six doubles and the sequence register.
    pub fn inputs(&self) -> [Variable; 7] {
        let r = self.register;
        [
            Variable::InputDoubleRegister(r),
            Variable::InputDoubleRegister(r + 1),
            Variable::InputDoubleRegister(r + 2),
            Variable::InputDoubleRegister(r + 3),
            Variable::InputDoubleRegister(r + 4),
            Variable::InputDoubleRegister(r + 5),
            Variable::InputIntRegister(r),
        ]
    }

    fn check(&self) -> Result<(), LinkError> {
        if !(24..=42).contains(&self.register) {
            return Err(LinkError::InvalidValue {
                protocol: P,
                reason: "robot.rtde_register must lie in 24..=42 (six doubles within 24-47)",
            });
        }
        Ok(())
    }
}

/// The robot over RTDE (see the module documentation).
#[derive(Debug)]
pub struct RtdeLink {
    controller: SocketAddr,
    config: RtdeLinkConfig,
    session: Option<Session>,
    last_attempt: Instant,
    guard: SessionGuard,
    status: RtdeStatus,
    sequence: i32,
    packages: u64,
    last_time_s: Option<f64>,
    stats: LinkCounters,
}

impl RtdeLink {
    /// Connects to the controller's RTDE server at `controller` and sets the session up.
    pub fn connect(controller: SocketAddr, config: RtdeLinkConfig) -> Result<Self, LinkError> {
        config.check()?;
        let outputs = config.outputs();
        let inputs = config.inputs();
        let session = open_with_retry(
            controller,
            Spec {
                outputs: &outputs,
                inputs: &inputs,
                needs_path_offset: true,
            },
            config.connect_wait,
        )?;
        let mut status = RtdeStatus {
            controller_version: session.version,
            ..RtdeStatus::default()
        };
        status.robot_mode = -1;
        Ok(RtdeLink {
            controller,
            config,
            session: Some(session),
            last_attempt: Instant::now(),
            guard: SessionGuard::new(),
            status,
            sequence: 0,
            packages: 0,
            last_time_s: None,
            stats: LinkCounters {
                connections: 1,
                ..LinkCounters::default()
            },
        })
    }

    /// What the controller last reported about itself.
    pub fn status(&self) -> RtdeStatus {
        self.status
    }

    /// True while the session is up.
    pub fn is_connected(&self) -> bool {
        self.session.is_some()
    }

    /// The controller's stream period (s): 0.002 (e-Series) or 0.008 (CB3).
    pub fn period_s(&self) -> f64 {
        self.session.as_ref().map_or(0.002, |s| s.period_s)
    }

    fn reconnect(&mut self, timeout: Duration) {
        if self.last_attempt.elapsed() < RECONNECT_PERIOD {
            std::thread::sleep(timeout.min(RECONNECT_PERIOD));
            return;
        }
        self.last_attempt = Instant::now();
        let outputs = self.config.outputs();
        let inputs = self.config.inputs();
        if let Ok(s) = Session::open(
            self.controller,
            Spec {
                outputs: &outputs,
                inputs: &inputs,
                needs_path_offset: true,
            },
            SETUP_TIMEOUT,
        ) {
            self.session = Some(s);
            self.guard.restart_stream();
            self.last_time_s = None;
            self.stats.connections += 1;
        }
    }

    fn state_from_values(&mut self) -> Result<Option<RobotState>, LinkError> {
        let Some(s) = self.session.as_ref() else {
            return Ok(None);
        };
        let v = &s.values;
        let (Some(t), Some(q), Some(pose)) = (v[0].as_f64(), v[1].as_v6(), v[2].as_v6()) else {
            return Err(super::bad("robot recipe values of other types"));
        };
        self.status.robot_mode = v[3].as_i64().unwrap_or(-1) as i32;
        self.status.safety_status = v[4].as_i64().unwrap_or(-1) as i32;
        self.status.runtime_state = v[5].as_i64().unwrap_or(0) as u32;
        self.status.script_heartbeat = v[6].as_i64().unwrap_or(0) as i32;
        if let Some(last) = self.last_time_s
            && t - last > 1.5 * s.period_s
        {
            self.status.gaps += 1;
        }
        self.packages += 1;
        if let Err(reason) = self
            .guard
            .admit(6, Some(self.packages), Some(Stamp::Seconds(t)))
        {
            return Err(LinkError::Dropped {
                protocol: P,
                reason,
            });
        }
        self.last_time_s = Some(t);
        let rotation = rotation_from_rotation_vector([pose[3], pose[4], pose[5]]);
        let tcp = Pose::from_parts(
            Translation3::from(Vector3::new(pose[0], pose[1], pose[2])),
            rotation,
        );
        Ok(Some(RobotState {
            tcp_pose: Some(tcp),
            cycle_id: self.packages,
            robot_time_s: Some(t),
            ..RobotState::with_joints(&q)
        }))
    }
}

impl RobotLink for RtdeLink {
    fn receive(&mut self, timeout: Duration) -> Result<Option<RobotState>, LinkError> {
        let Some(session) = self.session.as_mut() else {
            self.reconnect(timeout);
            return Ok(None);
        };
        match session.next_data(timeout, &mut self.status) {
            Ok(Data::Fresh) => self.state_from_values(),
            Ok(Data::Timeout) => Ok(None),
            Err(e) if e.is_bad_packet() && !matches!(e, LinkError::Oversize { .. }) => Err(e),
            Err(e) => {
                // The framing or the connection is lost: a new session on the next receive.
                if e.is_bad_packet() {
                    self.status.bad_packages += 1;
                }
                self.session = None;
                self.last_attempt = Instant::now();
                Err(e)
            }
        }
    }

    fn send_correction(&mut self, c: &Correction) -> Result<(), LinkError> {
        if !c.is_finite() {
            return Err(LinkError::InvalidValue {
                protocol: P,
                reason: "non-finite correction",
            });
        }
        let session = self
            .session
            .as_mut()
            .ok_or(LinkError::NoPeer { protocol: P })?;
        self.sequence = if self.sequence == i32::MAX {
            1
        } else {
            self.sequence + 1
        };
        let a = c.to_array();
        let values = [
            Value::F64(a[0]),
            Value::F64(a[1]),
            Value::F64(a[2]),
            Value::F64(a[3]),
            Value::F64(a[4]),
            Value::F64(a[5]),
            Value::I32(self.sequence),
        ];
        if let Err(e) = session.send_inputs(&values) {
            self.session = None;
            self.last_attempt = Instant::now();
            return Err(e);
        }
        self.stats.answers += 1;
        Ok(())
    }

    fn protocol(&self) -> crate::Protocol {
        P
    }

    fn counters(&self) -> LinkCounters {
        let mut c = self.stats;
        c.bad_packets = self.status.bad_packages;
        self.guard.add_to(&mut c);
        c
    }
}

impl Drop for RtdeLink {
    fn drop(&mut self) {
        if let Some(s) = self.session.as_mut() {
            s.pause();
        }
    }
}

// ---------------------------------------------------------------- flange sensor

/// The arm's own force/torque sensor over RTDE: `ft_raw_wrench` (the flange sensor's raw
/// reading, not payload-compensated, in the sensor's axes at the tool flange on e-Series and
/// UR-Series), on a connection of its own with an output-only recipe (a controller serves
/// several RTDE clients; only input registers are exclusive).
///
/// [`ForceSensorLink::bias`] is a software bias: the next sample becomes the offset subtracted
/// from every later one (URScript's `zero_ftsensor()` zeroes the sensor itself, at the start of
/// the program). Samples carry the package count as sequence and the packages missed (from the
/// controller time) as gap; a non-finite reading is a bad packet.
#[derive(Debug)]
pub struct RtdeSensor {
    controller: SocketAddr,
    session: Option<Session>,
    last_attempt: Instant,
    status: RtdeStatus,
    bias: Wrench,
    take_bias: bool,
    sequence: u32,
    last_time_s: Option<f64>,
    streaming: bool,
}

const SENSOR_OUTPUTS: [Variable; 2] = [Variable::Timestamp, Variable::FtRawWrench];

impl RtdeSensor {
    /// Connects to the controller's RTDE server at `controller` (retrying a refused connection
    /// for `wait`) and starts the stream. A controller without `ft_raw_wrench` (CB3) is refused.
    pub fn connect(controller: SocketAddr, wait: Duration) -> Result<Self, LinkError> {
        let session = open_with_retry(
            controller,
            Spec {
                outputs: &SENSOR_OUTPUTS,
                inputs: &[],
                needs_path_offset: false,
            },
            wait,
        )?;
        Ok(RtdeSensor {
            controller,
            status: RtdeStatus {
                controller_version: session.version,
                ..RtdeStatus::default()
            },
            session: Some(session),
            last_attempt: Instant::now(),
            bias: Wrench::zeros(),
            take_bias: false,
            sequence: 0,
            last_time_s: None,
            streaming: true,
        })
    }

    /// What the controller last reported (version, messages, bad packages, gaps).
    pub fn status(&self) -> RtdeStatus {
        self.status
    }
}

impl ForceSensorLink for RtdeSensor {
    fn start(&mut self) -> Result<(), LinkError> {
        if self.session.is_some() && self.streaming {
            return Ok(());
        }
        if self.session.is_none() {
            if self.last_attempt.elapsed() < RECONNECT_PERIOD {
                return Err(LinkError::NoPeer { protocol: P });
            }
            self.last_attempt = Instant::now();
            self.session = Some(Session::open(
                self.controller,
                Spec {
                    outputs: &SENSOR_OUTPUTS,
                    inputs: &[],
                    needs_path_offset: false,
                },
                SETUP_TIMEOUT,
            )?);
            self.last_time_s = None;
        } else if let Some(s) = self.session.as_mut() {
            let n = encode_empty(&mut s.tx, PackageType::Start)?;
            s.stream.write_all(&s.tx[..n])?;
        }
        self.streaming = true;
        Ok(())
    }

    fn bias(&mut self) -> Result<(), LinkError> {
        self.take_bias = true;
        Ok(())
    }

    fn receive(&mut self, timeout: Duration) -> Result<Option<WrenchSample>, LinkError> {
        let Some(session) = self.session.as_mut() else {
            std::thread::sleep(timeout.min(RECONNECT_PERIOD));
            return Ok(None);
        };
        match session.next_data(timeout, &mut self.status) {
            Ok(Data::Fresh) => {}
            Ok(Data::Timeout) => return Ok(None),
            Err(e) if e.is_bad_packet() && !matches!(e, LinkError::Oversize { .. }) => {
                return Err(e);
            }
            Err(e) => {
                self.session = None;
                self.last_attempt = Instant::now();
                return Err(e);
            }
        }
        let (Some(t), Some(w)) = (session.values[0].as_f64(), session.values[1].as_v6()) else {
            return Err(super::bad("sensor recipe values of other types"));
        };
        let period = session.period_s;
        let gap = match self.last_time_s {
            Some(last) if t > last => {
                (((t - last) / period).round() as i64 - 1).clamp(0, i64::from(u32::MAX)) as u32
            }
            _ => 0,
        };
        if gap > 0 {
            self.status.gaps += 1;
        }
        self.last_time_s = Some(t);
        let raw = Wrench::from(w);
        if self.take_bias {
            self.bias = raw;
            self.take_bias = false;
        }
        self.sequence = self.sequence.wrapping_add(1);
        Ok(Some(WrenchSample {
            wrench: raw - self.bias,
            sequence: self.sequence,
            status: 0,
            gap,
        }))
    }

    fn stop(&mut self) -> Result<(), LinkError> {
        if let Some(s) = self.session.as_mut() {
            s.pause();
        }
        self.streaming = false;
        Ok(())
    }
}
