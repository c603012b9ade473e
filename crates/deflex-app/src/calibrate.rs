//! Stiffness identification (`deflex calibrate`) and validation (`deflex validate`) from a
//! measurement file or an in-memory table, with the CLI's checks and messages.
//!
//! Thin layer over `deflex-stiffness` (re-pointed at merge time): [`read_checked`],
//! [`calibrate`], [`validate`], [`report_text`], [`write_report`].

use crate::error::{Error, Result, bounded};
use deflex_calibrate::measurements::{DataError, MeasurementFile, MeasurementRow};
use deflex_calibrate::stiffness::consistency::{
    GeometryCheck, MAX_FK_TOLERANCE_M, MIN_FK_TOLERANCE_M, check_geometry, enforce,
};
pub use deflex_calibrate::stiffness::search::Criterion;
use deflex_calibrate::stiffness::search::{SearchOptions, SearchStep, search_structure};
use deflex_calibrate::stiffness::stiffness_fit::{Calibration, Status, Structure, calibrate_fixed};
use deflex_model::Robot;
use serde_json::{Value, json};
use std::path::{Path, PathBuf};

/// Where measurement rows come from.
#[derive(Clone, Debug)]
pub enum Source {
    /// A CSV file.
    File(PathBuf),
    /// CSV text made from an in-memory table (a DataFrame or a mapping of columns): its rows
    /// are named by index in errors (`DataFrame row 3: …`).
    Table {
        /// The CSV text (header on the first line).
        text: String,
        /// What the table is, for messages (`DataFrame`).
        origin: String,
    },
}

impl Source {
    /// The data as named to the user.
    pub fn name(&self) -> String {
        match self {
            Source::File(p) => p.display().to_string(),
            Source::Table { origin, .. } => origin.clone(),
        }
    }
}

/// The error of a table made in memory: a row's `path:line: message` re-told as
/// `origin row i: message` (the header is line 1, row 0 is line 2), any other as it is.
pub fn table_error(error: DataError) -> Error {
    match error {
        DataError::Row { path, line, error } => Error::TableRow {
            origin: path,
            row: line.saturating_sub(2),
            message: error.to_string(),
        },
        other => other.into(),
    }
}

/// Read measurement rows (displacements required when `measured`).
pub fn read_rows(source: &Source, joint_count: usize, measured: bool) -> Result<MeasurementFile> {
    match source {
        Source::File(path) => Ok(crate::load::read_file(path, Some(joint_count), measured)?),
        Source::Table { text, origin } => {
            deflex_calibrate::measurements::check_joint_columns(text, origin, joint_count)?;
            deflex_calibrate::measurements::parse_file(text, origin, measured).map_err(table_error)
        }
    }
}

/// Rows read and checked against the robot's forward kinematics.
pub struct CheckedRows {
    /// The rows.
    pub rows: Vec<MeasurementRow>,
    /// The forward-kinematics check.
    pub check: GeometryCheck,
    /// Warnings (a mismatch used anyway, a header naming another robot).
    pub warnings: Vec<String>,
    /// The file's header comments (`SIMULATED` marks simulated data).
    pub notes: Vec<String>,
}

/// The CLI's `read_checked`: the tolerance in range, the rows read, every point where the
/// forward kinematics puts it (or the file refused naming the rows).
pub fn read_checked(
    robot: &Robot,
    source: &Source,
    fk_tolerance_m: f64,
    ignore_fk_check: bool,
) -> Result<CheckedRows> {
    if !(fk_tolerance_m.is_finite()
        && (MIN_FK_TOLERANCE_M..=MAX_FK_TOLERANCE_M).contains(&fk_tolerance_m))
    {
        return Err(Error::invalid(
            "fk_tolerance_m",
            format!(
                "expected {MIN_FK_TOLERANCE_M:e} to {MAX_FK_TOLERANCE_M} m, got {fk_tolerance_m}"
            ),
        ));
    }
    let file = read_rows(source, robot.joint_count(), true)?;
    let name = source.name();
    let check = check_geometry(
        robot,
        &file.rows,
        Some(&file.lines),
        Some(&file.header),
        fk_tolerance_m,
    )?;
    let warnings = enforce(
        &check,
        &name,
        ignore_fk_check,
        "Is this the robot the data was measured on? Widen fk_tolerance_m, or use the data anyway with ignore_fk_check=True.",
    )?;
    Ok(CheckedRows {
        rows: file.rows,
        check,
        warnings,
        notes: file.header.notes,
    })
}

/// How the structure is chosen.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum StructureChoice {
    /// Structure search from one z-eDoF per joint (Fig. 6 of the paper, automated).
    Auto,
    /// The start model's eDoFs and centre shifts as given.
    Fixed {
        /// Also fit the centre shift of every joint with an x or y eDoF.
        fit_shifts: bool,
    },
}

/// Options of [`calibrate`] (the CLI's flags, SI).
#[derive(Clone, Debug)]
pub struct CalibrateOptions {
    /// Search or fixed structure.
    pub structure: StructureChoice,
    /// Rank structures by BIC or by cross-validated χ² (`min_relative_gain` a fraction).
    pub criterion: Criterion,
    /// Folds of the cross-validation shown in the iteration table (2 to 100).
    pub folds: usize,
    /// Stop once the RMS residual is at most this (m).
    pub target_rms_m: Option<f64>,
    /// Smallest BIC decrease to accept a refinement.
    pub min_bic_gain: f64,
    /// Consider base tilt eDoFs.
    pub allow_base: bool,
    /// Largest distance between a row's coordinates and the forward kinematics (m).
    pub fk_tolerance_m: f64,
    /// Use the data even when it disagrees with the forward kinematics.
    pub ignore_fk_check: bool,
}

/// A stiffness calibration and everything needed to print, save and report it.
pub struct StiffnessCalibration {
    /// The start model.
    pub start: Robot,
    /// The calibrated model (named as the CLI names it).
    pub model: Robot,
    /// The fit.
    pub calibration: Calibration,
    /// The search's steps (empty for a fixed structure).
    pub steps: Vec<SearchStep>,
    /// Why the search stopped.
    pub stop_reason: Option<String>,
    /// The rows fitted.
    pub rows: Vec<MeasurementRow>,
    /// The forward-kinematics check.
    pub check: GeometryCheck,
    /// Warnings of the check and of the fit.
    pub warnings: Vec<String>,
    /// Header notes of the data.
    pub notes: Vec<String>,
    /// The data, as named.
    pub data_name: String,
    /// Measured − predicted displacement of every row (m), with the calibrated model.
    pub residuals: Vec<[f64; 3]>,
    /// Predicted displacement of every row (m).
    pub predicted: Vec<[f64; 3]>,
    /// Wall time of the identification (s).
    pub elapsed_s: f64,
}

/// `deflex calibrate`: the CLI's checks, the identification, the calibrated model.
pub fn calibrate(
    start: &Robot,
    source: &Source,
    options: &CalibrateOptions,
) -> Result<StiffnessCalibration> {
    if let Some(t) = options.target_rms_m {
        bounded("target_rms_m", t, 0.0, 1.0, "m")?;
    }
    bounded("min_bic_gain", options.min_bic_gain, 0.0, 1e6, "")?;
    if let Criterion::CrossValidated {
        min_relative_gain, ..
    } = options.criterion
    {
        bounded("min_cv_gain", min_relative_gain, 0.0, 0.99999, "")?;
    }
    if !(2..=100).contains(&options.folds) {
        return Err(Error::invalid(
            "folds",
            format!("expected 2 to 100, got {}", options.folds),
        ));
    }
    let checked = read_checked(
        start,
        source,
        options.fk_tolerance_m,
        options.ignore_fk_check,
    )?;
    let t0 = std::time::Instant::now();
    let (calibration, steps, stop_reason) = match options.structure {
        StructureChoice::Fixed { fit_shifts } => {
            let mut structure = Structure::from_robot(start);
            if fit_shifts {
                structure = structure.with_free_shifts();
            }
            (
                calibrate_fixed(start, &checked.rows, &structure)?,
                Vec::new(),
                None,
            )
        }
        StructureChoice::Auto => {
            let search = SearchOptions {
                criterion: options.criterion,
                report_folds: options.folds,
                target_rms_m: options.target_rms_m,
                min_bic_gain: options.min_bic_gain,
                allow_base: options.allow_base,
                ..SearchOptions::default()
            };
            let result = search_structure(start, &checked.rows, &search, &mut |_| {})?;
            (result.calibration, result.steps, Some(result.stop_reason))
        }
    };
    let elapsed_s = t0.elapsed().as_secs_f64();
    let data_name = source.name();
    if !calibration.edofs.iter().any(|e| e.stiffness.is_some()) {
        return Err(Error::NothingIdentified { data: data_name });
    }
    let mut model = calibration.to_robot(start);
    let geometry = model
        .name
        .split(" — calibrated")
        .next()
        .unwrap_or("")
        .to_string();
    model.name = format!(
        "{geometry} — calibrated from {data_name} ({})",
        calibration.structure.label()
    );
    let predicted = deflex_calibrate::stiffness::validation::predict(&model, &checked.rows)?;
    let residuals = checked
        .rows
        .iter()
        .zip(&predicted)
        .map(|(row, p)| {
            let d = row.displacement_m.unwrap_or([f64::NAN; 3]);
            [d[0] - p[0], d[1] - p[1], d[2] - p[2]]
        })
        .collect();
    let mut warnings = checked.warnings;
    warnings.extend(calibration.warnings.iter().cloned());
    Ok(StiffnessCalibration {
        start: start.clone(),
        model,
        calibration,
        steps,
        stop_reason,
        rows: checked.rows,
        check: checked.check,
        warnings,
        notes: checked.notes,
        data_name,
        residuals,
        predicted,
        elapsed_s,
    })
}

/// `identified`, `weak` (the 95 % interval reaches k = ∞) or `not_identifiable`.
pub fn status_name(status: &Status) -> &'static str {
    match status {
        Status::Identified => "identified",
        Status::Weak => "weak",
        Status::NotIdentifiable(_) => "not_identifiable",
    }
}

fn finite_or_null(x: f64) -> Value {
    if x.is_finite() { json!(x) } else { Value::Null }
}

/// The calibration as the CLI's `--json` (SI): estimates, shifts, fit statistics, iterations,
/// file check, warnings.
pub fn summary_json(s: &StiffnessCalibration) -> Value {
    let cal = &s.calibration;
    let edofs: Vec<Value> = cal
        .edofs
        .iter()
        .map(|e| {
            let reason = match &e.status {
                Status::NotIdentifiable(r) => Some(r.clone()),
                _ => None,
            };
            json!({"edof": e.label, "status": status_name(&e.status), "reason": reason,
                   "stiffness_Nm_per_rad": e.stiffness, "stiffness_se": e.stiffness_se,
                   "interval95": e.interval95.map(|(a, b)| json!([a, finite_or_null(b)])),
                   "compliance": e.compliance, "compliance_se": finite_or_null(e.compliance_se)})
        })
        .collect();
    let r = &cal.residuals;
    let steps: Vec<Value> = s
        .steps
        .iter()
        .map(|st| {
            json!({"step": st.iteration, "change": st.change, "structure": st.structure,
                   "parameters": st.parameters, "rms_m": st.residuals.rms_all_m,
                   "rms_axis_m": st.residuals.position.rms, "bic": st.bic,
                   "delta_bic": finite_or_null(st.delta_bic), "cv_rms_m": st.cv_rms_m})
        })
        .collect();
    let c = &s.check;
    json!({
        "structure": cal.structure.label(),
        "edofs": edofs,
        "center_shifts": cal.shifts.iter().map(|sh| json!({"joint": sh.joint, "center_shift_m": sh.value_m, "se_m": sh.se_m, "fitted": sh.free})).collect::<Vec<_>>(),
        "parameters": cal.parameter_labels,
        "condition_number": finite_or_null(cal.condition_number),
        "reduced_chi2": cal.reduced_chi2,
        "bic": cal.bic,
        "rows": cal.rows,
        "residual_rms_m": r.position.rms, "residual_max_m": r.position.max_abs, "residual_rms_all_m": r.rms_all_m,
        "residual_rms_norm_m": r.position.norm.rms, "residual_max_norm_m": r.position.norm.max,
        "chi2_well_above_one": cal.reduced_chi2 > deflex_calibrate::stiffness::stiffness_fit::CHI2_WELL_ABOVE_ONE,
        "model_form_note": cal.model_form_note(),
        "iterations": steps,
        "stop_reason": s.stop_reason,
        "elapsed_s": s.elapsed_s,
        "geometry_check": {"robot": c.robot, "geometry": c.geometry, "tolerance_m": c.tolerance_m,
            "rows": c.rows, "checked_points": c.checked_points, "checked_loads": c.checked_loads,
            "disagreeing_rows": c.disagreeing_rows(), "max_distance_m": c.max_distance_m,
            "header_mismatch": c.header_mismatch},
        "warnings": s.warnings,
        "simulated_data": s.notes.iter().any(|n| n.contains("SIMULATED")),
    })
}

/// The CLI's text output of `deflex calibrate` (iteration table, estimates, residuals,
/// correlation, file check, warnings).
pub fn report_text(cal: &StiffnessCalibration) -> String {
    use crate::report::calibration_tables::{
        ITERATION_HEADERS, SHIFT_HEADERS, STIFFNESS_HEADERS, correlation_table, iteration_rows,
        residual_summary, shift_rows, stiffness_rows,
    };
    use deflex_plot::text_table::render_table;
    let c = &cal.calibration;
    let mut t = String::new();
    if !cal.steps.is_empty() {
        t.push_str(&format!(
            "Structure search ({} rows, {:.2} s)\n",
            c.rows, cal.elapsed_s
        ));
        t.push_str(&render_table(
            &ITERATION_HEADERS,
            &iteration_rows(&cal.steps),
        ));
        if let Some(s) = &cal.stop_reason {
            t.push_str(&format!("stopped: {s}\n"));
        }
        t.push('\n');
    }
    t.push_str(&format!("Identified model: {}\n", c.structure.label()));
    t.push_str(&render_table(&STIFFNESS_HEADERS, &stiffness_rows(c)));
    let shifts = shift_rows(c);
    if !shifts.is_empty() {
        t.push_str(&render_table(&SHIFT_HEADERS, &shifts));
    }
    t.push('\n');
    t.push_str(&residual_summary(c));
    t.push_str("\nParameter correlation:\n");
    t.push_str(&correlation_table(c));
    let check = &cal.check;
    t.push_str(&format!(
        "\nfile check: {} points and {} load points agree with the forward kinematics within {:.3} mm (largest {:.3} mm)\n",
        check.checked_points,
        check.checked_loads,
        check.tolerance_m * 1e3,
        check.max_distance_m * 1e3
    ));
    for w in &cal.warnings {
        t.push_str(&format!("warning: {w}\n"));
    }
    t
}

/// The calibration's HTML report with plots and CSV tables (`deflex calibrate --report`),
/// written whole into `dir`; `output_name` is where the model was (or will be) saved.
pub fn write_report(cal: &StiffnessCalibration, dir: &Path, output_name: &str) -> Result<()> {
    use crate::report::calibration_report::{CalibrationReport, write_calibration_report};
    let io = |source| Error::Io {
        path: dir.display().to_string(),
        source,
    };
    let folder = deflex_files::AtomicDir::create(dir).map_err(io)?;
    let report = CalibrationReport {
        start_name: &cal.start.name,
        data_name: &cal.data_name,
        output_name,
        calibration: &cal.calibration,
        predicted: &cal.predicted,
        steps: &cal.steps,
        stop_reason: cal.stop_reason.as_deref(),
        rows: &cal.rows,
        warnings: &cal.warnings,
        data_notes: &cal.notes,
        couplings: None,
    };
    write_calibration_report(folder.path(), &report)?;
    folder.commit().map_err(io)?;
    Ok(())
}

/// A validation with its file check.
pub struct Validation {
    /// Prediction errors of the model (and the baseline).
    pub validation: deflex_calibrate::stiffness::validation::Validation,
    /// The forward-kinematics check.
    pub check: GeometryCheck,
    /// Warnings.
    pub warnings: Vec<String>,
}

/// `deflex validate`: prediction errors of `model` (and `baseline`) on measured rows.
pub fn validate(
    model: &Robot,
    baseline: Option<&Robot>,
    source: &Source,
    fk_tolerance_m: f64,
    ignore_fk_check: bool,
) -> Result<Validation> {
    let checked = read_checked(model, source, fk_tolerance_m, ignore_fk_check)?;
    let validation =
        deflex_calibrate::stiffness::validation::validate(model, baseline, &checked.rows)?;
    Ok(Validation {
        validation,
        check: checked.check,
        warnings: checked.warnings,
    })
}

/// The validation as the CLI's `--json` (SI).
pub fn validation_json(v: &Validation) -> Value {
    let m = |e: &deflex_calibrate::stiffness::validation::ModelErrors| {
        json!({"name": e.name, "rms_m": e.stats.rms, "max_abs_m": e.stats.max_abs,
               "mean_m": e.stats.mean, "rms_norm_m": e.stats.norm.rms,
               "max_norm_m": e.stats.norm.max})
    };
    let val = &v.validation;
    json!({"rows": val.measured.len(), "model": m(&val.model), "baseline": val.baseline.as_ref().map(m),
           "measured_rms_m": val.measured_rms_m, "warnings": v.warnings,
           "geometry_check": {"max_distance_m": v.check.max_distance_m, "tolerance_m": v.check.tolerance_m}})
}

/// The validation's plots and HTML page (`deflex validate --out`).
pub fn write_validation_report(v: &Validation, dir: &Path) -> Result<Vec<PathBuf>> {
    Ok(crate::report::validation_report::write_validation_report(
        &v.validation,
        dir,
    )?)
}

/// Predicted displacement `[δp; δφ]` of every row of a measurement or plan table (m, rad).
pub fn predict_displacements(robot: &Robot, source: &Source) -> Result<Vec<[f64; 6]>> {
    let file = read_rows(source, robot.joint_count(), false)?;
    Ok(deflex_calibrate::stiffness::validation::predict_full(
        robot, &file.rows,
    )?)
}
