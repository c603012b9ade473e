//! The README's results, rendered from a study's own summary so the README never drifts from
//! what `deflex demo` measures: the headline table ("paper vs deflex") and the details under it
//! (identified structure, Figs. 8–9, the fixture plunges, the sensitivity). The demo writes both
//! as `results.md`, and a test compares each with its block between the README's markers.

use crate::study::compensation::{FEED_FORWARD, OFFLINE_LOG, OFFLINE_PROCESS, PRECOMPENSATED};
use crate::study::{BASELINE, DemoSummary, IDENTIFIED, paper};
use std::fmt::Write;

/// A generated block of the README.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum ReadmeBlock {
    /// The headline table ([`results_table`]).
    Results,
    /// The details under it ([`details_list`]).
    Details,
    /// The closed loop's sensitivity ([`sensitivity_list`]; only when the study ran it).
    Sensitivity,
}

impl ReadmeBlock {
    /// The marker line before the block.
    pub fn begin_marker(self) -> &'static str {
        match self {
            ReadmeBlock::Results => {
                "<!-- demo-results:begin (written by `deflex demo --seed 1` as results.md; kept by a test) -->"
            }
            ReadmeBlock::Details => {
                "<!-- demo-details:begin (written by `deflex demo --seed 1` as results.md; kept by a test) -->"
            }
            ReadmeBlock::Sensitivity => {
                "<!-- demo-sensitivity:begin (written by `deflex demo --seed 1` as results.md; kept by a test) -->"
            }
        }
    }

    /// The marker line after the block.
    pub fn end_marker(self) -> &'static str {
        match self {
            ReadmeBlock::Results => "<!-- demo-results:end -->",
            ReadmeBlock::Details => "<!-- demo-details:end -->",
            ReadmeBlock::Sensitivity => "<!-- demo-sensitivity:end -->",
        }
    }
}

/// What the demo writes as `results.md`: the table, then the details, each between its markers
/// (so the file can be pasted into the README as it is).
pub fn results_markdown(summary: &DemoSummary) -> String {
    let mut text = String::new();
    for (block, body) in [
        (ReadmeBlock::Results, results_table(summary)),
        (ReadmeBlock::Details, details_list(summary)),
        (ReadmeBlock::Sensitivity, sensitivity_list(summary)),
    ] {
        if body.is_empty() {
            continue;
        }
        let _ = write!(
            text,
            "{}\n{body}{}\n\n",
            block.begin_marker(),
            block.end_marker()
        );
    }
    text
}

/// Max / RMS δz of `model` on the grid at `load` ("600", "1100"), as "0.081 / 0.034 mm".
fn grid(summary: &DemoSummary, model: &str, load: &str, bold: bool) -> String {
    match summary.errors(model, &format!("grid {load} N")) {
        Some(e) if bold => format!("**{:.3} / {:.3} mm**", e.max_z_mm, e.rms_z_mm),
        Some(e) => format!("{:.3} / {:.3} mm", e.max_z_mm, e.rms_z_mm),
        None => "–".into(),
    }
}

/// The kind of a latched fault from its text (`force_over_limit: value … at t = …` →
/// `force_over_limit`).
fn fault_name(fault: &str) -> &str {
    fault.split(':').next().unwrap_or(fault)
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
    let models = [
        (
            BASELINE,
            "one eDoF per joint",
            paper::ONE_EDOF_MAX_MM,
            paper::ONE_EDOF_RMS_MM,
            false,
        ),
        (
            IDENTIFIED,
            "identified model",
            paper::MODEL_MAX_MM,
            paper::MODEL_RMS_MM,
            true,
        ),
    ];
    for (model, label, max_mm, rms_mm, identified) in models {
        for (i, load) in ["600", "1100"].iter().enumerate() {
            row(
                &format!("grid, {label}: max / RMS δz error, {load} N"),
                &format!("{:.2} / {:.2} mm", max_mm[i], rms_mm[i]),
                grid(summary, model, load, identified),
            );
        }
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
            fault_name(fault)
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

/// `readme` with `block` replaced by `text`; `None` when its markers are missing or out of order.
pub fn replace_block(readme: &str, block: ReadmeBlock, text: &str) -> Option<String> {
    let begin = readme.find(block.begin_marker())?;
    let after_begin = begin + block.begin_marker().len();
    let end = after_begin + readme[after_begin..].find(block.end_marker())?;
    Some(format!(
        "{}\n{}{}",
        &readme[..after_begin],
        text,
        &readme[end..]
    ))
}

/// The text of `block` (without the marker lines), if present.
pub fn current_block(readme: &str, block: ReadmeBlock) -> Option<&str> {
    let begin = readme.find(block.begin_marker())? + block.begin_marker().len();
    let end = begin + readme[begin..].find(block.end_marker())?;
    Some(readme[begin..end].trim_start_matches('\n'))
}

/// `value` with `decimals` decimals, a true minus sign, and no negative zero ("−0.03", "0.00").
fn signed(value: f64, decimals: usize) -> String {
    let text = format!("{value:.decimals$}");
    if text
        .trim_start_matches('-')
        .chars()
        .all(|c| c == '0' || c == '.')
    {
        text.trim_start_matches('-').to_string()
    } else {
        text.replace('-', "−")
    }
}

/// `100 (identified / truth − 1)` as "+3 %" / "−2 %".
fn deviation_percent(identified: f64, truth: f64) -> String {
    let p = 100.0 * (identified / truth - 1.0);
    if p >= 0.0 || signed(p, 0) == "0" {
        format!("+{} %", signed(p, 0))
    } else {
        format!("{} %", signed(p, 0))
    }
}

/// A unit or a per cent sign, kept on the line of the number before it.
fn is_unit(word: &str) -> bool {
    let bare = word.trim_end_matches([',', ';', '.', ')', ':']);
    word.starts_with('%') || ["mm", "N", "N/m", "µm", "ms", "s", "mrad"].contains(&bare)
}

/// `text` (one markdown bullet) wrapped at 100 columns, continuation lines indented by two; a
/// unit stays with its number.
fn wrapped_bullet(text: &str) -> String {
    let words: Vec<&str> = text.split_whitespace().collect();
    // Words glued to their unit: "+1 %", "0.52 mm".
    let mut tokens: Vec<String> = Vec::new();
    for word in words {
        match tokens.last_mut() {
            Some(last) if is_unit(word) => {
                last.push(' ');
                last.push_str(word);
            }
            _ => tokens.push(word.to_string()),
        }
    }
    let mut out = String::new();
    let mut line = String::new();
    for word in &tokens {
        if !line.is_empty() && line.chars().count() + 1 + word.chars().count() > 100 {
            out.push_str(&line);
            out.push('\n');
            line = String::from(" ");
        }
        if !line.is_empty() {
            line.push(' ');
        }
        line.push_str(word);
    }
    out.push_str(&line);
    out.push('\n');
    out
}

/// Numbers joined by " / ", each formatted by `f`.
fn slashed<T>(values: impl IntoIterator<Item = T>, f: impl Fn(T) -> String) -> String {
    values.into_iter().map(f).collect::<Vec<_>>().join(" / ")
}

/// The details under the headline table (markdown bullets, ending with a newline): the
/// identified structure against the twin's hidden truth, the paper's Figs. 8–9 test and the
/// plunges into fixtures of every stiffness.
pub fn details_list(summary: &DemoSummary) -> String {
    let mut t = String::new();
    identification_bullet(&mut t, summary);
    fig7_bullet(&mut t, summary);
    plunge_bullet(&mut t, summary);
    t
}

/// The closed loop's sensitivity as one markdown bullet; empty when the study did not run it.
pub fn sensitivity_list(summary: &DemoSummary) -> String {
    let mut t = String::new();
    sensitivity_bullet(&mut t, summary);
    t
}

fn identification_bullet(t: &mut String, s: &DemoSummary) {
    let mut b = String::new();
    let _ = write!(
        b,
        "- Identified structure (seed {}): `{}` in {} search steps; residual {:.0} µm RMS, χ²/dof \
         {:.2}.",
        s.seed,
        s.identified_structure,
        s.search_steps,
        s.identification_rms_um,
        s.identification_reduced_chi2
    );
    let shifts: Vec<String> = s
        .stiffness
        .iter()
        .filter(|r| r.name.starts_with('δ'))
        .filter_map(|r| {
            let name = r.name.split(' ').next().unwrap_or(&r.name);
            if !s.identified_structure.split(' ').any(|part| part == name) {
                return None;
            }
            let v = r.identified?;
            let mut text = format!("{name} = {} mm", signed(v * 1e3, 0));
            let refs: Vec<String> = [("paper", r.table1), ("twin", r.plant)]
                .iter()
                .filter_map(|(who, x)| x.map(|x| format!("{who} {} mm", signed(x * 1e3, 0))))
                .collect();
            if !refs.is_empty() {
                let _ = write!(text, " ({})", refs.join(", "));
            }
            Some(text)
        })
        .collect();
    if !shifts.is_empty() {
        let _ = write!(b, " Centre shifts: {}.", shifts.join("; "));
    }
    let against: Vec<String> = s
        .stiffness
        .iter()
        .filter(|r| !r.name.starts_with('δ'))
        .filter_map(|r| match (r.identified, r.plant) {
            (Some(v), Some(truth)) if truth > 0.0 => {
                Some(format!("{} {}", r.name, deviation_percent(v, truth)))
            }
            _ => None,
        })
        .collect();
    if !against.is_empty() {
        let _ = write!(
            b,
            " Identified stiffness against the twin's hidden linear truth: {}.",
            against.join(", ")
        );
    }
    t.push_str(&wrapped_bullet(&b));
}

fn fig7_bullet(t: &mut String, s: &DemoSummary) {
    let Some(first) = s.fig7.first() else {
        return;
    };
    let names = slashed(&s.fig7, |p| p.point.clone());
    let sigma = s.fig7.iter().map(|p| p.sigma_mm).fold(0.0, f64::max);
    let mut b = String::new();
    let _ = write!(
        b,
        "- Figs. 8–9 on the twin (q = 0, 90°, 0, 0, 0, 0, f_y = {:.0} N at the TCP, tracker 1σ \
         {sigma:.2} mm), displacements of {names}:",
        crate::study::fig7::FIG7_FY_N
    );
    for (axis, label) in ["δx", "δy"].iter().enumerate() {
        let _ = write!(
            b,
            " {label} measured {} mm",
            slashed(&s.fig7, |p| signed(p.measured_mm[axis], 2))
        );
        for (m, (model, _)) in first.predicted_mm.iter().enumerate() {
            let _ = write!(
                b,
                ", {model} {} mm",
                slashed(&s.fig7, |p| p
                    .predicted_mm
                    .get(m)
                    .map(|(_, d)| signed(d[axis], 2))
                    .unwrap_or_else(|| "–".into()))
            );
        }
        b.push(if axis == 0 { ';' } else { '.' });
    }
    t.push_str(&wrapped_bullet(&b));
}

fn plunge_bullet(t: &mut String, s: &DemoSummary) {
    if s.stiff_contact_sweep.is_empty() {
        return;
    }
    let mut b = String::new();
    let _ = write!(
        b,
        "- Plunges into fixtures ({:.1} mm programmed interference; largest force without \
         correction → with it, no runaway guard → with the guard):",
        s.stiff_contact.interference_mm
    );
    let plunges: Vec<String> = s
        .stiff_contact_sweep
        .iter()
        .map(|c| {
            let unguarded = match &c.unguarded.fault {
                Some(fault) => format!(
                    "{:.0} N (fault `{}`)",
                    c.unguarded.max_force_N,
                    fault_name(fault)
                ),
                None => format!(
                    "{:.0} N ({:.2}×)",
                    c.unguarded.max_force_N, c.unguarded.force_ratio_to_uncorrected
                ),
            };
            format!(
                " {} N/m: {:.0} N → {unguarded} → {:.0} N ({:.2}×, {} `contact_runaway` warning{})",
                power_of_ten(c.stiffness_n_m),
                c.open_max_force_N,
                c.guarded.max_force_N,
                c.guarded.force_ratio_to_uncorrected,
                c.guarded.runaway_warnings,
                if c.guarded.runaway_warnings == 1 {
                    ""
                } else {
                    "s"
                }
            )
        })
        .collect();
    let _ = write!(b, "{}.", plunges.join(";"));
    t.push_str(&wrapped_bullet(&b));
}

fn sensitivity_bullet(t: &mut String, s: &DemoSummary) {
    let Some(sens) = &s.sensitivity else {
        return;
    };
    let improvement = |p: f64| signed(p, 0);
    let mut b = String::new();
    let _ = write!(
        b,
        "- Sensitivity (sensitivity cone, every error source on; `sensitivity.csv`; improvement of \
         the max path error norm, %):"
    );
    let n_delays = sens.heatmap_delays_s.len();
    if n_delays > 0 {
        let delays = slashed(&sens.heatmap_delays_s, |d| format!("{:.0}", d * 1e3));
        for (i, scale) in sens.heatmap_scales.iter().enumerate() {
            let cells = sens
                .heatmap_improvement_percent
                .get(i * n_delays..(i + 1) * n_delays)
                .unwrap_or(&[]);
            let _ = write!(
                b,
                " model compliance ×{scale:.2} at {delays} ms delay: {};",
                slashed(cells, |p| improvement(*p))
            );
        }
    }
    let mut factors: Vec<&str> = Vec::new();
    for row in &sens.rows {
        if row.factor != "delay × model scale" && !factors.contains(&row.factor.as_str()) {
            factors.push(&row.factor);
        }
    }
    let parts: Vec<String> = factors
        .iter()
        .map(|factor| {
            let rows: Vec<_> = sens.rows.iter().filter(|r| r.factor == *factor).collect();
            format!(
                " {factor} {}: {}",
                slashed(&rows, |r| r.condition.clone()),
                slashed(&rows, |r| match &r.fault {
                    Some(f) => format!("{} (fault `{f}`)", improvement(r.improvement_percent)),
                    None => improvement(r.improvement_percent),
                })
            )
        })
        .collect();
    let _ = write!(b, "{}.", parts.join(";"));
    t.push_str(&wrapped_bullet(&b));
}
