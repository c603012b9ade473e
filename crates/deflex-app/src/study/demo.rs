//! `deflex demo`: the whole study on the twin cell of a robot, written into its report folder,
//! and the summary both the folder and the command line show (text and JSON).

use crate::error::{Error, Result};
use crate::study::contact::ContactLoopNumbers;
use crate::study::{DemoOptions, DemoSummary, paper_vs_deflex_rows, run_study};
use deflex_telemetry::OnProgress;
use std::fmt::Write as _;
use std::path::Path;

/// Run the study of `options` on the twin cell of `options.robot` and write it into the folder
/// `out` (built aside and swapped in whole: `crate::report::study::write_study`); `progress`
/// hears of every stage. Returns the study's numbers. The folder holds the study's figures and
/// page: without the `report` feature the demo is refused before the study runs
/// ([`run_study`] computes the study in every build).
pub fn demo(options: &DemoOptions, out: &Path, progress: OnProgress<'_>) -> Result<DemoSummary> {
    let drawing = crate::report::require("the study's report folder (`deflex demo`)")?;
    let cell = crate::cell::twin_cell_file::cell_for_robot(&options.robot)?;
    let study = run_study(options, cell, progress)?;
    drawing.study(&study, out)?;
    Ok(study.summary)
}

/// The study's numbers as JSON text (the fields of `summary.json`, in their order).
pub fn summary_json(summary: &DemoSummary) -> Result<String> {
    serde_json::to_string_pretty(summary).map_err(|e| Error::Serialise {
        what: "the study's summary",
        reason: e.to_string(),
    })
}

/// How a closed loop into the stiff fixture ended, in words: its fault, or its runaway
/// warnings.
fn outcome(l: &ContactLoopNumbers) -> String {
    match (&l.fault, l.runaway_warnings) {
        (Some(f), _) => format!(" ({f})"),
        (None, 0) => String::new(),
        (None, n) => format!(
            " ({n} contact_runaway warning{})",
            if n == 1 { "" } else { "s" }
        ),
    }
}

/// The study's headline numbers as text (mm, N): the paper's comparison for the TX200 (else the
/// identified model's errors), forming without and with correction, the stiff contact, the
/// worst sensitivity condition, the identified structure, and the report page written into
/// `out` after `elapsed_s` seconds.
pub fn summary_text(summary: &DemoSummary, out: &Path, elapsed_s: f64) -> String {
    let mut text = String::new();
    let _ = writeln!(text);
    let _ = writeln!(
        text,
        "deflex demo — SIMULATED cell of the {} (seed {}){}",
        summary.robot,
        summary.seed,
        if summary.quick { ", quick" } else { "" }
    );
    if summary.paper_comparison {
        let _ = writeln!(
            text,
            "{:<52} {:>10} {:>12}",
            "quantity", "paper", "deflex (sim)"
        );
        for (quantity, paper, ours, unit) in paper_vs_deflex_rows(summary) {
            let _ = writeln!(
                text,
                "{:<52} {:>7.3} {unit:<2} {:>9.3} {unit}",
                quantity, paper, ours
            );
        }
    } else {
        for v in &summary.validation {
            if v.model.starts_with("identified") {
                let _ = writeln!(
                    text,
                    "identified model, {}: RMS / max δz error {:.3} / {:.3} mm",
                    v.data, v.rms_z_mm, v.max_z_mm
                );
            }
        }
    }
    let (o, c) = (&summary.forming_open, &summary.forming_closed);
    let _ = writeln!(
        text,
        "cone, every error source on: max |error| {:.3} → {:.3} mm ({:.1} % better), RMS {:.3} → {:.3} mm, \
         max |F| {:.0} → {:.0} N",
        o.max_error_norm_mm,
        c.max_error_norm_mm,
        summary.improvement_percent,
        o.rms_error_norm_mm,
        c.rms_error_norm_mm,
        o.max_force_norm_N,
        c.max_force_norm_N
    );
    let sc = &summary.stiff_contact;
    let _ = writeln!(
        text,
        "plunge into a {:.0e} N/m fixture: max |F| {:.0} N without correction, {:.0} N with \
         correction and no runaway guard{}, {:.0} N with the guard{}",
        sc.stiffness_n_m,
        sc.open_max_force_N,
        sc.unguarded.max_force_N,
        outcome(&sc.unguarded),
        sc.guarded.max_force_N,
        outcome(&sc.guarded)
    );
    if let Some(s) = &summary.sensitivity {
        let worst = s
            .rows
            .iter()
            .min_by(|a, b| a.improvement_percent.total_cmp(&b.improvement_percent));
        if let Some(w) = worst {
            let _ = writeln!(
                text,
                "sensitivity: {} runs, worst improvement {:.1} % ({}: {})",
                s.runs, w.improvement_percent, w.factor, w.condition
            );
        }
    }
    let _ = writeln!(
        text,
        "identified structure: {}",
        summary.identified_structure
    );
    let _ = writeln!(
        text,
        "report: {} ({:.1} s)",
        out.join("index.html").display(),
        elapsed_s
    );
    text
}
