//! Validation: prediction errors of a model (and optionally a baseline) against measurements
//! (the paper's Section 3.2), with predicted-vs-measured plots (Figs. 8–10, 12) and error
//! heatmaps over the measured grid (Figs. 11, 13) as PNG, gathered in one HTML page. When rows
//! carry a measured link rotation, its prediction errors are reported too (statistics only; the
//! plots stay position-only).

use crate::CalibError;
use crate::data::MeasurementRow;
use deflex_model::{Data, Robot, Wrench};
use deflex_report::{HtmlReport, PlotSpec, Series, line_plot, parity_plot, scatter_heatmap};
use nalgebra::Vector3;
use std::path::{Path, PathBuf};

/// Error statistics (measured − predicted), metres.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct ErrorStats {
    /// RMS per axis.
    pub rms_m: [f64; 3],
    /// Largest absolute error per axis.
    pub max_abs_m: [f64; 3],
    /// Mean (bias) per axis.
    pub mean_m: [f64; 3],
    /// RMS of the error norm.
    pub rms_norm_m: f64,
    /// Largest error norm.
    pub max_norm_m: f64,
}

/// Rotation error statistics (measured − predicted), radians, over the rows with a measured
/// rotation.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct RotationStats {
    /// Number of rows with a measured rotation.
    pub rows: usize,
    /// RMS per axis.
    pub rms_rad: [f64; 3],
    /// Largest absolute error per axis.
    pub max_abs_rad: [f64; 3],
    /// Mean (bias) per axis.
    pub mean_rad: [f64; 3],
    /// RMS of the error norm.
    pub rms_norm_rad: f64,
    /// Largest error norm.
    pub max_norm_rad: f64,
}

/// Rotation predictions and errors of one model, for the rows with a measured rotation.
#[derive(Clone, Debug)]
pub struct RotationErrors {
    /// Index of each row used (rows with a measured rotation).
    pub rows: Vec<usize>,
    /// Predicted rotation per used row (rad).
    pub predicted_rad: Vec<[f64; 3]>,
    /// Measured − predicted per used row (rad).
    pub errors_rad: Vec<[f64; 3]>,
    /// Statistics.
    pub stats: RotationStats,
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
    /// Statistics.
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
    for row in rows {
        if row.q_rad.len() != robot.joint_count() {
            return Err(CalibError::Invalid(format!(
                "the data has {} joint columns but robot \"{}\" has {} joints",
                row.q_rad.len(),
                robot.name,
                robot.joint_count()
            )));
        }
        if row.point_link > robot.joint_count() || row.load_link > robot.joint_count() {
            return Err(CalibError::Invalid(format!(
                "load case {}: link index out of range for a {}-joint robot",
                row.load_case,
                robot.joint_count()
            )));
        }
        if last != Some(row.q_rad.as_slice()) {
            robot
                .forward_kinematics(&mut data, &row.q_rad)
                .map_err(|e| CalibError::Invalid(e.to_string()))?;
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
        return Err(CalibError::Invalid("no data rows".into()));
    }
    let mut measured = Vec::with_capacity(rows.len());
    for (i, r) in rows.iter().enumerate() {
        let d = r.displacement_m.ok_or_else(|| {
            CalibError::Invalid(format!("row {}: no measured displacement", i + 1))
        })?;
        if !d.iter().all(|v| v.is_finite()) {
            return Err(CalibError::Invalid(format!(
                "row {}: displacement is NaN or infinite",
                i + 1
            )));
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
            return Err(CalibError::Invalid(format!(
                "row {}: rotation is NaN or infinite",
                i + 1
            )));
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
            let s = stats(&errors_rad);
            RotationErrors {
                rows: rotation_rows.clone(),
                predicted_rad,
                stats: RotationStats {
                    rows: errors_rad.len(),
                    rms_rad: s.rms_m,
                    max_abs_rad: s.max_abs_m,
                    mean_rad: s.mean_m,
                    rms_norm_rad: s.rms_norm_m,
                    max_norm_rad: s.max_norm_m,
                },
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
            stats: stats(&errors),
            predicted,
            errors,
            rotation,
        })
    };
    let model_errors = errors_of(model)?;
    let baseline = baseline.map(errors_of).transpose()?;
    let measured_rms_m = stats(&measured).rms_m;
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

/// Statistics of a set of 3D errors (any unit; the fields are named for metres).
pub fn stats(errors: &[[f64; 3]]) -> ErrorStats {
    let mut s = ErrorStats::default();
    let n = errors.len().max(1) as f64;
    let mut sum2 = [0.0; 3];
    let mut norm2 = 0.0;
    for e in errors {
        let mut n2 = 0.0;
        for ax in 0..3 {
            sum2[ax] += e[ax] * e[ax];
            s.mean_m[ax] += e[ax] / n;
            s.max_abs_m[ax] = s.max_abs_m[ax].max(e[ax].abs());
            n2 += e[ax] * e[ax];
        }
        norm2 += n2;
        s.max_norm_m = s.max_norm_m.max(n2.sqrt());
    }
    for (rms, s2) in s.rms_m.iter_mut().zip(sum2) {
        *rms = (s2 / n).sqrt();
    }
    s.rms_norm_m = (norm2 / n).sqrt();
    s
}

fn report_err(e: deflex_report::ReportError) -> CalibError {
    CalibError::Invalid(format!("report: {e}"))
}

/// Write PNG plots and `validation.html` into the folder `dir`, whole or not at all: the folder
/// is built aside and swapped in when complete (`deflex_files::AtomicDir`; an existing folder is
/// replaced, and kept as it was when anything fails). Returns the files (final paths).
pub fn write_report(v: &Validation, dir: &Path) -> Result<Vec<PathBuf>, CalibError> {
    let io = |e: std::io::Error| CalibError::Invalid(format!("{}: {e}", dir.display()));
    let folder = deflex_files::AtomicDir::create(dir).map_err(io)?;
    let files = write_report_into(v, folder.path())?;
    folder.commit().map_err(io)?;
    Ok(files
        .iter()
        .filter_map(|f| f.file_name())
        .map(|name| dir.join(name))
        .collect())
}

/// [`write_report`]'s files, written into an existing folder.
fn write_report_into(v: &Validation, dir: &Path) -> Result<Vec<PathBuf>, CalibError> {
    let mut files = Vec::new();
    let mut html = HtmlReport::new(format!("Validation of {}", v.model.name));
    html.section("Prediction errors (measured − predicted)");
    html.table(
        &crate::report::VALIDATION_HEADERS,
        &crate::report::validation_rows(v),
    );
    if v.model.rotation.is_some() {
        html.section("Rotation errors (measured − predicted)");
        html.table(
            &crate::report::VALIDATION_ROTATION_HEADERS,
            &crate::report::validation_rotation_rows(v),
        );
    }
    html.paragraph(format!(
        "{} measured points; RMS of the measured displacement x/y/z: {:.4} / {:.4} / {:.4} mm.",
        v.measured.len(),
        v.measured_rms_m[0] * 1e3,
        v.measured_rms_m[1] * 1e3,
        v.measured_rms_m[2] * 1e3
    ));

    // Predicted vs measured (Figs. 8–10, 12).
    html.section("Predicted vs measured");
    let axes = ["x", "y", "z"];
    for (tag, m) in
        std::iter::once(("model", &v.model)).chain(v.baseline.as_ref().map(|b| ("baseline", b)))
    {
        for ax in 0..3 {
            let path = dir.join(format!("parity_{tag}_{}.png", axes[ax]));
            let meas: Vec<f64> = v.measured.iter().map(|d| d[ax] * 1e3).collect();
            let pred: Vec<f64> = m.predicted.iter().map(|d| d[ax] * 1e3).collect();
            let spec = PlotSpec::new(
                format!("δp{}: predicted vs measured ({tag})", axes[ax]),
                format!("measured δp{} [mm]", axes[ax]),
                format!("predicted δp{} [mm]", axes[ax]),
            )
            .size(700, 700);
            parity_plot(&path, &spec, &pred, &meas, tag).map_err(report_err)?;
            html.image(
                &path,
                format!("Predicted vs measured δp{} ({tag}: {})", axes[ax], m.name),
            );
            files.push(path);
        }
    }
    // δz along the measurement order (Figs. 10, 12).
    let path = dir.join("dz_along_points.png");
    let mut series = vec![Series::indexed(
        "measured",
        v.measured.iter().map(|d| d[2] * 1e3).collect(),
        deflex_report::SeriesStyle::LineAndPoints,
    )];
    for m in std::iter::once(&v.model).chain(v.baseline.as_ref()) {
        series.push(Series::indexed(
            m.name.clone(),
            m.predicted.iter().map(|d| d[2] * 1e3).collect(),
            deflex_report::SeriesStyle::Line,
        ));
    }
    let spec = PlotSpec::new("δp_z: measured and predicted", "point #", "δp_z [mm]");
    line_plot(&path, &spec, &series).map_err(report_err)?;
    html.image(
        &path,
        "Vertical displacement along the measured points (cf. Figs. 10, 12)",
    );
    files.push(path);

    // Heatmaps of the error norm over the measured points (Figs. 11, 13): one per model and per
    // load level (the paper's 600 N and 1100 N grids share their points), each with its own
    // colour scale so that a good model's pattern stays visible beside a poor one.
    html.section("Error over the measured grid");
    // The TCP grid when the TCP was measured (as in the paper), else every point.
    let tcp_only = v.labels.iter().any(|l| l == "TCP");
    let mut levels: Vec<f64> = Vec::new();
    for &f in &v.load_n {
        let level = (f / 10.0).round() * 10.0;
        if !levels.iter().any(|l| (l - level).abs() < 1e-9) {
            levels.push(level);
        }
    }
    levels.sort_by(f64::total_cmp);
    let many_levels = levels.len() > 4;
    for level in if many_levels { vec![f64::NAN] } else { levels } {
        let keep: Vec<usize> = (0..v.labels.len())
            .filter(|&i| !tcp_only || v.labels[i] == "TCP")
            .filter(|&i| {
                level.is_nan() || ((v.load_n[i] / 10.0).round() * 10.0 - level).abs() < 1e-9
            })
            .collect();
        if keep.is_empty() {
            continue;
        }
        let xs: Vec<f64> = keep.iter().map(|&i| v.points[i][0] * 1e3).collect();
        let ys: Vec<f64> = keep.iter().map(|&i| v.points[i][1] * 1e3).collect();
        let load = if level.is_nan() {
            "all loads".to_string()
        } else {
            format!("{level:.0} N")
        };
        let file_tag = if level.is_nan() {
            "all".to_string()
        } else {
            format!("{level:.0}N")
        };
        for (tag, m) in
            std::iter::once(("model", &v.model)).chain(v.baseline.as_ref().map(|b| ("baseline", b)))
        {
            let norm: Vec<f64> = keep
                .iter()
                .map(|&i| {
                    let e = m.errors[i];
                    (e[0] * e[0] + e[1] * e[1] + e[2] * e[2]).sqrt() * 1e3
                })
                .collect();
            let top = norm.iter().copied().fold(0.0, f64::max).max(1e-9);
            let path = dir.join(format!("heatmap_{tag}_{file_tag}.png"));
            let spec = PlotSpec::new(format!("|error| of the {tag}, {load}"), "x [mm]", "y [mm]")
                .size(800, 700)
                .color_range(0.0, top);
            scatter_heatmap(&path, &spec, &xs, &ys, &norm, "|measured − predicted| [mm]")
                .map_err(report_err)?;
            html.image(
                &path,
                format!(
                    "Error norm over the measured points, {load}: {} (cf. Figs. 11, 13)",
                    m.name
                ),
            );
            files.push(path);
        }
    }
    let page = dir.join("validation.html");
    html.write(&page).map_err(report_err)?;
    files.push(page);
    Ok(files)
}
