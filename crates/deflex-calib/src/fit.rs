//! Fixed-structure calibration: compliances `c = 1/k` by weighted NNLS (eq. 15 is linear in c),
//! centre shifts by variable projection, with standard errors, 95 % intervals, correlations,
//! condition number and residual statistics.
//!
//! Covariance: `s² (JᵀWJ)⁻¹` over the free parameters (compliances not at the c ≥ 0 bound, free
//! shifts), with `s² = χ²/(n − p)` the reduced chi-square, so that an unrepresentable truth or a
//! wrong σ inflates the intervals honestly. Stiffness `k = 1/c`: SE by the delta method
//! (`SE_k = SE_c / c²`), interval by mapping the c-interval (upper bound ∞ when
//! `c − 1.96 SE_c ≤ 0`: weakly identified).

use crate::CalibError;
use crate::data::MeasurementRow;
use crate::design::{Design, EdofId, edof_label, edof_order};
use crate::shift::{self, Inner, jacobian, normal_system, scales};
use deflex_model::{Axis, EdofSite, Robot};
use nalgebra::{DMatrix, DVector};

/// Relative standard error of a compliance above which it is reported not identifiable.
pub const MAX_RELATIVE_SE: f64 = 5.0;
/// Two-sided 95 % normal quantile.
pub const Z95: f64 = 1.959964;

/// A model structure: which eDoFs, which centre shifts, and which shifts are fitted.
#[derive(Clone, Debug, PartialEq)]
pub struct Structure {
    /// eDoFs, in robot order.
    pub edofs: Vec<EdofId>,
    /// Centre shift δr of each joint (m), index = joint − 1.
    pub shifts_m: Vec<f64>,
    /// Whether each joint's shift is a fitted parameter.
    pub free_shift: Vec<bool>,
}

impl Structure {
    /// The structure of a robot model: its eDoFs and (fixed) centre shifts.
    pub fn from_robot(robot: &Robot) -> Structure {
        Structure {
            edofs: robot.edofs().map(|e| (e.site, e.axis)).collect(),
            shifts_m: robot.joints.iter().map(|j| j.center_shift).collect(),
            free_shift: vec![false; robot.joint_count()],
        }
    }

    /// The classical VJM start of the paper: one z-eDoF per joint, no shift.
    pub fn one_z_per_joint(joint_count: usize) -> Structure {
        Structure {
            edofs: (1..=joint_count)
                .map(|i| (EdofSite::Joint(i), Axis::Z))
                .collect(),
            shifts_m: vec![0.0; joint_count],
            free_shift: vec![false; joint_count],
        }
    }

    /// Free the shifts of every joint that has an x or y eDoF.
    pub fn with_free_shifts(mut self) -> Structure {
        for &(site, axis) in &self.edofs {
            if let (EdofSite::Joint(i), Axis::X | Axis::Y) = (site, axis) {
                self.free_shift[i - 1] = true;
            }
        }
        self
    }

    /// Keep the eDoFs sorted in robot order.
    pub fn normalize(&mut self) {
        self.edofs.sort_by_key(edof_order);
        self.edofs.dedup();
    }

    /// Number of parameters (compliances + free shifts).
    pub fn parameter_count(&self) -> usize {
        self.edofs.len() + self.free_shift.iter().filter(|f| **f).count()
    }

    /// Compact label, e.g. `J1.z J2.z J3.xz δr3 J4.z J5.z`.
    pub fn label(&self) -> String {
        let mut parts = Vec::new();
        let mut sites: Vec<EdofSite> = self.edofs.iter().map(|e| e.0).collect();
        sites.dedup();
        for site in sites {
            let axes: String = self
                .edofs
                .iter()
                .filter(|e| e.0 == site)
                .map(|e| e.1.letter())
                .collect();
            parts.push(format!("{site}.{axes}"));
            if let EdofSite::Joint(i) = site
                && self.free_shift[i - 1]
            {
                parts.push(format!("δr{i}"));
            }
        }
        parts.join(" ")
    }
}

/// How well the data determines an eDoF.
#[derive(Clone, Debug, PartialEq)]
pub enum Status {
    /// Finite 95 % interval on the stiffness.
    Identified,
    /// Positive estimate but the 95 % interval reaches k = ∞ (c interval touches 0).
    Weak,
    /// The data cannot determine it; the reason says why. Left out of the output model.
    NotIdentifiable(String),
}

/// Estimate of one eDoF.
#[derive(Clone, Debug)]
pub struct EdofEstimate {
    /// The eDoF.
    pub id: EdofId,
    /// Label (`J3.x`).
    pub label: String,
    /// Identifiability.
    pub status: Status,
    /// Compliance c = 1/k (rad/(N·m)); 0 when not identifiable.
    pub compliance: f64,
    /// Standard error of the compliance (NaN when unavailable).
    pub compliance_se: f64,
    /// Stiffness k (N·m/rad), `None` when not identifiable.
    pub stiffness: Option<f64>,
    /// Standard error of k by the delta method.
    pub stiffness_se: Option<f64>,
    /// 95 % interval of k (upper bound may be +∞).
    pub interval95: Option<(f64, f64)>,
}

/// Estimate of one joint's centre shift δr.
#[derive(Clone, Debug)]
pub struct ShiftEstimate {
    /// Joint (1-based).
    pub joint: usize,
    /// Value (m).
    pub value_m: f64,
    /// Whether it was fitted.
    pub free: bool,
    /// Standard error (m), when fitted and identifiable.
    pub se_m: Option<f64>,
}

/// Residual statistics (measured − predicted), metres.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct ResidualStats {
    /// RMS per axis x, y, z.
    pub rms_m: [f64; 3],
    /// Largest absolute residual per axis.
    pub max_abs_m: [f64; 3],
    /// RMS of the residual norm per point.
    pub rms_norm_m: f64,
    /// Largest residual norm.
    pub max_norm_m: f64,
    /// RMS over all components (the "RMS" of the iteration table).
    pub rms_all_m: f64,
}

/// A calibrated model structure with its uncertainty.
#[derive(Clone, Debug)]
pub struct Calibration {
    /// The structure as calibrated (not-identifiable eDoFs removed, shifts at their estimates).
    pub structure: Structure,
    /// Every eDoF of the requested structure, identifiable or not.
    pub edofs: Vec<EdofEstimate>,
    /// Centre shifts of joints with an x or y eDoF, or fitted.
    pub shifts: Vec<ShiftEstimate>,
    /// Labels of the free parameters (rows/columns of [`Calibration::correlation`]).
    pub parameter_labels: Vec<String>,
    /// Parameter correlation matrix.
    pub correlation: DMatrix<f64>,
    /// Condition number of the weighted, column-scaled Jacobian.
    pub condition_number: f64,
    /// Weighted residual sum of squares χ².
    pub chi2: f64,
    /// Degrees of freedom n − p.
    pub dof: usize,
    /// χ²/(n − p); ≈ 1 when the model and σ are right.
    pub reduced_chi2: f64,
    /// Bayesian information criterion `n ln(χ²/n) + p ln n`.
    pub bic: f64,
    /// Residuals.
    pub residuals: ResidualStats,
    /// Number of data rows.
    pub rows: usize,
    /// Non-fatal observations (unobservable eDoFs, …).
    pub warnings: Vec<String>,
}

impl Calibration {
    /// The start robot with this calibration's eDoFs, stiffnesses and centre shifts: a drop-in
    /// robot for every other command. Geometry, limits and tool are kept.
    pub fn to_robot(&self, start: &Robot) -> Robot {
        let mut robot = start.clone();
        for axis in Axis::ALL {
            robot.base_stiffness.set(axis, None);
        }
        for joint in &mut robot.joints {
            joint.stiffness = deflex_model::AxisStiffness::RIGID;
        }
        for est in &self.edofs {
            if let Some(k) = est.stiffness {
                robot.set_stiffness(est.id.0, est.id.1, Some(k));
            }
        }
        for (i, joint) in robot.joints.iter_mut().enumerate() {
            joint.center_shift = self.structure.shifts_m.get(i).copied().unwrap_or(0.0);
        }
        robot
    }

    /// The estimate of one eDoF.
    pub fn edof(&self, id: EdofId) -> Option<&EdofEstimate> {
        self.edofs.iter().find(|e| e.id == id)
    }
}

/// Calibrate a fixed structure on measurement rows (builds the design for that structure only).
pub fn calibrate_fixed(
    robot: &Robot,
    rows: &[MeasurementRow],
    structure: &Structure,
) -> Result<Calibration, CalibError> {
    if structure.shifts_m.len() != robot.joint_count() {
        return Err(CalibError::Invalid(format!(
            "structure has {} shifts but the robot has {} joints",
            structure.shifts_m.len(),
            robot.joint_count()
        )));
    }
    if structure.edofs.is_empty() {
        return Err(CalibError::Invalid(
            "the structure has no eDoF to calibrate".into(),
        ));
    }
    let design = Design::build(robot, rows, &structure.edofs, true)?;
    fit_in_design(&design, structure)
}

/// Calibrate a structure within a prebuilt design (whose candidates include its eDoFs).
/// Unobservable and collinear eDoFs are reported not identifiable and removed, then the rest is
/// refitted.
pub fn fit_in_design(design: &Design, structure: &Structure) -> Result<Calibration, CalibError> {
    let mut active: Vec<EdofId> = structure.edofs.clone();
    let mut dropped: Vec<(EdofId, String)> = Vec::new();
    let mut shifts = structure.shifts_m.clone();
    let mut warnings = design.warnings.clone();
    for id in &active {
        if design.index_of(*id).is_none() {
            return Err(CalibError::Invalid(format!(
                "eDoF {} is not in the design",
                edof_label(*id)
            )));
        }
    }
    loop {
        let idx: Vec<usize> = active
            .iter()
            .map(|id| design.index_of(*id).unwrap_or(0))
            .collect();
        // Unobservable or collinear columns at the current shifts.
        if let Some((k, reason)) = rank_problem(design, &idx, &shifts, &active) {
            dropped.push((active[k], reason));
            active.remove(k);
            if active.is_empty() {
                let detail: Vec<String> = dropped
                    .iter()
                    .map(|(id, r)| format!("{}: {r}", edof_label(*id)))
                    .collect();
                return Err(CalibError::Invalid(format!(
                    "no eDoF of the structure is observable in this data ({})",
                    detail.join("; ")
                )));
            }
            continue;
        }
        let free: Vec<usize> = (1..=design.joint_count)
            .filter(|&j| structure.free_shift[j - 1])
            .collect();
        let sol = shift::optimize(design, &idx, &mut shifts, &free);
        let cal = analyse(
            design, structure, &active, &idx, &sol, &shifts, &dropped, &free,
        );
        // Refit without eDoFs judged not identifiable after the fit.
        let newly: Vec<(EdofId, String)> = cal
            .edofs
            .iter()
            .filter(|e| active.contains(&e.id))
            .filter_map(|e| match &e.status {
                Status::NotIdentifiable(r) => Some((e.id, r.clone())),
                _ => None,
            })
            .collect();
        if newly.is_empty() || newly.len() == active.len() {
            let mut cal = cal;
            warnings.append(&mut cal.warnings);
            cal.warnings = warnings;
            return Ok(cal);
        }
        for (id, r) in newly {
            active.retain(|a| *a != id);
            dropped.push((id, r));
        }
    }
}

/// First eDoF (position in `idx`) whose column is zero or collinear with others.
fn rank_problem(
    design: &Design,
    idx: &[usize],
    shifts: &[f64],
    active: &[EdofId],
) -> Option<(usize, String)> {
    let cols = shift::columns(design, idx, shifts);
    let (g, _) = normal_system(design, &cols);
    let d = scales(&g);
    if let Some(k) = d.iter().position(|&v| v == 0.0) {
        return Some((
            k,
            "not identifiable: no measured point moves with it under the applied loads".into(),
        ));
    }
    let p = idx.len();
    let gs = DMatrix::from_fn(p, p, |i, j| g[(i, j)] * d[i] * d[j]);
    let eig = gs.symmetric_eigen();
    let (imin, &lmin) = eig
        .eigenvalues
        .iter()
        .enumerate()
        .min_by(|a, b| a.1.total_cmp(b.1))?;
    if lmin > 1e-10 {
        return None;
    }
    let v = eig.eigenvectors.column(imin);
    let involved: Vec<usize> = (0..p).filter(|&k| v[k].abs() > 0.1).collect();
    let worst = *involved.iter().max_by(|&&a, &&b| {
        (v[a].abs(), a)
            .partial_cmp(&(v[b].abs(), b))
            .unwrap_or(std::cmp::Ordering::Equal)
    })?;
    let others: Vec<String> = involved
        .iter()
        .filter(|&&k| k != worst)
        .map(|&k| edof_label(active[k]))
        .collect();
    Some((
        worst,
        format!(
            "not identifiable: indistinguishable from {} in this data (only their combination is seen)",
            others.join(", ")
        ),
    ))
}

#[allow(clippy::too_many_arguments)]
fn analyse(
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
    let mut shift_ok: Vec<usize> = free
        .iter()
        .copied()
        .filter(|&j| {
            idx.iter()
                .zip(&sol.c)
                .any(|(&ci, &c)| design.shift_joint(ci) == Some(j) && c > 0.0)
        })
        .collect();
    let mut cov;
    let mut labels;
    let mut cond;
    loop {
        let (cols, l) = jacobian(design, idx, &sol.c, shifts, &include, &shift_ok);
        labels = l;
        let (nm, _) = normal_system(design, &cols);
        let d = scales(&nm);
        let m = cols.len();
        let ns = DMatrix::from_fn(m, m, |i, j| nm[(i, j)] * d[i] * d[j]);
        let eig = ns.clone().symmetric_eigen();
        let lmax = eig.eigenvalues.amax();
        let lmin = eig
            .eigenvalues
            .iter()
            .copied()
            .fold(f64::INFINITY, f64::min);
        cond = if m == 0 {
            1.0
        } else {
            (lmax / lmin.max(1e-300)).sqrt()
        };
        if m > 0 && (lmin <= 1e-12 * lmax || d.contains(&0.0)) && !shift_ok.is_empty() {
            shift_ok.pop();
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
        cov = DMatrix::from_fn(m, m, |i, j| inv[(i, j)] * d[i] * d[j]);
        break;
    }
    let p = labels.len();
    let dof = n.saturating_sub(p).max(1);
    let s2 = sol.chi2 / dof as f64;
    cov *= s2;
    let se = |k: usize| cov[(k, k)].max(0.0).sqrt();
    let correlation = DMatrix::from_fn(p, p, |i, j| {
        let den = se(i) * se(j);
        if den > 0.0 { cov[(i, j)] / den } else { 0.0 }
    });

    let mut edofs = Vec::new();
    for &id in &structure.edofs {
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
        if let Some((_, reason)) = dropped.iter().find(|(d, _)| *d == id) {
            edofs.push(not(reason.clone()));
            continue;
        }
        let Some(k) = active.iter().position(|a| *a == id) else {
            continue;
        };
        let c = sol.c[k];
        if c <= 0.0 {
            let bound = bound_se(design, idx, shifts, &sol.c, k, s2)
                .map(|se| format!(" (k > {:.3e} N·m/rad at 95 %)", 1.0 / (Z95 * se)))
                .unwrap_or_default();
            edofs.push(not(format!(
                "not identifiable: the fit hit the c ≥ 0 bound, stiffer than the data can resolve{bound}"
            )));
            continue;
        }
        let pos = labels.iter().position(|l| *l == Ok(k)).unwrap_or(0);
        let sc = se(pos);
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
            edofs.push(e);
            continue;
        }
        let lo_c = c - Z95 * sc;
        let hi = if lo_c > 0.0 {
            1.0 / lo_c
        } else {
            f64::INFINITY
        };
        edofs.push(EdofEstimate {
            id,
            label,
            status,
            compliance: c,
            compliance_se: sc,
            stiffness: Some(1.0 / c),
            stiffness_se: Some(sc / (c * c)),
            interval95: Some((1.0 / (c + Z95 * sc), hi)),
        });
    }

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
    let mut beta = DVector::zeros(design.gram.nrows());
    for (k, &ci) in idx.iter().enumerate() {
        for (b, coef) in design.col(ci, shift::shift_of(design, ci, shifts)) {
            beta[b] += coef * sol.c[k];
        }
    }
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

/// Residual statistics in metres from a weighted prediction.
pub(crate) fn residual_stats(design: &Design, pred: &DVector<f64>) -> ResidualStats {
    let mut stats = ResidualStats::default();
    let mut sum = [0.0; 3];
    let mut sum_norm = 0.0;
    for r in 0..design.rows {
        let mut norm2 = 0.0;
        for (ax, (acc, max)) in sum.iter_mut().zip(stats.max_abs_m.iter_mut()).enumerate() {
            let e = 3 * r + ax;
            let res = (design.y[e] - pred[e]) * design.sigma[e];
            *acc += res * res;
            norm2 += res * res;
            *max = max.max(res.abs());
        }
        sum_norm += norm2;
        stats.max_norm_m = stats.max_norm_m.max(norm2.sqrt());
    }
    let rows = design.rows.max(1) as f64;
    for (rms, s) in stats.rms_m.iter_mut().zip(sum) {
        *rms = (s / rows).sqrt();
    }
    stats.rms_norm_m = (sum_norm / rows).sqrt();
    stats.rms_all_m = (sum_norm / (3.0 * rows)).sqrt();
    stats
}
