//! The controller side of RTDE, as the digital twin plays a Universal Robots controller
//! (SIMULATED): [`RtdeServer`] serves several RTDE clients at once (deflex's robot link, its
//! flange-sensor link, any independent client such as SDU's `ur_rtde`), with protocol version
//! 2, the controller version, output and input recipes (`NOT_FOUND` for unknown names, `IN_USE`
//! for input registers another client holds), start, pause and text messages.
//! [`RtdeRobotEndpoint`] adds what the URScript program `docs/ur/deflex_rtde.script` does in
//! the controller: read the correction registers every 2 ms and apply them through
//! `path_offset_set` with the controller's alpha filter and maximum offset, ramping the offset
//! out when the sequence register stops advancing ([`PathOffsetModel`]).
//!
//! The server never blocks on a client: it accepts and reads without waiting (one bounded wait
//! on the client holding the correction registers), a client whose framing breaks, that sends
//! a package beyond [`super::MAX_PACKAGE`] or cannot take its data is closed and counted, and at
//! most [`MAX_CLIENTS`] are served.

use super::client::{Next, PackageBuf, read_once};
use super::{
    FieldType, HEADER_LEN, MAX_FIELDS, MAX_PACKAGE, PROTOCOL_VERSION, PackageType, REGISTER_COUNT,
    Recipe, Value, Variable, decode_data, decode_protocol_request, decode_setup_outputs,
    encode_data, encode_package, encode_text_message, for_each_name,
};
use crate::error::LinkError;
use crate::link::{Correction, ReceivedCorrection, RobotSideLink, RobotState};
use deflex_model::Wrench;
use deflex_model::conventions::rotation_vector;
use std::io::{ErrorKind, Write};
use std::net::{SocketAddr, TcpListener, TcpStream, ToSocketAddrs};
use std::time::{Duration, Instant};

/// Most clients served at once (a real controller serves a handful).
pub const MAX_CLIENTS: usize = 8;
/// The controller version the twin reports (an e-Series on PolyScope 5.16).
pub const TWIN_CONTROLLER_VERSION: [u32; 4] = [5, 16, 0, 0];
/// The controller's cycle (s): 500 Hz.
pub const CONTROLLER_PERIOD_S: f64 = 0.002;

/// What the server has done, for tests and the twin's summary.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub struct RtdeServerCounters {
    /// Clients accepted.
    pub clients: u64,
    /// Clients refused because [`MAX_CLIENTS`] were served.
    pub refused_full: u64,
    /// Clients closed: broken framing, oversized package, too slow to take their data.
    pub closed_bad: u64,
    /// Bad packages answered with a text message (other recipe id, size, non-finite, unknown
    /// type) on connections that stay.
    pub bad_packages: u64,
    /// Recipe set-ups refused with `IN_USE`.
    pub in_use: u64,
    /// Recipe set-ups refused with `NOT_FOUND`.
    pub not_found: u64,
    /// Input data packages applied to the registers.
    pub input_packages: u64,
    /// Output data packages sent.
    pub output_packages: u64,
}

/// The output values the controller streams.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct OutputValues {
    /// `timestamp` (s).
    pub timestamp: f64,
    /// `actual_q` (rad).
    pub q: [f64; 6],
    /// `actual_TCP_pose` (m, rotation vector rad).
    pub tcp_pose: [f64; 6],
    /// `actual_TCP_force` (N, N·m).
    pub tcp_force: [f64; 6],
    /// `ft_raw_wrench` (N, N·m).
    pub ft_raw_wrench: [f64; 6],
    /// `robot_mode`.
    pub robot_mode: i32,
    /// `safety_status`.
    pub safety_status: i32,
    /// `runtime_state`.
    pub runtime_state: u32,
    /// `output_int_register_N`.
    pub output_int: [i32; REGISTER_COUNT],
    /// `output_double_register_N`.
    pub output_double: [f64; REGISTER_COUNT],
}

impl Default for OutputValues {
    fn default() -> Self {
        OutputValues {
            timestamp: 0.0,
            q: [0.0; 6],
            tcp_pose: [0.0; 6],
            tcp_force: [0.0; 6],
            ft_raw_wrench: [0.0; 6],
            robot_mode: 7,
            safety_status: 1,
            runtime_state: 2,
            output_int: [0; REGISTER_COUNT],
            output_double: [0.0; REGISTER_COUNT],
        }
    }
}

impl OutputValues {
    fn value(&self, v: Variable) -> Value {
        match v {
            Variable::Timestamp => Value::F64(self.timestamp),
            Variable::ActualQ => Value::V6(self.q),
            Variable::ActualTcpPose => Value::V6(self.tcp_pose),
            Variable::ActualTcpForce => Value::V6(self.tcp_force),
            Variable::FtRawWrench => Value::V6(self.ft_raw_wrench),
            Variable::RobotMode => Value::I32(self.robot_mode),
            Variable::SafetyStatus => Value::I32(self.safety_status),
            Variable::RuntimeState => Value::U32(self.runtime_state),
            Variable::OutputIntRegister(n) => Value::I32(self.output_int[usize::from(n)]),
            Variable::OutputDoubleRegister(n) => Value::F64(self.output_double[usize::from(n)]),
            Variable::InputDoubleRegister(_) | Variable::InputIntRegister(_) => Value::I32(0),
        }
    }
}

#[derive(Debug)]
struct Client {
    id: u64,
    stream: TcpStream,
    rx: PackageBuf,
    read_mode: Option<Option<Duration>>,
    outputs: Vec<(Recipe, u64)>,
    input: Option<Recipe>,
    next_recipe: u8,
    started: bool,
    closed: bool,
}

/// An RTDE controller (see the module documentation).
#[derive(Debug)]
pub struct RtdeServer {
    listener: TcpListener,
    clients: Vec<Client>,
    version: [u32; 4],
    /// What the next data packages carry.
    pub outputs: OutputValues,
    input_double: [f64; REGISTER_COUNT],
    input_int: [i32; REGISTER_COUNT],
    owner_double: [Option<u64>; REGISTER_COUNT],
    owner_int: [Option<u64>; REGISTER_COUNT],
    counters: RtdeServerCounters,
    next_id: u64,
    cycle: u64,
    tx: Vec<u8>,
    recording: Option<Vec<OutputValues>>,
}

impl RtdeServer {
    /// Listens on `local` (`127.0.0.1:30004` in the twin, `127.0.0.1:0` in tests).
    pub fn bind(local: impl ToSocketAddrs) -> Result<Self, LinkError> {
        let listener = TcpListener::bind(local)?;
        listener.set_nonblocking(true)?;
        Ok(RtdeServer {
            listener,
            clients: Vec::with_capacity(MAX_CLIENTS),
            version: TWIN_CONTROLLER_VERSION,
            outputs: OutputValues::default(),
            input_double: [0.0; REGISTER_COUNT],
            input_int: [0; REGISTER_COUNT],
            owner_double: [None; REGISTER_COUNT],
            owner_int: [None; REGISTER_COUNT],
            counters: RtdeServerCounters::default(),
            next_id: 1,
            cycle: 0,
            tx: vec![0; MAX_PACKAGE],
            recording: None,
        })
    }

    /// Local address.
    pub fn local_addr(&self) -> Result<SocketAddr, LinkError> {
        Ok(self.listener.local_addr()?)
    }

    /// The controller version reported (tests play a CB3 or an old e-Series with it).
    pub fn set_controller_version(&mut self, version: [u32; 4]) {
        self.version = version;
    }

    /// The counters.
    pub fn counters(&self) -> RtdeServerCounters {
        self.counters
    }

    /// Clients connected.
    pub fn client_count(&self) -> usize {
        self.clients.len()
    }

    /// `input_double_register_N`.
    pub fn input_double(&self, n: u8) -> f64 {
        self.input_double[usize::from(n) % REGISTER_COUNT]
    }

    /// `input_int_register_N`.
    pub fn input_int(&self, n: u8) -> i32 {
        self.input_int[usize::from(n) % REGISTER_COUNT]
    }

    /// True if a started client streams `v`.
    pub fn streams(&self, v: Variable) -> bool {
        self.clients
            .iter()
            .any(|c| c.started && c.outputs.iter().any(|(r, _)| r.position(v).is_some()))
    }

    /// Keep every set of output values published (`true`), for a test comparing them with what
    /// a client read; [`RtdeServer::take_recorded`] hands them out.
    pub fn set_recording(&mut self, on: bool) {
        self.recording = on.then(Vec::new);
    }

    /// The output values published since recording started.
    pub fn take_recorded(&mut self) -> Vec<OutputValues> {
        self.recording
            .as_mut()
            .map(std::mem::take)
            .unwrap_or_default()
    }

    /// Accepts pending clients and handles everything they sent, without waiting; returns the
    /// input data packages applied.
    pub fn poll(&mut self) -> u64 {
        self.accept();
        let before = self.counters.input_packages;
        for i in 0..self.clients.len() {
            self.serve_client(i, Duration::ZERO);
        }
        self.drop_closed();
        self.counters.input_packages - before
    }

    /// [`RtdeServer::poll`], and when no input arrived, waits up to `timeout` for the client
    /// holding `register` (its input recipe) to send one.
    pub fn poll_wait(&mut self, timeout: Duration, register: u8) -> u64 {
        let n = self.poll();
        if n > 0 || timeout.is_zero() {
            return n;
        }
        let owner = self.owner_int[usize::from(register) % REGISTER_COUNT];
        let Some(i) = owner.and_then(|id| self.clients.iter().position(|c| c.id == id)) else {
            std::thread::sleep(timeout.min(Duration::from_millis(1)));
            return self.poll();
        };
        let before = self.counters.input_packages;
        self.serve_client(i, timeout);
        self.drop_closed();
        self.counters.input_packages - before
    }

    fn accept(&mut self) {
        loop {
            match self.listener.accept() {
                Ok((stream, _from)) => {
                    if self.clients.len() >= MAX_CLIENTS {
                        self.counters.refused_full += 1;
                        continue;
                    }
                    if stream.set_nodelay(true).is_err() || stream.set_nonblocking(true).is_err() {
                        continue;
                    }
                    let _ = stream.set_write_timeout(Some(Duration::from_millis(20)));
                    self.counters.clients += 1;
                    self.clients.push(Client {
                        id: self.next_id,
                        stream,
                        rx: PackageBuf::new(),
                        read_mode: Some(None),
                        outputs: Vec::new(),
                        input: None,
                        next_recipe: 1,
                        started: false,
                        closed: false,
                    });
                    self.next_id += 1;
                }
                Err(_) => return,
            }
        }
    }

    fn drop_closed(&mut self) {
        let mut i = 0;
        while i < self.clients.len() {
            if self.clients[i].closed {
                let id = self.clients[i].id;
                for o in self
                    .owner_double
                    .iter_mut()
                    .chain(self.owner_int.iter_mut())
                {
                    if *o == Some(id) {
                        *o = None;
                    }
                }
                self.clients.swap_remove(i);
            } else {
                i += 1;
            }
        }
    }

    /// Reads what client `i` sent (the first read waiting up to `wait`) and answers it.
    fn serve_client(&mut self, i: usize, wait: Duration) {
        let mut wait = wait;
        loop {
            let next = self.clients[i].rx.next_package();
            match next {
                Ok(Next::Package(t, size)) => {
                    let mut package = [0u8; MAX_PACKAGE];
                    package[..size].copy_from_slice(self.clients[i].rx.package(size));
                    self.clients[i].rx.consume(size);
                    if let Err(e) = self.handle(i, t, &package[HEADER_LEN..size]) {
                        self.counters.bad_packages += 1;
                        self.say(i, &e.to_string());
                    }
                    wait = Duration::ZERO;
                }
                Ok(Next::UnknownType(_)) => {
                    self.counters.bad_packages += 1;
                    self.say(i, "unknown package type");
                }
                Ok(Next::Incomplete) => {
                    let c = &mut self.clients[i];
                    match read_once(&mut c.stream, &mut c.rx, wait, &mut c.read_mode) {
                        Ok(true) => wait = Duration::ZERO,
                        Ok(false) => return,
                        Err(_) => {
                            c.closed = true;
                            return;
                        }
                    }
                }
                Err(_) => {
                    // A size the stream cannot carry: the framing is lost.
                    self.counters.closed_bad += 1;
                    self.clients[i].closed = true;
                    return;
                }
            }
            if self.clients[i].closed {
                return;
            }
        }
    }

    /// Sends a warning text message to client `i`.
    fn say(&mut self, i: usize, text: &str) {
        if let Ok(n) = encode_text_message(&mut self.tx, text.as_bytes(), b"RTDE", 2) {
            let tx = std::mem::take(&mut self.tx);
            self.write(i, &tx[..n]);
            self.tx = tx;
        }
    }

    fn write(&mut self, i: usize, data: &[u8]) {
        let c = &mut self.clients[i];
        if c.closed {
            return;
        }
        if c.read_mode == Some(None) {
            // Non-blocking: a partial write would break the framing; write whole or close.
            let _ = c.stream.set_nonblocking(false);
            c.read_mode = None;
        }
        if let Err(e) = c.stream.write_all(data) {
            c.closed = true;
            // A client that went away is no bad client; one that does not take its data is.
            if matches!(e.kind(), ErrorKind::WouldBlock | ErrorKind::TimedOut) {
                self.counters.closed_bad += 1;
            }
        }
    }

    fn reply(
        &mut self,
        i: usize,
        t: PackageType,
        payload: impl FnOnce(&mut super::Writer<'_>) -> Result<(), LinkError>,
    ) -> Result<(), LinkError> {
        let mut tx = std::mem::take(&mut self.tx);
        let r = encode_package(&mut tx, t, payload);
        if let Ok(n) = r {
            self.write(i, &tx[..n]);
        }
        self.tx = tx;
        r.map(|_| ())
    }

    fn handle(&mut self, i: usize, t: PackageType, payload: &[u8]) -> Result<(), LinkError> {
        match t {
            PackageType::RequestProtocolVersion => {
                let v = decode_protocol_request(payload)?;
                let ok = v == PROTOCOL_VERSION;
                self.reply(i, t, |w| w.u8(u8::from(ok)))
            }
            PackageType::GetUrControlVersion => {
                let v = self.version;
                self.reply(i, t, |w| {
                    v.iter().try_for_each(|x| w.bytes(&x.to_be_bytes()))
                })
            }
            PackageType::SetupOutputs => {
                let (frequency, names) = decode_setup_outputs(payload)?;
                self.setup(i, t, names, Some(frequency))
            }
            PackageType::SetupInputs => self.setup(i, t, payload, None),
            PackageType::Start => {
                let c = &mut self.clients[i];
                let ok = !c.outputs.is_empty() || c.input.is_some();
                c.started = ok;
                self.reply(i, t, |w| w.u8(u8::from(ok)))
            }
            PackageType::Pause => {
                self.clients[i].started = false;
                self.reply(i, t, |w| w.u8(1))
            }
            PackageType::DataPackage => self.apply_inputs(i, payload),
            PackageType::TextMessage => Err(super::bad("a client sends no text messages")),
        }
    }

    /// Answers a recipe set-up: the types, `NOT_FOUND` or `IN_USE` per name.
    fn setup(
        &mut self,
        i: usize,
        t: PackageType,
        names: &[u8],
        frequency: Option<f64>,
    ) -> Result<(), LinkError> {
        let id = self.clients[i].id;
        let inputs = frequency.is_none();
        let mut vars = [Variable::Timestamp; MAX_FIELDS];
        let mut answers: [Result<FieldType, &'static str>; MAX_FIELDS] = [Err(""); MAX_FIELDS];
        let n = for_each_name(names, |k, v| {
            answers[k] = match v {
                Some(v) if v.is_input() == inputs => {
                    vars[k] = v;
                    let owner = match v {
                        Variable::InputDoubleRegister(r) => self.owner_double[usize::from(r)],
                        Variable::InputIntRegister(r) => self.owner_int[usize::from(r)],
                        _ => None,
                    };
                    if owner.is_some_and(|o| o != id) {
                        Err("IN_USE")
                    } else {
                        Ok(v.field_type())
                    }
                }
                _ => Err("NOT_FOUND"),
            };
            Ok(())
        })?;
        let all_ok = answers[..n].iter().all(|a| a.is_ok());
        for a in &answers[..n] {
            match a {
                Err("IN_USE") => self.counters.in_use += 1,
                Err(_) => self.counters.not_found += 1,
                Ok(_) => {}
            }
        }
        let c = &mut self.clients[i];
        let recipe_id = if all_ok { c.next_recipe } else { 0 };
        if all_ok {
            let recipe = Recipe::new(recipe_id, &vars[..n])?;
            c.next_recipe = c.next_recipe.saturating_add(1);
            match frequency {
                Some(f) => {
                    let every = (1.0 / (f * CONTROLLER_PERIOD_S)).round().max(1.0) as u64;
                    c.outputs.push((recipe, every));
                }
                None => {
                    c.input = Some(recipe);
                    for v in recipe.variables() {
                        match *v {
                            Variable::InputDoubleRegister(r) => {
                                self.owner_double[usize::from(r)] = Some(id);
                            }
                            Variable::InputIntRegister(r) => {
                                self.owner_int[usize::from(r)] = Some(id);
                            }
                            _ => {}
                        }
                    }
                }
            }
        }
        self.reply(i, t, |w| {
            w.u8(recipe_id)?;
            for (k, a) in answers[..n].iter().enumerate() {
                if k > 0 {
                    w.u8(b',')?;
                }
                match a {
                    Ok(ft) => w.bytes(ft.name().as_bytes())?,
                    Err(e) => w.bytes(e.as_bytes())?,
                }
            }
            Ok(())
        })
    }

    fn apply_inputs(&mut self, i: usize, payload: &[u8]) -> Result<(), LinkError> {
        let recipe = self.clients[i]
            .input
            .ok_or(super::bad("input data before an input recipe"))?;
        let mut values = [Value::default(); MAX_FIELDS];
        decode_data(payload, &recipe, &mut values)?;
        for (v, x) in recipe.variables().iter().zip(values) {
            match (*v, x) {
                (Variable::InputDoubleRegister(r), Value::F64(d)) => {
                    self.input_double[usize::from(r)] = d;
                }
                (Variable::InputIntRegister(r), Value::I32(n)) => {
                    self.input_int[usize::from(r)] = n;
                }
                _ => {}
            }
        }
        self.counters.input_packages += 1;
        Ok(())
    }

    /// One controller cycle: sends every started client the data packages of its output
    /// recipes due this cycle (a recipe at 125 Hz every fourth cycle).
    pub fn publish(&mut self) {
        self.cycle += 1;
        if let Some(r) = self.recording.as_mut() {
            r.push(self.outputs);
        }
        let mut tx = std::mem::take(&mut self.tx);
        for i in 0..self.clients.len() {
            if !self.clients[i].started {
                continue;
            }
            for k in 0..self.clients[i].outputs.len() {
                let (recipe, every) = self.clients[i].outputs[k];
                if !self.cycle.is_multiple_of(every) {
                    continue;
                }
                let mut values = [Value::default(); MAX_FIELDS];
                for (slot, v) in values.iter_mut().zip(recipe.variables()) {
                    *slot = self.outputs.value(*v);
                }
                if let Ok(n) = encode_data(&mut tx, &recipe, &values[..recipe.variables().len()]) {
                    self.write(i, &tx[..n]);
                    self.counters.output_packages += 1;
                }
            }
        }
        self.tx = tx;
        self.drop_closed();
    }
}

/// What the URScript program does with the correction registers every controller cycle:
/// the sequence register must advance (else, after `watchdog_cycles`, the target is zero: the
/// ramp-out), the target is limited like `path_offset_set_max_offset` (translation and rotation
/// norms) and filtered like `path_offset_set_alpha_filter`:
/// `applied = alpha · target + (1 − alpha) · applied`.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct PathOffsetModel {
    /// The alpha filter's coefficient (0 < alpha ≤ 1; 1 = no filter).
    pub alpha: f64,
    /// Largest translation offset (m).
    pub max_offset_m: f64,
    /// Largest rotation offset (rad).
    pub max_offset_rad: f64,
    /// Cycles without a new sequence number before the target drops to zero.
    pub watchdog_cycles: u32,
    applied: [f64; 6],
    last_sequence: i32,
    stale: u32,
}

impl PathOffsetModel {
    /// A model at rest (no offset applied).
    pub fn new(alpha: f64, max_offset_m: f64, max_offset_rad: f64, watchdog_cycles: u32) -> Self {
        PathOffsetModel {
            alpha: alpha.clamp(1e-6, 1.0),
            max_offset_m,
            max_offset_rad,
            watchdog_cycles,
            applied: [0.0; 6],
            last_sequence: 0,
            stale: 0,
        }
    }

    /// The offset applied now.
    pub fn applied(&self) -> [f64; 6] {
        self.applied
    }

    /// One controller cycle with the registers `target` and the sequence register `sequence`;
    /// returns the offset applied.
    pub fn step(&mut self, target: [f64; 6], sequence: i32) -> [f64; 6] {
        if sequence == self.last_sequence {
            self.stale = self.stale.saturating_add(1);
        } else {
            self.stale = 0;
            self.last_sequence = sequence;
        }
        let mut t = if self.stale > self.watchdog_cycles || !target.iter().all(|v| v.is_finite()) {
            [0.0; 6]
        } else {
            target
        };
        for (range, limit) in [(0..3, self.max_offset_m), (3..6, self.max_offset_rad)] {
            let norm = t[range.clone()].iter().map(|v| v * v).sum::<f64>().sqrt();
            if norm > limit && norm > 0.0 {
                let k = limit / norm;
                t[range].iter_mut().for_each(|v| *v *= k);
            }
        }
        for (a, t) in self.applied.iter_mut().zip(t) {
            *a = self.alpha * t + (1.0 - self.alpha) * *a;
        }
        self.applied
    }
}

/// The robot side of RTDE for the twin: an [`RtdeServer`] streaming the robot's state and the
/// flange sensor's wrench, and the URScript program's [`PathOffsetModel`] applying the
/// correction registers.
#[derive(Debug)]
pub struct RtdeRobotEndpoint {
    server: RtdeServer,
    register: u8,
    model: PathOffsetModel,
    heartbeat: i32,
    previous_rotation: Option<[f64; 3]>,
    applied_inputs: u64,
}

impl RtdeRobotEndpoint {
    /// Serves on `local` with the correction at `register` (24–42) applied by `model`.
    pub fn bind(
        local: impl ToSocketAddrs,
        register: u8,
        model: PathOffsetModel,
    ) -> Result<Self, LinkError> {
        if !(24..=42).contains(&register) {
            return Err(LinkError::InvalidValue {
                protocol: super::P,
                reason: "robot.rtde_register must lie in 24..=42",
            });
        }
        Ok(RtdeRobotEndpoint {
            server: RtdeServer::bind(local)?,
            register,
            model,
            heartbeat: 0,
            previous_rotation: None,
            applied_inputs: 0,
        })
    }

    /// The server.
    pub fn server(&mut self) -> &mut RtdeServer {
        &mut self.server
    }

    /// The flange sensor's raw wrench of this cycle (sensor axes, N and N·m), streamed as
    /// `ft_raw_wrench` with the next state.
    pub fn set_flange_wrench(&mut self, w: &Wrench) {
        self.server.outputs.ft_raw_wrench = (*w).into();
    }

    /// True while a client streams `ft_raw_wrench`.
    pub fn flange_sensor_streaming(&self) -> bool {
        self.server.streams(Variable::FtRawWrench)
    }

    /// The path-offset model.
    pub fn path_offset(&self) -> &PathOffsetModel {
        &self.model
    }

    /// A controller cycle in which no correction arrived: the URScript program still runs its
    /// cycle on the registers as they stand (the sequence not advancing, so after the watchdog
    /// the offset ramps out). `None` until a client has written the registers once.
    pub fn unanswered_cycle(&mut self) -> Option<Correction> {
        if self.applied_inputs == 0 {
            return None;
        }
        let r = self.register;
        let target = std::array::from_fn(|k| self.server.input_double(r + k as u8));
        let applied = self.model.step(target, self.server.input_int(r));
        Some(Correction::from_array(applied))
    }
}

impl RobotSideLink for RtdeRobotEndpoint {
    /// The robot's state of this cycle: controller time (2 ms per cycle), joints, TCP pose
    /// (rotation vector continuous along the path), the program running (robot mode 7, normal
    /// safety, runtime playing) and its heartbeat in `output_int_register_N`.
    fn send_state(&mut self, s: &RobotState) -> Result<(), LinkError> {
        let o = &mut self.server.outputs;
        o.timestamp += CONTROLLER_PERIOD_S;
        let q = s.joints();
        o.q = [0.0; 6];
        let n = q.len().min(6);
        o.q[..n].copy_from_slice(&q[..n]);
        if let Some(p) = s.tcp_pose {
            let r = rotation_vector(&p.rotation, self.previous_rotation);
            self.previous_rotation = Some(r);
            let t = p.translation.vector;
            o.tcp_pose = [t.x, t.y, t.z, r[0], r[1], r[2]];
        }
        self.heartbeat = self.heartbeat.wrapping_add(1);
        o.output_int[usize::from(self.register)] = self.heartbeat;
        self.server.poll();
        self.server.publish();
        Ok(())
    }

    /// Waits up to `timeout` for the client's next correction registers, then runs one cycle of
    /// the URScript program on them; the cycle id is the sequence register.
    fn receive_correction(
        &mut self,
        timeout: Duration,
    ) -> Result<Option<ReceivedCorrection>, LinkError> {
        let deadline = Instant::now() + timeout;
        loop {
            let total = self.server.counters().input_packages;
            if total > self.applied_inputs {
                self.applied_inputs = total;
                let r = self.register;
                let target = std::array::from_fn(|k| self.server.input_double(r + k as u8));
                let sequence = self.server.input_int(r);
                let applied = self.model.step(target, sequence);
                return Ok(Some(ReceivedCorrection {
                    correction: Correction::from_array(applied),
                    cycle_id: u64::from(sequence as u32),
                    joint_correction_rad: None,
                }));
            }
            let left = deadline.saturating_duration_since(Instant::now());
            if left.is_zero() {
                return Ok(None);
            }
            self.server.poll_wait(left, self.register);
        }
    }
}
