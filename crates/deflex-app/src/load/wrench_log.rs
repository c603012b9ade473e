//! A previous run's log as the compensation's wrench source (`deflex compensate --wrench
//! log:FILE`, Python's `wrench="log:FILE"`, the study's log compensation): the file read here
//! (bounded), its rows through the recorder's one log reader ([`deflex_record::log_reader`]),
//! handed to the compensation typed ([`LogSample`], [`WrenchLog`]).
//!
//! Which log a file is comes from its header:
//!
//! * a **`deflex run` log** ([`deflex_record::run_log`]) when it has the TCP wrench
//!   `w_fx_n … w_mz_nm`, `flags` and joint columns `q1_rad …` (as many as the robot has). Rows
//!   flagged taring, stale wrench, latched or with a fault bit
//!   ([`deflex_record::run_log::RUN_LOG_SKIP_FLAGS`]) are skipped: their wrench is not a
//!   measurement of the process; a row's place is the forward kinematics of its joints
//!   ([`LogSample::from_joints`]);
//! * else a **`deflex sim isf` log** ([`deflex_record::isf_log`]) when it has the desired TCP
//!   `des_x_mm …` and the wrench `fx_N … mz_Nm` (part frame), and optionally the commanded
//!   (`cmd_*_mm`) and measured (`tracked_*_mm`) TCP, all three columns of each or none
//!   ([`LogSample::from_part_frame`]);
//! * otherwise an error naming the columns missing from the closer of the two.
//!
//! The numbers a row uses must be finite; errors name the file, the line and the column.

use deflex_compensate::log::{LogKind, LogSample, WrenchLog};
use deflex_files::{FileIoError, FileTooLarge};
use deflex_model::{Data, Pose, Robot, Wrench};
use deflex_record::isf_log;
use deflex_record::log_reader::{LogReadError, LogReader, LogRow};
use deflex_record::run_log::{RUN_LOG_SKIP_FLAGS, RunLogBlock, RunLogColumn, joint_columns};
use nalgebra::Vector3;
use std::path::Path;

pub use deflex_record::log_reader::{MAX_LOG_BYTES, MAX_LOG_ROWS};

/// A log file that cannot serve as a wrench source.
#[derive(Debug, thiserror::Error)]
pub enum WrenchLogError {
    /// Reading the file failed: `PATH: cannot read: ERROR` (a [`FileIoError`] becomes this with
    /// that context).
    #[error(transparent)]
    Io(FileIoError),
    /// Larger than [`MAX_LOG_BYTES`].
    #[error(transparent)]
    TooLarge(#[from] FileTooLarge),
    /// Neither a `deflex run` log nor a `sim isf` log: required columns are missing.
    #[error("{file}: not a deflex run or sim isf log: missing column(s) {missing}")]
    UnknownKind {
        /// The file.
        file: String,
        /// The columns that are missing for the closest kind.
        missing: String,
    },
    /// A `deflex run` log whose joint count does not match the robot model.
    #[error("{file}: the log has {log} joint columns, the robot has {robot} joints")]
    JointCount {
        /// The file.
        file: String,
        /// Joint columns in the log.
        log: usize,
        /// Joints of the robot.
        robot: usize,
    },
    /// The log's text (malformed CSV, too many rows, a value that is not a finite number).
    #[error(transparent)]
    Read(#[from] LogReadError),
}

impl From<FileIoError> for WrenchLogError {
    fn from(error: FileIoError) -> Self {
        WrenchLogError::Io(error.context("cannot read"))
    }
}

/// Where a log's columns are.
enum Layout {
    /// A `deflex run` log.
    Run {
        /// `q1_rad …`.
        joints: Vec<usize>,
        /// The wrench at the TCP.
        wrench: Vec<usize>,
        /// `flags`.
        flags: usize,
    },
    /// A `deflex sim isf` log.
    Isf {
        /// The desired TCP in the part frame (mm).
        desired: Vec<usize>,
        /// The wrench in the part frame.
        wrench: Vec<usize>,
        /// The commanded TCP (all three columns or none).
        commanded: Option<Vec<usize>>,
        /// The measured TCP (all three columns or none).
        measured: Option<Vec<usize>>,
    },
}

/// The layout of a log from its header (see the module documentation).
fn layout(log: &LogReader<'_>, robot: &Robot) -> Result<Layout, WrenchLogError> {
    let file = log.file();
    let joints = joint_columns(log);
    let run = RunLogColumn::find_all(&RunLogBlock::TcpWrench.columns(), log)
        .and_then(|w| RunLogColumn::find_all(&[RunLogColumn::Flags], log).map(|f| (w, f[0])));
    let isf = log
        .columns_of(&isf_log::DESIRED_MM)
        .and_then(|p| log.columns_of(&isf_log::WRENCH).map(|w| (p, w)));
    match (run, isf) {
        (Ok((wrench, flags)), _) if !joints.is_empty() => {
            if joints.len() != robot.joint_count() {
                return Err(WrenchLogError::JointCount {
                    file: file.to_string(),
                    log: joints.len(),
                    robot: robot.joint_count(),
                });
            }
            Ok(Layout::Run {
                joints,
                wrench,
                flags,
            })
        }
        (_, Ok((desired, wrench))) => Ok(Layout::Isf {
            desired,
            wrench,
            commanded: log.columns_of(&isf_log::COMMANDED_MM).ok(),
            measured: log.columns_of(&isf_log::TRACKED_MM).ok(),
        }),
        (Ok(_), Err(_)) => Err(WrenchLogError::UnknownKind {
            file: file.to_string(),
            missing: RunLogColumn::Joint(0).name(),
        }),
        (Err(run_missing), Err(isf_missing)) => {
            let missing = if run_missing.len() <= isf_missing.len() {
                run_missing
            } else {
                isf_missing
            };
            Err(WrenchLogError::UnknownKind {
                file: file.to_string(),
                missing: missing.join(", "),
            })
        }
    }
}

/// A part-frame position in mm from three columns, in m.
fn millimetres(row: &LogRow<'_>, columns: &[usize]) -> Result<Vector3<f64>, LogReadError> {
    let mut p = Vector3::zeros();
    for (k, column) in columns.iter().enumerate() {
        p[k] = row.finite(*column)? * 1e-3;
    }
    Ok(p)
}

/// Parse a log's `text` (`file` names it in errors). `robot` gives the forward kinematics of a
/// `deflex run` log's joints and must have its joint count; `part_frame` (world) places a `sim
/// isf` log's part-frame positions and wrenches.
pub fn parse_wrench_log(
    text: &str,
    file: &str,
    robot: &Robot,
    part_frame: &Pose,
) -> Result<WrenchLog, WrenchLogError> {
    let mut log = LogReader::new(text, file)?;
    let simulated = log.simulated();
    let layout = layout(&log, robot)?;
    let mut samples = Vec::new();
    let mut skipped_rows = 0;
    let mut data = Data::new();
    let mut q = vec![0.0; robot.joint_count()];
    while let Some(row) = log.next_row()? {
        let sample = match &layout {
            Layout::Run {
                joints,
                wrench,
                flags,
            } => {
                if row.unsigned(*flags)? & RUN_LOG_SKIP_FLAGS != 0 {
                    skipped_rows += 1;
                    continue;
                }
                for (value, column) in q.iter_mut().zip(joints) {
                    *value = row.finite(*column)?;
                }
                let mut w = Wrench::zeros();
                for (k, column) in wrench.iter().enumerate() {
                    w[k] = row.finite(*column)?;
                }
                LogSample::from_joints(robot, &mut data, &q, w).map_err(|_| {
                    WrenchLogError::JointCount {
                        file: file.to_string(),
                        log: joints.len(),
                        robot: robot.joint_count(),
                    }
                })?
            }
            Layout::Isf {
                desired,
                wrench,
                commanded,
                measured,
            } => {
                let desired_m = millimetres(&row, desired)?;
                let commanded_m = commanded
                    .as_ref()
                    .map(|c| millimetres(&row, c))
                    .transpose()?;
                let measured_m = measured
                    .as_ref()
                    .map(|c| millimetres(&row, c))
                    .transpose()?;
                let mut w = [0.0; 6];
                for (value, column) in w.iter_mut().zip(wrench) {
                    *value = row.finite(*column)?;
                }
                LogSample::from_part_frame(part_frame, desired_m, commanded_m, measured_m, &w)
            }
        };
        samples.push(sample);
    }
    let kind = match layout {
        Layout::Run { .. } => LogKind::DeflexRun,
        Layout::Isf { .. } => LogKind::SimIsf,
    };
    Ok(WrenchLog::new(kind, file, samples, skipped_rows, simulated))
}

/// Read the log at `path` (at most [`MAX_LOG_BYTES`], the file named in every error) and parse
/// it ([`parse_wrench_log`]).
pub fn read_wrench_log(
    path: &Path,
    robot: &Robot,
    part_frame: &Pose,
) -> Result<WrenchLog, WrenchLogError> {
    let text = deflex_files::read_bounded(path, MAX_LOG_BYTES)
        .map_err(|e| e.reported_as::<WrenchLogError>("a log"))?;
    parse_wrench_log(&text, &path.display().to_string(), robot, part_frame)
}
