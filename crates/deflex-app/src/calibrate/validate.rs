//! The validation of a stiffness model on measured displacements (`deflex validate`,
//! `deflex.validate`): prediction errors beside a baseline, their plots and page, and the
//! per-row prediction of a measurement or plan table.

use super::data::{DataCheck, MeasurementSource, geometry_json, read_checked, read_rows};
use crate::OptionNames;
use crate::error::Result;
use crate::report::text_table::render_table;
use crate::report::validation_tables::{
    VALIDATION_HEADERS, validation_rotation_summary, validation_rows,
};
use deflex_calibrate::stiffness::consistency::GeometryCheck;
use deflex_calibrate::stiffness::validation::ModelErrors;
use deflex_model::Robot;
use serde_json::{Value, json};
use std::path::{Path, PathBuf};

/// A validation with its file check.
pub struct ValidationRun {
    /// Prediction errors of the model (and the baseline).
    pub validation: deflex_calibrate::stiffness::validation::Validation,
    /// The forward-kinematics check.
    pub check: GeometryCheck,
    /// Warnings.
    pub warnings: Vec<String>,
}

/// Prediction errors of `model` (and `baseline`) on the measured rows of the data, after the
/// data's check against the model's forward kinematics.
pub fn validate(
    model: &Robot,
    baseline: Option<&Robot>,
    source: &MeasurementSource,
    check: &DataCheck,
    names: OptionNames,
) -> Result<ValidationRun> {
    let checked = read_checked(model, source, check, names)?;
    let validation =
        deflex_calibrate::stiffness::validation::validate(model, baseline, &checked.rows)?;
    Ok(ValidationRun {
        validation,
        check: checked.check,
        warnings: checked.warnings,
    })
}

/// What [`write_validation_report`] writes, in the words of [`crate::Error::ReportsNotBuilt`].
const VALIDATION_REPORT: &str =
    "the validation report (`deflex validate --out`; Python: `Validation.save`)";

/// The validation's plots and HTML page (`validation.html`) into the folder `dir`, replaced
/// whole (or left as it was on error). Returns the files written. Needs the `report` feature:
/// refused without it, nothing written.
pub fn write_validation_report(v: &ValidationRun, dir: &Path) -> Result<Vec<PathBuf>> {
    crate::report::require(VALIDATION_REPORT)?.validation_report(&v.validation, dir)
}

/// The validation as JSON (SI; `deflex validate --json`): the errors of the model and the
/// baseline, the file check, the warnings, and with `files` the files written.
pub fn validation_json(v: &ValidationRun, files: Option<&[PathBuf]>) -> Value {
    let m = |e: &ModelErrors| {
        let rotation = e.rotation.as_ref().map(|r| {
            let s = &r.stats;
            json!({"rows": s.norm.count, "rms_rad": s.rms, "max_abs_rad": s.max_abs, "mean_rad": s.mean, "rms_norm_rad": s.norm.rms, "max_norm_rad": s.norm.max})
        });
        json!({"name": e.name, "rms_m": e.stats.rms, "max_abs_m": e.stats.max_abs, "mean_m": e.stats.mean, "rms_norm_m": e.stats.norm.rms, "max_norm_m": e.stats.norm.max, "rotation": rotation})
    };
    let val = &v.validation;
    let mut value = json!({
        "rows": val.measured.len(),
        "model": m(&val.model),
        "baseline": val.baseline.as_ref().map(m),
        "geometry_check": geometry_json(&v.check),
        "warnings": v.warnings,
    });
    if let Some(files) = files {
        value["files"] = json!(
            files
                .iter()
                .map(|f| f.display().to_string())
                .collect::<Vec<_>>()
        );
    }
    value
}

/// The validation as text (`deflex validate`): the measured displacement's size, the error
/// table, the rotation errors when measured, the warnings.
pub fn validation_text(v: &ValidationRun) -> String {
    let val = &v.validation;
    let mut t = format!(
        "Prediction errors (measured − predicted), {} points; measured RMS x/y/z {:.4} / {:.4} / {:.4} mm\n",
        val.measured.len(),
        val.measured_rms_m[0] * 1e3,
        val.measured_rms_m[1] * 1e3,
        val.measured_rms_m[2] * 1e3
    );
    t.push_str(&render_table(&VALIDATION_HEADERS, &validation_rows(val)));
    if let Some(rotation) = validation_rotation_summary(val) {
        t.push_str(&rotation);
    }
    for w in &v.warnings {
        t.push_str(&format!("warning: {w}\n"));
    }
    t
}

/// What was written, as `deflex validate --out` says it after [`validation_text`].
pub fn validation_written_text(files: &[PathBuf], dir: &Path) -> String {
    format!(
        "wrote {} files to {} (validation.html)\n",
        files.len(),
        dir.display()
    )
}

/// Predicted displacement `[δp; δφ]` of every row of a measurement or plan table (m, rad).
pub fn predict_displacements(robot: &Robot, source: &MeasurementSource) -> Result<Vec<[f64; 6]>> {
    let file = read_rows(source, robot.joint_count(), false)?;
    Ok(deflex_calibrate::stiffness::validation::predict_full(
        robot, &file.rows,
    )?)
}
