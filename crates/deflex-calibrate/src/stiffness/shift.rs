//! Compliances and centre shifts together: variable projection.
//!
//! For fixed centre shifts δr the deflection (eq. 15) is linear in the compliances, which are
//! found by NNLS ([`crate::stiffness::nnls`]). The shifts enter nonlinearly (each x/y column is quadratic in
//! its joint's shift, see [`crate::stiffness::design`]); they are found by Levenberg–Marquardt on the
//! projected objective `f(δr) = min_{c ≥ 0} χ²(c, δr)`, each step taken from the joint
//! Gauss–Newton system of `[∂r/∂c, ∂r/∂δr]` (Kaufman's variable-projection approximation),
//! with multi-start for a newly freed shift.

use crate::stiffness::design::{Combo, Design};
use crate::stiffness::nnls::nnls;
use nalgebra::{DMatrix, DVector};

/// Largest centre shift magnitude considered (m).
pub const MAX_SHIFT_M: f64 = 5.0;

/// Result of the inner problem.
#[derive(Clone, Debug)]
pub(crate) struct Inner {
    /// Compliance of each structure eDoF (same order as `idx`).
    pub c: Vec<f64>,
    /// Weighted residual sum of squares.
    pub chi2: f64,
}

/// Shift of the joint a candidate depends on (0 for candidates without a shift).
pub(crate) fn shift_of(design: &Design, ci: usize, shifts: &[f64]) -> f64 {
    design.shift_joint(ci).map(|j| shifts[j - 1]).unwrap_or(0.0)
}

/// Columns of the structure at the given shifts.
pub(crate) fn columns(design: &Design, idx: &[usize], shifts: &[f64]) -> Vec<Combo> {
    idx.iter()
        .map(|&ci| design.col(ci, shift_of(design, ci, shifts)))
        .collect()
}

/// Basis coefficients β of the weighted prediction `X β` (eq. 13–15) for compliances `c` of the
/// candidates `idx` at the given shifts.
pub(crate) fn basis_coefficients(
    design: &Design,
    idx: &[usize],
    c: &[f64],
    shifts: &[f64],
) -> DVector<f64> {
    let mut beta = DVector::zeros(design.gram.nrows());
    for (&ci, &ck) in idx.iter().zip(c) {
        for (b, coef) in design.col(ci, shift_of(design, ci, shifts)) {
            beta[b] += coef * ck;
        }
    }
    beta
}

/// Gram matrix and right-hand side of a set of basis combinations.
pub(crate) fn normal_system(design: &Design, cols: &[Combo]) -> (DMatrix<f64>, DVector<f64>) {
    let p = cols.len();
    let mut g = DMatrix::zeros(p, p);
    for i in 0..p {
        for j in i..p {
            let v = design.ip(&cols[i], &cols[j]);
            g[(i, j)] = v;
            g[(j, i)] = v;
        }
    }
    let b = DVector::from_fn(p, |i, _| design.iy(&cols[i]));
    (g, b)
}

/// Column scale factors `1/√G_ii`; a column whose diagonal is negligible (relative to the
/// largest) gets 0: it is invisible to the data.
pub(crate) fn scales(g: &DMatrix<f64>) -> Vec<f64> {
    let p = g.nrows();
    let max = (0..p).map(|i| g[(i, i)]).fold(0.0, f64::max);
    (0..p)
        .map(|i| {
            let d = g[(i, i)];
            if d > 1e-20 * max && d > 0.0 {
                1.0 / d.sqrt()
            } else {
                0.0
            }
        })
        .collect()
}

/// NNLS for the compliances at fixed shifts.
pub(crate) fn inner(design: &Design, idx: &[usize], shifts: &[f64]) -> Inner {
    let cols = columns(design, idx, shifts);
    let (g, b) = normal_system(design, &cols);
    let d = scales(&g);
    let p = idx.len();
    let gs = DMatrix::from_fn(p, p, |i, j| g[(i, j)] * d[i] * d[j]);
    let bs = DVector::from_fn(p, |i, _| b[i] * d[i]);
    let z = nnls(&gs, &bs);
    let c: Vec<f64> = (0..p).map(|i| z[i] * d[i]).collect();
    let cv = DVector::from_column_slice(&c);
    let chi2 = (design.yty - 2.0 * cv.dot(&b) + (cv.transpose() * &g * &cv)[0]).max(0.0);
    Inner { c, chi2 }
}

/// Jacobian columns (as basis combinations) of the weighted prediction with respect to the
/// active compliances and the given shift joints, at `(c, shifts)`. Returns the columns and, for
/// each, a label index: `Ok(k)` = compliance of structure eDoF k, `Err(j)` = shift of joint j.
pub(crate) fn jacobian(
    design: &Design,
    idx: &[usize],
    c: &[f64],
    shifts: &[f64],
    include_c: &[bool],
    shift_joints: &[usize],
) -> (Vec<Combo>, Vec<Result<usize, usize>>) {
    let mut cols = Vec::new();
    let mut labels = Vec::new();
    for (k, &ci) in idx.iter().enumerate() {
        if include_c[k] {
            cols.push(design.col(ci, shift_of(design, ci, shifts)));
            labels.push(Ok(k));
        }
    }
    for &j in shift_joints {
        let mut combo: Combo = Vec::new();
        for (k, &ci) in idx.iter().enumerate() {
            if design.shift_joint(ci) == Some(j) && c[k] > 0.0 {
                for (b, coef) in design.dcol(ci, shifts[j - 1]) {
                    combo.push((b, coef * c[k]));
                }
            }
        }
        cols.push(combo);
        labels.push(Err(j));
    }
    (cols, labels)
}

/// The joints of `free` whose shift the data can move: they carry an x/y eDoF with a positive
/// compliance in `c` (a shift acts only through those, z × z = 0).
pub(crate) fn active_shift_joints(
    design: &Design,
    idx: &[usize],
    c: &[f64],
    free: &[usize],
) -> Vec<usize> {
    free.iter()
        .copied()
        .filter(|&j| {
            idx.iter()
                .zip(c)
                .any(|(&ci, &cv)| design.shift_joint(ci) == Some(j) && cv > 0.0)
        })
        .collect()
}

/// Minimise over the free shifts (joints listed in `free`, 1-based) starting from `shifts`,
/// which are updated in place. Returns the final inner solution.
pub(crate) fn optimize(
    design: &Design,
    idx: &[usize],
    shifts: &mut [f64],
    free: &[usize],
) -> Inner {
    let mut best = inner(design, idx, shifts);
    if free.is_empty() {
        return best;
    }
    let mut lambda = 1e-3;
    for _ in 0..200 {
        let include: Vec<bool> = best.c.iter().map(|&v| v > 0.0).collect();
        let sj = active_shift_joints(design, idx, &best.c, free);
        if sj.is_empty() {
            break;
        }
        let (cols, labels) = jacobian(design, idx, &best.c, shifts, &include, &sj);
        let (n, _) = normal_system(design, &cols);
        // Jᵀr = Jᵀy − Σ_e c_e Jᵀcol_e
        let current = columns(design, idx, shifts);
        let g = DVector::from_fn(cols.len(), |k, _| {
            let mut v = design.iy(&cols[k]);
            for (e, col) in current.iter().enumerate() {
                if best.c[e] > 0.0 {
                    v -= best.c[e] * design.ip(&cols[k], col);
                }
            }
            v
        });
        let d = scales(&n);
        let m = cols.len();
        let mut a = DMatrix::from_fn(m, m, |i, j| n[(i, j)] * d[i] * d[j]);
        for i in 0..m {
            a[(i, i)] += lambda * a[(i, i)].max(1e-12);
        }
        let gs = DVector::from_fn(m, |i, _| g[i] * d[i]);
        let Some(step) = a.clone().cholesky().map(|ch| ch.solve(&gs)) else {
            lambda *= 10.0;
            if lambda > 1e10 {
                break;
            }
            continue;
        };
        let mut trial = shifts.to_vec();
        let mut step_norm: f64 = 0.0;
        for (k, label) in labels.iter().enumerate() {
            if let Err(j) = label {
                let delta = step[k] * d[k];
                step_norm = step_norm.max(delta.abs());
                trial[j - 1] = (trial[j - 1] + delta).clamp(-MAX_SHIFT_M, MAX_SHIFT_M);
            }
        }
        let candidate = inner(design, idx, &trial);
        if candidate.chi2 < best.chi2 {
            let gain = best.chi2 - candidate.chi2;
            shifts.copy_from_slice(&trial);
            best = candidate;
            lambda = (lambda / 5.0).max(1e-12);
            if gain <= 1e-12 * best.chi2.max(1e-300) && step_norm < 1e-9 {
                break;
            }
            if step_norm < 1e-10 {
                break;
            }
        } else {
            lambda *= 5.0;
            if lambda > 1e10 || step_norm < 1e-12 {
                break;
            }
        }
    }
    best
}

/// [`optimize`] from several starting values of the shift of joint `new_joint` (spread over
/// ±`scale_m`), keeping the best.
pub(crate) fn optimize_multistart(
    design: &Design,
    idx: &[usize],
    shifts: &mut [f64],
    free: &[usize],
    new_joint: usize,
    scale_m: f64,
) -> Inner {
    let mut best: Option<(Inner, Vec<f64>)> = None;
    let current = shifts[new_joint - 1];
    let mut starts = vec![current];
    for f in [-1.0, -0.5, -0.2, 0.2, 0.5, 1.0] {
        starts.push(current + f * scale_m);
    }
    for start in starts {
        let mut trial = shifts.to_vec();
        trial[new_joint - 1] = start;
        let result = optimize(design, idx, &mut trial, free);
        if best.as_ref().is_none_or(|(b, _)| result.chi2 < b.chi2) {
            best = Some((result, trial));
        }
    }
    let (result, trial) = best.expect("at least one start");
    shifts.copy_from_slice(&trial);
    result
}
