//! Measurement and plan files (CSV, SI units, one row per measured point per load case).
//!
//! Columns, by exact name (order free): `load_case`, `q1_rad` … `qN_rad`,
//! `fx_N, fy_N, fz_N, mx_Nm, my_Nm, mz_Nm` (applied wrench, world axes, moment about the load
//! point), `load_link`, `load_x_m, load_y_m, load_z_m` (load point, world, unloaded pose),
//! `point`, `point_link`, `x_m, y_m, z_m` (measured point, world, unloaded),
//! `dx_m, dy_m, dz_m` (displacement, loaded − unloaded, world axes).
//! A plan is the same file without the displacement columns.
//!
//! Optional columns:
//!
//! | column | unit | meaning |
//! |---|---|---|
//! | `sigma_m` | m | standard deviation of each displacement component of this row (default [`DEFAULT_SIGMA_M`], 15 µm) |
//! | `drx_rad, dry_rad, drz_rad` | rad | measured small rotation of the measured point's link, loaded − unloaded, world axes (e.g. a 6-DoF tracker probe); all three or none per row |
//! | `sigma_rad` | rad | standard deviation of each rotation component of this row (default [`DEFAULT_SIGMA_RAD`], 20 µrad); only used on rows with a rotation |
//! | `purpose` | – | free text (plans) |
//!
//! Rows with a rotation add three rotation equations to the calibration, weighted by
//! `1/sigma_rad`; rows without one are used exactly as before. Cells of optional columns may be
//! left empty.
//!
//! **Header comments.** Lines starting with `#` are comments. Those before the column names may
//! say which robot the file was made for ([`FileHeader`]): `# robot: <name>` and
//! `# geometry: <16 hex digits>` (`Robot::geometry_fingerprint`). Plans and simulated
//! measurements carry them; `calibrate` and `validate` compare them with the robot they are
//! given (see [`crate::consistency`]).
//!
//! **Bounds.** Every number must be finite and within a physical bound, checked with the line
//! and column named: joint values ±[`MAX_JOINT_RAD`], forces ±[`MAX_FORCE_N`], moments
//! ±[`MAX_MOMENT_NM`], coordinates ±[`MAX_COORDINATE_M`], displacements ±[`MAX_DISPLACEMENT_M`],
//! rotations ±[`MAX_ROTATION_RAD`], `sigma_m` in [[`MIN_SIGMA_M`], [`MAX_SIGMA_M`]], `sigma_rad`
//! in [[`MIN_SIGMA_RAD`], [`MAX_SIGMA_RAD`]]; labels at most [`MAX_LABEL_CHARS`] characters; a file at most
//! [`MAX_FILE_BYTES`] bytes and [`MAX_ROWS`] rows.
//!
//! [`DEFAULT_SIGMA_M`]: crate::design::DEFAULT_SIGMA_M
//! [`DEFAULT_SIGMA_RAD`]: crate::design::DEFAULT_SIGMA_RAD

mod bounds;
mod header;

use bounds::{
    DISPLACEMENT_COLUMNS, LOAD_POINT_COLUMNS, POINT_COLUMNS, ROTATION_COLUMNS, WRENCH_COLUMNS,
    column_bound,
};
pub use bounds::{
    MAX_COORDINATE_M, MAX_DISPLACEMENT_M, MAX_FILE_BYTES, MAX_FORCE_N, MAX_JOINT_RAD,
    MAX_LABEL_CHARS, MAX_MOMENT_NM, MAX_ROTATION_RAD, MAX_ROWS, MAX_SIGMA_M, MAX_SIGMA_RAD,
    MIN_SIGMA_M, MIN_SIGMA_RAD, check_row_values,
};
pub use header::FileHeader;

use deflex_model::Robot;
use std::collections::HashMap;
use std::path::Path;
use thiserror::Error;

/// One measured (or planned) point under one load case.
#[derive(Clone, Debug, PartialEq)]
pub struct MeasurementRow {
    /// Load-case label; rows sharing it share configuration and load.
    pub load_case: String,
    /// Joint values (rad).
    pub q_rad: Vec<f64>,
    /// Applied wrench `[fx, fy, fz, mx, my, mz]` (N, N·m), world axes, moment about the load point.
    pub wrench: [f64; 6],
    /// Link carrying the load (0 = base … N = last link).
    pub load_link: usize,
    /// Load point, world coordinates in the unloaded pose (m).
    pub load_point_m: [f64; 3],
    /// Point label (`TCP`, `M1`, …).
    pub point: String,
    /// Link carrying the measured point.
    pub point_link: usize,
    /// Measured point, world coordinates in the unloaded pose (m).
    pub point_m: [f64; 3],
    /// Displacement loaded − unloaded, world axes (m). `None` in a plan.
    pub displacement_m: Option<[f64; 3]>,
    /// Measurement standard deviation for this row (m).
    pub sigma_m: Option<f64>,
    /// Measured small rotation of the point's link (rad), when orientation was measured, with
    /// its standard deviation.
    pub rotation_rad: Option<MeasuredRotation>,
    /// Why this row is in a plan (free text).
    pub purpose: Option<String>,
}

/// A measured small rotation (columns `drx_rad, dry_rad, drz_rad` and `sigma_rad`).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct MeasuredRotation {
    /// Rotation vector loaded − unloaded of the measured point's link, world axes (rad).
    pub value_rad: [f64; 3],
    /// Standard deviation of each component (rad); `None` = [`crate::design::DEFAULT_SIGMA_RAD`].
    pub sigma_rad: Option<f64>,
}

impl MeasuredRotation {
    /// A rotation with the default standard deviation.
    pub fn new(value_rad: [f64; 3]) -> MeasuredRotation {
        MeasuredRotation {
            value_rad,
            sigma_rad: None,
        }
    }

    /// The standard deviation used for weighting (rad).
    pub fn sigma(&self) -> f64 {
        self.sigma_rad.unwrap_or(crate::design::DEFAULT_SIGMA_RAD)
    }
}
/// A measurement or plan file as read: its header, its rows and the line of each row.
#[derive(Clone, Debug, PartialEq)]
pub struct MeasurementFile {
    /// The header comments.
    pub header: FileHeader,
    /// The rows.
    pub rows: Vec<MeasurementRow>,
    /// 1-based line number of each row in the file.
    pub lines: Vec<u64>,
}

/// A bad measurement or plan file. Nothing of a file with an error is used.
#[derive(Debug, Error)]
pub enum DataError {
    /// The file could not be read or written.
    #[error("{path}: {source}")]
    Io {
        /// File.
        path: String,
        /// Cause.
        source: std::io::Error,
    },
    /// A problem with the header (missing or duplicate column).
    #[error("{path}: header: {message}")]
    Header {
        /// File.
        path: String,
        /// What is wrong.
        message: String,
    },
    /// A problem with one row.
    #[error("{path}:{line}: {message}")]
    Row {
        /// File.
        path: String,
        /// 1-based line number in the file.
        line: u64,
        /// What is wrong, naming the column.
        message: String,
    },
    /// The data as a whole cannot be used.
    #[error("{path}: {message}")]
    Content {
        /// File.
        path: String,
        /// What is wrong.
        message: String,
    },
}

/// Read a measurement (or plan) file for a robot with `joint_count` joints: like
/// [`read_measurements`] / [`read_plan`], but a file written for a different joint count is
/// reported as such ("the data has 5 joint columns … but the robot has 6 joints") before any
/// row-level check.
pub fn read_for_robot(
    path: &Path,
    joint_count: usize,
    require_displacement: bool,
) -> Result<Vec<MeasurementRow>, DataError> {
    Ok(read_file(path, Some(joint_count), require_displacement)?.rows)
}

/// Read a measurement (or plan) file with its header comments and row line numbers. With
/// `joint_count`, a file written for another joint count is reported as such before any
/// row-level check. Files over [`MAX_FILE_BYTES`] are not read.
pub fn read_file(
    path: &Path,
    joint_count: Option<usize>,
    require_displacement: bool,
) -> Result<MeasurementFile, DataError> {
    let text = read_text(path)?;
    let origin = path.display().to_string();
    if let Some(joint_count) = joint_count {
        check_joint_columns(&text, &origin, joint_count)?;
    }
    parse_file(&text, &origin, require_displacement)
}

fn read_text(path: &Path) -> Result<String, DataError> {
    let origin = path.display().to_string();
    let io = |source| DataError::Io {
        path: origin.clone(),
        source,
    };
    let size = std::fs::metadata(path).map_err(io)?.len();
    if size > MAX_FILE_BYTES {
        return Err(DataError::Content {
            path: origin,
            message: format!(
                "{size} bytes is more than the {MAX_FILE_BYTES} bytes a measurement file may have"
            ),
        });
    }
    std::fs::read_to_string(path).map_err(io)
}

fn check_joint_columns(text: &str, origin: &str, joint_count: usize) -> Result<(), DataError> {
    let header = text
        .lines()
        .find(|l| !l.trim_start().starts_with('#'))
        .unwrap_or("");
    let names: Vec<&str> = header.split(',').map(str::trim).collect();
    let mut found = 0;
    while names.contains(&format!("q{}_rad", found + 1).as_str()) {
        found += 1;
    }
    if found > 0 && found != joint_count {
        return Err(DataError::Content {
            path: origin.to_string(),
            message: format!(
                "the data has {found} joint columns (q1_rad…q{found}_rad) but the robot has {joint_count} joints"
            ),
        });
    }
    Ok(())
}

/// Read a measurement file: every row must carry the displacement columns.
pub fn read_measurements(path: &Path) -> Result<Vec<MeasurementRow>, DataError> {
    read_rows(path, true)
}

/// Read a plan file: displacement columns are not expected (ignored if present).
pub fn read_plan(path: &Path) -> Result<Vec<MeasurementRow>, DataError> {
    read_rows(path, false)
}

/// Parse measurement or plan CSV text. `origin` names the file in errors.
pub fn parse_rows(
    text: &str,
    origin: &str,
    require_displacement: bool,
) -> Result<Vec<MeasurementRow>, DataError> {
    Ok(parse_file(text, origin, require_displacement)?.rows)
}

/// Parse measurement or plan CSV text with its header comments and the line of every row.
/// `origin` names the file in errors.
pub fn parse_file(
    text: &str,
    origin: &str,
    require_displacement: bool,
) -> Result<MeasurementFile, DataError> {
    let header_error = |message: String| DataError::Header {
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
    let mut index: HashMap<&str, usize> = HashMap::new();
    for (i, name) in headers.iter().enumerate() {
        if index.insert(name, i).is_some() {
            return Err(header_error(format!("column `{name}` appears twice")));
        }
    }
    let mut joint_count = 0;
    while index.contains_key(format!("q{}_rad", joint_count + 1).as_str()) {
        joint_count += 1;
    }
    if joint_count == 0 {
        return Err(header_error(
            "no joint columns: expected q1_rad, q2_rad, …".into(),
        ));
    }
    let mut required: Vec<String> = vec![
        "load_case".into(),
        "load_link".into(),
        "point".into(),
        "point_link".into(),
    ];
    required.extend(
        WRENCH_COLUMNS
            .iter()
            .chain(&LOAD_POINT_COLUMNS)
            .chain(&POINT_COLUMNS)
            .map(|s| s.to_string()),
    );
    if require_displacement {
        required.extend(DISPLACEMENT_COLUMNS.iter().map(|s| s.to_string()));
    }
    let missing: Vec<&String> = required
        .iter()
        .filter(|c| !index.contains_key(c.as_str()))
        .collect();
    if !missing.is_empty() {
        return Err(header_error(format!(
            "missing column(s) {}",
            missing
                .iter()
                .map(|s| format!("`{s}`"))
                .collect::<Vec<_>>()
                .join(", ")
        )));
    }
    let has_displacement = DISPLACEMENT_COLUMNS.iter().all(|c| index.contains_key(c));
    let has_rotation = ROTATION_COLUMNS.iter().all(|c| index.contains_key(c));
    let width = headers.len();
    let mut rows = Vec::new();
    let mut lines = Vec::new();
    for record in reader.records() {
        let record = record.map_err(|e| DataError::Row {
            path: origin.to_string(),
            line: e.position().map(|p| p.line()).unwrap_or(0),
            message: e.to_string(),
        })?;
        let line = record.position().map(|p| p.line()).unwrap_or(0);
        let row_error = |message: String| DataError::Row {
            path: origin.to_string(),
            line,
            message,
        };
        if record.len() != width {
            return Err(row_error(format!(
                "expected {width} fields as in the header, found {}",
                record.len()
            )));
        }
        if rows.len() >= MAX_ROWS {
            return Err(row_error(format!(
                "more than {MAX_ROWS} data rows: split the campaign"
            )));
        }
        let text_of = |name: &str| record.get(index[name]).unwrap_or("");
        let number = |name: &str| -> Result<f64, DataError> {
            let text = text_of(name);
            let value: f64 = text.parse().map_err(|_| {
                row_error(format!(
                    "column `{name}`: expected a number, got \"{}\"",
                    text.chars().take(40).collect::<String>()
                ))
            })?;
            if !value.is_finite() {
                return Err(row_error(format!(
                    "column `{name}`: value must be finite, got {}",
                    text.chars().take(40).collect::<String>()
                )));
            }
            let (limit, unit) = column_bound(name);
            if value.abs() > limit {
                return Err(row_error(format!(
                    "column `{name}`: {value:e} {unit} is beyond the ±{limit:e} {unit} a file may hold"
                )));
            }
            Ok(value)
        };
        let link = |name: &str| -> Result<usize, DataError> {
            let text = text_of(name);
            let value: usize = text.parse().map_err(|_| {
                row_error(format!(
                    "column `{name}`: expected a link index 0..={joint_count}, got \"{text}\""
                ))
            })?;
            if value > joint_count {
                return Err(row_error(format!(
                    "column `{name}`: link {value} does not exist (0 = base … {joint_count} = last link)"
                )));
            }
            Ok(value)
        };
        let triple = |names: &[&str; 3]| -> Result<[f64; 3], DataError> {
            Ok([number(names[0])?, number(names[1])?, number(names[2])?])
        };
        let q_rad = (1..=joint_count)
            .map(|i| number(&format!("q{i}_rad")))
            .collect::<Result<Vec<_>, _>>()?;
        let mut wrench = [0.0; 6];
        for (value, name) in wrench.iter_mut().zip(WRENCH_COLUMNS) {
            *value = number(name)?;
        }
        let label = |name: &str| -> Result<String, DataError> {
            let text = text_of(name);
            if text.is_empty() {
                return Err(row_error(format!("column `{name}`: empty label")));
            }
            if text.chars().count() > MAX_LABEL_CHARS {
                return Err(row_error(format!(
                    "column `{name}`: a label of more than {MAX_LABEL_CHARS} characters"
                )));
            }
            Ok(text.to_string())
        };
        let load_case = label("load_case")?;
        let point = label("point")?;
        let optional_number = |name: &str| -> Result<Option<f64>, DataError> {
            match index.get(name) {
                Some(_) if !text_of(name).is_empty() => number(name).map(Some),
                _ => Ok(None),
            }
        };
        let sigma_m = optional_number("sigma_m")?;
        if let Some(sigma) = sigma_m
            && !(MIN_SIGMA_M..=MAX_SIGMA_M).contains(&sigma)
        {
            return Err(row_error(format!(
                "column `sigma_m`: must be positive, from {MIN_SIGMA_M:e} to {MAX_SIGMA_M} m, got {sigma}"
            )));
        }
        let displacement_m =
            if has_displacement && (require_displacement || !text_of("dx_m").is_empty()) {
                Some(triple(&DISPLACEMENT_COLUMNS)?)
            } else {
                None
            };
        let rotation_rad = if has_rotation && !text_of("drx_rad").is_empty() {
            let sigma_rad = optional_number("sigma_rad")?;
            if let Some(sigma) = sigma_rad
                && !(MIN_SIGMA_RAD..=MAX_SIGMA_RAD).contains(&sigma)
            {
                return Err(row_error(format!(
                    "column `sigma_rad`: must be positive, from {MIN_SIGMA_RAD:e} to {MAX_SIGMA_RAD} rad, got {sigma}"
                )));
            }
            Some(MeasuredRotation {
                value_rad: triple(&ROTATION_COLUMNS)?,
                sigma_rad,
            })
        } else {
            None
        };
        let purpose = index
            .get("purpose")
            .map(|_| {
                text_of("purpose")
                    .chars()
                    .take(MAX_LABEL_CHARS)
                    .collect::<String>()
            })
            .filter(|s| !s.is_empty());
        rows.push(MeasurementRow {
            load_case,
            q_rad,
            wrench,
            load_link: link("load_link")?,
            load_point_m: triple(&LOAD_POINT_COLUMNS)?,
            point,
            point_link: link("point_link")?,
            point_m: triple(&POINT_COLUMNS)?,
            displacement_m,
            sigma_m,
            rotation_rad,
            purpose,
        });
        lines.push(line);
    }
    if rows.is_empty() {
        return Err(DataError::Content {
            path: origin.to_string(),
            message: "no data rows".into(),
        });
    }
    Ok(MeasurementFile {
        header: FileHeader::parse(text),
        rows,
        lines,
    })
}

fn read_rows(path: &Path, require_displacement: bool) -> Result<Vec<MeasurementRow>, DataError> {
    Ok(read_file(path, None, require_displacement)?.rows)
}

/// Number of distinct load cases among `rows`.
pub fn load_case_count(rows: &[MeasurementRow]) -> usize {
    rows.iter()
        .map(|r| r.load_case.as_str())
        .collect::<std::collections::BTreeSet<_>>()
        .len()
}

/// Format rows as CSV text (full precision). Displacement, `sigma_m`, rotation, `sigma_rad` and
/// purpose columns are written when any row has them.
pub fn format_rows(rows: &[MeasurementRow]) -> String {
    let joint_count = rows.first().map(|r| r.q_rad.len()).unwrap_or(0);
    let with_displacement = rows.iter().any(|r| r.displacement_m.is_some());
    let with_sigma = rows.iter().any(|r| r.sigma_m.is_some());
    let with_rotation = rows.iter().any(|r| r.rotation_rad.is_some());
    let with_sigma_rad = rows
        .iter()
        .any(|r| r.rotation_rad.is_some_and(|m| m.sigma_rad.is_some()));
    let with_purpose = rows.iter().any(|r| r.purpose.is_some());
    let mut header: Vec<String> = vec!["load_case".into()];
    header.extend((1..=joint_count).map(|i| format!("q{i}_rad")));
    header.extend(WRENCH_COLUMNS.iter().map(|s| s.to_string()));
    header.push("load_link".into());
    header.extend(LOAD_POINT_COLUMNS.iter().map(|s| s.to_string()));
    header.extend(["point".to_string(), "point_link".to_string()]);
    header.extend(POINT_COLUMNS.iter().map(|s| s.to_string()));
    if with_displacement {
        header.extend(DISPLACEMENT_COLUMNS.iter().map(|s| s.to_string()));
    }
    if with_sigma {
        header.push("sigma_m".into());
    }
    if with_rotation {
        header.extend(ROTATION_COLUMNS.iter().map(|s| s.to_string()));
    }
    if with_sigma_rad {
        header.push("sigma_rad".into());
    }
    if with_purpose {
        header.push("purpose".into());
    }
    let mut writer = csv::WriterBuilder::new().from_writer(Vec::new());
    let _ = writer.write_record(&header);
    let num = |v: f64| format!("{v:e}");
    for row in rows {
        let mut record: Vec<String> = vec![row.load_case.clone()];
        record.extend(row.q_rad.iter().map(|v| format!("{v:?}")));
        record.extend(row.wrench.iter().map(|v| format!("{v:?}")));
        record.push(row.load_link.to_string());
        record.extend(row.load_point_m.iter().map(|v| format!("{v:?}")));
        record.push(row.point.clone());
        record.push(row.point_link.to_string());
        record.extend(row.point_m.iter().map(|v| format!("{v:?}")));
        if with_displacement {
            match row.displacement_m {
                Some(d) => record.extend(d.iter().map(|v| num(*v))),
                None => record.extend(["".to_string(), "".to_string(), "".to_string()]),
            }
        }
        if with_sigma {
            record.push(row.sigma_m.map(num).unwrap_or_default());
        }
        if with_rotation {
            match row.rotation_rad {
                Some(r) => record.extend(r.value_rad.iter().map(|v| num(*v))),
                None => record.extend(["".to_string(), "".to_string(), "".to_string()]),
            }
        }
        if with_sigma_rad {
            record.push(
                row.rotation_rad
                    .and_then(|r| r.sigma_rad)
                    .map(num)
                    .unwrap_or_default(),
            );
        }
        if with_purpose {
            record.push(row.purpose.clone().unwrap_or_default());
        }
        let _ = writer.write_record(&record);
    }
    String::from_utf8(writer.into_inner().unwrap_or_default()).unwrap_or_default()
}

/// Write rows to a CSV file (see [`format_rows`]), whole or not at all.
pub fn write_rows(path: &Path, rows: &[MeasurementRow]) -> Result<(), DataError> {
    write_text(path, &format_rows(rows))
}

/// [`format_rows`] after a header naming the robot the rows were made for (`# robot: …`,
/// `# geometry: …`, see [`FileHeader`]), preceded by `notes` as comment lines (e.g.
/// `SIMULATED …`).
pub fn format_rows_for(robot: &Robot, rows: &[MeasurementRow], notes: &[&str]) -> String {
    format_rows_with_header(&FileHeader::for_robot(robot), rows, notes)
}

/// [`format_rows`] after `notes` and the robot lines of `robot_lines` (e.g. the header of the
/// plan the rows measured, so the file names the robot its coordinates were made for).
pub fn format_rows_with_header(
    robot_lines: &FileHeader,
    rows: &[MeasurementRow],
    notes: &[&str],
) -> String {
    let mut header = FileHeader::default();
    for note in notes {
        header = header.with_note(*note);
    }
    header.robot = robot_lines.robot.clone();
    header.geometry = robot_lines.geometry.clone();
    format!("{}{}", header.render(), format_rows(rows))
}

/// Write rows for `robot` ([`format_rows_for`]) to a CSV file, whole or not at all.
pub fn write_rows_for(
    path: &Path,
    robot: &Robot,
    rows: &[MeasurementRow],
    notes: &[&str],
) -> Result<(), DataError> {
    write_text(path, &format_rows_for(robot, rows, notes))
}

fn write_text(path: &Path, text: &str) -> Result<(), DataError> {
    deflex_files::write_atomic(path, text).map_err(|source| DataError::Io {
        path: path.display().to_string(),
        source,
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    fn sample() -> Vec<MeasurementRow> {
        vec![MeasurementRow {
            load_case: "L1".into(),
            q_rad: vec![0.0, std::f64::consts::FRAC_PI_2, 0.0, 0.0, 0.0, 0.0],
            wrench: [0.0, 1400.0, 0.0, 0.0, 0.0, 0.0],
            load_link: 6,
            load_point_m: [2.194, 0.0, 0.0],
            point: "M2, elbow".into(),
            point_link: 3,
            point_m: [1.2, 0.1, 0.0],
            displacement_m: Some([1.25e-4, -3.5e-4, 2e-6]),
            sigma_m: Some(1.5e-5),
            rotation_rad: None,
            purpose: Some("J1.z".into()),
        }]
    }

    #[test]
    fn round_trip_is_exact() {
        let rows = sample();
        let text = format_rows(&rows);
        assert_eq!(parse_rows(&text, "t.csv", true).unwrap(), rows);
    }

    #[test]
    fn bad_rows_name_line_and_column() {
        let text = format_rows(&sample());
        let bad = text.replace("1400.0", "NaN");
        let err = parse_rows(&bad, "t.csv", true).unwrap_err().to_string();
        assert!(err.contains("t.csv:2") && err.contains("fy_N"), "{err}");
        let bad = text.replace("1400.0", "12x");
        let err = parse_rows(&bad, "t.csv", true).unwrap_err().to_string();
        assert!(
            err.contains("expected a number") && err.contains("\"12x\""),
            "{err}"
        );
        let short = format!("{}{}", text, "L2,0,0\n");
        let err = parse_rows(&short, "t.csv", true).unwrap_err().to_string();
        assert!(err.contains("t.csv:3") && err.contains("fields"), "{err}");
        let no_dx = text.replacen("dx_m", "dq_m", 1);
        let err = parse_rows(&no_dx, "t.csv", true).unwrap_err().to_string();
        assert!(
            err.contains("missing column") && err.contains("dx_m"),
            "{err}"
        );
        let bad_link = text.replace(",6,2.194", ",9,2.194");
        let err = parse_rows(&bad_link, "t.csv", true)
            .unwrap_err()
            .to_string();
        assert!(
            err.contains("load_link") && err.contains("does not exist"),
            "{err}"
        );
    }

    #[test]
    fn plan_needs_no_displacement() {
        let mut rows = sample();
        rows[0].displacement_m = None;
        rows[0].sigma_m = None;
        let text = format_rows(&rows);
        assert!(!text.contains("dx_m"));
        assert_eq!(parse_rows(&text, "p.csv", false).unwrap(), rows);
        assert!(parse_rows(&text, "p.csv", true).is_err());
    }

    #[test]
    fn rotation_and_sigma_rad_round_trip() {
        let mut rows = sample();
        rows.push(rows[0].clone());
        rows.push(rows[0].clone());
        rows[0].rotation_rad = Some(MeasuredRotation {
            value_rad: [1.25e-5, -3.0e-6, 7.1e-7],
            sigma_rad: Some(2.5e-5),
        });
        rows[1].rotation_rad = Some(MeasuredRotation::new([-2e-6, 0.0, 4.5e-5]));
        rows[2].point = "TCP".into();
        let text = format_rows(&rows);
        let header = text.lines().next().unwrap();
        assert!(
            header.ends_with("drx_rad,dry_rad,drz_rad,sigma_rad,purpose"),
            "{header}"
        );
        let back = parse_rows(&text, "t.csv", true).unwrap();
        assert_eq!(back, rows);
        assert_eq!(back[0].rotation_rad.unwrap().sigma(), 2.5e-5);
        assert_eq!(
            back[1].rotation_rad.unwrap().sigma(),
            crate::design::DEFAULT_SIGMA_RAD
        );
        // Without any sigma_rad the column is not written.
        rows[0].rotation_rad = Some(MeasuredRotation::new([1.0e-5, 0.0, 0.0]));
        let text = format_rows(&rows);
        assert!(!text.contains("sigma_rad") && text.contains("drz_rad"));
        assert_eq!(parse_rows(&text, "t.csv", true).unwrap(), rows);
        // A bad sigma_rad names the column.
        let mut rows = sample();
        rows[0].rotation_rad = Some(MeasuredRotation {
            value_rad: [0.0; 3],
            sigma_rad: Some(-1.0),
        });
        let err = parse_rows(&format_rows(&rows), "t.csv", true)
            .unwrap_err()
            .to_string();
        assert!(
            err.contains("sigma_rad") && err.contains("positive"),
            "{err}"
        );
    }
}
