//! The calibration as text and CSV tables: the search iteration table (like the paper's Tables
//! A1/A2), the identified stiffnesses with standard errors and 95 % intervals (like Table 1), the
//! centre shifts, the correlation matrix and the residual summary; with `--couplings`, the
//! fitted off-diagonal compliances and the stiffnesses refitted with them.

use crate::report::text_table::render_table;
use deflex_calibrate::stiffness::CouplingFit;
use deflex_calibrate::stiffness::search::SearchStep;
use deflex_calibrate::stiffness::stiffness_fit::{Calibration, Status};
use deflex_model::Robot;
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
                um(s.residuals.position.rms[0]),
                um(s.residuals.position.rms[1]),
                um(s.residuals.position.rms[2]),
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
                    mm(s.value_m - deflex_calibrate::stiffness::stiffness_fit::Z95 * v),
                    mm(s.value_m + deflex_calibrate::stiffness::stiffness_fit::Z95 * v),
                )
            })
            .unwrap_or(("-".into(), "-".into()));
        rows.push(vec![
            format!("δr{}", s.joint),
            mm(s.value_m),
            se,
            lo,
            hi,
            if s.free && s.value_m.abs() >= deflex_calibrate::stiffness::MAX_SHIFT_M * (1.0 - 1e-9)
            {
                format!(
                    "at the ±{} m search bound: not identified",
                    deflex_calibrate::stiffness::MAX_SHIFT_M
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

/// Every pair of estimates correlated at |ρ| ≥ 0.95, one line each (empty when none): the flag
/// printed by `deflex calibrate` and shown in its report, beside the full correlation table.
pub fn correlated_pairs_text(cal: &Calibration) -> String {
    let pairs = cal.correlated_pairs();
    if pairs.is_empty() {
        return String::new();
    }
    let mut out = format!(
        "WARNING: {} pair(s) of estimates correlated at |ρ| ≥ {}:\n",
        pairs.len(),
        deflex_calibrate::stiffness::stiffness_fit::STRONG_CORRELATION
    );
    for pair in &pairs {
        out += &format!("  {pair}\n");
    }
    out
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
        r.position.rms[0] * 1e6,
        r.position.rms[1] * 1e6,
        r.position.rms[2] * 1e6,
        r.rms_all_m * 1e6,
        r.position.norm.rms * 1e6,
        r.position.max_abs[0] * 1e6,
        r.position.max_abs[1] * 1e6,
        r.position.max_abs[2] * 1e6,
        r.position.norm.max * 1e6
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

/// Headers of [`coupling_rows`].
pub const COUPLING_HEADERS: [&str; 7] = [
    "coupling",
    "c [rad/(N·m)]",
    "SE [rad/(N·m)]",
    "95% low [rad/(N·m)]",
    "95% high [rad/(N·m)]",
    "ρ = c/√(c_a c_b)",
    "SE ρ",
];

/// Table rows of the fitted couplings: compliance, standard error, 95 % interval, correlation
/// and its standard error.
pub fn coupling_rows(fit: &CouplingFit) -> Vec<Vec<String>> {
    fit.robot
        .couplings
        .iter()
        .enumerate()
        .map(|(k, c)| {
            let (lo, hi) = fit.interval95(k);
            vec![
                c.label(),
                k_fmt(c.compliance),
                k_fmt(fit.coupling_se[k]),
                k_fmt(lo),
                k_fmt(hi),
                format!("{:.3}", fit.correlations[k]),
                format!("{:.3}", fit.correlation_se[k]),
            ]
        })
        .collect()
}

/// Headers of [`refit_rows`].
pub const REFIT_HEADERS: [&str; 4] = [
    "eDoF",
    "k diagonal fit [N·m/rad]",
    "k with the couplings [N·m/rad]",
    "SE [N·m/rad]",
];

/// Table rows of the eDoF stiffnesses refitted with the couplings, beside the diagonal
/// calibration's (`diagonal`): SE of `k = 1/c` by the delta method, `SE_c / c²`.
pub fn refit_rows(diagonal: &Robot, fit: &CouplingFit) -> Vec<Vec<String>> {
    fit.robot
        .edofs()
        .zip(&fit.compliance_se)
        .map(|(e, se_c)| {
            let c = 1.0 / e.stiffness;
            vec![
                e.label(),
                diagonal.stiffness(e.site, e.axis).map_or("-".into(), k_fmt),
                k_fmt(e.stiffness),
                k_fmt(se_c / (c * c)),
            ]
        })
        .collect()
}

/// What the coupling fit changed, one line: χ²/dof and the RMS position residual of the
/// diagonal model and of the coupled one on the same rows.
pub fn coupling_summary(fit: &CouplingFit) -> String {
    format!(
        "fitted with the eDoF compliances by weighted least squares ({} equations, {} unknowns): \
         χ²/dof {:.3} → {:.3}, RMS position residual {} → {} µm\n",
        fit.equations,
        fit.unknowns,
        fit.reduced_chi2_before,
        fit.reduced_chi2,
        um(fit.rms_before_m),
        um(fit.rms_m)
    )
}
