//! `deflex cell --sim`: the digital twin served on loopback over the protocols of a real cell
//! (SIMULATED). It plays the robot of `robot.kind` (a KUKA sending RSI telegrams, an ABB
//! streaming EGM, the Stäubli VAL3 program, a UR script on the simple UDP/TCP line links, a
//! FANUC controller following the joints deflex streams over Stream Motion) at the
//! twin's robot cycle and the ATI Net F/T streaming its readings while the twin forms the path,
//! so `deflex run` can be tried end to end with no hardware. Its ends ([`CellSides`]) come from
//! the same `CELL.toml` as `deflex run`'s (`deflex-app` builds both), and each protocol's robot
//! side is the protocol crate's own ([`deflex_io::robot_side`]), so both sides agree on the
//! protocol by construction. With Stream Motion the robot has no program of its own to run:
//! its drives take the last command each cycle, from its first (no dwell: deflex's approach and
//! ramp move it), its desired point is the path's closest to the true tool
//! ([`crate::controller_emulation`]), and the session ends at deflex's stop packet, or after
//! 2 s without a command (the robot's watchdog). The twin
//! plays any robot (`crate::CellConfig::for_robot`: part position, force level, controller
//! rate, sensor) and names it in every output.

use crate::twin::twin_stream::TwinCellStream;
use crate::{Cell, CellConfig, ToolPath};
use deflex_io::netft::{NetFtCalibration, NetFtSensorServer};
use deflex_io::{LinkError, RobotEndpoint, RobotKind, RobotSide, RobotState};
use deflex_model::{Data, Robot, Wrench};
use deflex_runtime::stats::{CycleStats, StatsSummary};
use deflex_telemetry::CellState;
use nalgebra::{Rotation3, Vector3};
use std::net::SocketAddr;
use std::sync::atomic::{AtomicBool, Ordering};
use std::time::{Duration, Instant};

/// How the twin is served.
#[derive(Clone, Debug)]
pub struct ServeOptions {
    /// The twin's cell (the robot it plays, its part, sensor, rates).
    pub twin: CellConfig,
    /// The tool path the robot's program runs.
    pub path: ToolPath,
    /// Random seed of the twin.
    pub seed: u64,
    /// Time scale: cycles run this many times faster than the robot's cycle in wall time.
    pub speed: f64,
    /// How long to wait for the controller's first answer (s).
    pub wait_s: f64,
    /// Dwell at the start pose, out of contact, once the controller answers and the sensor
    /// streams, before the path starts (s of robot time): the controller tares its sensor there.
    pub dwell_s: f64,
    /// A fault for tests: the TCP pose the robot reports jumps during the path (`None` in a
    /// normal run).
    pub pose_jump: Option<PoseJump>,
}

/// The TCP pose the simulated robot reports (KUKA RSI `RIst`, ABB EGM feedback) shifted from
/// some time of the path on: what a controller whose tool or base was changed mid-session
/// reports, for the model check's fault ([`deflex_telemetry::FaultKind::ModelMismatch`]).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct PoseJump {
    /// Time of the path (s of robot time since the twin started stepping) from which on the
    /// pose is shifted.
    pub after_s: f64,
    /// The shift, robot base axes (m).
    pub offset_m: [f64; 3],
}

/// The ends of the served cell: the robot controller's and the sensor's, and the controller's
/// model (which must have the joints of the robot the twin plays).
#[derive(Clone, Debug)]
pub struct CellSides {
    /// Where the settings come from (the `CELL.toml`), for messages.
    pub origin: String,
    /// The robot side of `robot.kind`, sending to `robot.bind`.
    pub robot: RobotSide,
    /// Where the Net F/T server answers (`sensor.address`).
    pub sensor_address: SocketAddr,
    /// The Net F/T count scaling.
    pub sensor_calibration: NetFtCalibration,
    /// The sensor is the UR arm's own (`sensor.kind = "ur-rtde"`): its raw wrench streams as
    /// `ft_raw_wrench` from the robot's RTDE server, no Net F/T is served.
    pub sensor_over_rtde: bool,
    /// The controller's robot model (`model.file`).
    pub model: Robot,
}

/// Why the twin could not be served.
#[derive(Debug, thiserror::Error)]
pub enum CellServeError {
    /// An address of the CELL.toml is not a loopback address.
    #[error("{origin}: {field} = {address}: the simulated cell only uses loopback addresses")]
    NotLoopback {
        /// The CELL.toml.
        origin: String,
        /// `robot.bind` or `sensor.address`.
        field: &'static str,
        /// The address.
        address: SocketAddr,
    },
    /// The CELL.toml's model has another number of joints than the robot the twin plays.
    #[error(
        "{origin}: model.file: {model} has {model_joints} joints, the robot the twin plays ({played}) has {played_joints}"
    )]
    JointCountMismatch {
        /// The CELL.toml.
        origin: String,
        /// The model's name.
        model: String,
        /// Its joints.
        model_joints: usize,
        /// The robot the twin plays.
        played: String,
        /// Its joints.
        played_joints: usize,
    },
    /// A FANUC Stream Motion cell whose `robot.cycle_s` is not the cycle of the robot the twin
    /// plays: deflex would stream one cycle's path per status at another pace.
    #[error(
        "{origin}: robot.cycle_s = {cycle_s} s, but the FANUC controller the twin plays runs every \
         {twin_cycle_s} s (its cell's controller.rate_hz; give --twin a [cell.controller] rate_hz \
         of 1/cycle_s)"
    )]
    StreamCycleMismatch {
        /// The CELL.toml.
        origin: String,
        /// `robot.cycle_s`.
        cycle_s: f64,
        /// The twin's robot cycle (s).
        twin_cycle_s: f64,
    },
    /// The twin refuses its settings or the path.
    #[error(transparent)]
    Twin(#[from] crate::SimError),
    /// The Net F/T server cannot be bound.
    #[error("sensor.address {address}: {error}")]
    Sensor {
        /// `sensor.address`.
        address: SocketAddr,
        /// Why.
        error: LinkError,
    },
    /// The robot's endpoint cannot be opened (or, for simple TCP, connect).
    #[error("simulated {} robot towards {bind}: {error}", kind.name())]
    RobotEndpoint {
        /// `robot.kind`.
        kind: RobotKind,
        /// `robot.bind`.
        bind: SocketAddr,
        /// Why.
        error: LinkError,
    },
    /// No controller answered within the wait.
    #[error("no answer from a controller on {bind} within {wait_s} s")]
    NoAnswer {
        /// `robot.bind`.
        bind: SocketAddr,
        /// The wait (s).
        wait_s: f64,
    },
}

/// How the served session ended.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum CellEnd {
    /// The simulated robot program reached the end of its path.
    ProgramFinished,
    /// Stopped by a signal before the end.
    Stopped,
}

/// What the served twin did.
pub struct CellOutcome {
    /// The robot the twin played (its description's name).
    pub robot: String,
    /// How it was given (`--robot`, the twin file's, or `tx200`).
    pub robot_spec: String,
    /// The CELL.toml model has the geometry (fingerprint) of the robot the twin played.
    pub model_geometry_matches: bool,
    /// The twin's ground-truth statistics.
    pub summary: crate::forming::RunningStats,
    /// Robot-side round trip (state sent → answer received).
    pub round_trip: StatsSummary,
    /// Robot cycles served.
    pub cycles: u64,
    /// Robot cycles whose answer did not arrive within the cycle, judged when the next cycle
    /// starts — KUKA's own definition of a late answer (`Delay`), which the simulated KUKA
    /// sends in its telegrams, so `deflex run` reports the same number.
    pub late: u64,
    /// Simulated time (s).
    pub duration_s: f64,
    /// How it ended.
    pub end: CellEnd,
    /// The twin's ground-truth log (the `deflex sim isf` `log.csv` format:
    /// [`crate::FormingLog::to_csv`]).
    pub log: crate::FormingLog,
}

/// What the served twin reports while it runs.
#[derive(Clone, Debug, PartialEq)]
pub enum CellEvent {
    /// Serving starts: the robot the twin plays, its cycle, and a warning when the CELL.toml
    /// model is not its geometry (empty otherwise; [`geometry_note`]).
    Playing {
        /// The robot's name.
        robot: String,
        /// How it was given.
        robot_spec: String,
        /// Its interpolation cycle (s).
        robot_cycle_s: f64,
        /// The geometry warning, or empty.
        geometry_note: String,
    },
    /// Every two seconds of wall time.
    Progress {
        /// Forming (else waiting for the controller, then dwelling).
        forming: bool,
        /// Simulated time (s).
        time_s: f64,
        /// The path's duration (s).
        path_s: f64,
        /// Robot cycles served.
        cycles: u64,
        /// Of which late.
        late: u64,
        /// The true contact force norm (N).
        force_n: f64,
        /// The correction the robot applies, position norm (m).
        correction_m: f64,
        /// The largest path error so far (m).
        max_error_m: f64,
    },
}

/// Empty when the CELL.toml model has the geometry of the robot the twin plays (with the cell's
/// tool); else a warning saying whether only the tool differs.
pub fn geometry_note(model: &Robot, nominal: &Robot) -> String {
    if model.geometry_fingerprint() == nominal.geometry_fingerprint() {
        return String::new();
    }
    let mut with_cell_tool = model.clone();
    with_cell_tool.tool = nominal.tool;
    if with_cell_tool.geometry_fingerprint() == nominal.geometry_fingerprint() {
        let t = nominal.tool.translation.vector;
        format!(
            "; warning: the CELL.toml model ({}) has another tool than the cell's (flange → TCP \
             [{:.3}, {:.3}, {:.3}] m): the controller estimates the deflection at another point",
            model.name, t.x, t.y, t.z
        )
    } else {
        format!(
            "; warning: the CELL.toml model ({}, geometry {}) is not the geometry of the robot the \
             twin plays ({})",
            model.name,
            model.geometry_fingerprint(),
            nominal.geometry_fingerprint()
        )
    }
}

/// The robot controller's own kinematics, for what a real controller does itself: turn joint
/// corrections (RSI `AK`) into a Cartesian one and know its tool orientation (EGM's sensor
/// frame). The simulated controller uses the nominal geometry of the robot the twin plays, with
/// the cell's tool.
struct ControllerKinematics {
    robot: Robot,
    data: Data,
}

impl ControllerKinematics {
    fn at(&mut self, q: &[f64]) -> bool {
        self.robot.forward_kinematics(&mut self.data, q).is_ok()
    }

    /// TCP orientation in base axes.
    fn tcp_rotation(&self) -> Rotation3<f64> {
        self.robot.base.rotation.inverse() * self.data.tcp.rotation
    }

    /// J(q) Δq in base axes: the TCP motion of a joint correction.
    fn joint_to_cartesian(&self, dq: &[f64]) -> [f64; 6] {
        let tcp = self.data.tcp_position();
        let columns = self.robot.geometric_jacobian_columns(&self.data, &tcp);
        let mut v = nalgebra::Vector6::zeros();
        for (c, d) in columns.iter().zip(dq).take(self.robot.joint_count()) {
            v += c * *d;
        }
        let r_t = self.robot.base.rotation.inverse();
        let lin = r_t * Vector3::new(v[0], v[1], v[2]);
        let ang = r_t * Vector3::new(v[3], v[4], v[5]);
        [lin.x, lin.y, lin.z, ang.x, ang.y, ang.z]
    }
}

/// Checks the ends of the simulated cell: loopback addresses, a model with the joints of the
/// robot the twin plays. Returns the robot the twin plays.
fn check_sides(sides: &CellSides, twin: &CellConfig) -> Result<Robot, CellServeError> {
    let stream = sides.robot.stream.map(|s| ("robot.peer", s.address));
    for (field, address) in [
        ("robot.bind", sides.robot.controller),
        ("sensor.address", sides.sensor_address),
    ]
    .into_iter()
    .chain(stream)
    {
        if !address.ip().is_loopback() {
            return Err(CellServeError::NotLoopback {
                origin: sides.origin.clone(),
                field,
                address,
            });
        }
    }
    if let Some(stream) = sides.robot.stream
        && (stream.period_s - twin.robot_period_s()).abs() > 1e-9
    {
        return Err(CellServeError::StreamCycleMismatch {
            origin: sides.origin.clone(),
            cycle_s: stream.period_s,
            twin_cycle_s: twin.robot_period_s(),
        });
    }
    let model = &sides.model;
    let nominal = twin.nominal_robot()?;
    if model.joint_count() != nominal.joint_count() {
        return Err(CellServeError::JointCountMismatch {
            origin: sides.origin.clone(),
            model: model.name.clone(),
            model_joints: model.joint_count(),
            played: nominal.name.clone(),
            played_joints: nominal.joint_count(),
        });
    }
    Ok(nominal)
}

/// The served session's state between robot cycles.
struct Serving {
    cell: Cell,
    /// The Net F/T, unless the sensor streams over the robot's RTDE server.
    server: Option<NetFtSensorServer>,
    robot: RobotEndpoint,
    kinematics: ControllerKinematics,
    step: crate::CellStep,
    round_trip: CycleStats,
    ipoc: u64,
    cycles: u64,
    late: u64,
    /// The controller answers and the sensor streams: the program runs.
    serving: bool,
    /// Robot cycles still to hold the start pose once the controller answers and the sensor
    /// streams.
    dwell_cycles: u64,
    /// The controller answers and the sensor streams, the program has not started yet.
    dwelling: bool,
    /// The test's jump of the reported pose.
    pose_jump: Option<PoseJump>,
    /// The robot follows the joints deflex streams (FANUC Stream Motion).
    joint_stream: bool,
    /// Robot cycles in a row without a command while following a joint stream.
    silent: u64,
    /// After this many silent cycles the robot's own watchdog ends the stream (2 s).
    silent_limit: u64,
}

impl Serving {
    /// Steps the twin (once serving; before, it holds the start pose) and streams the cycle's
    /// F/T samples; returns how many it streamed and whether the twin stepped.
    fn step_twin(&mut self) -> (usize, bool) {
        if let Some(server) = self.server.as_mut() {
            while let Ok(Some(_)) = server.poll_request(Duration::ZERO) {}
        }
        let stepped = self.serving;
        if stepped {
            self.cell.step_into(&mut self.step);
        }
        let samples: &[crate::SensorSample] = if stepped {
            &self.step.sensor_samples
        } else {
            // Waiting for the controller, then dwelling: hold the start pose, keep streaming.
            match self.step.sensor_samples.last() {
                Some(last) => std::slice::from_ref(last),
                None => &[],
            }
        };
        match self.server.as_mut() {
            Some(server) => {
                for s in samples {
                    let _ = server.send_sample(&Wrench::from(s.wrench_sensor), 0);
                }
                (samples.len(), stepped)
            }
            None => {
                // The UR controller streams one reading per cycle: the cycle's last.
                let streamed = samples
                    .last()
                    .is_some_and(|s| self.robot.set_flange_wrench(&Wrench::from(s.wrench_sensor)));
                (usize::from(streamed), stepped)
            }
        }
    }

    /// The sensor streams to the controller (the Net F/T was started, or an RTDE client reads
    /// the flange wrench).
    fn sensor_streaming(&self) -> bool {
        match &self.server {
            Some(server) => server.streaming(),
            None => self.robot.flange_sensor_streaming(),
        }
    }

    /// The cell's state for its telemetry.
    fn state(&self) -> CellState {
        if self.serving {
            if self.step.finished {
                CellState::Finished
            } else {
                CellState::Forming
            }
        } else if self.dwelling {
            CellState::Dwelling
        } else {
            CellState::Waiting
        }
    }

    /// The TCP pose the robot reports this cycle: its controller's kinematics at the measured
    /// joints ([`crate::CellStep::tcp_reported`]), shifted by the test's jump once due.
    fn reported_pose(&self) -> deflex_model::Pose {
        let mut pose = self.step.tcp_reported;
        if let Some(jump) = self.pose_jump
            && self.serving
            && self.step.time_s >= jump.after_s
        {
            pose.translation.vector += Vector3::from(jump.offset_m);
        }
        pose
    }

    /// Sends the robot's state of this cycle; returns when it was sent and whether the robot
    /// controller's kinematics of it are known.
    fn send_state(&mut self) -> (Instant, bool) {
        self.ipoc += 4;
        let kinematics_ok = self.kinematics.at(&self.step.q_measured_rad);
        if kinematics_ok {
            self.robot.set_tcp_rotation(&self.kinematics.tcp_rotation());
        }
        let state = RobotState {
            cycle_id: self.ipoc,
            // A KUKA reports its count of late answers in every telegram.
            late_answers: Some(self.late.min(u64::from(u32::MAX)) as u32),
            // The controller's own TCP pose at the measured joints (sent by the protocols that
            // carry one: RSI `RIst`, EGM feedback), shifted by the test's jump once due.
            tcp_pose: Some(self.reported_pose()),
            ..RobotState::with_joints(&self.step.q_measured_rad)
        };
        let sent = Instant::now();
        let _ = self.robot.send_state(&state);
        (sent, kinematics_ok)
    }

    /// Waits until `until` for this cycle's answer and applies it; returns its round trip when
    /// it came.
    fn await_answer(
        &mut self,
        until: Instant,
        sent: Instant,
        kinematics_ok: bool,
    ) -> Option<Duration> {
        let echoes_cycle = self.robot.echoes_cycle();
        loop {
            let wait = until.saturating_duration_since(Instant::now());
            if wait.is_zero() {
                return None;
            }
            let expected = self.robot.expected_cycle_id(self.ipoc);
            match self.robot.receive(wait) {
                Ok(Some(r)) if r.cycle_id == expected || !echoes_cycle => {
                    let correction = match r.joint_correction_rad {
                        // A joint stream's command is the joints themselves (below).
                        _ if self.joint_stream => [0.0; 6],
                        Some(dq) if kinematics_ok => self.kinematics.joint_to_cartesian(&dq),
                        Some(_) => [0.0; 6],
                        None => r.correction.to_array(),
                    };
                    let round_trip = sent.elapsed();
                    if self.serving {
                        self.round_trip.record(round_trip);
                    }
                    if !self.serving && self.sensor_streaming() {
                        if self.dwell_cycles == 0 {
                            self.serving = true;
                            self.dwelling = false;
                        } else {
                            self.dwelling = true;
                            self.dwell_cycles -= 1;
                        }
                    }
                    if self.joint_stream {
                        if let Some(q) = self.robot.joint_command() {
                            self.cell.set_joint_command(q);
                        }
                    } else {
                        self.cell.set_correction(correction);
                    }
                    return Some(round_trip);
                }
                Ok(Some(_)) | Err(_) => continue,
                Ok(None) => {}
            }
        }
    }

    /// Counts the cycle; a missing answer is late, as the robot counts it (and reports it in its
    /// next telegram; the program's last telegram has no next).
    fn account(&mut self, answered: bool) {
        if self.joint_stream && self.serving {
            // The stream's end (the device's stop packet), or its silence past the robot's
            // watchdog, makes the next cycle the run's last: the robot stands at its last
            // command.
            self.silent = if answered { 0 } else { self.silent + 1 };
            if self.robot.stream_ended() || self.silent > self.silent_limit {
                self.cell.end_joint_stream();
                if !answered {
                    // The stop packet answers no status: not a late answer.
                    if self.silent <= self.silent_limit {
                        self.cycles += 1;
                        return;
                    }
                }
            }
        }
        if self.serving && !answered {
            self.round_trip.record_miss();
            if !self.step.finished {
                self.late += 1;
            }
        }
        if self.serving {
            self.cycles += 1;
        }
    }

    fn progress(&self) -> CellEvent {
        let (force_n, correction_m) = self.cell.truth().map_or((0.0, 0.0), |t| {
            let c = &t.correction;
            (
                t.force_norm_n(),
                (c[0] * c[0] + c[1] * c[1] + c[2] * c[2]).sqrt(),
            )
        });
        CellEvent::Progress {
            forming: self.serving,
            time_s: self.step.time_s,
            path_s: self.cell.path_duration_s(),
            cycles: self.cycles,
            late: self.late,
            force_n,
            correction_m,
            max_error_m: self.cell.stats().max_error_norm_m,
        }
    }
}

/// Serves the twin described by `options` over the ends `sides` until the path is done (or
/// `stop`), telling `events` what it does (when serving starts, then every two seconds).
pub fn serve_cell(
    sides: &CellSides,
    options: &ServeOptions,
    stop: &AtomicBool,
    events: &mut dyn FnMut(CellEvent),
) -> Result<CellOutcome, CellServeError> {
    serve_cell_with(sides, options, stop, events, None)
}

/// [`serve_cell`] feeding the twin's own stream `stream` ([`crate::twin::twin_stream`]): a sample at
/// every change of the cell's state before the program starts, then at every row of its log,
/// with the largest round trip of the controller's answers since the previous sample.
pub fn serve_cell_with(
    sides: &CellSides,
    options: &ServeOptions,
    stop: &AtomicBool,
    events: &mut dyn FnMut(CellEvent),
    mut stream: Option<&mut TwinCellStream>,
) -> Result<CellOutcome, CellServeError> {
    let twin = &options.twin;
    let nominal = check_sides(sides, twin)?;
    let model = &sides.model;
    events(CellEvent::Playing {
        robot: nominal.name.clone(),
        robot_spec: twin.part.robot.clone(),
        robot_cycle_s: twin.robot_period_s(),
        geometry_note: geometry_note(model, &nominal),
    });
    let mut cell = Cell::new(twin, options.path.clone(), options.seed)?;
    let server = if sides.sensor_over_rtde {
        None
    } else {
        Some(
            NetFtSensorServer::bind(sides.sensor_address, sides.sensor_calibration).map_err(
                |error| CellServeError::Sensor {
                    address: sides.sensor_address,
                    error,
                },
            )?,
        )
    };
    let wait = Duration::from_secs_f64(options.wait_s);
    let robot = sides
        .robot
        .open(wait, stop)
        .map_err(|error| CellServeError::RobotEndpoint {
            kind: sides.robot.kind,
            bind: sides.robot.controller,
            error,
        })?;
    let period = Duration::from_secs_f64(cell.robot_period_s() / options.speed);
    let joint_stream = robot.follows_joint_stream();
    if joint_stream {
        // FANUC Stream Motion: the robot follows deflex's joints from its first command (which
        // moves it: no dwell, deflex's approach and ramp hold it near the start).
        cell.follow_joint_stream();
    }
    let mut s = Serving {
        joint_stream,
        silent: 0,
        silent_limit: (2.0 / cell.robot_period_s()).ceil() as u64,
        dwell_cycles: if joint_stream {
            0
        } else {
            (options.dwell_s / cell.robot_period_s()).ceil() as u64
        },
        step: cell.step(),
        cell,
        server,
        robot,
        kinematics: ControllerKinematics {
            data: Data::new(),
            robot: nominal.clone(),
        },
        round_trip: CycleStats::new(period),
        ipoc: 0,
        cycles: 0,
        late: 0,
        serving: false,
        dwelling: false,
        pose_jump: options.pose_jump,
    };
    let mut state = s.state();
    if let Some(st) = stream.as_deref_mut() {
        // The start pose, the first row of the twin's log.
        st.record(&s.cell, &s.step, state);
    }
    let mut end = CellEnd::ProgramFinished;
    let start = Instant::now();
    let mut last_progress = Instant::now();
    let mut next = Instant::now();
    loop {
        if stop.load(Ordering::SeqCst) {
            end = CellEnd::Stopped;
            if let Some(st) = stream.as_deref_mut() {
                st.record_state(CellState::Stopped);
            }
            break;
        }
        let (streamed, stepped) = s.step_twin();
        let (sent, kinematics_ok) = s.send_state();
        next += period;
        let answer = s.await_answer(next, sent, kinematics_ok);
        if answer.is_none()
            && s.serving
            && let Some(c) = s.robot.unanswered_cycle()
        {
            // A UR program's path_offset runs every cycle, answered or not.
            s.cell.set_correction(c.to_array());
        }
        s.account(answer.is_some());
        if let Some(st) = stream.as_deref_mut() {
            st.count_sensor_samples(streamed);
            if let (Some(rt), true) = (answer, s.serving) {
                st.note_round_trip(rt.as_secs_f64());
            }
            let now = s.state();
            if stepped && s.step.logged {
                st.set_robot_counts(s.cycles, s.late);
                st.record(&s.cell, &s.step, now);
            } else if now != state && !stepped {
                st.record_state(now);
            }
            state = now;
        }
        if s.serving && s.step.finished {
            break;
        }
        if !s.serving && start.elapsed().as_secs_f64() > options.wait_s {
            return Err(CellServeError::NoAnswer {
                bind: sides.robot.controller,
                wait_s: options.wait_s,
            });
        }
        if last_progress.elapsed() >= Duration::from_secs(2) {
            last_progress = Instant::now();
            events(s.progress());
        }
        std::thread::sleep(next.saturating_duration_since(Instant::now()));
    }
    let model_geometry_matches = model.geometry_fingerprint() == nominal.geometry_fingerprint();
    Ok(CellOutcome {
        robot: nominal.name,
        robot_spec: twin.part.robot.clone(),
        model_geometry_matches,
        summary: s.cell.stats().clone(),
        round_trip: s.round_trip.summary(),
        cycles: s.cycles,
        late: s.late,
        duration_s: s.step.time_s,
        end,
        log: s.cell.log().clone(),
    })
}
