//! Logged forces of a previous run as a wrench source: the rows of a `deflex run` log (one per
//! control cycle) or of a `deflex sim isf` log (`log.csv`, 50 Hz, SIMULATED), as typed samples,
//! resampled on the path's arc length.
//!
//! This crate reads no log: the caller reads the file through the recorder's log reader
//! (`deflex_record`: the run log's type and the sim log's columns) and hands over one
//! [`LogSample`] per usable row, built here from the row's typed values:
//!
//! * **`deflex run` log** ([`LogSample::from_joints`]): the TCP position of a row is the robot
//!   model's forward kinematics of its joints (the *commanded* TCP: the robot reports motor
//!   positions, which do not see the deflection), the wrench is the TCP wrench (base axes,
//!   eq. 2). Rows whose flags say their wrench is not a measurement of the process (taring,
//!   stale, a fault) are the caller's to skip, and to count ([`WrenchLog::skipped_rows`]).
//! * **`deflex sim isf` log** ([`LogSample::from_part_frame`]): the desired TCP and the contact
//!   wrench in the part frame, mapped to the world with the part frame; the commanded TCP when
//!   the log has it, else the desired one, and the *measured* TCP when the log has the
//!   laser-tracker columns: what [`crate::logged`] identifies the process law and the robot
//!   model's misses from.
//!
//! ## Resampling on arc length
//!
//! [`resample_on_path`]: the rows as the tool moved along the path, linear in arc length
//! between them, averaged over a window, at the path's points (documented in its module).

use deflex_model::{Data, ModelError, Pose, Robot, Wrench};
use nalgebra::Vector3;

mod resample;
pub use resample::{ResampleOptions, Resampled, resample_on_path};

/// Which program wrote the log.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum LogKind {
    /// `deflex run` (the real-time controller).
    DeflexRun,
    /// `deflex sim isf` (the twin).
    SimIsf,
}

impl LogKind {
    /// Name for reports.
    pub fn name(self) -> &'static str {
        match self {
            LogKind::DeflexRun => "deflex run log",
            LogKind::SimIsf => "deflex sim isf log",
        }
    }
}

/// One usable row: the TCP position (world, m) and the wrench on the tool (world axes, at the
/// TCP).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct LogSample {
    /// TCP position that places the row on the path (world, m): the desired TCP of a sim log,
    /// the forward kinematics of a run log's joints.
    pub position_m: Vector3<f64>,
    /// TCP the robot was commanded to (world, m): the forward kinematics of a run log's joints
    /// (the robot reports its motor positions, which do not see the deflection); a sim log's
    /// `cmd_*_mm` columns, or its desired TCP when it has none.
    pub commanded_m: Vector3<f64>,
    /// Where the tool actually was, measured (world, m): a sim log's laser-tracker columns
    /// `tracked_*_mm`, when it has them.
    pub measured_m: Option<Vector3<f64>>,
    /// Wrench on the tool (N, N·m).
    pub wrench: Wrench,
}

/// A log read for resampling.
#[derive(Clone, Debug, PartialEq)]
pub struct WrenchLog {
    /// Which program wrote it.
    pub kind: LogKind,
    /// The file (for messages).
    pub file: String,
    /// Usable rows, in order.
    pub samples: Vec<LogSample>,
    /// Rows skipped for their flags.
    pub skipped_rows: usize,
    /// The log comes from the twin.
    pub simulated: bool,
    /// Every row carries a measured TCP ([`LogSample::measured_m`]).
    pub measured: bool,
}

impl LogSample {
    /// A `deflex run` log's row: joint values `q_rad` (as many as `robot` has) and the TCP
    /// wrench (base axes, at the TCP). The row's place on the path, and its commanded TCP, is
    /// the forward kinematics of its joints (`data` is the work space, reused across rows); an
    /// error when the joint count is not the robot's.
    pub fn from_joints(
        robot: &Robot,
        data: &mut Data,
        q_rad: &[f64],
        wrench: Wrench,
    ) -> Result<LogSample, ModelError> {
        robot.forward_kinematics(data, q_rad)?;
        Ok(LogSample {
            position_m: data.tcp_position(),
            commanded_m: data.tcp_position(),
            measured_m: None,
            wrench,
        })
    }

    /// A `deflex sim isf` log's row: the desired TCP, the commanded TCP when the log has it
    /// (else the desired one) and the measured TCP when it has one, all in the part frame (m);
    /// the wrench on the tool in part-frame axes `[f; m]` (N, N·m). Placed in the world with
    /// `part_frame` (positions transformed, force and moment rotated).
    pub fn from_part_frame(
        part_frame: &Pose,
        desired_m: Vector3<f64>,
        commanded_m: Option<Vector3<f64>>,
        measured_m: Option<Vector3<f64>>,
        wrench: &[f64; 6],
    ) -> LogSample {
        let world = |p: Vector3<f64>| (part_frame * nalgebra::Point3::from(p)).coords;
        let position_m = world(desired_m);
        let r = part_frame.rotation;
        let f = r * Vector3::new(wrench[0], wrench[1], wrench[2]);
        let m = r * Vector3::new(wrench[3], wrench[4], wrench[5]);
        LogSample {
            position_m,
            commanded_m: commanded_m.map_or(position_m, world),
            measured_m: measured_m.map(world),
            wrench: Wrench::new(f.x, f.y, f.z, m.x, m.y, m.z),
        }
    }
}

impl WrenchLog {
    /// A log of `kind` read from `file`: its usable `samples` in order, the rows skipped for
    /// their flags and whether it is SIMULATED. [`WrenchLog::measured`] when every sample carries
    /// a measured TCP (and there is one).
    pub fn new(
        kind: LogKind,
        file: &str,
        samples: Vec<LogSample>,
        skipped_rows: usize,
        simulated: bool,
    ) -> WrenchLog {
        let measured = !samples.is_empty() && samples.iter().all(|s| s.measured_m.is_some());
        WrenchLog {
            kind,
            file: file.to_string(),
            samples,
            skipped_rows,
            simulated,
            measured,
        }
    }
}
