//! The bounds every value of a measurement or plan file must respect (see the module
//! documentation of [`crate::measurements`]), and the column names they apply to.

use crate::measurements::{MeasurementRow, RowValueError, SigmaColumn};

/// Largest |joint value| in a file (rad), as for robot files' joint limits.
pub const MAX_JOINT_RAD: f64 = 100.0;
/// Largest |force component| in a file (N): 1 MN, far above any robot's rating.
pub const MAX_FORCE_N: f64 = 1e6;
/// Largest |moment component| in a file (N·m).
pub const MAX_MOMENT_NM: f64 = 1e6;
/// Largest |coordinate| in a file (m), as for robot files' lengths.
pub const MAX_COORDINATE_M: f64 = 100.0;
/// Largest |displacement component| (m): an elastic deflection is millimetres, not a metre.
pub const MAX_DISPLACEMENT_M: f64 = 1.0;
/// Largest |rotation component| (rad): a small rotation.
pub const MAX_ROTATION_RAD: f64 = 1.0;
/// Largest `sigma_m` (m).
pub const MAX_SIGMA_M: f64 = 1.0;
/// Smallest `sigma_m` (m): 1 nm (a weight of 1/σ must stay finite).
pub const MIN_SIGMA_M: f64 = 1e-9;
/// Largest `sigma_rad` (rad).
pub const MAX_SIGMA_RAD: f64 = 1.0;
/// Smallest `sigma_rad` (rad).
pub const MIN_SIGMA_RAD: f64 = 1e-9;
/// Longest label (`load_case`, `point`) or `purpose` text, in characters.
pub const MAX_LABEL_CHARS: usize = 200;
/// Largest file read (bytes): 128 MiB, about 200 000 rows.
pub const MAX_FILE_BYTES: u64 = 128 << 20;
/// Most data rows in a file (the calibration's design matrix grows with them).
pub const MAX_ROWS: usize = 100_000;

pub(crate) const WRENCH_COLUMNS: [&str; 6] = ["fx_N", "fy_N", "fz_N", "mx_Nm", "my_Nm", "mz_Nm"];
pub(crate) const LOAD_POINT_COLUMNS: [&str; 3] = ["load_x_m", "load_y_m", "load_z_m"];
pub(crate) const POINT_COLUMNS: [&str; 3] = ["x_m", "y_m", "z_m"];
pub(crate) const DISPLACEMENT_COLUMNS: [&str; 3] = ["dx_m", "dy_m", "dz_m"];
pub(crate) const ROTATION_COLUMNS: [&str; 3] = ["drx_rad", "dry_rad", "drz_rad"];

/// The bound on a numeric column's magnitude and its unit (see the module documentation).
pub(crate) fn column_bound(name: &str) -> (f64, &'static str) {
    match name {
        "fx_N" | "fy_N" | "fz_N" => (MAX_FORCE_N, "N"),
        "mx_Nm" | "my_Nm" | "mz_Nm" => (MAX_MOMENT_NM, "N·m"),
        "dx_m" | "dy_m" | "dz_m" => (MAX_DISPLACEMENT_M, "m"),
        "drx_rad" | "dry_rad" | "drz_rad" => (MAX_ROTATION_RAD, "rad"),
        "sigma_m" => (MAX_SIGMA_M, "m"),
        "sigma_rad" => (MAX_SIGMA_RAD, "rad"),
        n if n.starts_with('q') && n.ends_with("_rad") => (MAX_JOINT_RAD, "rad"),
        _ => (MAX_COORDINATE_M, "m"),
    }
}

/// Check a row built in code (not read from a file) against the same bounds as a file row:
/// `Err` names the value that is NaN, infinite or beyond its bound.
pub fn check_row_values(row: &MeasurementRow) -> Result<(), RowValueError> {
    let check = |name: &str, value: f64| -> Result<(), RowValueError> {
        let (limit, unit) = column_bound(name);
        if value.is_finite() && value.abs() <= limit {
            Ok(())
        } else {
            Err(RowValueError::OutOfBound {
                column: name.to_string(),
                value,
                limit,
                unit,
            })
        }
    };
    for (i, q) in row.q_rad.iter().enumerate() {
        check(&format!("q{}_rad", i + 1), *q)?;
    }
    for (name, value) in WRENCH_COLUMNS.iter().zip(row.wrench) {
        check(name, value)?;
    }
    for (name, value) in LOAD_POINT_COLUMNS.iter().zip(row.load_point_m) {
        check(name, value)?;
    }
    for (name, value) in POINT_COLUMNS.iter().zip(row.point_m) {
        check(name, value)?;
    }
    if let Some(d) = row.displacement_m {
        for (name, value) in DISPLACEMENT_COLUMNS.iter().zip(d) {
            check(name, value)?;
        }
    }
    if let Some(sigma) = row.sigma_m
        && !SigmaColumn::Position.accepts(sigma)
    {
        return Err(RowValueError::Sigma {
            sigma: SigmaColumn::Position,
            value: sigma,
        });
    }
    if let Some(rotation) = row.rotation_rad {
        for (name, value) in ROTATION_COLUMNS.iter().zip(rotation.value_rad) {
            check(name, value)?;
        }
        if let Some(sigma) = rotation.sigma_rad
            && !SigmaColumn::Rotation.accepts(sigma)
        {
            return Err(RowValueError::Sigma {
                sigma: SigmaColumn::Rotation,
                value: sigma,
            });
        }
    }
    Ok(())
}
