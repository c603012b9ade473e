//! The README's headline table ("paper vs deflex"), rendered from a study's own summary so the
//! README never drifts from what `deflex demo` measures: the demo writes it as `results.md`, and
//! a test compares it with the block between the README's `demo-results` markers.

use deflex_study::compensation::{FEED_FORWARD, OFFLINE_LOG, OFFLINE_PROCESS, PRECOMPENSATED};
use deflex_study::{BASELINE, DemoSummary, IDENTIFIED, paper};
use std::fmt::Write;

/// The marker lines around the table in README.md.
pub const BEGIN_MARKER: &str =
    "<!-- demo-results:begin (written by `deflex demo --seed 1` as results.md; kept by a test) -->";
/// The closing marker.
pub const END_MARKER: &str = "<!-- demo-results:end -->";

/// Max / RMS δz of `model` on the grid at `load` ("600", "1100"), as "0.081 / 0.034 mm".
fn grid(summary: &DemoSummary, model: &str, load: &str, bold: bool) -> String {
    match summary.errors(model, &format!("grid {load} N")) {
        Some(e) if bold => format!("**{:.3} / {:.3} mm**", e.max_z_mm, e.rms_z_mm),
        Some(e) => format!("{:.3} / {:.3} mm", e.max_z_mm, e.rms_z_mm),
        None => "–".into(),
    }
}

/// `1e7` as "10⁷" (other values as they are).
fn power_of_ten(value: f64) -> String {
    const SUPERSCRIPT: [char; 10] = ['⁰', '¹', '²', '³', '⁴', '⁵', '⁶', '⁷', '⁸', '⁹'];
    let exponent = value.log10().round();
    if value > 0.0 && (10f64.powf(exponent) - value).abs() <= 1e-9 * value && exponent < 100.0 {
        let digits: String = format!("{exponent:.0}")
            .chars()
            .filter_map(|c| c.to_digit(10).map(|d| SUPERSCRIPT[d as usize]))
            .collect();
        format!("10{digits}")
    } else {
        format!("{value}")
    }
}

/// The headline table of a study (markdown, one line per row, ending with a newline).
pub fn results_table(summary: &DemoSummary) -> String {
    let mut t = String::new();
    let mut row = |quantity: &str, paper: &str, deflex: String| {
        let _ = writeln!(t, "| {quantity} | {paper} | {deflex} |");
    };
    row(
        "quantity",
        "paper (real TX200)",
        "deflex (SIMULATED cell)".into(),
    );
    row("---", "---", "---".into());
    for (i, load) in ["600", "1100"].iter().enumerate() {
        row(
            &format!("grid, one eDoF per joint: max / RMS δz error, {load} N"),
            &format!(
                "{:.2} / {:.2} mm",
                paper::ONE_EDOF_MAX_MM[i],
                paper::ONE_EDOF_RMS_MM[i]
            ),
            grid(summary, BASELINE, load, false),
        );
    }
    for (i, load) in ["600", "1100"].iter().enumerate() {
        row(
            &format!("grid, identified model: max / RMS δz error, {load} N"),
            &format!(
                "{:.2} / {:.2} mm",
                paper::MODEL_MAX_MM[i],
                paper::MODEL_RMS_MM[i]
            ),
            grid(summary, IDENTIFIED, load, true),
        );
    }
    let (o, k) = (&summary.forming_open, &summary.forming_closed);
    row(
        "forming, max path error norm without correction",
        &format!("{:.2} mm", paper::FORMING_OPEN_MAX_MM),
        format!(
            "{:.2} mm (RMS {:.2} mm)",
            o.max_error_norm_mm, o.rms_error_norm_mm
        ),
    );
    row(
        "forming, max path error norm with correction",
        &format!("{:.2} mm", paper::FORMING_CLOSED_MAX_MM),
        format!(
            "**{:.2} mm** (RMS {:.2} mm)",
            k.max_error_norm_mm, k.rms_error_norm_mm
        ),
    );
    row(
        "forming, improvement of the max error norm",
        &format!("{:.0} %", paper::FORMING_IMPROVEMENT_PERCENT),
        format!("**{:.1} %**", summary.improvement_percent),
    );
    row(
        "forming, max Fz / in-plane force without correction",
        &format!(
            "≈{:.0} / ≈{:.0} N",
            paper::FORMING_OPEN_FZ_N,
            paper::FORMING_OPEN_FXY_N
        ),
        format!("{:.0} / {:.0} N", o.max_fz_N, o.max_fxy_N),
    );
    row(
        "forming, max force norm without / with correction",
        "≈1300 / ≈1500 N (Figs. 18–19)",
        format!("{:.0} / {:.0} N", o.max_force_norm_N, k.max_force_norm_N),
    );
    if let Some(cone) = summary
        .compensation
        .parts
        .iter()
        .find(|p| p.part.starts_with("cone"))
    {
        let pair = |a: &str, b: &str| match (cone.way(a), cone.way(b)) {
            (Some(x), Some(y)) => Some((x, y)),
            _ => None,
        };
        if let Some((process, log)) = pair(OFFLINE_PROCESS, OFFLINE_LOG) {
            row(
                "cone, offline compensation only (no real-time option), forces from the process model / from the uncorrected run's log",
                "–",
                format!(
                    "{:.2} / {:.2} mm max (RMS {:.2} / {:.2} mm)",
                    process.max_error_mm, log.max_error_mm, process.rms_error_mm, log.rms_error_mm
                ),
            );
        }
        if let Some((ff, pre)) = pair(FEED_FORWARD, PRECOMPENSATED) {
            row(
                "cone, offline + online (feed-forward / pre-compensated program)",
                "–",
                format!(
                    "**{:.2} / {:.2} mm** max (RMS {:.2} / {:.2} mm)",
                    ff.max_error_mm, pre.max_error_mm, ff.rms_error_mm, pre.rms_error_mm
                ),
            );
        }
    }
    let c = &summary.stiff_contact;
    let unguarded = match (&c.unguarded.fault, c.unguarded.runaway_at_s) {
        (Some(fault), _) => format!(
            "{:.0} N (runs away, stopped by the `{}` fault)",
            c.unguarded.max_force_N,
            fault.split(':').next().unwrap_or(fault)
        ),
        (None, _) => format!(
            "{:.0} N ({:.2}×)",
            c.unguarded.max_force_N, c.unguarded.force_ratio_to_uncorrected
        ),
    };
    let guarded = format!(
        "**{:.0} N** ({:.2}×, {} `contact_runaway` warning{}{})",
        c.guarded.max_force_N,
        c.guarded.force_ratio_to_uncorrected,
        c.guarded.runaway_warnings,
        if c.guarded.runaway_warnings == 1 {
            ""
        } else {
            "s"
        },
        c.guarded
            .fault
            .as_ref()
            .map(|f| format!(", fault `{f}`"))
            .unwrap_or_default()
    );
    row(
        &format!(
            "plunge into a {} N/m fixture, max force without correction / with correction, no runaway guard / with the guard",
            power_of_ten(c.stiffness_n_m)
        ),
        "–",
        format!("{:.0} N / {unguarded} / {guarded}", c.open_max_force_N),
    );
    t
}

/// `readme` with the block between the markers replaced by `table`; `None` when the markers
/// are missing or out of order.
pub fn replace_block(readme: &str, table: &str) -> Option<String> {
    let begin = readme.find(BEGIN_MARKER)?;
    let after_begin = begin + BEGIN_MARKER.len();
    let end = after_begin + readme[after_begin..].find(END_MARKER)?;
    Some(format!(
        "{}\n{}{}",
        &readme[..after_begin],
        table,
        &readme[end..]
    ))
}

/// The block between the markers (without the marker lines), if present.
pub fn current_block(readme: &str) -> Option<&str> {
    let begin = readme.find(BEGIN_MARKER)? + BEGIN_MARKER.len();
    let end = begin + readme[begin..].find(END_MARKER)?;
    Some(readme[begin..end].trim_start_matches('\n'))
}
