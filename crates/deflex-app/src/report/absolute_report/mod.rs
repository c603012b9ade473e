//! The report of an elasto-geometric calibration (`deflex calibrate-geometry --report`): text
//! tables, JSON (SI), CSV files, plots (`plots`) and an HTML page, rendered from the
//! `deflex_calibrate::geometry` fit result. (Here rather than in the CLI so that every front end, the
//! Python package too, prints and writes the same report.) The text, JSON and CSV are in every
//! build; the plots and the report folder (`write_report`) only with the `report` feature.

#[cfg(feature = "report")]
mod page;
#[cfg(feature = "report")]
pub mod plots;
pub mod prediction;
pub mod registration;
pub mod tables;

#[cfg(feature = "report")]
pub use page::write_report;

use deflex_calibrate::geometry::campaign::Campaign;
use deflex_calibrate::geometry::fit::{FitResult, StepReport, TestGroup};
use deflex_calibrate::geometry::params::Unit;
use deflex_calibrate::stats::ErrorNormStats;
use serde_json::{Value, json};
use std::fmt::Write as _;

fn mm(v: f64) -> String {
    format!("{:.3}", v * 1e3)
}

fn mrad(v: f64) -> String {
    format!("{:.3}", v * 1e3)
}

fn stats_cells(s: &ErrorNormStats) -> [String; 4] {
    [mm(s.rms), mm(s.mean), mm(s.p95), mm(s.max)]
}

fn orientation_cells(s: Option<&ErrorNormStats>) -> [String; 2] {
    match s {
        Some(s) => [mrad(s.rms), mrad(s.p95)],
        None => ["-".into(), "-".into()],
    }
}

/// Pooled RMS of the left-out groups of a step (m).
fn cross_rms(step: &StepReport) -> Option<f64> {
    let groups: Vec<&TestGroup> = step.cross_groups.iter().collect();
    deflex_calibrate::geometry::fit::pooled_rms(&groups)
}

/// Whether a step is in the written model.
fn kept_cell(step: &StepReport) -> String {
    match step.acceptance {
        Some(a) if a.accepted => "yes (held out)".into(),
        Some(_) => "no (held out)".into(),
        None => "yes".into(),
    }
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

/// The iteration table's rows: step, params, fit RMS, CV RMS, loaded RMS, each test group's
/// RMS, the left-out groups' pooled RMS, orientation RMS (fit), and whether the step is kept.
pub fn iteration_rows(result: &FitResult) -> (Vec<String>, Vec<Vec<String>>) {
    let mut headers = vec![
        "step".to_string(),
        "params".to_string(),
        "RMS fit (mm)".to_string(),
        "RMS CV (mm)".to_string(),
    ];
    let first = result.steps.first();
    let loaded = first.is_some_and(|s| s.loaded_rms.is_some());
    let cross = result.steps.iter().any(|s| !s.cross_groups.is_empty());
    let orientation = result.steps.iter().any(|s| s.fit_orientation.is_some());
    if loaded {
        headers.push("loaded RMS (mm)".into());
    }
    if let Some(first) = first {
        for g in &first.test {
            headers.push(format!("RMS held out (mm): {}", g.name));
        }
    }
    if cross {
        headers.push("RMS left-out groups (mm)".into());
    }
    if orientation {
        headers.push("orientation RMS fit (mrad)".into());
    }
    headers.push("kept".into());
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
            if loaded {
                row.push(s.loaded_rms.map_or("-".into(), mm));
            }
            row.extend(s.test.iter().map(|g| mm(g.stats.rms)));
            if cross {
                row.push(cross_rms(s).map_or("-".into(), mm));
            }
            if orientation {
                row.push(s.fit_orientation.map_or("-".into(), |o| mrad(o.rms)));
            }
            row.push(kept_cell(s));
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
        for g in s.test.iter().chain(&s.cross_groups) {
            let mut row = vec![s.step.name(), g.name.clone(), g.stats.count.to_string()];
            row.extend(stats_cells(&g.stats));
            row.push(draw_spread(g));
            row.extend(orientation_cells(g.orientation.as_ref()));
            rows.push(row);
        }
    }
    rows
}

/// Spread of the per-draw RMS: `min … max` over the registration draws.
fn draw_spread(g: &TestGroup) -> String {
    if g.draw_rms.len() < 2 {
        return "-".into();
    }
    let lo = g.draw_rms.iter().copied().fold(f64::INFINITY, f64::min);
    let hi = g.draw_rms.iter().copied().fold(f64::NEG_INFINITY, f64::max);
    format!("{} … {}", mm(lo), mm(hi))
}

const HELDOUT_HEADERS: [&str; 10] = [
    "model",
    "held-out readings",
    "n",
    "RMS (mm)",
    "mean (mm)",
    "p95 (mm)",
    "max (mm)",
    "RMS per draw (mm)",
    "orientation RMS (mrad)",
    "orientation p95 (mrad)",
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
        "Errors are norms of the 3-D position error; orientation errors are rotation angles.{}\n\nIteration table:",
        if campaign.orientation_rows.is_empty() {
            ""
        } else {
            " Orientations are fitted with the positions."
        }
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
        .filter(|(_, i)| **i < deflex_calibrate::geometry::identify::WEAK_THRESHOLD)
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
        let _ = writeln!(
            out,
            "\nWARNING: {} pair(s) of estimates correlated at |ρ| ≥ 0.95 (the data determines their combination, not each):",
            result.correlations.len()
        );
        for (a, b, r) in &result.correlations {
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
    let rejected: Vec<String> = result
        .steps
        .iter()
        .filter(|s| s.acceptance.is_some_and(|a| !a.accepted))
        .map(|s| s.step.name())
        .collect();
    if !rejected.is_empty() {
        let _ = writeln!(
            out,
            "Not kept (no held-out gain of at least {:.1} %): {}",
            deflex_calibrate::geometry::fit::ACCEPTANCE_GAIN * 100.0,
            rejected.join("; ")
        );
    }
    let model = &result.model;
    if let Some(maps) = &model.joint_maps {
        let sizes: Vec<String> = maps
            .maps
            .iter()
            .map(|map| {
                let (rms, max) = deflex_calibrate::geometry::joint_maps::map_size(map);
                format!(
                    "J{} RMS {:.0} µrad, max {:.0} µrad",
                    map.joint + 1,
                    rms * 1e6,
                    max * 1e6
                )
            })
            .collect();
        let _ = writeln!(
            out,
            "Joint-angle error maps ({}): {}",
            maps.hyper.describe(),
            sizes.join("; ")
        );
    }
    if !model.harmonics.is_empty()
        || model.backlash.iter().any(|b| *b != 0.0)
        || !model.torsion.is_empty()
        || model.residual.is_some()
        || model.joint_maps.is_some()
    {
        let _ = writeln!(
            out,
            "Note: joint-angle terms and the residual model have no place in a robot file; they are written to the terms file beside it."
        );
    }
    out
}

/// The JSON report (SI).
pub fn json(result: &FitResult, campaign: &Campaign) -> Value {
    let stats = |s: &ErrorNormStats| json!({"count": s.count, "rms_m": s.rms, "mean_m": s.mean, "p95_m": s.p95, "max_m": s.max});
    let group_json = |g: &TestGroup| {
        json!({
            "group": g.name,
            "stats": stats(&g.stats),
            "orientation_rad": g.orientation.as_ref().map(stats),
            "draw_rms_m": g.draw_rms,
            "registered": g.registered,
        })
    };
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
            "held_out": s.test.iter().map(&group_json).collect::<Vec<_>>(),
            "left_out_groups": s.cross_groups.iter().map(&group_json).collect::<Vec<_>>(),
            "left_out_rms_m": cross_rms(s),
            "fit_orientation": s.fit_orientation.as_ref().map(stats),
            "residual_hyper": s.residual_hyper.map(|h| json!({"length_scale_rad": h.length_scale_rad, "ridge": h.ridge, "joint_mask": h.joints})),
            "joint_maps_hyper": s.maps_hyper.map(|h| json!({"joint_mask": h.joints, "spacing_rad": h.spacing_rad, "value_sigma_rad": h.value_sigma_rad, "curvature_sigma_rad": h.curvature_sigma_rad})),
            "acceptance": s.acceptance.map(|a| json!({"before_m": a.before_m, "after_m": a.after_m, "accepted": a.accepted})),
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
        "correlated_pairs": result.correlations.iter().map(|(a, b, rho)| json!({"first": a, "second": b, "rho": rho})).collect::<Vec<_>>(),
        "correlation_flag_threshold": 0.95,
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
        "backlash_rad": result.model.backlash,
        "torsion": result.model.torsion.iter().map(|t| json!({
            "edof": t.edof, "shape": t.shape.name(), "value_rad_per_nm": t.value,
        })).collect::<Vec<_>>(),
        "residual_model": result.model.residual.as_ref().map(|r| json!({"length_scale_rad": r.hyper.length_scale_rad, "ridge": r.hyper.ridge, "joint_mask": r.hyper.joints, "inducing": r.inducing.len()})),
        "joint_maps": result.model.joint_maps.as_ref().map(|m| json!({
            "spacing_rad": m.hyper.spacing_rad,
            "value_sigma_rad": m.hyper.value_sigma_rad,
            "curvature_sigma_rad": m.hyper.curvature_sigma_rad,
            "maps": m.maps.iter().map(|map| {
                let (rms, max) = deflex_calibrate::geometry::joint_maps::map_size(map);
                let (from, to) = map.range_rad();
                json!({"joint": map.joint + 1, "coefficients": map.coefficients.len(), "from_rad": from, "to_rad": to, "rms_rad": rms, "max_rad": max})
            }).collect::<Vec<_>>(),
        })),
        "kept_steps": result.kept_steps.iter().map(|s| s.name()).collect::<Vec<_>>(),
        "orientations_fitted": !campaign.orientation_rows.is_empty(),
    })
}
