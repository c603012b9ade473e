//! Validation: prediction errors of a model (and optionally a baseline) against measurements
//! (the paper's Section 3.2), with their statistics ([`ErrorStats`]). When rows carry a measured
//! link rotation, its prediction errors are reported too. The predicted-vs-measured plots
//! (Figs. 8–10, 12), the error heatmaps over the measured grid (Figs. 11, 13) and their HTML page
//! are `deflex_app::report::validation`'s.

use crate::measurements::MeasurementRow;
use crate::stats::ErrorStats;
use crate::stiffness::{CalibError, RowRef, RowsError};
use deflex_model::{Data, Robot, Wrench};
use nalgebra::Vector3;

/// Rotation predictions and errors of one model, for the rows with a measured rotation.
#[derive(Clone, Debug)]
pub struct RotationErrors {
    /// Index of each row used (rows with a measured rotation).
    pub rows: Vec<usize>,
    /// Predicted rotation per used row (rad).
    pub predicted_rad: Vec<[f64; 3]>,
    /// Measured − predicted per used row (rad).
    pub errors_rad: Vec<[f64; 3]>,
    /// Statistics (rad; their count is the number of rows used).
    pub stats: ErrorStats,
}

/// Predictions and errors of one model.
#[derive(Clone, Debug)]
pub struct ModelErrors {
    /// Model name.
    pub name: String,
    /// Predicted displacement per row (m).
    pub predicted: Vec<[f64; 3]>,
    /// Measured − predicted per row (m).
    pub errors: Vec<[f64; 3]>,
    /// Statistics (m).
    pub stats: ErrorStats,
    /// Rotation errors, when some rows have a measured rotation.
    pub rotation: Option<RotationErrors>,
}

/// A validation of a model on measurements.
#[derive(Clone, Debug)]
pub struct Validation {
    /// The model under test.
    pub model: ModelErrors,
    /// The baseline, when given.
    pub baseline: Option<ModelErrors>,
    /// Measured displacement per row (m).
    pub measured: Vec<[f64; 3]>,
    /// Measured point per row (world, m).
    pub points: Vec<[f64; 3]>,
    /// Point label per row.
    pub labels: Vec<String>,
    /// Applied force magnitude per row (N): heatmaps are drawn per load level.
    pub load_n: Vec<f64>,
    /// RMS of the measured displacement per axis (m), for scale.
    pub measured_rms_m: [f64; 3],
}

/// VJM prediction (eq. 15, any point and load link) of every row's displacement.
pub fn predict(robot: &Robot, rows: &[MeasurementRow]) -> Result<Vec<[f64; 3]>, CalibError> {
    Ok(predict_full(robot, rows)?
        .into_iter()
        .map(|d| [d[0], d[1], d[2]])
        .collect())
}

/// VJM prediction of every row's displacement and link rotation `[δp; δφ]` (m, rad).
pub fn predict_full(robot: &Robot, rows: &[MeasurementRow]) -> Result<Vec<[f64; 6]>, CalibError> {
    let mut data = Data::new();
    let mut last: Option<&[f64]> = None;
    let mut out = Vec::with_capacity(rows.len());
    for (i, row) in rows.iter().enumerate() {
        crate::stiffness::design::check_row_fits(robot, i, row)?;
        if last != Some(row.q_rad.as_slice()) {
            robot.forward_kinematics(&mut data, &row.q_rad)?;
            last = Some(row.q_rad.as_slice());
        }
        let d = robot.point_displacement(
            &data,
            &Vector3::from(row.point_m),
            row.point_link,
            &Vector3::from(row.load_point_m),
            row.load_link,
            &Wrench::from_row_slice(&row.wrench),
        );
        out.push([d[0], d[1], d[2], d[3], d[4], d[5]]);
    }
    Ok(out)
}

/// Compare `model` (and `baseline`) with measured rows.
pub fn validate(
    model: &Robot,
    baseline: Option<&Robot>,
    rows: &[MeasurementRow],
) -> Result<Validation, CalibError> {
    if rows.is_empty() {
        return Err(RowsError::NoRows.into());
    }
    let mut measured = Vec::with_capacity(rows.len());
    for (i, r) in rows.iter().enumerate() {
        let d = r.displacement_m.ok_or_else(|| RowsError::NoDisplacement {
            row: RowRef::of(i, r),
        })?;
        if !d.iter().all(|v| v.is_finite()) {
            return Err(RowsError::NotFinite {
                row: RowRef::of(i, r),
                what: "displacement",
            }
            .into());
        }
        measured.push(d);
    }
    let rotation_rows: Vec<usize> = (0..rows.len())
        .filter(|&i| rows[i].rotation_rad.is_some())
        .collect();
    for &i in &rotation_rows {
        if !rows[i]
            .rotation_rad
            .is_some_and(|m| m.value_rad.iter().all(|v| v.is_finite()))
        {
            return Err(RowsError::NotFinite {
                row: RowRef::of(i, &rows[i]),
                what: "rotation",
            }
            .into());
        }
    }
    let errors_of = |robot: &Robot| -> Result<ModelErrors, CalibError> {
        let full = predict_full(robot, rows)?;
        let rotation = (!rotation_rows.is_empty()).then(|| {
            let predicted_rad: Vec<[f64; 3]> = rotation_rows
                .iter()
                .map(|&i| [full[i][3], full[i][4], full[i][5]])
                .collect();
            let errors_rad: Vec<[f64; 3]> = rotation_rows
                .iter()
                .zip(&predicted_rad)
                .map(|(&i, p)| {
                    let m = rows[i]
                        .rotation_rad
                        .map(|m| m.value_rad)
                        .unwrap_or_default();
                    [m[0] - p[0], m[1] - p[1], m[2] - p[2]]
                })
                .collect();
            RotationErrors {
                rows: rotation_rows.clone(),
                predicted_rad,
                stats: ErrorStats::of(&errors_rad),
                errors_rad,
            }
        });
        let predicted: Vec<[f64; 3]> = full.iter().map(|d| [d[0], d[1], d[2]]).collect();
        let errors: Vec<[f64; 3]> = predicted
            .iter()
            .zip(&measured)
            .map(|(p, m)| [m[0] - p[0], m[1] - p[1], m[2] - p[2]])
            .collect();
        Ok(ModelErrors {
            name: robot.name.clone(),
            stats: ErrorStats::of(&errors),
            predicted,
            errors,
            rotation,
        })
    };
    let model_errors = errors_of(model)?;
    let baseline = baseline.map(errors_of).transpose()?;
    let measured_rms_m = ErrorStats::of(&measured).rms;
    Ok(Validation {
        model: model_errors,
        baseline,
        points: rows.iter().map(|r| r.point_m).collect(),
        labels: rows.iter().map(|r| r.point.clone()).collect(),
        load_n: rows
            .iter()
            .map(|r| (r.wrench[0].powi(2) + r.wrench[1].powi(2) + r.wrench[2].powi(2)).sqrt())
            .collect(),
        measured,
        measured_rms_m,
    })
}

/// Residuals (measured − predicted by `model`) per row, in metres; NaN where a row has no
/// measured displacement.
pub fn residuals(model: &Robot, rows: &[MeasurementRow]) -> Result<Vec<[f64; 3]>, CalibError> {
    let predicted = predict(model, rows)?;
    Ok(rows
        .iter()
        .zip(&predicted)
        .map(|(r, p)| {
            let m = r.displacement_m.unwrap_or([f64::NAN; 3]);
            [m[0] - p[0], m[1] - p[1], m[2] - p[2]]
        })
        .collect())
}
