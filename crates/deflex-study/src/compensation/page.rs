//! The compensation comparison in the report: CSV files, figures and the page section
//! (SIMULATED).

use super::{CompensationStudy, PartRuns, lag};
use crate::figures::Figure;
use crate::tables::write_text;
use deflex_report::{HtmlReport, PlotSpec, Series, line_plot};
use std::fmt::Write as _;
use std::path::Path;

/// Ways drawn in the figures (the double correction and the log compensation are in the table).
const DRAWN: [&str; 5] = [
    super::UNCORRECTED,
    super::OFFLINE_PROCESS,
    super::ONLINE,
    super::FEED_FORWARD,
    super::PRECOMPENSATED,
];

fn file_tag(part: usize) -> &'static str {
    if part == 0 { "cone" } else { "part" }
}

/// `compensation.csv` (one row per part and way), each part's process-model table
/// (`compensation_<tag>_compensated_path.csv`) and the error over time at 10 Hz
/// (`compensation_<tag>_error.csv`).
pub(crate) fn write_files(
    out: &Path,
    study: &CompensationStudy,
    runs: &[PartRuns],
) -> Result<(), String> {
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
    write_text(&out.join("compensation.csv"), &csv)?;
    for (i, part) in runs.iter().enumerate() {
        let tag = file_tag(i);
        write_text(
            &out.join(format!("compensation_{tag}_compensated_path.csv")),
            &part.table_csv,
        )?;
        let mut text = String::from("# SIMULATED: path error norm (mm) of each way, 10 Hz\ntime_s");
        for (way, _) in &part.runs {
            let _ = write!(text, ",\"{way}\"");
        }
        text.push('\n');
        let rows = part
            .runs
            .iter()
            .map(|(_, r)| r.log.rows.len())
            .min()
            .unwrap_or(0);
        for k in (0..rows).step_by(5) {
            let _ = write!(text, "{:.2}", part.runs[0].1.log.rows[k].time_s);
            for (_, run) in &part.runs {
                let t = &run.log.rows[k].truth;
                let _ = write!(text, ",{:.5}", (t.true_m - t.desired_m).norm() * 1e3);
            }
            text.push('\n');
        }
        write_text(&out.join(format!("compensation_{tag}_error.csv")), &text)?;
    }
    Ok(())
}

fn error_series(
    run: &deflex_sim::FormingRun,
    from: usize,
    to: usize,
    t0: f64,
) -> (Vec<f64>, Vec<f64>) {
    run.log.rows[from..to]
        .iter()
        .map(|r| (r.time_s - t0, r.truth.path_error_m().norm() * 1e3))
        .unzip()
}

/// The path error over the run for each part, and one force ramp of the CAM part up close.
pub(crate) fn figures(out: &Path, runs: &[PartRuns]) -> Result<Vec<Figure>, String> {
    let mut figures = Vec::new();
    for (i, part) in runs.iter().enumerate() {
        let tag = file_tag(i);
        let series: Vec<Series> = part
            .runs
            .iter()
            .filter(|(way, _)| DRAWN.contains(&way.as_str()))
            .map(|(way, run)| {
                let (t, e) = error_series(run, 0, run.log.rows.len(), 0.0);
                Series::line(way.clone(), t, e)
            })
            .collect();
        let path = out.join(format!("compensation_{tag}_error.png"));
        let name = &part.runs[0].1.summary.path;
        let spec = PlotSpec::new(
            format!("SIMULATED cell — path error norm, {name}: offline, online and both"),
            "time [s]",
            "|error| [mm]",
        )
        .size(1100, 500);
        line_plot(&path, &spec, &series).map_err(|e| e.to_string())?;
        figures.push((
            path,
            format!(
                "Path error norm along {name} without correction, with the offline compensation \
                 (process model), the online correction, and both (SIMULATED)"
            ),
        ));
    }
    // A ramp of the CAM part up close: the middle one.
    if let Some(part) = runs.get(1)
        && let Some(&s) = part.ramps.get(part.ramps.len() / 2)
    {
        let series: Vec<Series> = part
            .runs
            .iter()
            .filter(|(way, _)| DRAWN.contains(&way.as_str()))
            .map(|(way, run)| {
                let arc = lag::desired_arc_length(run);
                let start = arc.partition_point(|a| *a < s);
                let t0 = run.log.rows.get(start).map_or(0.0, |r| r.time_s);
                let from = run.log.rows.partition_point(|r| r.time_s < t0 - 0.5);
                let to = run
                    .log
                    .rows
                    .partition_point(|r| r.time_s <= t0 + lag::SETTLE_WINDOW_S);
                let (t, e) = error_series(run, from, to, t0);
                Series::line(way.clone(), t, e)
            })
            .collect();
        let path = out.join("compensation_ramp.png");
        let spec = PlotSpec::new(
            "SIMULATED cell — path error at a force ramp of the CAM part (t = 0: the force at 50 % of its step)",
            "time from the 50 % point [s]",
            "|error| [mm]",
        )
        .size(1100, 500);
        line_plot(&path, &spec, &series).map_err(|e| e.to_string())?;
        figures.push((
            path,
            format!(
                "The lag at a force ramp (ramp {} of {}, after a plunge): the online correction \
                 catches up with the deflection after the force has risen; the feed-forward and \
                 the pre-compensated program do not wait for it (SIMULATED)",
                part.ramps.len() / 2 + 1,
                part.ramps.len()
            ),
        ));
    }
    Ok(figures)
}

/// The report's section.
pub(crate) fn section(html: &mut HtmlReport, study: &CompensationStudy, figures: &[Figure]) {
    html.section("Compensation without a real-time option: offline, online and both");
    html.paragraph(format!(
        "For cells without a real-time correction option, deflex compensate gives the robot a \
         compensated program (commanded = desired − predicted deflection, with the identified \
         model) from forces predicted by a process model or logged in a previous run; where the \
         option exists, the same table is the online controller's feed-forward, or the \
         controller runs on top of the compensated program knowing what it already applies. \
         SIMULATED: the twin's robot with every error source on; the process model is the twin's \
         own forming law (optimistic), driven by the identified robot model, not the plant; the \
         compensations are position only (the twin holds the tool orientation); feed-forward \
         lead {:.3} s. The controller runs with its defaults, the contact-runaway guard on; \
         on the CAM part each plunge's elastic onset into the sheet reads as a loop gain of \
         0.8–1.2 and trips it (the guard cannot tell that onset from a fixture), so the part \
         also shows the online correction with the guard off. In contact: the rows whose \
         contact force is at least {:.0} N (the error that forms the part, without the \
         transients in the air after a retract, where a correction still ramping out at its \
         rate limit moves the tool). Lag: {}.",
        study.lead_s,
        super::lag::CONTACT_FORCE_N,
        study.lag_definition
    ));
    for part in &study.parts {
        let p = &part.offline_process;
        html.paragraph(format!(
            "{} ({} points, {:.0} mm, {} force ramp(s)). Process-model compensation: {} \
             iteration(s){}, predicted error {:.3} → {:.4} mm, largest compensation {:.3} mm, \
             force {:.0} N, {:.2} s. Log compensation: predicted error {:.3} → {:.4} mm.",
            part.part,
            part.points,
            part.length_mm,
            part.ramps,
            p.iterations,
            if p.converged { "" } else { " (not converged)" },
            p.predicted_error_before_mm,
            p.predicted_error_after_mm,
            p.max_compensation_mm,
            p.max_force_N,
            p.seconds,
            part.offline_log.predicted_error_before_mm,
            part.offline_log.predicted_error_after_mm,
        ));
        let rows: Vec<Vec<String>> = part
            .ways
            .iter()
            .map(|w| {
                let n = &w.numbers;
                vec![
                    w.way.clone(),
                    format!("{:.3}", n.max_error_mm),
                    format!("{:.3}", n.rms_error_mm),
                    n.max_contact_error_mm
                        .map_or("–".into(), |v| format!("{v:.3}")),
                    n.rms_contact_error_mm
                        .map_or("–".into(), |v| format!("{v:.3}")),
                    n.ramp_error_integral_mm_s
                        .map_or("– (no force ramp)".into(), |v| format!("{v:.4}")),
                    match n.ramp_settle_s {
                        None => "–".into(),
                        Some(v) if n.ramps_not_settled > 0 => {
                            format!("{v:.2} ({} not settled)", n.ramps_not_settled)
                        }
                        Some(v) => format!("{v:.2}"),
                    },
                    format!("{:.0}", n.max_force_N),
                ]
            })
            .collect();
        html.table(
            &[
                "way",
                "max |e| [mm]",
                "RMS |e| [mm]",
                "max |e| in contact [mm]",
                "RMS |e| in contact [mm]",
                "ramp ∫|e|dt [mm·s]",
                "ramp settle [s]",
                "max |F| [N]",
            ],
            &rows,
        );
    }
    for (path, caption) in figures {
        html.image(path, caption.clone());
    }
}
