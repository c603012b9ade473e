//! The study's derived numbers: validation error statistics, stiffnesses beside Table 1 and the
//! plant, and the "paper vs deflex" comparison (their CSV files and tables are
//! `crate::report::study`'s).

use crate::study::paper;
use crate::study::summary::{BASELINE, DemoSummary, IDENTIFIED, ModelErrorNumbers, StiffnessRow};
use deflex_calibrate::measurements::MeasurementRow;
use deflex_calibrate::stiffness::SearchResult;
use deflex_model::{Axis, EdofSite, Robot};

/// Indices of the validation-grid rows loaded by the `load_n` dead weight (the twin labels them
/// `grid<load>N-…`).
pub fn grid_rows(grid: &[MeasurementRow], load_n: f64) -> Vec<usize> {
    let prefix = format!("grid{load_n:.0}N");
    (0..grid.len())
        .filter(|&i| grid[i].load_case.starts_with(&prefix))
        .collect()
}

/// Errors (measured − predicted) of one model on the selected rows.
pub fn error_numbers(
    model: &str,
    data: &str,
    rows: &[MeasurementRow],
    predicted: &[[f64; 3]],
    selected: &[usize],
) -> ModelErrorNumbers {
    let n = selected.len().max(1) as f64;
    let (mut sum_z, mut sum_norm, mut sum_meas) = (0.0, 0.0, 0.0);
    let (mut max_z, mut max_norm) = (0.0f64, 0.0f64);
    for &i in selected {
        let measured = rows[i].displacement_m.unwrap_or([0.0; 3]);
        let e = [
            measured[0] - predicted[i][0],
            measured[1] - predicted[i][1],
            measured[2] - predicted[i][2],
        ];
        let norm = (e[0] * e[0] + e[1] * e[1] + e[2] * e[2]).sqrt();
        sum_z += e[2] * e[2];
        sum_norm += norm * norm;
        sum_meas += measured[2] * measured[2];
        max_z = max_z.max(e[2].abs());
        max_norm = max_norm.max(norm);
    }
    ModelErrorNumbers {
        model: model.to_string(),
        data: data.to_string(),
        points: selected.len(),
        rms_z_mm: (sum_z / n).sqrt() * 1e3,
        max_z_mm: max_z * 1e3,
        rms_norm_mm: (sum_norm / n).sqrt() * 1e3,
        max_norm_mm: max_norm * 1e3,
        measured_rms_z_mm: (sum_meas / n).sqrt() * 1e3,
    }
}

/// The identified stiffnesses and centre shifts beside Table 1 and the twin plant's values.
pub fn stiffness_rows(search: &SearchResult, plant: &Robot) -> Vec<StiffnessRow> {
    let table1 = |label: &str| {
        paper::TABLE1
            .iter()
            .find(|(l, _)| *l == label)
            .map(|(_, k)| *k)
    };
    let mut rows: Vec<StiffnessRow> = search
        .calibration
        .edofs
        .iter()
        .map(|e| {
            let (site, axis): (EdofSite, Axis) = e.id;
            let status = match &e.status {
                deflex_calibrate::stiffness::Status::Identified => "identified".to_string(),
                deflex_calibrate::stiffness::Status::Weak => "weakly identified".to_string(),
                deflex_calibrate::stiffness::Status::NotIdentifiable(reason) => {
                    format!("not identifiable: {reason}")
                }
            };
            StiffnessRow {
                name: e.label.clone(),
                identified: e.stiffness,
                se: e.stiffness_se,
                interval95: e.interval95,
                status,
                table1: table1(&e.label),
                plant: plant.stiffness(site, axis),
            }
        })
        .collect();
    for shift in &search.calibration.shifts {
        rows.push(StiffnessRow {
            name: format!("δr{} [m]", shift.joint),
            identified: Some(shift.value_m),
            se: shift.se_m,
            interval95: shift
                .se_m
                .map(|se| (shift.value_m - 1.96 * se, shift.value_m + 1.96 * se)),
            status: if shift.free {
                "fitted".into()
            } else {
                "fixed".into()
            },
            table1: (shift.joint == 3).then_some(paper::DELTA_R3_M),
            plant: plant.joints.get(shift.joint - 1).map(|j| j.center_shift),
        });
    }
    rows
}

/// Rows of the "paper vs deflex" table: (quantity, paper, deflex on the SIMULATED cell, unit).
pub fn paper_vs_deflex(summary: &DemoSummary) -> Vec<(String, f64, f64, &'static str)> {
    let mut rows = Vec::new();
    for (i, load) in ["600", "1100"].iter().enumerate() {
        let data = format!("grid {load} N");
        if let Some(e) = summary.errors(BASELINE, &data) {
            rows.push((
                format!("one eDoF per joint, max δz error, {load} N"),
                paper::ONE_EDOF_MAX_MM[i],
                e.max_z_mm,
                "mm",
            ));
            rows.push((
                format!("one eDoF per joint, RMS δz error, {load} N"),
                paper::ONE_EDOF_RMS_MM[i],
                e.rms_z_mm,
                "mm",
            ));
        }
        if let Some(e) = summary.errors(IDENTIFIED, &data) {
            rows.push((
                format!("identified model, max δz error, {load} N"),
                paper::MODEL_MAX_MM[i],
                e.max_z_mm,
                "mm",
            ));
            rows.push((
                format!("identified model, RMS δz error, {load} N"),
                paper::MODEL_RMS_MM[i],
                e.rms_z_mm,
                "mm",
            ));
        }
    }
    rows.push((
        "forming, max error norm without correction".into(),
        paper::FORMING_OPEN_MAX_MM,
        summary.forming_open.max_error_norm_mm,
        "mm",
    ));
    rows.push((
        "forming, max error norm with correction".into(),
        paper::FORMING_CLOSED_MAX_MM,
        summary.forming_closed.max_error_norm_mm,
        "mm",
    ));
    rows.push((
        "forming, improvement of the max error norm".into(),
        paper::FORMING_IMPROVEMENT_PERCENT,
        summary.improvement_percent,
        "%",
    ));
    rows.push((
        "forming, max Fz without correction".into(),
        paper::FORMING_OPEN_FZ_N,
        summary.forming_open.max_fz_N,
        "N",
    ));
    rows.push((
        "forming, max in-plane force without correction".into(),
        paper::FORMING_OPEN_FXY_N,
        summary.forming_open.max_fxy_N,
        "N",
    ));
    rows
}
