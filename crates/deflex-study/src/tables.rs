//! Tables and CSV files of the study: validation error statistics, predictions, stiffnesses
//! beside Table 1 and the plant, and the "paper vs deflex" comparison.

use crate::paper;
use crate::study::{BASELINE, DemoSummary, IDENTIFIED, ModelErrorNumbers, StiffnessRow};
use deflex_stiffness::{MeasurementRow, SearchResult};
use deflex_model::{Axis, EdofSite, Robot};
use std::fmt::Write as _;
use std::path::Path;

/// Indices of the validation-grid rows loaded by the `load_n` dead weight (the twin labels them
/// `grid<load>N-…`).
pub(crate) fn grid_rows(grid: &[MeasurementRow], load_n: f64) -> Vec<usize> {
    let prefix = format!("grid{load_n:.0}N");
    (0..grid.len())
        .filter(|&i| grid[i].load_case.starts_with(&prefix))
        .collect()
}

/// Write a text file whole or not at all.
pub(crate) fn write_text(path: &Path, text: &str) -> Result<(), String> {
    deflex_files::write_atomic(path, text).map_err(|e| format!("{}: {e}", path.display()))
}

/// Errors (measured − predicted) of one model on the selected rows.
pub(crate) fn error_numbers(
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

/// Per-row measured and predicted displacements (m) of every model.
pub(crate) fn predictions_csv(
    rows: &[MeasurementRow],
    predictions: &[(&str, Vec<[f64; 3]>)],
) -> String {
    let mut s = String::from(
        "# SIMULATED measurements from the deflex digital twin; predictions of each model\n",
    );
    s.push_str("load_case,fz_N,x_m,y_m,z_m,dx_m,dy_m,dz_m");
    for (name, _) in predictions {
        let tag = column_tag(name);
        let _ = write!(s, ",{tag}_dx_m,{tag}_dy_m,{tag}_dz_m");
    }
    s.push('\n');
    for (i, row) in rows.iter().enumerate() {
        let d = row.displacement_m.unwrap_or([f64::NAN; 3]);
        let _ = write!(
            s,
            "{},{},{:?},{:?},{:?},{:e},{:e},{:e}",
            row.load_case,
            row.wrench[2],
            row.point_m[0],
            row.point_m[1],
            row.point_m[2],
            d[0],
            d[1],
            d[2]
        );
        for (_, predicted) in predictions {
            let p = predicted[i];
            let _ = write!(s, ",{:e},{:e},{:e}", p[0], p[1], p[2]);
        }
        s.push('\n');
    }
    s
}

/// Short column prefix of a model in the prediction CSVs.
pub(crate) fn column_tag(model: &str) -> &'static str {
    match model {
        IDENTIFIED => "identified",
        BASELINE => "one_edof",
        _ => "table1",
    }
}

pub(crate) fn stiffness_rows(search: &SearchResult, plant: &Robot) -> Vec<StiffnessRow> {
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
                deflex_stiffness::Status::Identified => "identified".to_string(),
                deflex_stiffness::Status::Weak => "weakly identified".to_string(),
                deflex_stiffness::Status::NotIdentifiable(reason) => {
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

pub(crate) fn stiffness_csv(rows: &[StiffnessRow]) -> String {
    let mut s = String::from(
        "# identified from the SIMULATED twin campaign; plant = the twin's hidden linear truth\n\
         name,identified,se,low95,high95,status,table1,plant\n",
    );
    let opt = |v: Option<f64>| v.map(|v| format!("{v:e}")).unwrap_or_default();
    for r in rows {
        let _ = writeln!(
            s,
            "{},{},{},{},{},\"{}\",{},{}",
            r.name,
            opt(r.identified),
            opt(r.se),
            opt(r.interval95.map(|i| i.0)),
            opt(r.interval95.map(|i| i.1)),
            r.status.replace('"', "'"),
            opt(r.table1),
            opt(r.plant)
        );
    }
    s
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

pub(crate) fn paper_vs_deflex_csv(summary: &DemoSummary) -> String {
    let mut s = String::from(
        "# deflex column: measured on the SIMULATED twin cell\nquantity,paper,deflex,unit\n",
    );
    for (quantity, paper, ours, unit) in paper_vs_deflex(summary) {
        let _ = writeln!(s, "\"{quantity}\",{paper},{ours:.4},{unit}");
    }
    s
}

/// `forming_closed/controller_log.csv`: every control cycle of the corrected run, with the
/// column names of the `deflex run` log (SI units) for the quantities the twin's controller
/// has: the TCP wrench, δŝ (eq. 15), ξ (eq. 7), ε (eq. 5), the runaway guard's loop-gain
/// estimate and the flags (integer and by name). No joint, raw-sensor or cycle-time columns: the
/// twin's run is in simulated time.
pub(crate) fn controller_log_csv(trace: &[deflex_control::CycleOutput], robot: &str) -> String {
    const AXES: [&str; 6] = ["x_m", "y_m", "z_m", "rx_rad", "ry_rad", "rz_rad"];
    const WRENCH: [&str; 6] = ["fx_n", "fy_n", "fz_n", "mx_nm", "my_nm", "mz_nm"];
    let mut s = String::with_capacity(trace.len() * 300 + 512);
    let _ = writeln!(
        s,
        "# SIMULATED deflex correction controller driving the digital twin (not a measurement); \
         robot: {robot}; one row per control cycle, columns as in the deflex run log"
    );
    let mut columns = vec!["time_s".to_string()];
    columns.extend(WRENCH.iter().map(|c| format!("w_{c}")));
    for prefix in ["ds", "xi", "eps"] {
        columns.extend(AXES.iter().map(|c| format!("{prefix}_{c}")));
    }
    columns.extend(["loop_gain", "flags", "status"].map(String::from));
    s.push_str(&columns.join(","));
    s.push('\n');
    for c in trace {
        let _ = write!(s, "{:.4}", c.time_s);
        for v in c.wrench_tcp {
            let _ = write!(s, ",{v:.3}");
        }
        for block in [&c.delta_s_hat, &c.xi, &c.epsilon] {
            for v in block {
                let _ = write!(s, ",{v:.5e}");
            }
        }
        if c.loop_gain.is_finite() {
            let _ = write!(s, ",{:.4}", c.loop_gain);
        } else {
            s.push(',');
        }
        let _ = writeln!(s, ",{},{}", c.flags.0, c.flags.describe());
    }
    s
}
