//! The compensated path as a table: CSV text with SI columns (what `deflex compensate` writes
//! as `compensated_path.csv`) and its reader. An online controller that runs on top of a
//! compensated program, or takes the prediction as feed-forward, reads it through this reader
//! into the control law's table (`deflex_control::FeedForwardTable`, built by the application
//! layer's `deflex_app::cell::feedforward`).
//!
//! ## Columns
//!
//! | column | meaning |
//! | --- | --- |
//! | `index` | point index along the path |
//! | `s_m`, `t_s` | arc length (m) and time at the path's feeds (s) |
//! | `x_m, y_m, z_m` | desired TCP position, world frame of the robot model |
//! | `rx_rad, ry_rad, rz_rad` | desired TCP orientation as a rotation vector, world |
//! | `cx_m, cy_m, cz_m` | commanded (compensated) TCP position |
//! | `dx_m, dy_m, dz_m, drx_rad, dry_rad, drz_rad` | compensation `x`: commanded = desired ⊕ x |
//! | `fx_N … mz_Nm` | predicted wrench on the tool at the commanded path (world axes, at the TCP) |
//! | `defl_x_m … defl_rz_rad` | predicted deflection at the commanded configuration (eq. 15) |
//! | `err_m, err_rad` | predicted error of the commanded path (tool vs desired) |
//! | `q1_rad … qN_rad` | joint values of the commanded pose |
//! | `status` | `ok`, or why the point is not compensated ([`crate::PointFailure::code`]) |
//!
//! `desired ⊕ x = (p + dp, exp(dφ)·R)`; lines starting with `#` are comments (a `# SIMULATED`
//! line when the wrenches come from the twin).

use crate::compensate::{Compensation, commanded_pose};
use crate::path::TcpPath;
use deflex_model::spatial::rotation_log;
use deflex_model::{Displacement, Pose, Wrench};
use nalgebra::{Rotation3, Translation3, Vector3};
use std::collections::HashMap;
use std::fmt::Write as _;
use thiserror::Error;

/// Largest table read (rows).
pub const MAX_TABLE_ROWS: usize = crate::path::MAX_PATH_POINTS;

const SIX: [&str; 6] = ["x_m", "y_m", "z_m", "rx_rad", "ry_rad", "rz_rad"];
const WRENCH: [&str; 6] = ["fx_N", "fy_N", "fz_N", "mx_Nm", "my_Nm", "mz_Nm"];
/// Column names of the compensation (base of `compensated_path.csv`).
pub const COMPENSATION: [&str; 6] = ["dx_m", "dy_m", "dz_m", "drx_rad", "dry_rad", "drz_rad"];
/// Column names of the predicted deflection.
pub const DEFLECTION: [&str; 6] = [
    "defl_x_m",
    "defl_y_m",
    "defl_z_m",
    "defl_rx_rad",
    "defl_ry_rad",
    "defl_rz_rad",
];

/// The CSV header for `joints` joints.
pub fn csv_header(joints: usize) -> String {
    let mut columns: Vec<String> = vec!["index".into(), "s_m".into(), "t_s".into()];
    columns.extend(SIX.iter().map(|c| c.to_string()));
    columns.extend(["cx_m", "cy_m", "cz_m"].map(String::from));
    columns.extend(COMPENSATION.iter().map(|c| c.to_string()));
    columns.extend(WRENCH.iter().map(|c| c.to_string()));
    columns.extend(DEFLECTION.iter().map(|c| c.to_string()));
    columns.extend(["err_m", "err_rad"].map(String::from));
    columns.extend((1..=joints).map(|i| format!("q{i}_rad")));
    columns.push("status".into());
    columns.join(",")
}

/// The compensated path as CSV text: `comments` first (each prefixed with `# `), then the
/// header and one row per path point.
pub fn write_csv(
    path: &TcpPath,
    compensation: &Compensation,
    joints: usize,
    comments: &[String],
) -> String {
    let mut out = Vec::with_capacity(path.len() * 420 + 1024);
    write_csv_to(&mut out, path, compensation, joints, comments)
        .expect("writing to memory does not fail");
    String::from_utf8(out).expect("the table is UTF-8")
}

/// [`write_csv`] streamed to `out` (a file of a million rows is 400 MB: it need not be held in
/// memory).
pub fn write_csv_to<W: std::io::Write>(
    out: &mut W,
    path: &TcpPath,
    compensation: &Compensation,
    joints: usize,
    comments: &[String],
) -> std::io::Result<()> {
    for c in comments {
        for line in c.lines() {
            writeln!(out, "# {line}")?;
        }
    }
    writeln!(out, "{}", csv_header(joints))?;
    let mut row = String::with_capacity(512);
    for (i, (point, result)) in path.points().iter().zip(&compensation.points).enumerate() {
        row.clear();
        let d = &point.pose;
        let r = rotation_log(&d.rotation);
        let c = commanded_pose(d, &result.compensation).translation.vector;
        let _ = write!(row, "{i},{:.9},{:.6}", point.arc_length_m, point.time_s);
        let t = d.translation.vector;
        for v in [t.x, t.y, t.z] {
            let _ = write!(row, ",{v:.9}");
        }
        for v in r.iter() {
            let _ = write!(row, ",{v:.10}");
        }
        for v in c.iter() {
            let _ = write!(row, ",{v:.9}");
        }
        for (k, v) in result.compensation.iter().enumerate() {
            let _ = if k < 3 {
                write!(row, ",{v:.9}")
            } else {
                write!(row, ",{v:.10}")
            };
        }
        for v in result.wrench.iter() {
            let _ = write!(row, ",{v:.4}");
        }
        for (k, v) in result.deflection.iter().enumerate() {
            let _ = if k < 3 {
                write!(row, ",{v:.9}")
            } else {
                write!(row, ",{v:.10}")
            };
        }
        let _ = write!(
            row,
            ",{:.9},{:.10}",
            result.predicted_error_m, result.predicted_error_rad
        );
        for q in &result.q[..joints] {
            let _ = write!(row, ",{q:.10}");
        }
        match result.failure {
            None => row.push_str(",ok\n"),
            Some(f) => {
                let _ = writeln!(row, ",{}", f.code());
            }
        }
        out.write_all(row.as_bytes())?;
    }
    Ok(())
}

/// A compensated-path table that cannot be read.
#[derive(Debug, Error, PartialEq)]
pub enum TableError {
    /// A required column is missing.
    #[error("{file}: not a compensated path: missing column(s) {missing}")]
    MissingColumns {
        /// The file.
        file: String,
        /// Missing columns.
        missing: String,
    },
    /// A value is not a finite number.
    #[error("{file}:{line}: column `{column}`: expected a number, got \"{value}\"")]
    BadValue {
        /// The file.
        file: String,
        /// 1-based line.
        line: usize,
        /// Column.
        column: String,
        /// Text found.
        value: String,
    },
    /// Malformed CSV or too many rows.
    #[error("{file}:{line}: {message}")]
    Csv {
        /// The file.
        file: String,
        /// 1-based line.
        line: usize,
        /// What is wrong.
        message: String,
    },
}

/// One row read back.
#[derive(Clone, Debug, PartialEq)]
pub struct TableRow {
    /// 1-based line of the file the row was read from (for messages).
    pub line: usize,
    /// Arc length (m).
    pub arc_length_m: f64,
    /// Time (s).
    pub time_s: f64,
    /// Desired TCP pose (world).
    pub desired: Pose,
    /// Compensation `x` (commanded = desired ⊕ x).
    pub compensation: Displacement,
    /// Predicted wrench.
    pub wrench: Wrench,
    /// Predicted deflection at the commanded configuration.
    pub deflection: Displacement,
    /// `ok` or the failure code.
    pub status: String,
}

/// Read a compensated-path table (the columns of the module documentation; the joint columns
/// are not needed).
pub fn read_csv(text: &str, file: &str) -> Result<Vec<TableRow>, TableError> {
    let mut reader = csv::ReaderBuilder::new()
        .comment(Some(b'#'))
        .trim(csv::Trim::All)
        .from_reader(text.as_bytes());
    let csv_error = |e: csv::Error| TableError::Csv {
        file: file.to_string(),
        line: e.position().map_or(0, |p| p.line() as usize),
        message: e.to_string(),
    };
    let header = reader.headers().map_err(csv_error)?.clone();
    let columns: HashMap<&str, usize> = header.iter().enumerate().map(|(i, h)| (h, i)).collect();
    let mut needed: Vec<&str> = vec!["s_m", "t_s", "status"];
    needed.extend(SIX);
    needed.extend(COMPENSATION);
    needed.extend(WRENCH);
    needed.extend(DEFLECTION);
    let missing: Vec<&str> = needed
        .iter()
        .copied()
        .filter(|c| !columns.contains_key(c))
        .collect();
    if !missing.is_empty() {
        return Err(TableError::MissingColumns {
            file: file.to_string(),
            missing: missing.join(", "),
        });
    }
    let mut rows = Vec::new();
    for record in reader.records() {
        let record = record.map_err(csv_error)?;
        let line = record.position().map_or(0, |p| p.line() as usize);
        if rows.len() >= MAX_TABLE_ROWS {
            return Err(TableError::Csv {
                file: file.to_string(),
                line,
                message: format!("more than {MAX_TABLE_ROWS} rows"),
            });
        }
        let get = |name: &str| -> Result<f64, TableError> {
            let text = record.get(columns[name]).unwrap_or("");
            text.parse::<f64>()
                .ok()
                .filter(|v| v.is_finite())
                .ok_or_else(|| TableError::BadValue {
                    file: file.to_string(),
                    line,
                    column: name.to_string(),
                    value: text.to_string(),
                })
        };
        let six = |names: &[&str; 6]| -> Result<Displacement, TableError> {
            let mut v = Displacement::zeros();
            for (k, n) in names.iter().enumerate() {
                v[k] = get(n)?;
            }
            Ok(v)
        };
        let pose = six(&SIX)?;
        rows.push(TableRow {
            line,
            arc_length_m: get("s_m")?,
            time_s: get("t_s")?,
            desired: Pose::from_parts(
                Translation3::new(pose[0], pose[1], pose[2]),
                Rotation3::from_scaled_axis(Vector3::new(pose[3], pose[4], pose[5])),
            ),
            compensation: six(&COMPENSATION)?,
            wrench: six(&WRENCH)?,
            deflection: six(&DEFLECTION)?,
            status: record.get(columns["status"]).unwrap_or("").to_string(),
        });
    }
    Ok(rows)
}
