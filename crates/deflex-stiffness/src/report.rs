//! Text and CSV tables: the search iteration table (like the paper's Tables A1/A2), the
//! identified stiffnesses with standard errors and 95 % intervals (like Table 1), the correlation
//! matrix, residuals, expected standard errors of a plan, validation errors.

use crate::fit::{Calibration, Status};
use crate::plan::Plan;
use crate::search::SearchStep;
use crate::validate::Validation;
use std::fmt::Write as _;

fn um(x: f64) -> String {
    format!("{:.1}", x * 1e6)
}

fn k_fmt(k: f64) -> String {
    if k.is_infinite() {
        "∞".into()
    } else {
        format!("{:.4e}", k)
    }
}

/// Table rows of the search: iteration, change, structure, parameters, RMS (all, x, y, z), BIC,
/// ΔBIC and the cross-validated RMS (held-out load cases; "—" when not computed).
pub fn iteration_rows(steps: &[SearchStep]) -> Vec<Vec<String>> {
    steps
        .iter()
        .map(|s| {
            vec![
                s.iteration.to_string(),
                s.change.clone(),
                s.structure.clone(),
                s.parameters.to_string(),
                um(s.residuals.rms_all_m),
                um(s.residuals.rms_m[0]),
                um(s.residuals.rms_m[1]),
                um(s.residuals.rms_m[2]),
                format!("{:.1}", s.bic),
                if s.iteration == 0 {
                    "".into()
                } else {
                    format!("{:.1}", s.delta_bic)
                },
                s.cv_rms_m.map_or_else(|| "—".into(), um),
            ]
        })
        .collect()
}

/// Headers of [`iteration_rows`].
pub const ITERATION_HEADERS: [&str; 11] = [
    "step",
    "change",
    "structure",
    "params",
    "RMS [µm]",
    "RMS x [µm]",
    "RMS y [µm]",
    "RMS z [µm]",
    "BIC",
    "ΔBIC",
    "CV RMS [µm]",
];

/// Headers of [`stiffness_rows`].
pub const STIFFNESS_HEADERS: [&str; 6] = [
    "eDoF",
    "k [N·m/rad]",
    "SE [N·m/rad]",
    "95% low [N·m/rad]",
    "95% high [N·m/rad]",
    "status",
];

/// Table rows of the identified stiffnesses (the centre shifts are in [`shift_rows`]: one unit
/// per column).
pub fn stiffness_rows(cal: &Calibration) -> Vec<Vec<String>> {
    let mut rows = Vec::new();
    for e in &cal.edofs {
        let status = match &e.status {
            Status::Identified => "identified".to_string(),
            Status::Weak => "weakly identified".to_string(),
            Status::NotIdentifiable(r) => r.clone(),
        };
        let (lo, hi) = e
            .interval95
            .map(|(a, b)| (k_fmt(a), k_fmt(b)))
            .unwrap_or(("-".into(), "-".into()));
        rows.push(vec![
            e.label.clone(),
            e.stiffness.map(k_fmt).unwrap_or("-".into()),
            e.stiffness_se.map(k_fmt).unwrap_or("-".into()),
            lo,
            hi,
            status,
        ]);
    }
    rows
}

/// Headers of [`shift_rows`].
pub const SHIFT_HEADERS: [&str; 6] = [
    "centre shift",
    "δr [mm]",
    "SE [mm]",
    "95% low [mm]",
    "95% high [mm]",
    "status",
];

/// Table rows of the centre shifts δr, in millimetres.
pub fn shift_rows(cal: &Calibration) -> Vec<Vec<String>> {
    let mut rows = Vec::new();
    for s in &cal.shifts {
        let mm = |v: f64| format!("{:.1}", v * 1e3);
        let se = s.se_m.map(mm).unwrap_or("-".into());
        let (lo, hi) = s
            .se_m
            .map(|v| {
                (
                    mm(s.value_m - crate::fit::Z95 * v),
                    mm(s.value_m + crate::fit::Z95 * v),
                )
            })
            .unwrap_or(("-".into(), "-".into()));
        rows.push(vec![
            format!("δr{}", s.joint),
            mm(s.value_m),
            se,
            lo,
            hi,
            if s.free && s.value_m.abs() >= crate::shift::MAX_SHIFT_M * (1.0 - 1e-9) {
                format!(
                    "at the ±{} m search bound: not identified",
                    crate::shift::MAX_SHIFT_M
                )
            } else if s.free {
                "fitted".into()
            } else {
                "fixed".into()
            },
        ]);
    }
    rows
}

/// Render a table with aligned columns.
pub fn render_table(headers: &[&str], rows: &[Vec<String>]) -> String {
    let ncol = headers.len();
    let mut width: Vec<usize> = headers.iter().map(|h| h.chars().count()).collect();
    for r in rows {
        for (i, c) in r.iter().enumerate().take(ncol) {
            width[i] = width[i].max(c.chars().count());
        }
    }
    let mut out = String::new();
    let line = |cells: Vec<&str>, out: &mut String| {
        let parts: Vec<String> = cells
            .iter()
            .enumerate()
            .map(|(i, c)| format!("{c}{}", " ".repeat(width[i] - c.chars().count())))
            .collect();
        let _ = writeln!(out, "{}", parts.join("  ").trim_end());
    };
    line(headers.to_vec(), &mut out);
    let total: usize = width.iter().sum::<usize>() + 2 * (ncol - 1);
    let _ = writeln!(out, "{}", "-".repeat(total));
    for r in rows {
        line(r.iter().map(String::as_str).collect(), &mut out);
    }
    out
}

/// CSV of a table (RFC 4180 quoting).
pub fn table_csv(headers: &[&str], rows: &[Vec<String>]) -> String {
    let mut w = csv::WriterBuilder::new().from_writer(Vec::new());
    let _ = w.write_record(headers);
    for r in rows {
        let _ = w.write_record(r);
    }
    String::from_utf8(w.into_inner().unwrap_or_default()).unwrap_or_default()
}

/// Correlation matrix as text.
pub fn correlation_table(cal: &Calibration) -> String {
    let mut headers: Vec<&str> = vec![""];
    headers.extend(cal.parameter_labels.iter().map(String::as_str));
    let rows: Vec<Vec<String>> = cal
        .parameter_labels
        .iter()
        .enumerate()
        .map(|(i, l)| {
            let mut r = vec![l.clone()];
            r.extend(
                (0..cal.parameter_labels.len()).map(|j| format!("{:+.2}", cal.correlation[(i, j)])),
            );
            r
        })
        .collect();
    render_table(&headers, &rows)
}

/// Residual summary of a calibration.
pub fn residual_summary(cal: &Calibration) -> String {
    let r = &cal.residuals;
    let mut out = format!(
        "rows {}  χ²/dof {:.3}  condition number {:.1}  BIC {:.1}\n\
         residual RMS x/y/z {:.1} / {:.1} / {:.1} µm (all {:.1} µm, norm {:.1} µm)\n\
         residual max x/y/z {:.1} / {:.1} / {:.1} µm (norm {:.1} µm)\n",
        cal.rows,
        cal.reduced_chi2,
        cal.condition_number,
        cal.bic,
        r.rms_m[0] * 1e6,
        r.rms_m[1] * 1e6,
        r.rms_m[2] * 1e6,
        r.rms_all_m * 1e6,
        r.rms_norm_m * 1e6,
        r.max_abs_m[0] * 1e6,
        r.max_abs_m[1] * 1e6,
        r.max_abs_m[2] * 1e6,
        r.max_norm_m * 1e6
    );
    if let Some(rot) = r.rotation_rms_rad {
        let _ = writeln!(
            out,
            "rotation residual RMS {:.1} µrad ({} rows with a measured rotation)",
            rot * 1e6,
            cal.rotation_rows
        );
    }
    if let Some(note) = cal.model_form_note() {
        let _ = writeln!(out, "note: {note}");
    }
    out
}

/// Expected standard errors of a plan.
pub fn expected_se_rows(plan: &Plan) -> Vec<Vec<String>> {
    plan.expected
        .iter()
        .map(|e| {
            let axis = plan
                .axis_cases
                .iter()
                .find(|a| a.id == e.id && e.identifiable())
                .map(|a| {
                    format!(
                        "{} ({:.0} % share, {:.0} σ)",
                        a.load_case,
                        100.0 * a.share,
                        a.snr
                    )
                })
                .unwrap_or_else(|| {
                    if e.identifiable() {
                        "none (seen jointly by the other cases)".into()
                    } else {
                        "-".into()
                    }
                });
            vec![
                e.label.clone(),
                k_fmt(e.nominal_k),
                k_fmt(e.se_k),
                if e.relative.is_finite() {
                    format!("{:.2}", 100.0 * e.relative)
                } else {
                    "not identifiable".into()
                },
                axis,
            ]
        })
        .collect()
}

/// The technician's sheet: one line per load case with the joint values in degrees (wrapped
/// into the limits by the planner), where and how the load acts, the force vector (world
/// axes), the points to measure and why the case is there (the eDoFs whose axis-by-axis case
/// it is, the same as in [`expected_se_rows`]).
pub fn technician_rows(plan: &Plan) -> Vec<Vec<String>> {
    let mut out: Vec<Vec<String>> = Vec::new();
    for row in &plan.rows {
        match out.last_mut() {
            Some(last) if last[0] == row.load_case => {
                last[4] = format!("{}, {}", last[4], row.point);
            }
            _ => {
                let q: Vec<String> = row
                    .q_rad
                    .iter()
                    .map(|q| format!("{:.1}", q.to_degrees()))
                    .collect();
                let f = row.wrench;
                let purpose = row.purpose.clone().unwrap_or_default();
                let (why, how) = match purpose.split_once("; ") {
                    Some((why, how)) => (why.to_string(), how.to_string()),
                    None => (purpose, String::new()),
                };
                let at = if how.ends_with("at the bracket") {
                    "BR"
                } else {
                    "TCP"
                };
                out.push(vec![
                    row.load_case.clone(),
                    q.join(", "),
                    format!("{} at {at}", how.trim_end_matches(" at the bracket")),
                    format!("({:.0}, {:.0}, {:.0})", f[0], f[1], f[2]),
                    row.point.clone(),
                    why,
                ]);
            }
        }
    }
    out
}

/// Headers of [`technician_rows`].
pub const TECHNICIAN_HEADERS: [&str; 6] =
    ["case", "q [deg]", "load", "force [N]", "measure", "why"];

/// Headers of [`expected_se_rows`].
pub const EXPECTED_SE_HEADERS: [&str; 5] = [
    "eDoF",
    "nominal k [N·m/rad]",
    "expected SE [N·m/rad]",
    "expected SE [%]",
    "axis-by-axis case",
];

/// Expected centre-shift precision of a plan as table rows (mm).
pub fn expected_shift_rows(plan: &Plan) -> Vec<Vec<String>> {
    plan.expected_shifts
        .iter()
        .map(|e| {
            vec![
                format!("δr{}", e.joint),
                format!("{:.1}", e.nominal_m * 1e3),
                if e.se_m.is_finite() {
                    format!("{:.2}", e.se_m * 1e3)
                } else {
                    "not identifiable".into()
                },
            ]
        })
        .collect()
}

/// Headers of [`expected_shift_rows`].
pub const EXPECTED_SHIFT_HEADERS: [&str; 3] = ["centre shift", "nominal [mm]", "expected SE [mm]"];

/// Validation errors as table rows (mm).
pub fn validation_rows(v: &Validation) -> Vec<Vec<String>> {
    std::iter::once(&v.model)
        .chain(v.baseline.as_ref())
        .map(|m| {
            let s = &m.stats;
            let mut row = vec![m.name.clone()];
            row.extend(stat_cells(
                s.rms_m,
                s.rms_norm_m,
                s.max_abs_m,
                s.max_norm_m,
                |x| format!("{:.4}", x * 1e3),
            ));
            row
        })
        .collect()
}

/// RMS x, y, z, RMS norm, max x, y, z, max norm, each formatted by `fmt`.
fn stat_cells(
    rms: [f64; 3],
    rms_norm: f64,
    max_abs: [f64; 3],
    max_norm: f64,
    fmt: impl Fn(f64) -> String,
) -> Vec<String> {
    rms.iter()
        .chain(std::iter::once(&rms_norm))
        .chain(max_abs.iter())
        .chain(std::iter::once(&max_norm))
        .map(|&x| fmt(x))
        .collect()
}

/// Headers of [`validation_rows`].
pub const VALIDATION_HEADERS: [&str; 9] = [
    "model",
    "RMS x [mm]",
    "RMS y [mm]",
    "RMS z [mm]",
    "RMS norm [mm]",
    "max x [mm]",
    "max y [mm]",
    "max z [mm]",
    "max norm [mm]",
];

/// Rotation validation errors as table rows (µrad), one per model; empty when no row has a
/// measured rotation.
pub fn validation_rotation_rows(v: &Validation) -> Vec<Vec<String>> {
    std::iter::once(&v.model)
        .chain(v.baseline.as_ref())
        .filter_map(|m| {
            let s = &m.rotation.as_ref()?.stats;
            let mut row = vec![m.name.clone(), s.rows.to_string()];
            row.extend(stat_cells(
                s.rms_rad,
                s.rms_norm_rad,
                s.max_abs_rad,
                s.max_norm_rad,
                |x| format!("{:.1}", x * 1e6),
            ));
            Some(row)
        })
        .collect()
}

/// Headers of [`validation_rotation_rows`].
pub const VALIDATION_ROTATION_HEADERS: [&str; 10] = [
    "model",
    "rows",
    "rot RMS x [µrad]",
    "RMS y [µrad]",
    "RMS z [µrad]",
    "RMS norm [µrad]",
    "max x [µrad]",
    "max y [µrad]",
    "max z [µrad]",
    "max norm [µrad]",
];

/// One line per model with the rotation prediction errors, `None` when no row has a measured
/// rotation.
pub fn validation_rotation_summary(v: &Validation) -> Option<String> {
    let mut out = String::new();
    for m in std::iter::once(&v.model).chain(v.baseline.as_ref()) {
        let s = &m.rotation.as_ref()?.stats;
        let _ = writeln!(
            out,
            "rotation errors {} ({} rows): RMS x/y/z {:.1} / {:.1} / {:.1} µrad (norm {:.1} µrad), max norm {:.1} µrad",
            m.name,
            s.rows,
            s.rms_rad[0] * 1e6,
            s.rms_rad[1] * 1e6,
            s.rms_rad[2] * 1e6,
            s.rms_norm_rad * 1e6,
            s.max_norm_rad * 1e6
        );
    }
    Some(out)
}
