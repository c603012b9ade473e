//! Logged forces of a previous run as a wrench source: the `deflex run` log (one row per control
//! cycle, `crates/deflex-control/src/log.rs`) or the `deflex sim isf` log (`log.csv`, 50 Hz,
//! SIMULATED), read and resampled on the path's arc length.
//!
//! ## Reading
//!
//! * **`deflex run` log**: columns `q1_rad … qN_rad` (the robot's reported joints), the TCP
//!   wrench `w_fx_n … w_mz_nm` (base axes, eq. 2) and `flags`. The TCP position of a row is the
//!   robot model's forward kinematics of its joints (the *commanded* TCP: the robot reports motor
//!   positions, which do not see the deflection). Rows flagged taring, stale wrench, latched or
//!   with any fault bit (`flags & 0x601F`, the bits of `deflex_telemetry::Flags`) are
//!   skipped: their wrench is not a measurement of the process.
//! * **`deflex sim isf` log**: columns `des_x_mm … des_z_mm` (the desired TCP in the part frame)
//!   and the contact wrench `fx_N … mz_Nm` (part-frame axes); positions are mapped to the world
//!   with the part frame. Marked SIMULATED when its header says so.
//! * **Where the tool was.** Each row also carries the TCP the robot was *commanded* to (the run
//!   log's forward kinematics; the sim log's `cmd_x_mm …` when present, else its desired TCP)
//!   and, when the log has them, a *measured* TCP (the sim log's laser-tracker columns
//!   `tracked_x_mm …`): what [`crate::logged`] identifies the process law and the robot
//!   model's misses from.
//!
//! ## Resampling on arc length
//!
//! [`resample_on_path`]: the rows as the tool moved along the path, linear in arc length
//! between them, averaged over a window, at the path's points (documented in its module).

use crate::error::LogError;
use deflex_model::{Data, Pose, Robot, Wrench};
use nalgebra::Vector3;
use std::collections::HashMap;

mod resample;
pub use resample::{ResampleOptions, Resampled, resample_on_path};

/// Largest log read (bytes).
pub const MAX_LOG_BYTES: u64 = 1 << 30;
/// Largest number of rows read.
pub const MAX_LOG_ROWS: usize = 20_000_000;
/// `deflex run` flag bits whose rows are skipped: the eleven fault bits, latched, taring and
/// stale wrench (`deflex_telemetry::Flags`; a test in deflex-cli checks the bits against
/// it, since this crate does not depend on the controller).
pub const RUN_LOG_SKIP_FLAGS: u32 = 0x7FF | (1 << 16) | (1 << 21) | (1 << 22);

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

const RUN_WRENCH: [&str; 6] = [
    "w_fx_n", "w_fy_n", "w_fz_n", "w_mx_nm", "w_my_nm", "w_mz_nm",
];
const ISF_POSITION: [&str; 3] = ["des_x_mm", "des_y_mm", "des_z_mm"];
const ISF_WRENCH: [&str; 6] = ["fx_N", "fy_N", "fz_N", "mx_Nm", "my_Nm", "mz_Nm"];
const ISF_COMMANDED: [&str; 3] = ["cmd_x_mm", "cmd_y_mm", "cmd_z_mm"];
const ISF_MEASURED: [&str; 3] = ["tracked_x_mm", "tracked_y_mm", "tracked_z_mm"];

/// Where a log's columns are: a `deflex run` log (joints, wrench, flags) or a `sim isf` log
/// (part-frame positions, wrench, and optionally the commanded and measured TCP).
enum LogLayout {
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
        /// The tool's position in the part frame (mm).
        position: Vec<usize>,
        /// The wrench in the part frame.
        wrench: Vec<usize>,
        /// The commanded TCP (all three columns or none).
        commanded: Option<Vec<usize>>,
        /// The measured TCP (all three columns or none).
        measured: Option<Vec<usize>>,
    },
}

impl LogLayout {
    fn kind(&self) -> LogKind {
        match self {
            LogLayout::Run { .. } => LogKind::DeflexRun,
            LogLayout::Isf { .. } => LogKind::SimIsf,
        }
    }
}

/// The layout of a log from its header: a `deflex run` log when its wrench, flags and joint
/// columns are there (as many joints as `robot`), else a `sim isf` log; otherwise an error
/// naming the columns missing from the closer of the two.
fn log_layout(
    header: &csv::StringRecord,
    file: &str,
    robot: &Robot,
) -> Result<LogLayout, LogError> {
    let columns: HashMap<&str, usize> = header.iter().enumerate().map(|(i, h)| (h, i)).collect();
    let find = |names: &[&str]| -> Result<Vec<usize>, Vec<String>> {
        let missing: Vec<String> = names
            .iter()
            .filter(|n| !columns.contains_key(*n))
            .map(|n| n.to_string())
            .collect();
        if missing.is_empty() {
            Ok(names.iter().map(|n| columns[n]).collect())
        } else {
            Err(missing)
        }
    };
    let joint_columns: Vec<usize> = (1..)
        .map_while(|i| columns.get(format!("q{i}_rad").as_str()).copied())
        .collect();
    let run = find(&RUN_WRENCH).and_then(|w| find(&["flags"]).map(|f| (w, f[0])));
    let isf = find(&ISF_POSITION).and_then(|p| find(&ISF_WRENCH).map(|w| (p, w)));
    // Optional sim-log columns: all three or none.
    let isf_commanded = find(&ISF_COMMANDED).ok();
    let isf_measured = find(&ISF_MEASURED).ok();
    match (run, isf) {
        (Ok((wrench, flags)), _) if !joint_columns.is_empty() => {
            if joint_columns.len() != robot.joint_count() {
                return Err(LogError::JointCount {
                    file: file.to_string(),
                    log: joint_columns.len(),
                    robot: robot.joint_count(),
                });
            }
            Ok(LogLayout::Run {
                joints: joint_columns,
                wrench,
                flags,
            })
        }
        (_, Ok((position, wrench))) => Ok(LogLayout::Isf {
            position,
            wrench,
            commanded: isf_commanded,
            measured: isf_measured,
        }),
        (Ok(_), Err(_)) => Err(LogError::UnknownKind {
            file: file.to_string(),
            missing: "q1_rad".into(),
        }),
        (Err(run_missing), Err(isf_missing)) => {
            let missing = if run_missing.len() <= isf_missing.len() {
                run_missing
            } else {
                isf_missing
            };
            Err(LogError::UnknownKind {
                file: file.to_string(),
                missing: missing.join(", "),
            })
        }
    }
}

/// Parse log text. `robot` gives the forward kinematics of a `deflex run` log's joints and must
/// have its joint count; `part_frame` (world) places a `sim isf` log's part-frame positions and
/// wrenches.
pub fn parse_log(
    text: &str,
    file: &str,
    robot: &Robot,
    part_frame: &Pose,
) -> Result<WrenchLog, LogError> {
    let simulated = text
        .lines()
        .take_while(|l| l.starts_with('#'))
        .any(|l| l.contains("SIMULATED"));
    let mut reader = csv::ReaderBuilder::new()
        .comment(Some(b'#'))
        .trim(csv::Trim::All)
        .from_reader(text.as_bytes());
    let csv_error = |e: csv::Error| LogError::Csv {
        file: file.to_string(),
        line: e.position().map_or(0, |p| p.line() as usize),
        message: e.to_string(),
    };
    let header = reader.headers().map_err(csv_error)?.clone();
    let layout = log_layout(&header, file, robot)?;
    let kind = layout.kind();
    let mut samples = Vec::new();
    let mut skipped_rows = 0;
    let mut data = Data::new();
    let mut q = vec![0.0; robot.joint_count()];
    for (row_index, record) in reader.records().enumerate() {
        if row_index >= MAX_LOG_ROWS {
            return Err(LogError::TooLarge {
                file: file.to_string(),
                message: format!("more than {MAX_LOG_ROWS} rows"),
            });
        }
        let record = record.map_err(csv_error)?;
        let line = record.position().map_or(0, |p| p.line() as usize);
        let number = |column: usize| -> Result<f64, LogError> {
            let text = record.get(column).unwrap_or("");
            text.parse::<f64>()
                .ok()
                .filter(|v| v.is_finite())
                .ok_or_else(|| LogError::BadValue {
                    file: file.to_string(),
                    line,
                    column: header.get(column).unwrap_or("?").to_string(),
                    value: text.to_string(),
                })
        };
        let sample = match &layout {
            LogLayout::Run {
                joints: joint_columns,
                wrench: wrench_columns,
                flags: flags_column,
            } => {
                let flags_text = record.get(*flags_column).unwrap_or("");
                let flags: u32 = flags_text.parse().map_err(|_| LogError::BadValue {
                    file: file.to_string(),
                    line,
                    column: "flags".into(),
                    value: flags_text.to_string(),
                })?;
                if flags & RUN_LOG_SKIP_FLAGS != 0 {
                    skipped_rows += 1;
                    continue;
                }
                for (value, column) in q.iter_mut().zip(joint_columns) {
                    *value = number(*column)?;
                }
                robot
                    .forward_kinematics(&mut data, &q)
                    .map_err(|_| LogError::JointCount {
                        file: file.to_string(),
                        log: joint_columns.len(),
                        robot: robot.joint_count(),
                    })?;
                let mut w = Wrench::zeros();
                for (k, column) in wrench_columns.iter().enumerate() {
                    w[k] = number(*column)?;
                }
                LogSample {
                    position_m: data.tcp_position(),
                    commanded_m: data.tcp_position(),
                    measured_m: None,
                    wrench: w,
                }
            }
            LogLayout::Isf {
                position: position_columns,
                wrench: wrench_columns,
                commanded: isf_commanded,
                measured: isf_measured,
            } => {
                // A part-frame position in mm from three columns, in the world (m).
                let point = |columns: &[usize]| -> Result<Vector3<f64>, LogError> {
                    let mut p = Vector3::zeros();
                    for (k, column) in columns.iter().enumerate() {
                        p[k] = number(*column)? * 1e-3;
                    }
                    Ok((part_frame * nalgebra::Point3::from(p)).coords)
                };
                let position_m = point(position_columns)?;
                let commanded_m = match &isf_commanded {
                    Some(columns) => point(columns)?,
                    None => position_m,
                };
                let measured_m = match &isf_measured {
                    Some(columns) => Some(point(columns)?),
                    None => None,
                };
                let mut f = Vector3::zeros();
                let mut m = Vector3::zeros();
                for (k, column) in wrench_columns.iter().enumerate() {
                    let v = number(*column)?;
                    if k < 3 {
                        f[k] = v;
                    } else {
                        m[k - 3] = v;
                    }
                }
                let r = part_frame.rotation;
                let (f, m) = (r * f, r * m);
                LogSample {
                    position_m,
                    commanded_m,
                    measured_m,
                    wrench: Wrench::new(f.x, f.y, f.z, m.x, m.y, m.z),
                }
            }
        };
        samples.push(sample);
    }
    let measured = !samples.is_empty() && samples.iter().all(|s| s.measured_m.is_some());
    Ok(WrenchLog {
        kind,
        file: file.to_string(),
        samples,
        skipped_rows,
        simulated,
        measured,
    })
}
