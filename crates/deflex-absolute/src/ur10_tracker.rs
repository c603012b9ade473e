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

use crate::data::{AbsoluteRow, RowOrientation};
use nalgebra::{Rotation3, Vector3};
use std::path::{Path, PathBuf};
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

/// Largest series file read (bytes).
pub const MAX_SERIES_BYTES: u64 = 256 << 20;

/// A series file that cannot be imported.
#[derive(Debug, Error)]
pub enum ImportError {
    /// Read error.
    #[error("{path}: {source}")]
    Io {
        /// File.
        path: String,
        /// Cause.
        source: std::io::Error,
    },
    /// A folder with no single `measurements_*.csv`.
    #[error("{path}: {message}")]
    Folder {
        /// Folder.
        path: String,
        /// What was found.
        message: String,
    },
    /// Bad header.
    #[error("{path}: header: {message}")]
    Header {
        /// File.
        path: String,
        /// What is wrong.
        message: String,
    },
    /// Bad row.
    #[error("{path}:{line}: column `{column}`: {message}")]
    Row {
        /// File.
        path: String,
        /// 1-based line.
        line: usize,
        /// Column.
        column: String,
        /// What is wrong.
        message: String,
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

/// The single `measurements_*.csv` of a series folder (or the file itself).
pub fn series_file(path: &Path) -> Result<PathBuf, ImportError> {
    if path.is_file() {
        return Ok(path.to_path_buf());
    }
    let shown = path.display().to_string();
    let entries = std::fs::read_dir(path).map_err(|source| ImportError::Io {
        path: shown.clone(),
        source,
    })?;
    let mut found: Vec<PathBuf> = entries
        .filter_map(|e| e.ok().map(|e| e.path()))
        .filter(|p| {
            p.file_name()
                .and_then(|n| n.to_str())
                .is_some_and(|n| n.starts_with("measurements") && n.ends_with(".csv"))
        })
        .collect();
    found.sort();
    match found.len() {
        1 => Ok(found.remove(0)),
        n => Err(ImportError::Folder {
            path: shown,
            message: format!("expected one measurements_*.csv, found {n}"),
        }),
    }
}

/// Read a series (folder or file) into absolute rows.
pub fn import_series(
    path: &Path,
    options: &ImportOptions,
) -> Result<(Vec<AbsoluteRow>, ImportSummary), ImportError> {
    let file = series_file(path)?;
    let shown = file.display().to_string();
    let io = |source| ImportError::Io {
        path: shown.clone(),
        source,
    };
    let size = std::fs::metadata(&file).map_err(io)?.len();
    if size > MAX_SERIES_BYTES {
        return Err(ImportError::Folder {
            path: shown,
            message: format!("{size} bytes: more than the {MAX_SERIES_BYTES} bytes read"),
        });
    }
    let text = std::fs::read_to_string(&file).map_err(io)?;
    let (rows, mut summary) = parse_series(&text, &shown, options)?;
    summary.file = file;
    Ok((rows, summary))
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

/// Parse series text (see the module documentation).
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
            message: "empty file".into(),
        })?;
    let names: Vec<&str> = header_line.split(';').map(str::trim).collect();
    let column = |name: &str| names.iter().position(|n| *n == name);
    let require = |name: &str| {
        column(name).ok_or_else(|| ImportError::Header {
            path: origin.into(),
            message: format!("missing column `{name}`"),
        })
    };
    let joints = JOINT_COLUMNS
        .iter()
        .map(|n| require(n))
        .collect::<Result<Vec<_>, _>>()?;
    let position = [
        require("measurement_x")?,
        require("measurement_y")?,
        require("measurement_z")?,
    ];
    let rotation = ["measurement_rx", "measurement_ry", "measurement_rz"].map(column);
    let std = [
        "measurement_std_x",
        "measurement_std_y",
        "measurement_std_z",
    ]
    .map(column);
    let has_std = std.iter().all(Option::is_some);
    let has_rotation = rotation.iter().all(Option::is_some);
    let temperature = column("measurement_temperature");
    let timestamp = column("Timestamp");
    let mut rows = Vec::new();
    let mut stds = Vec::new();
    let mut without_time = 0;
    let mut t_range = [f64::INFINITY, f64::NEG_INFINITY];
    for (index, line) in lines {
        if line.trim().is_empty() {
            continue;
        }
        let line_no = index + 1;
        if rows.len() >= crate::data::limits::MAX_ROWS {
            return Err(ImportError::Row {
                path: origin.into(),
                line: line_no,
                column: "-".into(),
                message: format!("more than {} rows", crate::data::limits::MAX_ROWS),
            });
        }
        let fields: Vec<&str> = line.split(';').collect();
        if fields.len() != names.len() {
            return Err(ImportError::Row {
                path: origin.into(),
                line: line_no,
                column: "-".into(),
                message: format!("expected {} fields, found {}", names.len(), fields.len()),
            });
        }
        let number = |i: usize, limit: f64| -> Result<f64, ImportError> {
            decimal_comma(fields[i])
                .filter(|v| v.abs() <= limit)
                .ok_or_else(|| ImportError::Row {
                    path: origin.into(),
                    line: line_no,
                    column: names[i].to_string(),
                    message: format!(
                        "expected a decimal-comma number within ±{limit}, got \"{}\"",
                        fields[i]
                    ),
                })
        };
        let q_rad = joints
            .iter()
            .map(|&i| number(i, crate::data::limits::MAX_JOINT_RAD))
            .collect::<Result<Vec<_>, _>>()?;
        let mut position_m = [0.0; 3];
        for (v, &i) in position_m.iter_mut().zip(&position) {
            *v = number(i, 1e5)? * 1e-3;
        }
        let orientation = if has_rotation {
            let mut angles = [0.0; 3];
            for (v, i) in angles.iter_mut().zip(rotation) {
                *v = number(i.unwrap_or(0), 720.0)?.to_radians();
            }
            let r = Rotation3::from_axis_angle(&Vector3::x_axis(), angles[0])
                * Rotation3::from_axis_angle(&Vector3::y_axis(), angles[1])
                * Rotation3::from_axis_angle(&Vector3::z_axis(), angles[2]);
            let v = deflex_model::spatial::rotation_log(&r);
            Some(RowOrientation {
                rotation_vector_rad: [v.x, v.y, v.z],
                sigma_rad: None,
            })
        } else {
            None
        };
        let row_std = if has_std {
            let mut s = 0.0;
            for i in std {
                let v = number(i.unwrap_or(0), 1e3)? * 1e-3;
                s += v * v;
            }
            let rms = (s / 3.0).sqrt();
            stds.push(rms);
            (rms > 0.0).then_some(rms)
        } else {
            None
        };
        let temperature_c = match temperature {
            Some(i) => {
                let t = number(i, 1e3)?;
                t_range = [t_range[0].min(t), t_range[1].max(t)];
                Some(t)
            }
            None => None,
        };
        let time_s = timestamp.and_then(|i| timestamp_seconds(fields[i]));
        if time_s.is_none() {
            without_time += 1;
        }
        rows.push(AbsoluteRow {
            line: line_no as u64,
            setup: options.setup.clone(),
            target: options.target.clone(),
            config: None,
            q_rad,
            position_m,
            sigma_m: if options.tracker_sigma { row_std } else { None },
            orientation,
            payload: None,
            wrench: None,
            temperature_c,
            time_s,
        });
    }
    if rows.is_empty() {
        return Err(ImportError::Header {
            path: origin.into(),
            message: "no data rows".into(),
        });
    }
    let median_tracker_std_m = (!stds.is_empty()).then(|| {
        stds.sort_by(f64::total_cmp);
        stds[stds.len() / 2]
    });
    let summary = ImportSummary {
        file: PathBuf::from(origin),
        rows: rows.len(),
        rows_without_time: without_time,
        has_tracker_std: has_std,
        median_tracker_std_m,
        temperature_range_c: t_range[0].is_finite().then_some(t_range),
    };
    Ok((rows, summary))
}

#[cfg(test)]
mod tests {
    use super::*;

    const HEADER: &str = "Timestamp;Goal x;shoulder_pan_joint;shoulder_lift_joint;elbow_joint;wrist_1_joint;wrist_2_joint;wrist_3_joint;measurement_temperature;measurement_x;measurement_std_x;measurement_y;measurement_std_y;measurement_z;measurement_std_z;measurement_rx;measurement_ry;measurement_rz";

    fn options() -> ImportOptions {
        ImportOptions {
            setup: "A".into(),
            target: "tmac".into(),
            tracker_sigma: true,
        }
    }

    #[test]
    // 1.5708 is the file's own rounded value, not π/2.
    #[allow(clippy::approx_constant)]
    fn decimal_commas_units_and_rotation() {
        let text = format!(
            "{HEADER}\r\n20200714163904;0,365;-1,5708;-1,5708;0,0;-1,5708;0,0;0,0;23,68;2361,9831;0,03;-1368,5474;0,0;119,39713;0,0;90;0;90\r\n2,02011E+13;0;0;0;0;0;0;0;21,5;1;0;2;0;3;0;0;0;0"
        );
        let (rows, summary) = parse_series(&text, "s.csv", &options()).unwrap();
        assert_eq!(rows.len(), 2);
        assert_eq!(
            rows[0].q_rad,
            vec![-1.5708, -1.5708, 0.0, -1.5708, 0.0, 0.0]
        );
        assert!((rows[0].position_m[0] - 2.3619831).abs() < 1e-12);
        assert!((rows[0].position_m[1] + 1.3685474).abs() < 1e-12);
        // std: RMS of (0.03, 0, 0) mm.
        assert!((rows[0].sigma_m.unwrap() - 0.03e-3 / 3f64.sqrt()).abs() < 1e-15);
        // Intrinsic X-Y-Z 90°, 0, 90°: R = Rx(90°)·Rz(90°), by hand rows (0,-1,0), (0,0,-1), (1,0,0).
        let v = rows[0].orientation.unwrap().rotation_vector_rad;
        let r = Rotation3::from_scaled_axis(Vector3::from(v));
        let expected = nalgebra::Matrix3::new(0.0, -1.0, 0.0, 0.0, 0.0, -1.0, 1.0, 0.0, 0.0);
        assert!((r.matrix() - expected).abs().max() < 1e-12, "{r}");
        assert_eq!(rows[0].time_s, Some(1_594_744_744.0));
        assert_eq!(rows[1].time_s, None);
        assert_eq!(summary.rows_without_time, 1);
        assert_eq!(summary.temperature_range_c, Some([21.5, 23.68]));
    }

    #[test]
    fn bad_rows_are_named() {
        let text = format!("{HEADER}\n1;0;0;0;0;0;0;0;21;1;0;2x;0;3;0;0;0;0");
        let err = parse_series(&text, "s.csv", &options())
            .unwrap_err()
            .to_string();
        assert!(
            err.contains("s.csv:2") && err.contains("measurement_y"),
            "{err}"
        );
        let err = parse_series("Timestamp;x\n1;2", "s.csv", &options())
            .unwrap_err()
            .to_string();
        assert!(err.contains("shoulder_pan_joint"), "{err}");
        let text = format!("{HEADER}\n1;0;0");
        let err = parse_series(&text, "s.csv", &options())
            .unwrap_err()
            .to_string();
        assert!(err.contains("fields"), "{err}");
    }
}
