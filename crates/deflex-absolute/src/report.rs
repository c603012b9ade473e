//! Outputs of an elasto-geometric fit: text tables, JSON (SI), CSV files, plots and an HTML
//! page.

use crate::campaign::Campaign;
use crate::fit::{ErrorStats, FitResult};
use crate::params::Unit;
use deflex_report::{HtmlReport, html_escape};
use serde_json::{Value, json};
use std::fmt::Write as _;
use std::path::{Path, PathBuf};

/// A report that could not be written.
#[derive(Debug, thiserror::Error)]
pub enum ReportWriteError {
    /// File system.
    #[error("{path}: {source}")]
    Io {
        /// File.
        path: String,
        /// Cause.
        source: std::io::Error,
    },
    /// Plot.
    #[error(transparent)]
    Plot(#[from] deflex_report::ReportError),
}

fn mm(v: f64) -> String {
    format!("{:.3}", v * 1e3)
}

fn stats_cells(s: &ErrorStats) -> [String; 4] {
    [mm(s.rms), mm(s.mean), mm(s.p95), mm(s.max)]
}

/// Format a parameter value in display units.
fn display(unit: Unit, value: f64) -> String {
    let (factor, _) = unit.display();
    format!("{:+.4}", value * factor)
}

/// Plain-text tables.
fn table(headers: &[&str], rows: &[Vec<String>]) -> String {
    let mut widths: Vec<usize> = headers.iter().map(|h| h.chars().count()).collect();
    for row in rows {
        for (w, cell) in widths.iter_mut().zip(row) {
            *w = (*w).max(cell.chars().count());
        }
    }
    let mut out = String::new();
    let line = |cells: Vec<String>, out: &mut String| {
        let parts: Vec<String> = cells
            .iter()
            .zip(&widths)
            .map(|(c, w)| format!("{c:>w$}", w = *w))
            .collect();
        let _ = writeln!(out, "  {}", parts.join("  "));
    };
    line(headers.iter().map(|h| h.to_string()).collect(), &mut out);
    for row in rows {
        line(row.clone(), &mut out);
    }
    out
}

/// The iteration table's rows: step, params, fit RMS, CV RMS, then each test group's RMS.
pub fn iteration_rows(result: &FitResult) -> (Vec<String>, Vec<Vec<String>>) {
    let mut headers = vec![
        "step".to_string(),
        "params".to_string(),
        "RMS fit (mm)".to_string(),
        "RMS CV (mm)".to_string(),
    ];
    if let Some(first) = result.steps.first() {
        if first.loaded_rms.is_some() {
            headers.push("loaded RMS (mm)".into());
        }
        for g in &first.test {
            headers.push(format!("RMS held out (mm): {}", g.name));
        }
    }
    let rows = result
        .steps
        .iter()
        .map(|s| {
            let mut row = vec![
                s.step.name(),
                format!("{}/{}", s.identifiable, s.candidates),
                mm(s.fit.rms),
                s.cv_rms.map_or("-".into(), mm),
            ];
            if let Some(l) = s.loaded_rms {
                row.push(mm(l));
            }
            row.extend(s.test.iter().map(|g| mm(g.stats.rms)));
            row
        })
        .collect();
    (headers, rows)
}

/// The estimates table rows.
pub fn estimate_rows(result: &FitResult) -> Vec<Vec<String>> {
    result
        .estimates
        .iter()
        .map(|e| {
            let (_, label) = e.unit.display();
            let delta = e.value - e.start;
            vec![
                e.name.clone(),
                label.to_string(),
                display(e.unit, e.start),
                display(e.unit, e.value),
                display(e.unit, delta),
                display(e.unit, e.standard_error).replace('+', ""),
                format!(
                    "[{}, {}]",
                    display(e.unit, e.value - 1.96 * e.standard_error),
                    display(e.unit, e.value + 1.96 * e.standard_error)
                ),
                e.bootstrap_se
                    .map_or("-".into(), |b| display(e.unit, b).replace('+', "")),
            ]
        })
        .collect()
}

const ESTIMATE_HEADERS: [&str; 8] = [
    "parameter",
    "unit",
    "nominal",
    "estimate",
    "change",
    "SE",
    "95 % interval",
    "bootstrap SE",
];

/// The held-out distribution table of every step and group.
fn heldout_rows(result: &FitResult) -> Vec<Vec<String>> {
    let mut rows = Vec::new();
    for s in &result.steps {
        for g in &s.test {
            let mut row = vec![s.step.name(), g.name.clone(), g.stats.count.to_string()];
            row.extend(stats_cells(&g.stats));
            rows.push(row);
        }
    }
    rows
}

const HELDOUT_HEADERS: [&str; 7] = [
    "model",
    "held-out readings",
    "n",
    "RMS (mm)",
    "mean (mm)",
    "p95 (mm)",
    "max (mm)",
];

/// The human-readable report.
pub fn text(result: &FitResult, campaign: &Campaign) -> String {
    let mut out = String::new();
    let fit_rows = result.fit_rows.iter().filter(|f| **f).count();
    let _ = writeln!(
        out,
        "Elasto-geometric calibration: {} absolute and {} loaded readings ({} fitted), {} set-up(s), {} target(s); loss: {}",
        campaign.absolute.len(),
        campaign.loaded.len(),
        fit_rows,
        result.model.setups.len(),
        result.model.targets.len(),
        result.loss.name()
    );
    let _ = writeln!(
        out,
        "Errors are norms of the 3-D position error.\n\nIteration table:"
    );
    let (headers, rows) = iteration_rows(result);
    let headers: Vec<&str> = headers.iter().map(String::as_str).collect();
    out.push_str(&table(&headers, &rows));
    let held = heldout_rows(result);
    if !held.is_empty() {
        let _ = writeln!(
            out,
            "\nHeld-out error distribution (readings the fit did not see):"
        );
        out.push_str(&table(&HELDOUT_HEADERS, &held));
    }
    let _ = writeln!(
        out,
        "\nIdentified parameters (final step; {} identifiable, condition number {:.3e}; SE scaled by the residual):",
        result.reduction.kept.len(),
        result.reduction.condition_number
    );
    out.push_str(&table(&ESTIMATE_HEADERS, &estimate_rows(result)));
    if !result.reduction.dropped.is_empty() {
        let _ = writeln!(out, "\nNot identifiable (left at their nominal values):");
        for d in &result.reduction.dropped {
            let combination: Vec<String> = d
                .combination
                .iter()
                .take(4)
                .map(|(p, c)| {
                    let name = result.model.param_name(*p);
                    if c.abs() >= 1e-2 {
                        format!("{c:+.3}·{name}")
                    } else {
                        format!("{c:+.2e}·{name}")
                    }
                })
                .collect();
            let equivalent = if combination.is_empty() {
                String::new()
            } else {
                format!(" ≡ {}", combination.join(" "))
            };
            let _ = writeln!(
                out,
                "  {}{equivalent}: {}",
                result.model.param_name(d.param),
                d.reason
            );
        }
    }
    let weak: Vec<String> = result
        .reduction
        .kept
        .iter()
        .zip(&result.reduction.independence)
        .filter(|(_, i)| **i < crate::identify::WEAK_THRESHOLD)
        .map(|(p, i)| format!("{} ({i:.1e})", result.model.param_name(*p)))
        .collect();
    if !weak.is_empty() {
        let _ = writeln!(
            out,
            "\nWeakly identifiable (independent part < 1e-2): {}",
            weak.join(", ")
        );
    }
    if !result.correlations.is_empty() {
        let _ = writeln!(out, "\nStrong correlations (|ρ| ≥ 0.95):");
        for (a, b, r) in result.correlations.iter().take(10) {
            let _ = writeln!(out, "  {a} / {b}: {r:+.3}");
        }
    }
    let _ = writeln!(out, "\nχ²/dof = {:.2} (stated σ)", result.chi2_per_dof);
    if let Some(w) = &result.warning {
        let _ = writeln!(out, "WARNING: {w}");
    }
    let _ = writeln!(
        out,
        "Robust loss down-weighted {} reading(s); {} below half weight{}",
        result.downweighted,
        result.outliers.len(),
        if result.outliers.is_empty() { "." } else { ":" }
    );
    for o in result.outliers.iter().take(20) {
        let _ = writeln!(
            out,
            "  reading {} (line {}, {}): residual {:.3} mm, weight {:.3}",
            o.index,
            o.line,
            o.label,
            o.residual * 1e3,
            o.weight
        );
    }
    if result.outliers.len() > 20 {
        let _ = writeln!(
            out,
            "  … {} more in outliers.csv",
            result.outliers.len() - 20
        );
    }
    if !result.model.harmonics.is_empty() {
        let _ = writeln!(
            out,
            "Note: joint-angle harmonics are part of this fit but have no place in a robot file; the written robot omits them."
        );
    }
    out
}

/// The JSON report (SI).
pub fn json(result: &FitResult, campaign: &Campaign) -> Value {
    let stats = |s: &ErrorStats| json!({"count": s.count, "rms_m": s.rms, "mean_m": s.mean, "p95_m": s.p95, "max_m": s.max});
    json!({
        "absolute_readings": campaign.absolute.len(),
        "loaded_readings": campaign.loaded.len(),
        "loss": result.loss.name(),
        "steps": result.steps.iter().map(|s| json!({
            "step": s.step.name(),
            "candidates": s.candidates,
            "identifiable": s.identifiable,
            "fit": stats(&s.fit),
            "cv_rms_m": s.cv_rms,
            "loaded_rms_m": s.loaded_rms,
            "iterations": s.iterations,
            "held_out": s.test.iter().map(|g| json!({"group": g.name, "stats": stats(&g.stats)})).collect::<Vec<_>>(),
        })).collect::<Vec<_>>(),
        "estimates": result.estimates.iter().map(|e| json!({
            "name": e.name, "unit": e.unit.si(), "nominal": e.start, "estimate": e.value,
            "standard_error": e.standard_error, "bootstrap_se": e.bootstrap_se,
        })).collect::<Vec<_>>(),
        "not_identifiable": result.reduction.dropped.iter().map(|d| json!({
            "name": result.model.param_name(d.param),
            "independence": d.independence,
            "equivalent_to": d.combination.iter().map(|(p, c)| json!({"name": result.model.param_name(*p), "coefficient": c})).collect::<Vec<_>>(),
            "reason": d.reason,
        })).collect::<Vec<_>>(),
        "condition_number": result.reduction.condition_number,
        "chi2_per_dof": result.chi2_per_dof,
        "warning": result.warning,
        "downweighted": result.downweighted,
        "outliers": result.outliers.iter().map(|o| json!({
            "reading": o.index, "line": o.line, "label": o.label, "residual_m": o.residual, "weight": o.weight,
        })).collect::<Vec<_>>(),
        "harmonics": result.model.harmonics.iter().map(|h| json!({
            "joint": h.joint + 1, "order": h.order, "term": if h.sine {"sin"} else {"cos"}, "value_rad": h.value,
        })).collect::<Vec<_>>(),
    })
}

fn write_text(path: &Path, text: &str) -> Result<(), ReportWriteError> {
    deflex_files::write_atomic(path, text).map_err(|source| ReportWriteError::Io {
        path: path.display().to_string(),
        source,
    })
}

/// Write the report folder (whole or not at all): `report.txt`, `report.json`,
/// `iterations.csv`, `estimates.csv`, `residuals.csv`, `outliers.csv`, plots and `index.html`.
pub fn write_report(
    result: &FitResult,
    campaign: &Campaign,
    dir: &Path,
) -> Result<Vec<PathBuf>, ReportWriteError> {
    let io = |source| ReportWriteError::Io {
        path: dir.display().to_string(),
        source,
    };
    let staging = deflex_files::AtomicDir::create(dir).map_err(io)?;
    let root = staging.path().to_path_buf();
    let mut files = Vec::new();
    let mut put = |name: &str, text: &str| -> Result<(), ReportWriteError> {
        write_text(&root.join(name), text)?;
        files.push(dir.join(name));
        Ok(())
    };
    let text_report = text(result, campaign);
    put("report.txt", &text_report)?;
    put(
        "report.json",
        &serde_json::to_string_pretty(&json(result, campaign)).unwrap_or_default(),
    )?;
    let (headers, rows) = iteration_rows(result);
    put("iterations.csv", &csv_text(&headers, &rows))?;
    let estimate_headers: Vec<String> = vec![
        "parameter",
        "unit",
        "nominal",
        "estimate",
        "standard_error",
        "bootstrap_se",
    ]
    .into_iter()
    .map(String::from)
    .collect();
    let estimate_csv_rows: Vec<Vec<String>> = result
        .estimates
        .iter()
        .map(|e| {
            vec![
                e.name.clone(),
                e.unit.si().to_string(),
                format!("{:e}", e.start),
                format!("{:e}", e.value),
                format!("{:e}", e.standard_error),
                e.bootstrap_se.map_or(String::new(), |b| format!("{b:e}")),
            ]
        })
        .collect();
    put(
        "estimates.csv",
        &csv_text(&estimate_headers, &estimate_csv_rows),
    )?;
    let mut residual_rows = Vec::new();
    for r in &result.residuals {
        let (label, line, q) = if campaign.is_absolute(r.index) {
            let row = &campaign.absolute[r.index];
            (row.setup.clone(), row.line, row.q_rad.clone())
        } else {
            let row = &campaign.loaded[r.index - campaign.absolute.len()];
            (row.load_case.clone(), 0, row.q_rad.clone())
        };
        let mut cells = vec![
            r.index.to_string(),
            line.to_string(),
            label,
            r.role.to_string(),
            format!("{:e}", r.residual.x),
            format!("{:e}", r.residual.y),
            format!("{:e}", r.residual.z),
        ];
        cells.extend(q.iter().map(|v| format!("{v:?}")));
        residual_rows.push(cells);
    }
    let n = result.model.robot.joint_count();
    let mut residual_headers: Vec<String> = [
        "reading",
        "line",
        "setup_or_case",
        "role",
        "ex_m",
        "ey_m",
        "ez_m",
    ]
    .into_iter()
    .map(String::from)
    .collect();
    residual_headers.extend((1..=n).map(|i| format!("q{i}_rad")));
    put(
        "residuals.csv",
        &csv_text(&residual_headers, &residual_rows),
    )?;
    let outlier_rows: Vec<Vec<String>> = result
        .outliers
        .iter()
        .map(|o| {
            vec![
                o.index.to_string(),
                o.line.to_string(),
                o.label.clone(),
                format!("{:e}", o.residual),
                format!("{:.4}", o.weight),
            ]
        })
        .collect();
    let outlier_headers: Vec<String> = ["reading", "line", "setup_or_case", "residual_m", "weight"]
        .into_iter()
        .map(String::from)
        .collect();
    put("outliers.csv", &csv_text(&outlier_headers, &outlier_rows))?;
    let images = crate::plots::draw(result, campaign, &root)?;
    let mut html = HtmlReport::new("deflex: elasto-geometric calibration");
    html.section("Summary").preformatted(text_report.clone());
    if let Some(w) = &result.warning {
        html.note(html_escape(w));
    }
    let (headers, rows) = iteration_rows(result);
    let h: Vec<&str> = headers.iter().map(String::as_str).collect();
    html.section("Iteration table").table(&h, &rows);
    let held = heldout_rows(result);
    if !held.is_empty() {
        html.section("Held-out error distribution")
            .table(&HELDOUT_HEADERS, &held);
    }
    html.section("Identified parameters")
        .table(&ESTIMATE_HEADERS, &estimate_rows(result));
    html.section("Residual plots");
    for (file, caption) in &images {
        html.image(root.join(file), caption.clone());
        files.push(dir.join(file));
    }
    html.write(&root.join("index.html"))?;
    files.push(dir.join("index.html"));
    staging.commit().map_err(io)?;
    Ok(files)
}

fn csv_text(headers: &[String], rows: &[Vec<String>]) -> String {
    let mut writer = csv::WriterBuilder::new().from_writer(Vec::new());
    let _ = writer.write_record(headers);
    for row in rows {
        let _ = writer.write_record(row);
    }
    String::from_utf8(writer.into_inner().unwrap_or_default()).unwrap_or_default()
}
