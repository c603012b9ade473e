//! The study's data files as text: predictions, stiffnesses, the paper's numbers beside the
//! twin's, the controller's per-cycle log, the Fig. 7 points, the sensitivity runs and the
//! compensation comparison. Every file says SIMULATED in its first line.

use crate::study::compensation::{CompensationStudy, PartRuns};
use crate::study::fig7::Fig7Point;
use crate::study::sensitivity::SensitivityResult;
use crate::study::{BASELINE, DemoSummary, IDENTIFIED, StiffnessRow, paper_vs_deflex_rows};
use deflex_calibrate::measurements::MeasurementRow;
use deflex_sim::FormingRun;
use std::fmt::Write as _;

/// Per-row measured and predicted displacements (m) of every model.
pub fn predictions_csv(rows: &[MeasurementRow], predictions: &[(&str, Vec<[f64; 3]>)]) -> String {
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
pub fn column_tag(model: &str) -> &'static str {
    match model {
        IDENTIFIED => "identified",
        BASELINE => "one_edof",
        _ => "table1",
    }
}

/// `stiffness.csv`: identified stiffnesses and shifts beside Table 1 and the plant.
pub fn stiffness_csv(rows: &[StiffnessRow]) -> String {
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

/// `paper_vs_deflex.csv`.
pub fn paper_vs_deflex_csv(summary: &DemoSummary) -> String {
    let mut s = String::from(
        "# deflex column: measured on the SIMULATED twin cell\nquantity,paper,deflex,unit\n",
    );
    for (quantity, paper, ours, unit) in paper_vs_deflex_rows(summary) {
        let _ = writeln!(s, "\"{quantity}\",{paper},{ours:.4},{unit}");
    }
    s
}

/// `forming_closed/controller_log.csv`: every control cycle of the corrected run in the run
/// log's format ([`deflex_record::run_log::RunLogFormat::twin`]: the `deflex run` log's column
/// names and SI units, for the quantities the twin's controller has: the TCP wrench, δŝ
/// (eq. 15), ξ (eq. 7), ε (eq. 5), the runaway guard's loop-gain estimate and the flags, integer
/// and by name). No joint, raw-sensor or cycle-time columns: the twin's run is in simulated
/// time.
pub fn controller_log_csv(trace: &[deflex_control::CycleOutput], robot: &str) -> String {
    use deflex_control::RecordCycle as _;
    let format = deflex_record::run_log::RunLogFormat::twin();
    let mut s = String::with_capacity(trace.len() * 300 + 512);
    let _ = writeln!(
        s,
        "# SIMULATED deflex correction controller driving the digital twin (not a measurement); \
         robot: {robot}; one row per control cycle, columns as in the deflex run log"
    );
    s.push_str(&format.header());
    s.push('\n');
    let mut sample = deflex_telemetry::CycleSample::default();
    for c in trace {
        sample.record_output(c);
        format.write_row(&sample, &mut s);
        s.push('\n');
    }
    s
}
/// `fig7_points.csv`: per point its position, the SIMULATED measurement and each model's
/// prediction (SI units).
pub fn fig7_csv(rows: &[MeasurementRow], points: &[Fig7Point]) -> String {
    let mut s = String::from(
        "# SIMULATED Fig. 7 test on the deflex digital twin: q = 0, 90°, 0, 0, 0, 0; fy = 1400 N \
         at the TCP; displacements measured by the simulated tracker and predicted by each model\n\
         point,point_link,x_m,y_m,z_m,fy_N,dx_m,dy_m,dz_m,sigma_m",
    );
    if let Some(first) = points.first() {
        for (name, _) in &first.predicted_mm {
            let tag = column_tag(name);
            let _ = write!(s, ",{tag}_dx_m,{tag}_dy_m");
        }
    }
    s.push('\n');
    for (row, point) in rows.iter().zip(points) {
        let d = row.displacement_m.unwrap_or([f64::NAN; 3]);
        let _ = write!(
            s,
            "{},{},{:?},{:?},{:?},{},{:e},{:e},{:e},{:e}",
            row.point,
            row.point_link,
            row.point_m[0],
            row.point_m[1],
            row.point_m[2],
            row.wrench[1],
            d[0],
            d[1],
            d[2],
            row.sigma_m.unwrap_or(f64::NAN)
        );
        for (_, p) in &point.predicted_mm {
            let _ = write!(s, ",{:e},{:e}", p[0] * 1e-3, p[1] * 1e-3);
        }
        s.push('\n');
    }
    s
}

/// `sensitivity.csv` (SIMULATED).
pub fn sensitivity_csv(result: &SensitivityResult) -> String {
    let mut s = format!(
        "# SIMULATED closed-loop sensitivity on the deflex digital twin (sensitivity cone); robot: {}\n\
         factor,condition,open_max_mm,closed_max_mm,closed_rms_mm,improvement_percent,closed_max_force_N,fault\n",
        result.robot
    );
    for r in &result.rows {
        let _ = writeln!(
            s,
            "\"{}\",\"{}\",{:.4},{:.4},{:.4},{:.2},{:.1},\"{}\"",
            r.factor,
            r.condition,
            r.open_max_mm,
            r.closed_max_mm,
            r.closed_rms_mm,
            r.improvement_percent,
            r.closed_max_force_N,
            r.fault.clone().unwrap_or_default()
        );
    }
    s
}

/// Rows for a table: factor, condition, open, closed max, improvement, force, fault.
pub fn sensitivity_table_rows(result: &SensitivityResult) -> Vec<Vec<String>> {
    result
        .rows
        .iter()
        .map(|r| {
            vec![
                r.factor.clone(),
                r.condition.clone(),
                format!("{:.3}", r.open_max_mm),
                format!("{:.3}", r.closed_max_mm),
                format!("{:.1}", r.improvement_percent),
                format!("{:.0}", r.closed_max_force_N),
                r.fault.clone().unwrap_or_else(|| "–".into()),
            ]
        })
        .collect()
}

/// Headers of [`sensitivity_table_rows`].
pub const SENSITIVITY_HEADERS: [&str; 7] = [
    "factor",
    "condition",
    "open max |e| [mm]",
    "closed max |e| [mm]",
    "improvement [%]",
    "closed max |F| [N]",
    "fault",
];

/// The file tag of a compared part: the cone first, then the CAM part.
pub fn part_tag(part: usize) -> &'static str {
    if part == 0 { "cone" } else { "part" }
}

/// A data file of the study: its name beside the page, one line on what it holds (the page's
/// list of files), and its text.
#[derive(Clone, Debug, PartialEq)]
pub struct DataFile {
    /// Path relative to the page.
    pub name: String,
    /// What it holds, in one line.
    pub description: String,
    /// Its contents.
    pub text: String,
}

/// `compensation.csv` (one row per part and way), each part's process-model table
/// (`compensation_<tag>_compensated_path.csv`) and the error along the path of every way
/// (`compensation_<tag>_error.csv`, one row per way and every fifth logged row).
pub fn compensation_files(study: &CompensationStudy, runs: &[PartRuns]) -> Vec<DataFile> {
    let mut files = Vec::new();
    let mut csv = String::from(
        "# SIMULATED: the digital twin, every error source on\n\
         part,way,max_error_mm,rms_error_mm,max_contact_error_mm,rms_contact_error_mm,\
         ramp_error_integral_mm_s,ramp_settle_s,ramps_not_settled,max_force_N\n",
    );
    for part in &study.parts {
        for w in &part.ways {
            let n = &w.numbers;
            let optional = |v: Option<f64>, digits: usize| {
                v.map_or(String::new(), |v| format!("{v:.digits$}"))
            };
            let _ = writeln!(
                csv,
                "\"{}\",\"{}\",{:.4},{:.4},{},{},{},{},{},{:.1}",
                part.part,
                w.way,
                n.max_error_mm,
                n.rms_error_mm,
                optional(n.max_contact_error_mm, 4),
                optional(n.rms_contact_error_mm, 4),
                optional(n.ramp_error_integral_mm_s, 5),
                optional(n.ramp_settle_s, 3),
                n.ramps_not_settled,
                n.max_force_N
            );
        }
    }
    files.push(DataFile {
        name: "compensation.csv".to_string(),
        description: "offline, online and combined compensation compared: per part and way, \
                      the largest and RMS path error (all and in contact), the lag at the force \
                      ramps and the largest force (SIMULATED)"
            .to_string(),
        text: csv,
    });
    for (i, part) in runs.iter().enumerate() {
        let tag = part_tag(i);
        let name = runs[i]
            .runs
            .first()
            .map_or("", |(_, r)| r.summary.path.as_str());
        files.push(DataFile {
            name: format!("compensation_{tag}_compensated_path.csv"),
            description: format!(
                "{name}: the offline compensation along the path: desired and compensated pose, \
                 the shift between them, the force the process model expects and the deflection \
                 it causes (SI units, SIMULATED)"
            ),
            text: part.table_csv.clone(),
        });
        let mut text = String::from(
            "# SIMULATED: path error norm of each way against the position along the desired \
             path (arc length), every fifth logged row\nway,path_s_m,time_s,error_m\n",
        );
        for (way, run) in &part.runs {
            for (s, t, e) in error_along_path(run, 5) {
                let _ = writeln!(text, "\"{way}\",{s:.6},{t:.2},{e:.4e}");
            }
        }
        files.push(DataFile {
            name: format!("compensation_{tag}_error.csv"),
            description: format!(
                "{name}: path error norm (m) of every way against the position along the \
                 desired path (m) and time (s), one row per way and fifth logged row (SIMULATED)"
            ),
            text,
        });
    }
    files
}

/// A run's path error norm against its position along the desired path: `(arc length of the
/// desired path (m), time (s), |true − desired| (m))` at every `step`-th logged row. Position,
/// not time, is what two ways of running the same part share (a corrected run can take longer
/// or shorter to cover the same path), so their curves line up only against it.
pub(crate) fn error_along_path(run: &FormingRun, step: usize) -> Vec<(f64, f64, f64)> {
    let arc = crate::study::compensation::lag::desired_arc_length(run);
    run.log
        .rows
        .iter()
        .zip(arc)
        .step_by(step.max(1))
        .map(|(r, s)| (s, r.time_s, r.truth.path_error_m().norm()))
        .collect()
}
