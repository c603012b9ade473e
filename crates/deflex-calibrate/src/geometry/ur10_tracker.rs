//! Importer for the public UR10 laser-tracker data set (Landgraf, Ernst, Schleth, Fabritius,
//! Huber, "A Hybrid Neural Network Approach for Increasing the Absolute Accuracy of Industrial
//! Robots", IEEE CASE 2021; data: github.com/christianlandgraf/ipa-robot-accuracy, MIT licence).
//!
//! The series files (`measurements_*.csv`) are `;`-separated with decimal commas. Used columns:
//! the six UR joint angles `shoulder_pan_joint` … `wrist_3_joint` (rad, the DH model's joint
//! values), `measurement_x/y/z` (mm, the T-Mac probe in the tracker frame),
//! `measurement_rx/ry/rz` (deg, intrinsic X-Y-Z: `R = Rx·Ry·Rz`), optional
//! `measurement_std_x/y/z` (mm), `measurement_temperature` (°C) and `Timestamp`
//! (`yyyymmddhhmmss`; Series B's were turned into `2,02011E+13` by a spreadsheet and are left
//! out). The `Goal` columns (the commanded pose of the planned point in the ROS `base_link`
//! frame) are not measurements and are not imported.

use crate::geometry::data::{AbsoluteRow, RowOrientation};
use nalgebra::{Rotation3, Vector3};
use std::path::PathBuf;
use thiserror::Error;

/// The UR joint columns, base to flange.
pub const JOINT_COLUMNS: [&str; 6] = [
    "shoulder_pan_joint",
    "shoulder_lift_joint",
    "elbow_joint",
    "wrist_1_joint",
    "wrist_2_joint",
    "wrist_3_joint",
];

/// Largest series file a caller should read (bytes).
pub const MAX_SERIES_BYTES: u64 = 256 << 20;

/// A series file that cannot be imported.
#[derive(Debug, Error)]
pub enum ImportError {
    /// Bad header.
    #[error("{path}: header: {problem}")]
    Header {
        /// File.
        path: String,
        /// What is wrong.
        problem: SeriesHeaderProblem,
    },
    /// Bad row.
    #[error("{path}:{line}: column `{column}`: {problem}")]
    Row {
        /// File.
        path: String,
        /// 1-based line.
        line: usize,
        /// Column (`-`: the line as a whole).
        column: String,
        /// What is wrong.
        problem: SeriesRowProblem,
    },
}

/// What is wrong with a series header.
#[derive(Debug, Error)]
pub enum SeriesHeaderProblem {
    /// Nothing in the file.
    #[error("empty file")]
    Empty,
    /// A required column is missing.
    #[error("missing column `{0}`")]
    Missing(&'static str),
    /// A header and no data.
    #[error("no data rows")]
    NoRows,
}

/// What is wrong with a series row.
#[derive(Debug, Error)]
pub enum SeriesRowProblem {
    /// More rows than the absolute format allows.
    #[error("more than {0} rows")]
    TooManyRows(usize),
    /// Not as many fields as the header.
    #[error("expected {expected} fields, found {found}")]
    FieldCount {
        /// Header width.
        expected: usize,
        /// Fields found.
        found: usize,
    },
    /// Not a decimal-comma number within the bound.
    #[error("expected a decimal-comma number within ±{limit}, got \"{text}\"")]
    Number {
        /// The cell.
        text: String,
        /// The bound.
        limit: f64,
    },
}

/// What the import found besides the rows.
#[derive(Clone, Debug, PartialEq)]
pub struct ImportSummary {
    /// File read.
    pub file: PathBuf,
    /// Rows imported.
    pub rows: usize,
    /// Rows whose time stamp could not be read (mangled) and was left out.
    pub rows_without_time: usize,
    /// Whether the file had per-reading standard deviations.
    pub has_tracker_std: bool,
    /// Median of the per-reading position standard deviation (m), when present.
    pub median_tracker_std_m: Option<f64>,
    /// Temperature range (°C), when present.
    pub temperature_range_c: Option<[f64; 2]>,
}

/// Options of the import.
#[derive(Clone, Debug)]
pub struct ImportOptions {
    /// Set-up label written on every row.
    pub setup: String,
    /// Target label written on every row.
    pub target: String,
    /// Write the tracker's per-reading standard deviation into `sigma_m` (RMS of the three
    /// axes). Off by default: where the model error (≈ 0.4 mm) dwarfs the tracker noise
    /// (≈ 20 µm), weighting rows by the tracker's own noise figure would weight them
    /// arbitrarily.
    pub tracker_sigma: bool,
}

/// A decimal-comma number (`-0,5`, `2,02011E+13`).
fn decimal_comma(text: &str) -> Option<f64> {
    let value: f64 = text.trim().replace(',', ".").parse().ok()?;
    value.is_finite().then_some(value)
}

/// Seconds since 1970-01-01 of a `yyyymmddhhmmss` stamp (UTC assumed; only differences are
/// used).
fn timestamp_seconds(text: &str) -> Option<f64> {
    let t = text.trim();
    if t.len() != 14 || !t.bytes().all(|b| b.is_ascii_digit()) {
        return None;
    }
    let field = |a: usize, b: usize| t[a..b].parse::<i64>().ok();
    let (y, m, d) = (field(0, 4)?, field(4, 6)?, field(6, 8)?);
    let (hh, mm, ss) = (field(8, 10)?, field(10, 12)?, field(12, 14)?);
    if !(1..=12).contains(&m) || !(1..=31).contains(&d) || hh > 23 || mm > 59 || ss > 60 {
        return None;
    }
    // Days from civil (H. Hinnant's algorithm).
    let y = if m <= 2 { y - 1 } else { y };
    let era = y.div_euclid(400);
    let yoe = y - era * 400;
    let mp = (m + 9) % 12;
    let doy = (153 * mp + 2) / 5 + d - 1;
    let doe = yoe * 365 + yoe / 4 - yoe / 100 + doy;
    let days = era * 146_097 + doe - 719_468;
    Some((days * 86_400 + hh * 3600 + mm * 60 + ss) as f64)
}

/// Where the used columns sit in a series header.
struct SeriesColumns {
    width: usize,
    names: Vec<String>,
    joints: Vec<usize>,
    position: [usize; 3],
    position_std: Option<[usize; 3]>,
    rotation: Option<[usize; 3]>,
    rotation_std: Option<[usize; 3]>,
    temperature: Option<usize>,
    timestamp: Option<usize>,
}

impl SeriesColumns {
    fn of(header: &str, origin: &str) -> Result<SeriesColumns, ImportError> {
        let names: Vec<String> = header.split(';').map(|n| n.trim().to_string()).collect();
        let column = |name: &str| names.iter().position(|n| n == name);
        let require = |name: &'static str| {
            column(name).ok_or_else(|| ImportError::Header {
                path: origin.into(),
                problem: SeriesHeaderProblem::Missing(name),
            })
        };
        let group = |three: [&str; 3]| -> Option<[usize; 3]> {
            Some([column(three[0])?, column(three[1])?, column(three[2])?])
        };
        Ok(SeriesColumns {
            joints: JOINT_COLUMNS
                .iter()
                .map(|n| require(n))
                .collect::<Result<Vec<_>, _>>()?,
            position: [
                require("measurement_x")?,
                require("measurement_y")?,
                require("measurement_z")?,
            ],
            position_std: group([
                "measurement_std_x",
                "measurement_std_y",
                "measurement_std_z",
            ]),
            rotation: group(["measurement_rx", "measurement_ry", "measurement_rz"]),
            rotation_std: group([
                "measurement_std_rx",
                "measurement_std_ry",
                "measurement_std_rz",
            ]),
            temperature: column("measurement_temperature"),
            timestamp: column("Timestamp"),
            width: names.len(),
            names,
        })
    }
}

/// One series line, split, with its checked numbers.
struct SeriesLine<'a> {
    fields: Vec<&'a str>,
    columns: &'a SeriesColumns,
    origin: &'a str,
    line: usize,
}

impl SeriesLine<'_> {
    fn number(&self, i: usize, limit: f64) -> Result<f64, ImportError> {
        decimal_comma(self.fields[i])
            .filter(|v| v.abs() <= limit)
            .ok_or_else(|| ImportError::Row {
                path: self.origin.into(),
                line: self.line,
                column: self.columns.names[i].clone(),
                problem: SeriesRowProblem::Number {
                    text: self.fields[i].to_string(),
                    limit,
                },
            })
    }

    /// RMS over three columns (mm or deg in the file) times `unit`.
    fn rms(&self, three: [usize; 3], unit: f64) -> Result<f64, ImportError> {
        let mut sum = 0.0;
        for i in three {
            sum += (self.number(i, 1e3)? * unit).powi(2);
        }
        Ok((sum / 3.0).sqrt())
    }

    fn orientation(&self, tracker_sigma: bool) -> Result<Option<RowOrientation>, ImportError> {
        let Some(rotation) = self.columns.rotation else {
            return Ok(None);
        };
        let mut angles = [0.0; 3];
        for (v, i) in angles.iter_mut().zip(rotation) {
            *v = self.number(i, 720.0)?.to_radians();
        }
        // Intrinsic X-Y-Z (checked on the data: the probe's orientation in the flange frame
        // then stays constant to 1 mrad over Series A, against 0.2–0.7 rad for the other orders).
        let r = Rotation3::from_axis_angle(&Vector3::x_axis(), angles[0])
            * Rotation3::from_axis_angle(&Vector3::y_axis(), angles[1])
            * Rotation3::from_axis_angle(&Vector3::z_axis(), angles[2]);
        let v = deflex_model::spatial::rotation_log(&r);
        let sigma_rad = match (tracker_sigma, self.columns.rotation_std) {
            (true, Some(three)) => Some(self.rms(three, 1f64.to_radians())?).filter(|s| *s > 0.0),
            _ => None,
        };
        Ok(Some(RowOrientation {
            rotation_vector_rad: [v.x, v.y, v.z],
            sigma_rad,
        }))
    }

    fn row(&self, options: &ImportOptions) -> Result<(AbsoluteRow, Option<f64>), ImportError> {
        let c = self.columns;
        let q_rad = c
            .joints
            .iter()
            .map(|&i| self.number(i, crate::measurements::MAX_JOINT_RAD))
            .collect::<Result<Vec<_>, _>>()?;
        let mut position_m = [0.0; 3];
        for (v, &i) in position_m.iter_mut().zip(&c.position) {
            *v = self.number(i, 1e5)? * 1e-3;
        }
        let position_std = c
            .position_std
            .map(|three| self.rms(three, 1e-3))
            .transpose()?;
        let temperature_c = c.temperature.map(|i| self.number(i, 1e3)).transpose()?;
        let row = AbsoluteRow {
            line: self.line as u64,
            setup: options.setup.clone(),
            target: options.target.clone(),
            config: None,
            q_rad,
            position_m,
            sigma_m: position_std.filter(|s| options.tracker_sigma && *s > 0.0),
            orientation: self.orientation(options.tracker_sigma)?,
            payload: None,
            wrench: None,
            temperature_c,
            time_s: c.timestamp.and_then(|i| timestamp_seconds(self.fields[i])),
            approach_rad: None,
        };
        Ok((row, position_std))
    }
}

/// Parse series text (see the module documentation). Every row gets its approach motion
/// ([`crate::geometry::data::approach_from_sequence`]) from the measuring sequence: time-stamp order when
/// every row has one, file order otherwise.
pub fn parse_series(
    text: &str,
    origin: &str,
    options: &ImportOptions,
) -> Result<(Vec<AbsoluteRow>, ImportSummary), ImportError> {
    let mut lines = text.lines().enumerate();
    let header_line = lines
        .by_ref()
        .find(|(_, l)| !l.trim().is_empty())
        .map(|(_, l)| l)
        .ok_or_else(|| ImportError::Header {
            path: origin.into(),
            problem: SeriesHeaderProblem::Empty,
        })?;
    let columns = SeriesColumns::of(header_line, origin)?;
    let mut rows = Vec::new();
    let mut stds = Vec::new();
    for (index, line) in lines {
        if line.trim().is_empty() {
            continue;
        }
        let row_error = |problem| ImportError::Row {
            path: origin.into(),
            line: index + 1,
            column: "-".into(),
            problem,
        };
        if rows.len() >= crate::geometry::data::limits::MAX_ROWS {
            return Err(row_error(SeriesRowProblem::TooManyRows(
                crate::geometry::data::limits::MAX_ROWS,
            )));
        }
        let fields: Vec<&str> = line.split(';').collect();
        if fields.len() != columns.width {
            return Err(row_error(SeriesRowProblem::FieldCount {
                expected: columns.width,
                found: fields.len(),
            }));
        }
        let parsed = SeriesLine {
            fields,
            columns: &columns,
            origin,
            line: index + 1,
        };
        let (row, std) = parsed.row(options)?;
        stds.extend(std);
        rows.push(row);
    }
    if rows.is_empty() {
        return Err(ImportError::Header {
            path: origin.into(),
            problem: SeriesHeaderProblem::NoRows,
        });
    }
    fill_approach(&mut rows);
    let temperatures: Vec<f64> = rows.iter().filter_map(|r| r.temperature_c).collect();
    let summary = ImportSummary {
        file: PathBuf::from(origin),
        rows: rows.len(),
        rows_without_time: rows.iter().filter(|r| r.time_s.is_none()).count(),
        has_tracker_std: columns.position_std.is_some(),
        median_tracker_std_m: (!stds.is_empty()).then(|| {
            stds.sort_by(f64::total_cmp);
            stds[stds.len() / 2]
        }),
        temperature_range_c: (!temperatures.is_empty()).then(|| {
            [
                temperatures.iter().copied().fold(f64::INFINITY, f64::min),
                temperatures
                    .iter()
                    .copied()
                    .fold(f64::NEG_INFINITY, f64::max),
            ]
        }),
    };
    Ok((rows, summary))
}

/// Approach motions in the measuring order: by time stamp when every row has one (Series A
/// ends with ten re-measured readings out of time order), else in file order.
fn fill_approach(rows: &mut [AbsoluteRow]) {
    let mut order: Vec<usize> = (0..rows.len()).collect();
    if rows.iter().all(|r| r.time_s.is_some()) {
        order.sort_by(|&a, &b| {
            rows[a]
                .time_s
                .unwrap_or(0.0)
                .total_cmp(&rows[b].time_s.unwrap_or(0.0))
        });
    }
    let mut sequence: Vec<AbsoluteRow> = order.iter().map(|&i| rows[i].clone()).collect();
    crate::geometry::data::approach_from_sequence(&mut sequence);
    for (row, &i) in sequence.into_iter().zip(&order) {
        rows[i].approach_rad = row.approach_rad;
    }
}
