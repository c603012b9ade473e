//! What a stiffness calibration shows: the text `deflex calibrate` prints and Python's
//! `report()`, and the JSON of `deflex calibrate --json` and Python's `to_dict()`.

use super::couplings;
use super::data::{geometry_json, geometry_text};
use super::stiffness::StiffnessCalibration;
use crate::report::calibration_tables::{
    ITERATION_HEADERS, SHIFT_HEADERS, STIFFNESS_HEADERS, correlated_pairs_text, correlation_table,
    iteration_rows, residual_summary, shift_rows, stiffness_rows,
};
use crate::report::text_table::render_table;
use deflex_calibrate::stiffness::stiffness_fit::{
    CHI2_WELL_ABOVE_ONE, Calibration, STRONG_CORRELATION, Status,
};
use serde_json::{Value, json};
use std::path::Path;

/// `identified`, `weak` (the 95 % interval reaches k = ∞) or `not_identifiable`.
pub fn status_name(status: &Status) -> &'static str {
    match status {
        Status::Identified => "identified",
        Status::Weak => "weak",
        Status::NotIdentifiable(_) => "not_identifiable",
    }
}

/// A number, or null when it is infinite or NaN (not identifiable).
pub fn finite_or_null(x: f64) -> Value {
    if x.is_finite() { json!(x) } else { Value::Null }
}

/// The fit as JSON: estimates (an infinite upper bound of a 95 % interval as `"inf"`), shifts,
/// correlations, fit statistics.
fn calibration_json(cal: &Calibration) -> Value {
    let edofs: Vec<Value> = cal
        .edofs
        .iter()
        .map(|e| {
            let reason = match &e.status {
                Status::NotIdentifiable(r) => Some(r.clone()),
                _ => None,
            };
            json!({
                "edof": e.label,
                "status": status_name(&e.status),
                "reason": reason,
                "stiffness_Nm_per_rad": e.stiffness,
                "stiffness_se": e.stiffness_se,
                "interval95": e.interval95.map(|(a, b)| json!([a, if b.is_finite() { json!(b) } else { json!("inf") }])),
                "compliance": e.compliance,
                "compliance_se": finite_or_null(e.compliance_se),
            })
        })
        .collect();
    let shifts: Vec<Value> = cal
        .shifts
        .iter()
        .map(|s| json!({"joint": s.joint, "center_shift_m": s.value_m, "se_m": s.se_m, "fitted": s.free}))
        .collect();
    let r = &cal.residuals;
    json!({
        "structure": cal.structure.label(),
        "edofs": edofs,
        "center_shifts": shifts,
        "parameters": cal.parameter_labels,
        "correlation": (0..cal.correlation.nrows()).map(|i| (0..cal.correlation.ncols()).map(|j| cal.correlation[(i, j)]).collect::<Vec<_>>()).collect::<Vec<_>>(),
        "correlated_pairs": cal.correlated_pairs().iter().map(|p| json!({"first": p.first, "second": p.second, "rho": p.rho, "text": p.to_string()})).collect::<Vec<_>>(),
        "correlation_flag_threshold": STRONG_CORRELATION,
        "condition_number": cal.condition_number,
        "reduced_chi2": cal.reduced_chi2,
        "bic": cal.bic,
        "rows": cal.rows,
        "residual_rms_m": r.position.rms,
        "residual_max_m": r.position.max_abs,
        "residual_rms_all_m": r.rms_all_m,
        "residual_rms_norm_m": r.position.norm.rms,
        "residual_max_norm_m": r.position.norm.max,
        "rotation_rows": cal.rotation_rows,
        "residual_rotation_rms_rad": r.rotation_rms_rad,
        "chi2_well_above_one": cal.reduced_chi2 > CHI2_WELL_ABOVE_ONE,
        "model_form_note": cal.model_form_note(),
    })
}

/// The calibration as JSON (SI; `deflex calibrate --json`): the fit, the search's iterations and
/// why it stopped, the time it took, the file check, the couplings, every warning, and with
/// `output` where the model is written.
pub fn summary_json(cal: &StiffnessCalibration, output: Option<&Path>) -> Value {
    let steps: Vec<Value> = cal
        .steps
        .iter()
        .map(|s| json!({"step": s.iteration, "change": s.change, "structure": s.structure, "parameters": s.parameters, "rms_m": s.residuals.rms_all_m, "rms_axis_m": s.residuals.position.rms, "bic": s.bic, "delta_bic": s.delta_bic, "cv_rms_m": s.cv_rms_m}))
        .collect();
    let mut v = calibration_json(&cal.calibration);
    v["iterations"] = json!(steps);
    v["stop_reason"] = json!(cal.stop_reason);
    if let Some(output) = output {
        v["output"] = json!(output.display().to_string());
    }
    v["elapsed_s"] = json!(cal.elapsed_s);
    v["geometry_check"] = geometry_json(&cal.check);
    if let Some(fit) = &cal.couplings {
        let (list, summary) = couplings::json(fit);
        v["couplings"] = list;
        v["coupling_fit"] = summary;
    }
    v["warnings"] = json!(cal.warnings());
    v
}

/// The calibration as text (`deflex calibrate`): the search's iteration table, the estimates,
/// the residuals, the correlations (strong ones flagged), the couplings, the file check and
/// every warning.
pub fn report_text(cal: &StiffnessCalibration) -> String {
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
    let flagged = correlated_pairs_text(c);
    if !flagged.is_empty() {
        t.push('\n');
        t.push_str(&flagged);
    }
    if let Some(fit) = &cal.couplings {
        t.push_str(&couplings::text(&cal.diagonal, fit));
    }
    t.push('\n');
    t.push_str(&geometry_text(&cal.check));
    for w in cal.warnings() {
        t.push_str(&format!("warning: {w}\n"));
    }
    t
}

/// What was written, as `deflex calibrate` says it after [`report_text`]: the model file and
/// the report's page.
pub fn written_text(out: &Path, report: Option<&Path>) -> String {
    let mut t = format!("\nwrote {}\n", out.display());
    if let Some(dir) = report {
        t.push_str(&format!(
            "report: {}\n",
            dir.join("calibration.html").display()
        ));
    }
    t
}
