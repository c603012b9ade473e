//! Absolute measurement files (CSV, SI units): one row per measured target position in a
//! tracker set-up's frame.
//!
//! Required columns (exact names, any order): `setup` (label of the tracker set-up: where the
//! tracker stood), `target` (label of the measured point on the flange), `q1_rad` … `qN_rad`,
//! `x_m, y_m, z_m` (measured target position in the set-up's tracker frame).
//!
//! Optional columns (a cell may be left empty):
//!
//! | column | unit | meaning |
//! |---|---|---|
//! | `config` | – | configuration label: rows sharing it were measured at the same joint values (cross-validation and bootstrap hold out or resample whole configurations); default: rows with equal joint values (to 1 µrad) |
//! | `sigma_m` | m | standard deviation of each position component (default [`DEFAULT_ABSOLUTE_SIGMA_M`]) |
//! | `rx_rad, ry_rad, rz_rad` | rad | measured orientation of the target frame in the tracker frame, as a rotation vector (axis × angle); fitted when the fit uses orientations |
//! | `sigma_rad` | rad | its standard deviation (each component; default [`DEFAULT_ORIENTATION_SIGMA_RAD`] or the caller's) |
//! | `payload_kg` | kg | payload on the flange for this row (overrides the robot's `[payload]`) |
//! | `payload_com_x_m, payload_com_y_m, payload_com_z_m` | m | its centre of mass, flange frame |
//! | `fx_N, fy_N, fz_N, mx_Nm, my_Nm, mz_Nm` | N, N·m | external wrench applied at the target, robot world axes, moment about the target |
//! | `temperature_C` | °C | air or robot temperature at the reading |
//! | `time_s` | s | time stamp (any origin) |
//! | `approach_q1_rad … approach_qN_rad` | rad | joint motion that brought the robot to this reading (q here − q at the previous reading of the time-ordered sequence; [`approach_from_sequence`]): its sign is each joint's approach direction |
//!
//! Read by the crate's one measurement reader ([`crate::measurements::reader`]): lines starting
//! with `#` are comments; a file with one bad row is refused whole, with a
//! [`crate::measurements::DataError`] naming the line and the column. Every value is bounded
//! (see [`limits`]).

use std::collections::HashMap;

mod parse;
pub use parse::{parse_absolute, parse_absolute_ignoring};

/// Why a set-up, target or configuration label cannot be written to an absolute file and read
/// back the same by [`parse_absolute`] (which trims cells, takes `#` at a line's start for a
/// comment and refuses empty and long labels).
#[derive(Clone, Debug, PartialEq, Eq, thiserror::Error)]
pub enum LabelProblem {
    /// Nothing to read back: the reader refuses an empty label.
    #[error("is empty")]
    Empty,
    /// Longer than [`limits::MAX_LABEL_BYTES`].
    #[error("is {bytes} bytes long; the reader takes at most {max}")]
    TooLong {
        /// Its length (UTF-8 bytes).
        bytes: usize,
        /// The bound.
        max: usize,
    },
    /// White space at either end: the reader trims it, so another label would come back.
    #[error("starts or ends with white space, which the reader trims")]
    Whitespace,
    /// A leading `#`: the row would be read as a comment and vanish.
    #[error("starts with `#`, which would make its rows comments")]
    Comment,
    /// A control character (a line break, an escape, …): shown escaped, never written.
    #[error("holds the control character U+{code:04X}")]
    Control {
        /// Its code point.
        code: u32,
    },
}

/// Whether `label` reads back from an absolute file exactly as written (see [`LabelProblem`]).
pub fn check_label(label: &str) -> Result<(), LabelProblem> {
    if label.is_empty() {
        return Err(LabelProblem::Empty);
    }
    if label.len() > limits::MAX_LABEL_BYTES {
        return Err(LabelProblem::TooLong {
            bytes: label.len(),
            max: limits::MAX_LABEL_BYTES,
        });
    }
    if let Some(c) = label.chars().find(|c| c.is_control()) {
        return Err(LabelProblem::Control { code: u32::from(c) });
    }
    if label.trim() != label {
        return Err(LabelProblem::Whitespace);
    }
    if label.starts_with('#') {
        return Err(LabelProblem::Comment);
    }
    Ok(())
}

/// Standard deviation of an absolute position component when the file gives none (m): a laser
/// tracker at 2–4 m (the UR10 data set: 16–23 µm median).
pub const DEFAULT_ABSOLUTE_SIGMA_M: f64 = 25e-6;

/// Standard deviation of a measured orientation (each rotation-vector component, rad) when the
/// file gives none: a 6-DoF probe on a laser tracker (the UR10 data set's T-Mac reports
/// 20–70 µrad repeatability; its stated accuracy is about 0.01° ≈ 175 µrad).
pub const DEFAULT_ORIENTATION_SIGMA_RAD: f64 = 100e-6;

/// Bounds on file values: anything outside is refused with the column named. Joint values,
/// positions, forces, moments and standard deviations have the bounds of every measurement
/// file ([`crate::measurements::MAX_JOINT_RAD`], [`crate::measurements::MAX_COORDINATE_M`],
/// [`crate::measurements::MAX_FORCE_N`], [`crate::measurements::MAX_MOMENT_NM`],
/// [`crate::measurements::MAX_SIGMA_M`], [`crate::measurements::MAX_SIGMA_RAD`]); these are the
/// absolute format's own.
pub mod limits {
    /// Largest file read (bytes).
    pub const MAX_FILE_BYTES: u64 = 512 << 20;
    /// Largest number of rows.
    pub const MAX_ROWS: usize = 2_000_000;
    /// Largest rotation vector component (rad).
    pub const MAX_ROTATION_RAD: f64 = 4.0 * std::f64::consts::PI;
    /// Largest payload (kg).
    pub const MAX_PAYLOAD_KG: f64 = 1e4;
    /// Largest payload centre-of-mass offset (m).
    pub const MAX_COM_M: f64 = 10.0;
    /// Temperature range (°C).
    pub const TEMPERATURE_RANGE_C: [f64; 2] = [-60.0, 200.0];
    /// Largest |time| (s).
    pub const MAX_TIME_S: f64 = 1e10;
    /// Longest label (bytes).
    pub const MAX_LABEL_BYTES: usize = 200;
}

/// A payload carried at the flange for one row.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct RowPayload {
    /// Mass (kg).
    pub mass_kg: f64,
    /// Centre of mass in the flange frame (m).
    pub com_m: [f64; 3],
}

/// A measured orientation (rotation vector in the tracker frame).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct RowOrientation {
    /// Rotation vector, axis × angle (rad).
    pub rotation_vector_rad: [f64; 3],
    /// Standard deviation (rad), if given.
    pub sigma_rad: Option<f64>,
}

/// One absolute reading: a target on the flange measured in a set-up's tracker frame.
#[derive(Clone, Debug, PartialEq)]
pub struct AbsoluteRow {
    /// 1-based line of the file (0 for rows made in memory).
    pub line: u64,
    /// Tracker set-up label.
    pub setup: String,
    /// Target label.
    pub target: String,
    /// Configuration label (`None`: rows with equal joint values form one configuration).
    pub config: Option<String>,
    /// Joint values (rad).
    pub q_rad: Vec<f64>,
    /// Measured target position in the tracker frame (m).
    pub position_m: [f64; 3],
    /// Standard deviation of each position component (m); `None` = default.
    pub sigma_m: Option<f64>,
    /// Measured orientation, if any.
    pub orientation: Option<RowOrientation>,
    /// Payload, if this row names one.
    pub payload: Option<RowPayload>,
    /// External wrench at the target, world axes (N, N·m), if any.
    pub wrench: Option<[f64; 6]>,
    /// Temperature (°C).
    pub temperature_c: Option<f64>,
    /// Time stamp (s).
    pub time_s: Option<f64>,
    /// Joint motion that brought the robot to this reading (`q` here minus `q` at the previous
    /// reading of the measuring sequence, rad), when the file is time-ordered: its sign is the
    /// direction each joint approached from (backlash, hysteresis).
    pub approach_rad: Option<Vec<f64>>,
}

impl AbsoluteRow {
    /// A reading of position alone (no stated σ, orientation, payload, wrench, temperature, time
    /// or approach motion): set other fields with struct-update syntax.
    pub fn position(
        line: u64,
        setup: &str,
        target: &str,
        q_rad: Vec<f64>,
        position_m: [f64; 3],
    ) -> AbsoluteRow {
        AbsoluteRow {
            line,
            setup: setup.into(),
            target: target.into(),
            config: None,
            q_rad,
            position_m,
            sigma_m: None,
            orientation: None,
            payload: None,
            wrench: None,
            temperature_c: None,
            time_s: None,
            approach_rad: None,
        }
    }

    /// The standard deviation used for weighting (m).
    pub fn sigma(&self) -> f64 {
        self.sigma_m.unwrap_or(DEFAULT_ABSOLUTE_SIGMA_M)
    }
}

/// Fill every row's [`AbsoluteRow::approach_rad`] from the order of `rows` (the measuring
/// sequence, first to last): per joint, the last motion `q_i − q_{i−1}` larger than
/// [`crate::geometry::params::APPROACH_DEADBAND_RAD`] (a joint that stood still keeps the flank it last
/// came from); zero before a joint's first motion (direction unknown). Call it on the whole
/// sequence, before any decimation.
pub fn approach_from_sequence(rows: &mut [AbsoluteRow]) {
    let mut previous: Option<(Vec<f64>, Vec<f64>)> = None;
    for row in rows {
        let n = row.q_rad.len();
        let motion: Vec<f64> = match &previous {
            Some((q, last)) if q.len() == n => (0..n)
                .map(|j| {
                    let step = row.q_rad[j] - q[j];
                    if step.abs() > crate::geometry::params::APPROACH_DEADBAND_RAD {
                        step
                    } else {
                        last[j]
                    }
                })
                .collect(),
            _ => vec![0.0; n],
        };
        previous = Some((row.q_rad.clone(), motion.clone()));
        row.approach_rad = Some(motion);
    }
}

const POSITION: [&str; 3] = ["x_m", "y_m", "z_m"];
const ORIENTATION: [&str; 3] = ["rx_rad", "ry_rad", "rz_rad"];
const PAYLOAD_COM: [&str; 3] = ["payload_com_x_m", "payload_com_y_m", "payload_com_z_m"];
const WRENCH: [&str; 6] = ["fx_N", "fy_N", "fz_N", "mx_Nm", "my_Nm", "mz_Nm"];
/// Prefix of the approach columns `approach_q1_rad … approach_qN_rad`.
const APPROACH: &str = "approach_q";

/// Format rows as CSV (full precision); optional columns are written when any row has them.
/// `comments` are written first as `# ` lines.
pub fn format_absolute(rows: &[AbsoluteRow], comments: &[String]) -> String {
    let joint_count = rows.first().map_or(0, |r| r.q_rad.len());
    let any = |f: &dyn Fn(&AbsoluteRow) -> bool| rows.iter().any(f);
    let with_config = any(&|r| r.config.is_some());
    let with_sigma = any(&|r| r.sigma_m.is_some());
    let with_orientation = any(&|r| r.orientation.is_some());
    let with_sigma_rad = any(&|r| r.orientation.is_some_and(|o| o.sigma_rad.is_some()));
    let with_payload = any(&|r| r.payload.is_some());
    let with_wrench = any(&|r| r.wrench.is_some());
    let with_temperature = any(&|r| r.temperature_c.is_some());
    let with_time = any(&|r| r.time_s.is_some());
    let with_approach = any(&|r| r.approach_rad.is_some());
    let mut header: Vec<String> = vec!["setup".into(), "target".into()];
    if with_config {
        header.push("config".into());
    }
    header.extend((1..=joint_count).map(|i| format!("q{i}_rad")));
    header.extend(POSITION.map(String::from));
    if with_sigma {
        header.push("sigma_m".into());
    }
    if with_orientation {
        header.extend(ORIENTATION.map(String::from));
    }
    if with_sigma_rad {
        header.push("sigma_rad".into());
    }
    if with_payload {
        header.push("payload_kg".into());
        header.extend(PAYLOAD_COM.map(String::from));
    }
    if with_wrench {
        header.extend(WRENCH.map(String::from));
    }
    if with_temperature {
        header.push("temperature_C".into());
    }
    if with_time {
        header.push("time_s".into());
    }
    if with_approach {
        header.extend((1..=joint_count).map(|i| format!("{APPROACH}{i}_rad")));
    }
    let mut out = String::new();
    for comment in comments {
        for line in comment.lines() {
            out.push_str("# ");
            out.push_str(line);
            out.push('\n');
        }
    }
    let num = |v: f64| format!("{v:?}");
    let opt = |v: Option<f64>| v.map(num).unwrap_or_default();
    let record_of = |row: &AbsoluteRow| {
        let mut record: Vec<String> = vec![row.setup.clone(), row.target.clone()];
        if with_config {
            record.push(row.config.clone().unwrap_or_default());
        }
        record.extend(row.q_rad.iter().map(|v| num(*v)));
        record.extend(row.position_m.iter().map(|v| num(*v)));
        if with_sigma {
            record.push(opt(row.sigma_m));
        }
        if with_orientation {
            match row.orientation {
                Some(o) => record.extend(o.rotation_vector_rad.iter().map(|v| num(*v))),
                None => record.extend([String::new(), String::new(), String::new()]),
            }
        }
        if with_sigma_rad {
            record.push(opt(row.orientation.and_then(|o| o.sigma_rad)));
        }
        if with_payload {
            match row.payload {
                Some(p) => {
                    record.push(num(p.mass_kg));
                    record.extend(p.com_m.iter().map(|v| num(*v)));
                }
                None => record.extend([String::new(), String::new(), String::new(), String::new()]),
            }
        }
        if with_wrench {
            match row.wrench {
                Some(w) => record.extend(w.iter().map(|v| num(*v))),
                None => record.extend(std::iter::repeat_n(String::new(), 6)),
            }
        }
        if with_temperature {
            record.push(opt(row.temperature_c));
        }
        if with_time {
            record.push(opt(row.time_s));
        }
        if with_approach {
            match &row.approach_rad {
                Some(a) if a.len() == joint_count => record.extend(a.iter().map(|v| num(*v))),
                _ => record.extend(std::iter::repeat_n(String::new(), joint_count)),
            }
        }
        record
    };
    out.push_str(&deflex_files::csv_text(
        std::iter::once(header).chain(rows.iter().map(record_of)),
    ));
    out
}

/// Configuration label of every row: its `config` column, or else a label shared by the rows
/// of the same set-up with equal joint values (rounded to 1 µrad). Returns a dense index per
/// row and the number of configurations.
pub fn configuration_index(rows: &[AbsoluteRow]) -> (Vec<usize>, usize) {
    let mut labels: HashMap<String, usize> = HashMap::new();
    let mut out = Vec::with_capacity(rows.len());
    for row in rows {
        let key = match &row.config {
            Some(c) => format!("c:{c}"),
            None => {
                let mut key = String::from("q:");
                for q in &row.q_rad {
                    key.push_str(&format!("{},", (q * 1e6).round() as i64));
                }
                key
            }
        };
        let next = labels.len();
        out.push(*labels.entry(key).or_insert(next));
    }
    (out, labels.len())
}
