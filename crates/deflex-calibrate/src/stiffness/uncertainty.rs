//! Uncertainty and statistics of a calibration: covariance, standard errors, 95 % intervals,
//! correlations, condition number, BIC and residual statistics.
//!
//! Covariance: `s² (JᵀWJ)⁻¹` over the free parameters (compliances not at the c ≥ 0 bound, free
//! shifts), with `s² = χ²/(n − p)` the reduced chi-square, so that an unrepresentable truth or a
//! wrong σ inflates the intervals honestly. `n` counts every equation, rotation equations
//! included. Stiffness `k = 1/c`: SE by the delta method (`SE_k = SE_c / c²`), interval by
//! mapping the c-interval (upper bound ∞ when `c − 1.96 SE_c ≤ 0`: weakly identified).

use crate::stats::ErrorStats;
use crate::stiffness::calibration::{
    Calibration, EdofEstimate, MAX_RELATIVE_SE, ResidualStats, ShiftEstimate, Status, Structure,
    Z95,
};
use crate::stiffness::design::{Design, EdofId, edof_label};
use crate::stiffness::shift::{self, Inner, jacobian, normal_system, scales};
use deflex_model::{Axis, EdofSite};
use nalgebra::{DMatrix, DVector};

/// `(JᵀWJ)⁻¹` of a structure's free parameters: the covariance for a unit noise scale.
pub(crate) struct ParameterCovariance {
    /// Covariance (compliances in (rad/(N·m))², shifts in m²) for `s² = 1`.
    pub cov: DMatrix<f64>,
    /// Per parameter: `Ok(k)` compliance of structure eDoF k, `Err(j)` shift of joint j.
    pub labels: Vec<Result<usize, usize>>,
    /// Condition number of the column-scaled normal matrix.
    pub condition_number: f64,
    /// The shift joints kept (collinear ones dropped, last first).
    pub shift_joints: Vec<usize>,
}

/// Covariance `(JᵀWJ)⁻¹` (weights 1/σ² of the design) of the compliances `include`d and the
/// centre shifts of `shift_joints` at `(c, shifts)`, computed on the column-scaled normal
/// matrix. A shift that makes the matrix singular is dropped (the last one first).
pub(crate) fn unscaled_covariance(
    design: &Design,
    idx: &[usize],
    c: &[f64],
    shifts: &[f64],
    include: &[bool],
    mut shift_joints: Vec<usize>,
) -> ParameterCovariance {
    loop {
        let (cols, labels) = jacobian(design, idx, c, shifts, include, &shift_joints);
        let (nm, _) = normal_system(design, &cols);
        let d = scales(&nm);
        let m = cols.len();
        let ns = DMatrix::from_fn(m, m, |i, j| nm[(i, j)] * d[i] * d[j]);
        if m == 0 || !crate::stiffness::all_finite(&ns) {
            // Nothing free (every compliance at its bound), or a matrix no decomposition may
            // see: every parameter's variance is unknown (infinite).
            return ParameterCovariance {
                cov: DMatrix::from_fn(m, m, |i, j| if i == j { f64::INFINITY } else { 0.0 }),
                labels,
                condition_number: if m == 0 { 1.0 } else { f64::INFINITY },
                shift_joints,
            };
        }
        let eig = ns.clone().symmetric_eigen();
        let lmax = eig.eigenvalues.amax();
        let lmin = eig
            .eigenvalues
            .iter()
            .copied()
            .fold(f64::INFINITY, f64::min);
        let condition_number = if m == 0 {
            1.0
        } else {
            (lmax / lmin.max(1e-300)).sqrt()
        };
        if m > 0 && (lmin <= 1e-12 * lmax || d.contains(&0.0)) && !shift_joints.is_empty() {
            shift_joints.pop();
            continue;
        }
        let inv = ns
            .clone()
            .cholesky()
            .map(|ch| ch.inverse())
            .unwrap_or_else(|| {
                ns.pseudo_inverse(1e-14 * lmax)
                    .unwrap_or(DMatrix::zeros(m, m))
            });
        return ParameterCovariance {
            cov: DMatrix::from_fn(m, m, |i, j| inv[(i, j)] * d[i] * d[j]),
            labels,
            condition_number,
            shift_joints,
        };
    }
}

/// A fit and its scaled covariance, for the estimates of its parameters.
struct Fitted<'a> {
    design: &'a Design,
    idx: &'a [usize],
    shifts: &'a [f64],
    /// Compliances of the active eDoFs.
    c: &'a [f64],
    active: &'a [EdofId],
    dropped: &'a [(EdofId, String)],
    labels: &'a [Result<usize, usize>],
    /// Covariance scaled by the residual variance `s²`.
    cov: &'a DMatrix<f64>,
    s2: f64,
}

impl Fitted<'_> {
    /// Standard error of parameter `k`.
    fn se(&self, k: usize) -> f64 {
        self.cov[(k, k)].max(0.0).sqrt()
    }

    /// The estimate of eDoF `id` of the structure: not identifiable when it was dropped, at the
    /// c ≥ 0 bound or too uncertain; weak when its 95 % interval reaches c = 0; else identified,
    /// with its stiffness, standard error and interval. `None` when it is not in the fit.
    fn edof(&self, id: EdofId) -> Option<EdofEstimate> {
        let label = edof_label(id);
        let not = |reason: String| EdofEstimate {
            id,
            label: label.clone(),
            status: Status::NotIdentifiable(reason),
            compliance: 0.0,
            compliance_se: f64::NAN,
            stiffness: None,
            stiffness_se: None,
            interval95: None,
        };
        if let Some((_, reason)) = self.dropped.iter().find(|(d, _)| *d == id) {
            return Some(not(reason.clone()));
        }
        let k = self.active.iter().position(|a| *a == id)?;
        let c = self.c[k];
        if c <= 0.0 {
            let bound = bound_se(self.design, self.idx, self.shifts, self.c, k, self.s2)
                .map(|se| format!(" (k > {:.3e} N·m/rad at 95 %)", 1.0 / (Z95 * se)))
                .unwrap_or_default();
            return Some(not(format!(
                "not identifiable: the fit hit the c ≥ 0 bound, stiffer than the data can resolve{bound}"
            )));
        }
        let pos = self.labels.iter().position(|l| *l == Ok(k)).unwrap_or(0);
        let sc = self.se(pos);
        let rel = sc / c;
        let status = if !(rel.is_finite()) || rel > MAX_RELATIVE_SE {
            Status::NotIdentifiable(format!(
                "not identifiable: relative standard error of the compliance {:.0} %",
                100.0 * rel
            ))
        } else if c - Z95 * sc <= 0.0 {
            Status::Weak
        } else {
            Status::Identified
        };
        if matches!(status, Status::NotIdentifiable(_)) {
            let mut e = not(match &status {
                Status::NotIdentifiable(r) => r.clone(),
                _ => String::new(),
            });
            e.compliance = c;
            e.compliance_se = sc;
            return Some(e);
        }
        let lo_c = c - Z95 * sc;
        let hi = if lo_c > 0.0 {
            1.0 / lo_c
        } else {
            f64::INFINITY
        };
        Some(EdofEstimate {
            id,
            label,
            status,
            compliance: c,
            compliance_se: sc,
            stiffness: Some(1.0 / c),
            stiffness_se: Some(sc / (c * c)),
            interval95: Some((1.0 / (c + Z95 * sc), hi)),
        })
    }
}

/// Standard errors, status and statistics of a fitted structure.
#[allow(clippy::too_many_arguments)]
pub(crate) fn analyse(
    design: &Design,
    structure: &Structure,
    active: &[EdofId],
    idx: &[usize],
    sol: &Inner,
    shifts: &[f64],
    dropped: &[(EdofId, String)],
    free: &[usize],
) -> Calibration {
    let n = design.equations();
    let include: Vec<bool> = sol.c.iter().map(|&c| c > 0.0).collect();
    // Free shifts that are identifiable: the joint has an active x/y eDoF.
    let shift_ok = shift::active_shift_joints(design, idx, &sol.c, free);
    let ParameterCovariance {
        mut cov,
        labels,
        condition_number: cond,
        shift_joints: shift_ok,
    } = unscaled_covariance(design, idx, &sol.c, shifts, &include, shift_ok);
    let p = labels.len();
    let dof = n.saturating_sub(p).max(1);
    let s2 = sol.chi2 / dof as f64;
    cov *= s2;
    let se = |k: usize| cov[(k, k)].max(0.0).sqrt();
    let correlation = DMatrix::from_fn(p, p, |i, j| {
        let den = se(i) * se(j);
        if den > 0.0 { cov[(i, j)] / den } else { 0.0 }
    });

    let fitted = Fitted {
        design,
        idx,
        shifts,
        c: &sol.c,
        active,
        dropped,
        labels: &labels,
        cov: &cov,
        s2,
    };
    let edofs: Vec<EdofEstimate> = structure
        .edofs
        .iter()
        .filter_map(|&id| fitted.edof(id))
        .collect();

    let mut shift_estimates = Vec::new();
    for j in 1..=design.joint_count {
        let has_xy = structure
            .edofs
            .iter()
            .any(|e| e.0 == EdofSite::Joint(j) && e.1 != Axis::Z);
        let is_free = structure.free_shift[j - 1];
        if !has_xy && !is_free && shifts[j - 1] == 0.0 {
            continue;
        }
        let se_m = labels.iter().position(|l| *l == Err(j)).map(se);
        shift_estimates.push(ShiftEstimate {
            joint: j,
            value_m: shifts[j - 1],
            free: is_free,
            se_m,
        });
    }

    let parameter_labels: Vec<String> = labels
        .iter()
        .map(|l| match l {
            Ok(k) => edof_label(active[*k]),
            Err(j) => format!("δr{j}"),
        })
        .collect();

    // Residuals, directly from the rows.
    let beta = shift::basis_coefficients(design, idx, &sol.c, shifts);
    let pred = design.predict(&beta);
    let residuals = residual_stats(design, &pred);

    let mut out_structure = structure.clone();
    out_structure.shifts_m = shifts.to_vec();
    out_structure.edofs = edofs
        .iter()
        .filter(|e| e.stiffness.is_some())
        .map(|e| e.id)
        .collect();
    let bic = bic(sol.chi2, n, p);
    let mut warnings = Vec::new();
    for &j in free {
        if !shift_ok.contains(&j) {
            warnings.push(format!(
                "centre shift δr{j} is not identifiable (no active x/y eDoF on joint {j} or collinear); kept at {:.4} m",
                shifts[j - 1]
            ));
        }
    }
    Calibration {
        structure: out_structure,
        edofs,
        shifts: shift_estimates,
        parameter_labels,
        correlation,
        condition_number: cond,
        chi2: sol.chi2,
        dof,
        reduced_chi2: s2,
        bic,
        residuals,
        rows: design.rows,
        rotation_rows: design.rotation_rows,
        warnings,
    }
}

/// Standard error of a compliance sitting at the bound, from the information matrix with it
/// included (gives the one-sided lower bound on the stiffness).
fn bound_se(
    design: &Design,
    idx: &[usize],
    shifts: &[f64],
    c: &[f64],
    k: usize,
    s2: f64,
) -> Option<f64> {
    let keep: Vec<usize> = (0..idx.len()).filter(|&i| c[i] > 0.0 || i == k).collect();
    let sub: Vec<usize> = keep.iter().map(|&i| idx[i]).collect();
    let cols = shift::columns(design, &sub, shifts);
    let (g, _) = normal_system(design, &cols);
    let d = scales(&g);
    let m = sub.len();
    let gs = DMatrix::from_fn(m, m, |i, j| g[(i, j)] * d[i] * d[j]);
    let inv = gs.cholesky()?.inverse();
    let pos = keep.iter().position(|&i| i == k)?;
    let v = inv[(pos, pos)] * d[pos] * d[pos] * s2;
    (v > 0.0 && v.is_finite()).then(|| v.sqrt())
}

/// BIC with unknown noise scale: `n ln(χ²/n) + p ln n`.
pub fn bic(chi2: f64, n: usize, p: usize) -> f64 {
    let n_f = n.max(1) as f64;
    n_f * (chi2.max(1e-300) / n_f).ln() + p as f64 * n_f.ln()
}

/// Residual statistics from a weighted prediction: positions in metres (the first `3 · rows`
/// equations), rotation RMS in radians (the rest).
pub(crate) fn residual_stats(design: &Design, pred: &DVector<f64>) -> ResidualStats {
    let residual = |e: usize| (design.y[e] - pred[e]) * design.sigma[e];
    let positions: Vec<[f64; 3]> = (0..design.rows)
        .map(|r| [residual(3 * r), residual(3 * r + 1), residual(3 * r + 2)])
        .collect();
    let sum_squares = positions.iter().fold(0.0, |sum, e| {
        sum + (e[0] * e[0] + e[1] * e[1] + e[2] * e[2])
    });
    let first = 3 * design.rows;
    let count = design.equations() - first;
    let rotation_rms_rad = (count > 0).then(|| {
        let sum: f64 = (first..design.equations())
            .map(|e| residual(e).powi(2))
            .sum();
        (sum / count as f64).sqrt()
    });
    ResidualStats {
        position: ErrorStats::of(&positions),
        rms_all_m: (sum_squares / (3.0 * design.rows.max(1) as f64)).sqrt(),
        rotation_rms_rad,
    }
}
