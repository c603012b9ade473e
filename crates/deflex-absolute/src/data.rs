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
//! | `rx_rad, ry_rad, rz_rad` | rad | measured orientation of the target frame in the tracker frame, as a rotation vector (axis × angle); kept and written, not fitted |
//! | `sigma_rad` | rad | its standard deviation |
//! | `payload_kg` | kg | payload on the flange for this row (overrides the robot's `[payload]`) |
//! | `payload_com_x_m, payload_com_y_m, payload_com_z_m` | m | its centre of mass, flange frame |
//! | `fx_N, fy_N, fz_N, mx_Nm, my_Nm, mz_Nm` | N, N·m | external wrench applied at the target, robot world axes, moment about the target |
//! | `temperature_C` | °C | air or robot temperature at the reading |
//! | `time_s` | s | time stamp (any origin) |
//!
//! Lines starting with `#` are comments. A file with one bad row is refused whole, naming the
//! line and the column. Every value is bounded (see [`limits`]).

use std::collections::HashMap;
use std::path::Path;
use thiserror::Error;

/// Standard deviation of an absolute position component when the file gives none (m): a laser
/// tracker at 2–4 m (the UR10 data set: 16–23 µm median).
pub const DEFAULT_ABSOLUTE_SIGMA_M: f64 = 25e-6;

/// Bounds on file values: anything outside is refused with the column named.
pub mod limits {
    /// Largest file read (bytes).
    pub const MAX_FILE_BYTES: u64 = 512 << 20;
    /// Largest number of rows.
    pub const MAX_ROWS: usize = 2_000_000;
    /// Largest |position| (m).
    pub const MAX_POSITION_M: f64 = 100.0;
    /// Largest |joint value| (rad).
    pub const MAX_JOINT_RAD: f64 = 100.0;
    /// Largest standard deviation (m).
    pub const MAX_SIGMA_M: f64 = 1.0;
    /// Largest standard deviation (rad).
    pub const MAX_SIGMA_RAD: f64 = 1.0;
    /// Largest rotation vector norm (rad).
    pub const MAX_ROTATION_RAD: f64 = 4.0 * std::f64::consts::PI;
    /// Largest payload (kg).
    pub const MAX_PAYLOAD_KG: f64 = 1e4;
    /// Largest payload centre-of-mass offset (m).
    pub const MAX_COM_M: f64 = 10.0;
    /// Largest force (N).
    pub const MAX_FORCE_N: f64 = 1e6;
    /// Largest moment (N·m).
    pub const MAX_MOMENT_NM: f64 = 1e6;
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
}

impl AbsoluteRow {
    /// The standard deviation used for weighting (m).
    pub fn sigma(&self) -> f64 {
        self.sigma_m.unwrap_or(DEFAULT_ABSOLUTE_SIGMA_M)
    }
}

/// A bad absolute measurement file. Nothing of a file with an error is used.
#[derive(Debug, Error)]
pub enum AbsoluteDataError {
    /// The file could not be read or written.
    #[error("{path}: {source}")]
    Io {
        /// File.
        path: String,
        /// Cause.
        source: std::io::Error,
    },
    /// A problem with the header.
    #[error("{path}: header: {message}")]
    Header {
        /// File.
        path: String,
        /// What is wrong.
        message: String,
    },
    /// A problem with one row.
    #[error("{path}:{line}: column `{column}`: {message}")]
    Row {
        /// File.
        path: String,
        /// 1-based line.
        line: u64,
        /// Column concerned.
        column: String,
        /// What is wrong.
        message: String,
    },
    /// The file as a whole cannot be used.
    #[error("{path}: {message}")]
    Content {
        /// File.
        path: String,
        /// What is wrong.
        message: String,
    },
}

const POSITION: [&str; 3] = ["x_m", "y_m", "z_m"];
const ORIENTATION: [&str; 3] = ["rx_rad", "ry_rad", "rz_rad"];
const PAYLOAD_COM: [&str; 3] = ["payload_com_x_m", "payload_com_y_m", "payload_com_z_m"];
const WRENCH: [&str; 6] = ["fx_N", "fy_N", "fz_N", "mx_Nm", "my_Nm", "mz_Nm"];

/// Read an absolute measurement file for a robot with `joint_count` joints.
pub fn read_absolute(
    path: &Path,
    joint_count: usize,
) -> Result<Vec<AbsoluteRow>, AbsoluteDataError> {
    let origin = path.display().to_string();
    let io = |source| AbsoluteDataError::Io {
        path: origin.clone(),
        source,
    };
    let size = std::fs::metadata(path).map_err(io)?.len();
    if size > limits::MAX_FILE_BYTES {
        return Err(AbsoluteDataError::Content {
            path: origin,
            message: format!(
                "{size} bytes is more than the {} bytes an absolute measurement file may have",
                limits::MAX_FILE_BYTES
            ),
        });
    }
    let text = std::fs::read_to_string(path).map_err(io)?;
    parse_absolute(&text, &origin, joint_count)
}

/// Parse absolute measurement CSV text; `origin` names the file in errors.
pub fn parse_absolute(
    text: &str,
    origin: &str,
    joint_count: usize,
) -> Result<Vec<AbsoluteRow>, AbsoluteDataError> {
    let header_error = |message: String| AbsoluteDataError::Header {
        path: origin.to_string(),
        message,
    };
    let mut reader = csv::ReaderBuilder::new()
        .trim(csv::Trim::All)
        .flexible(true)
        .comment(Some(b'#'))
        .from_reader(text.as_bytes());
    let headers = reader
        .headers()
        .map_err(|e| header_error(e.to_string()))?
        .clone();
    let mut index: HashMap<String, usize> = HashMap::new();
    for (i, name) in headers.iter().enumerate() {
        if index.insert(name.to_string(), i).is_some() {
            return Err(header_error(format!("column `{name}` appears twice")));
        }
    }
    let mut found = 0;
    while index.contains_key(&format!("q{}_rad", found + 1)) {
        found += 1;
    }
    if found != joint_count {
        return Err(header_error(format!(
            "the file has {found} joint columns (q1_rad…) but the robot has {joint_count} joints"
        )));
    }
    let mut required: Vec<&str> = vec!["setup", "target"];
    required.extend(POSITION);
    let missing: Vec<String> = required
        .iter()
        .filter(|c| !index.contains_key(**c))
        .map(|c| format!("`{c}`"))
        .collect();
    if !missing.is_empty() {
        return Err(header_error(format!(
            "missing column(s) {}",
            missing.join(", ")
        )));
    }
    let all_or_none = |group: &[&str]| -> Result<bool, AbsoluteDataError> {
        let present = group.iter().filter(|c| index.contains_key(**c)).count();
        if present != 0 && present != group.len() {
            return Err(header_error(format!(
                "columns {} go together: give all or none",
                group.join(", ")
            )));
        }
        Ok(present == group.len())
    };
    let has_orientation = all_or_none(&ORIENTATION)?;
    let has_payload_com = all_or_none(&PAYLOAD_COM)?;
    let has_wrench = all_or_none(&WRENCH)?;
    let width = headers.len();
    let mut rows = Vec::new();
    for record in reader.records() {
        let record = record.map_err(|e| AbsoluteDataError::Row {
            path: origin.to_string(),
            line: e.position().map(|p| p.line()).unwrap_or(0),
            column: "-".into(),
            message: e.to_string(),
        })?;
        let line = record.position().map(|p| p.line()).unwrap_or(0);
        if rows.len() >= limits::MAX_ROWS {
            return Err(AbsoluteDataError::Content {
                path: origin.to_string(),
                message: format!("more than {} rows", limits::MAX_ROWS),
            });
        }
        let error = |column: &str, message: String| AbsoluteDataError::Row {
            path: origin.to_string(),
            line,
            column: column.to_string(),
            message,
        };
        if record.len() != width {
            return Err(error(
                "-",
                format!(
                    "expected {width} fields as in the header, found {}",
                    record.len()
                ),
            ));
        }
        let text_of = |name: &str| index.get(name).and_then(|&i| record.get(i)).unwrap_or("");
        let number = |name: &str, limit: f64, unit: &str| -> Result<f64, AbsoluteDataError> {
            let text = text_of(name);
            let value: f64 = text
                .parse()
                .map_err(|_| error(name, format!("expected a number in {unit}, got \"{text}\"")))?;
            if !value.is_finite() || value.abs() > limit {
                return Err(error(
                    name,
                    format!("expected a finite value within ±{limit} {unit}, got {text}"),
                ));
            }
            Ok(value)
        };
        let optional =
            |name: &str, limit: f64, unit: &str| -> Result<Option<f64>, AbsoluteDataError> {
                if index.contains_key(name) && !text_of(name).is_empty() {
                    number(name, limit, unit).map(Some)
                } else {
                    Ok(None)
                }
            };
        let label = |name: &str| -> Result<String, AbsoluteDataError> {
            let text = text_of(name);
            if text.is_empty() {
                return Err(error(name, "empty label".into()));
            }
            if text.len() > limits::MAX_LABEL_BYTES {
                return Err(error(
                    name,
                    format!("label longer than {} bytes", limits::MAX_LABEL_BYTES),
                ));
            }
            Ok(text.to_string())
        };
        let positive = |value: Option<f64>, name: &str| -> Result<Option<f64>, AbsoluteDataError> {
            match value {
                Some(v) if v <= 0.0 => Err(error(name, format!("must be positive, got {v}"))),
                other => Ok(other),
            }
        };
        let q_rad = (1..=joint_count)
            .map(|i| number(&format!("q{i}_rad"), limits::MAX_JOINT_RAD, "rad"))
            .collect::<Result<Vec<_>, _>>()?;
        let mut position_m = [0.0; 3];
        for (v, name) in position_m.iter_mut().zip(POSITION) {
            *v = number(name, limits::MAX_POSITION_M, "m")?;
        }
        let config = if index.contains_key("config") && !text_of("config").is_empty() {
            Some(label("config")?)
        } else {
            None
        };
        let sigma_m = positive(optional("sigma_m", limits::MAX_SIGMA_M, "m")?, "sigma_m")?;
        let orientation = if has_orientation && !text_of(ORIENTATION[0]).is_empty() {
            let mut v = [0.0; 3];
            for (value, name) in v.iter_mut().zip(ORIENTATION) {
                *value = number(name, limits::MAX_ROTATION_RAD, "rad")?;
            }
            Some(RowOrientation {
                rotation_vector_rad: v,
                sigma_rad: positive(
                    optional("sigma_rad", limits::MAX_SIGMA_RAD, "rad")?,
                    "sigma_rad",
                )?,
            })
        } else {
            None
        };
        let payload = match optional("payload_kg", limits::MAX_PAYLOAD_KG, "kg")? {
            Some(mass) if mass < 0.0 => {
                return Err(error(
                    "payload_kg",
                    format!("must not be negative, got {mass}"),
                ));
            }
            Some(mass_kg) => {
                let mut com_m = [0.0; 3];
                if has_payload_com {
                    for (v, name) in com_m.iter_mut().zip(PAYLOAD_COM) {
                        *v = optional(name, limits::MAX_COM_M, "m")?.unwrap_or(0.0);
                    }
                }
                Some(RowPayload { mass_kg, com_m })
            }
            None => None,
        };
        let wrench = if has_wrench && !text_of(WRENCH[0]).is_empty() {
            let mut w = [0.0; 6];
            for (k, (value, name)) in w.iter_mut().zip(WRENCH).enumerate() {
                let (limit, unit) = if k < 3 {
                    (limits::MAX_FORCE_N, "N")
                } else {
                    (limits::MAX_MOMENT_NM, "N·m")
                };
                *value = number(name, limit, unit)?;
            }
            Some(w)
        } else {
            None
        };
        let temperature_c = match optional("temperature_C", 1e3, "°C")? {
            Some(t)
                if !(limits::TEMPERATURE_RANGE_C[0]..=limits::TEMPERATURE_RANGE_C[1])
                    .contains(&t) =>
            {
                return Err(error(
                    "temperature_C",
                    format!(
                        "expected {}…{} °C, got {t}",
                        limits::TEMPERATURE_RANGE_C[0],
                        limits::TEMPERATURE_RANGE_C[1]
                    ),
                ));
            }
            other => other,
        };
        rows.push(AbsoluteRow {
            line,
            setup: label("setup")?,
            target: label("target")?,
            config,
            q_rad,
            position_m,
            sigma_m,
            orientation,
            payload,
            wrench,
            temperature_c,
            time_s: optional("time_s", limits::MAX_TIME_S, "s")?,
        });
    }
    if rows.is_empty() {
        return Err(AbsoluteDataError::Content {
            path: origin.to_string(),
            message: "no data rows".into(),
        });
    }
    Ok(rows)
}

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
    let mut out = String::new();
    for comment in comments {
        for line in comment.lines() {
            out.push_str("# ");
            out.push_str(line);
            out.push('\n');
        }
    }
    let mut writer = csv::WriterBuilder::new().from_writer(Vec::new());
    let _ = writer.write_record(&header);
    let num = |v: f64| format!("{v:?}");
    let opt = |v: Option<f64>| v.map(num).unwrap_or_default();
    for row in rows {
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
        let _ = writer.write_record(&record);
    }
    out.push_str(&String::from_utf8(writer.into_inner().unwrap_or_default()).unwrap_or_default());
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

#[cfg(test)]
mod tests {
    use super::*;

    fn sample() -> Vec<AbsoluteRow> {
        vec![
            AbsoluteRow {
                line: 0,
                setup: "A".into(),
                target: "tmac".into(),
                config: Some("c1".into()),
                q_rad: vec![0.1, -1.2, 0.5, 0.0, 1.5, -0.25],
                position_m: [2.361, -1.3685, 0.1194],
                sigma_m: Some(2.1e-5),
                orientation: Some(RowOrientation {
                    rotation_vector_rad: [0.1, -0.2, 1.3],
                    sigma_rad: Some(3e-5),
                }),
                payload: Some(RowPayload {
                    mass_kg: 2.5,
                    com_m: [0.0, 0.01, 0.05],
                }),
                wrench: Some([0.0, 0.0, -100.0, 0.0, 1.0, 0.0]),
                temperature_c: Some(22.5),
                time_s: Some(1.5e9),
            },
            AbsoluteRow {
                line: 0,
                setup: "B".into(),
                target: "tmac".into(),
                config: None,
                q_rad: vec![0.0; 6],
                position_m: [1.0, 2.0, 3.0],
                sigma_m: None,
                orientation: None,
                payload: None,
                wrench: None,
                temperature_c: None,
                time_s: None,
            },
        ]
    }

    #[test]
    fn round_trip_is_exact() {
        let rows = sample();
        let text = format_absolute(&rows, &["made by a test".into()]);
        let mut back = parse_absolute(&text, "t.csv", 6).unwrap();
        assert_eq!(back[0].line, 3);
        for r in &mut back {
            r.line = 0;
        }
        assert_eq!(back, rows);
    }

    #[test]
    fn bad_values_name_line_and_column() {
        let text = format_absolute(&sample(), &[]);
        let cases = [
            ("2.361", "NaN", "x_m", "finite"),
            ("2.361", "1e9", "x_m", "within"),
            ("2.1e-5", "-1e-5", "sigma_m", "positive"),
            ("22.5", "900.0", "temperature_C", "°C"),
            ("2.5", "-2.5", "payload_kg", "negative"),
            ("-100.0", "12x", "fz_N", "expected a number"),
        ];
        for (from, to, column, words) in cases {
            let bad = text.replacen(from, to, 1);
            let err = parse_absolute(&bad, "t.csv", 6).unwrap_err().to_string();
            assert!(
                err.contains("t.csv:2") && err.contains(column) && err.contains(words),
                "{from}->{to}: {err}"
            );
        }
        let err = parse_absolute(&text, "t.csv", 7).unwrap_err().to_string();
        assert!(
            err.contains("6 joint columns") && err.contains("7 joints"),
            "{err}"
        );
        let err = parse_absolute(&text.replacen("ry_rad", "ryy", 1), "t.csv", 6)
            .unwrap_err()
            .to_string();
        assert!(err.contains("go together"), "{err}");
        let err = parse_absolute(
            &text.replacen(",B,", ",,", 1).replacen("\nB,", "\n,", 1),
            "t.csv",
            6,
        )
        .unwrap_err()
        .to_string();
        assert!(err.contains("t.csv:3") && err.contains("setup"), "{err}");
    }

    #[test]
    fn configurations_group_equal_joint_values() {
        let mut rows = sample();
        rows[0].config = None;
        rows.push(rows[1].clone());
        rows.push(rows[0].clone());
        let (index, count) = configuration_index(&rows);
        assert_eq!(count, 2);
        assert_eq!(index, vec![0, 1, 1, 0]);
    }
}
