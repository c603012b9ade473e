//! What the telemetry stream carries: one [`CycleSample`] per control cycle, and the
//! [`SessionInfo`] that does not change during a session.
//!
//! Frames and signs follow `deflex-control`: SI units; the robot's base axes for the TCP wrench,
//! δŝ, ξ and ε; s_com = s_des + ξ. The robot realises s_com, so forward kinematics of the joint
//! values it reports is the **corrected** TCP ([`CycleSample::tcp_position_m`]) and the program's
//! **commanded** (desired) TCP is that minus ξ ([`CycleSample::program_position_m`]).

use crate::{FaultKind, Flags, Phase};
use bytemuck::{Pod, Zeroable};
use deflex_model::MAX_JOINTS;
use nalgebra::{Matrix3, Rotation3, Vector3, Vector6};

/// [`CycleSample::fault`] when no fault is latched.
pub const FAULT_NONE: u32 = 0;

/// [`CycleSample::robot_late`] when the robot does not report its late count.
pub const LATE_UNKNOWN: u64 = u64::MAX;

/// One control cycle, as published by the control thread (plain data, fixed size, no heap).
///
/// Fields that a source does not know are NaN (f64) or their documented "unknown" value.
#[repr(C)]
#[derive(Clone, Copy, Debug, PartialEq, Pod, Zeroable)]
pub struct CycleSample {
    /// Session time of the cycle (s), on the session's clock (wall or simulated).
    pub time_s: f64,
    /// Cycle number, from 1.
    pub cycle: u64,
    /// Joint values the robot reported (rad); the first [`Self::joint_count`] are used.
    pub q_rad: [f64; MAX_JOINTS],
    /// Raw force/torque reading, sensor frame (N, N·m), averaged over the cycle.
    pub wrench_raw: [f64; 6],
    /// Reading with bias and tool gravity removed, low-pass filtered, sensor frame (N, N·m).
    pub wrench_sensor: [f64; 6],
    /// Environment wrench at the TCP (eq. 2), base axes (N, N·m).
    pub wrench_tcp: [f64; 6],
    /// Estimated deflection δŝ = C(q) w (eq. 15): [m, m, m, rad, rad, rad].
    pub deflection: [f64; 6],
    /// Applied correction ξ (eq. 7): [m, m, m, rad, rad, rad].
    pub correction: [f64; 6],
    /// Tracking error ε = −ξ − δŝ (eq. 5): [m, m, m, rad, rad, rad].
    pub error: [f64; 6],
    /// Feed-forward prior at the robot's place on the path; zero without one.
    pub feedforward: [f64; 6],
    /// Forward kinematics of [`Self::q_rad`] with the model: the corrected TCP (m, base frame).
    pub tcp_position_m: [f64; 3],
    /// TCP orientation (rows of the rotation matrix, base frame).
    pub tcp_rotation: [[f64; 3]; 3],
    /// Twin only: true TCP minus desired TCP (m, base axes); NaN on a real cell. The twin
    /// knows it in its part frame R_p, whose axes are the world's; it is turned into the robot's
    /// base axes with the base orientation of the robot model.
    pub truth_error_m: [f64; 3],
    /// Arc length of the robot's place on the feed-forward path (m); NaN without one.
    pub path_s_m: f64,
    /// The runaway guard's loop-gain estimate; NaN when unknown.
    pub loop_gain: f64,
    /// Computation time of the cycle (s).
    pub cycle_time_s: f64,
    /// Robot telegrams answered so far.
    pub robot_telegrams: u64,
    /// Answers the robot itself counted as late (KUKA RSI `Delay`), [`LATE_UNKNOWN`] if it
    /// does not say.
    pub robot_late: u64,
    /// Answers the robot-link thread sent later than one robot cycle after the telegram.
    pub late_answers: u64,
    /// Force/torque samples received so far.
    pub sensor_samples: u64,
    /// Number of joint values used.
    pub joint_count: u32,
    /// Controller phase (see [`CycleSample::phase`]).
    pub phase_code: u32,
    /// Status bits ([`crate::Flags`]).
    pub flags: u32,
    /// Latched fault: [`FAULT_NONE`], else 1 + the index in [`FaultKind::ALL`].
    pub fault: u32,
}

impl Default for CycleSample {
    fn default() -> Self {
        let nan3 = [f64::NAN; 3];
        CycleSample {
            truth_error_m: nan3,
            path_s_m: f64::NAN,
            loop_gain: f64::NAN,
            robot_late: LATE_UNKNOWN,
            ..Zeroable::zeroed()
        }
    }
}

/// Phases in code order.
const PHASES: [Phase; 6] = [
    Phase::Idle,
    Phase::Taring,
    Phase::Running,
    Phase::Stopping,
    Phase::Stopped,
    Phase::Faulted,
];

impl CycleSample {
    /// The code of a phase in [`Self::phase_code`].
    pub fn phase_to_code(phase: Phase) -> u32 {
        PHASES.iter().position(|p| *p == phase).unwrap_or(0) as u32
    }

    /// The code of a latched fault in [`Self::fault`].
    pub fn fault_to_code(fault: Option<FaultKind>) -> u32 {
        fault.map_or(FAULT_NONE, |kind| {
            FaultKind::ALL
                .iter()
                .position(|k| *k == kind)
                .map_or(FAULT_NONE, |i| i as u32 + 1)
        })
    }

    /// The controller phase.
    pub fn phase(&self) -> Phase {
        PHASES[(self.phase_code as usize).min(PHASES.len() - 1)]
    }

    /// The latched fault, if any.
    pub fn fault_kind(&self) -> Option<FaultKind> {
        (self.fault as usize)
            .checked_sub(1)
            .and_then(|i| FaultKind::ALL.get(i).copied())
    }

    /// Status bits.
    pub fn status_flags(&self) -> Flags {
        Flags(self.flags)
    }

    /// The joint values used.
    pub fn q(&self) -> &[f64] {
        &self.q_rad[..(self.joint_count as usize).min(MAX_JOINTS)]
    }

    /// Environment wrench at the TCP, base axes.
    pub fn wrench_tcp(&self) -> Vector6<f64> {
        Vector6::from_column_slice(&self.wrench_tcp)
    }

    /// Force norm at the TCP (N).
    pub fn force_norm_n(&self) -> f64 {
        Vector3::from_column_slice(&self.wrench_tcp[..3]).norm()
    }

    /// The corrected TCP position (m, base frame).
    pub fn tcp_position(&self) -> Vector3<f64> {
        Vector3::from(self.tcp_position_m)
    }

    /// The program's (desired) TCP position: corrected TCP minus the position part of ξ.
    pub fn program_position_m(&self) -> Vector3<f64> {
        self.tcp_position() - Vector3::from_column_slice(&self.correction[..3])
    }

    /// TCP orientation.
    pub fn tcp_rotation(&self) -> Rotation3<f64> {
        let r = &self.tcp_rotation;
        Rotation3::from_matrix_unchecked(Matrix3::new(
            r[0][0], r[0][1], r[0][2], r[1][0], r[1][1], r[1][2], r[2][0], r[2][1], r[2][2],
        ))
    }

    /// Sets [`Self::tcp_rotation`] from a rotation.
    pub fn set_tcp_rotation(&mut self, rotation: &Rotation3<f64>) {
        let m = rotation.matrix();
        for (i, row) in self.tcp_rotation.iter_mut().enumerate() {
            for (j, v) in row.iter_mut().enumerate() {
                *v = m[(i, j)];
            }
        }
    }

    /// Sets the joint values (at most [`MAX_JOINTS`]).
    pub fn set_q(&mut self, q: &[f64]) {
        let n = q.len().min(MAX_JOINTS);
        self.q_rad = [0.0; MAX_JOINTS];
        self.q_rad[..n].copy_from_slice(&q[..n]);
        self.joint_count = n as u32;
    }
}

/// Who produced a stream.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum StreamSource {
    /// `deflex run` against a robot controller and a sensor (real or simulated cell).
    Runtime,
    /// The deflex controller in-process on the digital twin (`deflex sim isf --correction on`):
    /// the controller's own cycle, as `deflex run` publishes it, plus the twin's path error
    /// ([`CycleSample::truth_error_m`]). SIMULATED.
    Twin,
    /// The digital twin's own stream, with no controller in it (`deflex cell --sim`, whose
    /// controller is another process, and `deflex sim isf` open loop): what the robot reports
    /// and the plant's ground truth. In its samples [`CycleSample::wrench_tcp`] is the **true**
    /// contact wrench at the TCP, [`CycleSample::deflection`] the arm's **true** deflection
    /// under it, [`CycleSample::correction`] the correction the robot **applies** (after its
    /// transport delay, filter and bounds), [`CycleSample::tcp_position_m`] the TCP from the
    /// joints the robot reports (its controller's kinematics), [`CycleSample::cycle_time_s`]
    /// the round trip of the controller's answer (`cell --sim`; NaN in-process) and
    /// [`CycleSample::phase_code`] the cell's state ([`CellState`]); what only a controller
    /// knows (the processed reading, ε, the feed-forward, flags, faults) is NaN or zero.
    /// SIMULATED.
    TwinCell,
}

impl StreamSource {
    /// The key of the source in files and messages: `runtime`, `twin`, `twin-cell`.
    pub fn key(self) -> &'static str {
        match self {
            StreamSource::Runtime => "runtime",
            StreamSource::Twin => "twin",
            StreamSource::TwinCell => "twin-cell",
        }
    }

    /// The names of [`CycleSample::phase_code`]'s values for this source: the controller's
    /// phases, or for [`StreamSource::TwinCell`] the cell's states ([`CellState::name`]).
    pub fn phase_names(self) -> [&'static str; 6] {
        match self {
            StreamSource::Runtime | StreamSource::Twin => PHASES.map(|p| p.name()),
            StreamSource::TwinCell => CellState::ALL.map(CellState::name),
        }
    }

    /// The name of the phase code `code` of a sample of this source.
    pub fn phase_name(self, code: u32) -> &'static str {
        let names = self.phase_names();
        names[(code as usize).min(names.len() - 1)]
    }
}

/// The state of the simulated cell in a [`StreamSource::TwinCell`] sample's
/// [`CycleSample::phase_code`] (its index in [`CellState::ALL`]).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum CellState {
    /// The robot holds its start pose until a controller answers (`cell --sim`).
    Waiting,
    /// A controller answers: the robot dwells at the start pose (the controller tares there).
    Dwelling,
    /// The robot program runs.
    Forming,
    /// Stopped by a signal before the end of the program.
    Stopped,
    /// The program reached the end of its path.
    Finished,
    /// Not used (keeps the six codes of the controller's phases).
    Unused,
}

impl CellState {
    /// Every state, in code order.
    pub const ALL: [CellState; 6] = [
        CellState::Waiting,
        CellState::Dwelling,
        CellState::Forming,
        CellState::Stopped,
        CellState::Finished,
        CellState::Unused,
    ];

    /// The code in [`CycleSample::phase_code`].
    pub fn code(self) -> u32 {
        CellState::ALL.iter().position(|s| *s == self).unwrap_or(0) as u32
    }

    /// Its name.
    pub fn name(self) -> &'static str {
        match self {
            CellState::Waiting => "waiting",
            CellState::Dwelling => "dwelling",
            CellState::Forming => "forming",
            CellState::Stopped => "stopped",
            CellState::Finished => "finished",
            CellState::Unused => "-",
        }
    }
}

/// What does not change during a session: shared once, before the first sample.
#[derive(Clone, Debug, PartialEq)]
pub struct SessionInfo {
    /// Who publishes.
    pub source: StreamSource,
    /// True when the robot or the cell is the digital twin (labelled SIMULATED).
    pub simulated: bool,
    /// Robot name (the model's).
    pub robot: String,
    /// Joint names, in order.
    pub joint_names: Vec<String>,
    /// Robot protocol (e.g. `kuka-rsi`), or `in-process` for the twin.
    pub protocol: String,
    /// Control period (s).
    pub control_period_s: f64,
    /// Robot interpolation cycle (s).
    pub robot_cycle_s: f64,
    /// Correction size bound per axis: [m, m, m, rad, rad, rad].
    pub correction_limit: [f64; 6],
    /// Correction rate bound per axis: [m/s, …, rad/s].
    pub correction_rate_limit: [f64; 6],
    /// Force norm limit (N).
    pub force_limit_n: f64,
    /// Name of the robot base frame (the frame of positions, the TCP wrench, δŝ and ξ).
    pub base_frame: String,
    /// Name of the force/torque sensor frame (the frame of the raw and compensated readings).
    pub sensor_frame: String,
    /// Name of the TCP frame.
    pub tcp_frame: String,
}

impl SessionInfo {
    /// A session description with the default frame names `base`, `ft_sensor` and `tcp`.
    pub fn new(source: StreamSource, robot: impl Into<String>, joint_names: Vec<String>) -> Self {
        SessionInfo {
            source,
            simulated: matches!(source, StreamSource::Twin | StreamSource::TwinCell),
            robot: robot.into(),
            joint_names,
            protocol: String::new(),
            control_period_s: 0.01,
            robot_cycle_s: 0.004,
            correction_limit: [f64::INFINITY; 6],
            correction_rate_limit: [f64::INFINITY; 6],
            force_limit_n: f64::INFINITY,
            base_frame: "base".into(),
            sensor_frame: "ft_sensor".into(),
            tcp_frame: "tcp".into(),
        }
    }
}
