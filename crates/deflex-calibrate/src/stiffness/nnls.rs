//! Non-negative least squares (Lawson & Hanson, 1974, algorithm NNLS) on the normal equations.
//!
//! Minimises `½ xᵀGx − bᵀx` subject to `x ≥ 0`, with `G = AᵀWA` symmetric positive
//! semi-definite (p×p, small) and `b = AᵀWy`; equivalent to `min ‖W^½(Ax − y)‖²` with `x ≥ 0`.
//! Working on the p×p normal system keeps the cost independent of the number of rows.

use nalgebra::{DMatrix, DVector};

/// Solve `min ½ xᵀGx − bᵀx, x ≥ 0`. `G` should be well scaled (e.g. unit diagonal). Variables
/// whose diagonal is zero stay at 0. Returns the solution.
pub fn nnls(g: &DMatrix<f64>, b: &DVector<f64>) -> DVector<f64> {
    let p = b.len();
    let mut x = DVector::<f64>::zeros(p);
    let mut passive = vec![false; p];
    let scale = b.amax().max(g.amax()).max(1e-300);
    let tol = 1e-12 * scale * (p as f64).max(1.0);
    let usable: Vec<bool> = (0..p).map(|i| g[(i, i)] > 0.0).collect();
    let mut outer = 0;
    loop {
        outer += 1;
        if outer > 3 * p + 10 {
            break;
        }
        let w = b - g * &x;
        let mut best = None;
        let mut best_w = tol;
        for j in 0..p {
            if !passive[j] && usable[j] && w[j] > best_w {
                best_w = w[j];
                best = Some(j);
            }
        }
        let Some(t) = best else { break };
        passive[t] = true;
        let mut inner = 0;
        loop {
            inner += 1;
            let idx: Vec<usize> = (0..p).filter(|&j| passive[j]).collect();
            let z_p = solve_sub(g, b, &idx);
            let mut z = DVector::<f64>::zeros(p);
            for (k, &j) in idx.iter().enumerate() {
                z[j] = z_p[k];
            }
            if idx.iter().all(|&j| z[j] > 0.0) || inner > 3 * p + 10 {
                for &j in &idx {
                    x[j] = z[j].max(0.0);
                }
                break;
            }
            let mut alpha = f64::INFINITY;
            for &j in &idx {
                if z[j] <= 0.0 {
                    let a = x[j] / (x[j] - z[j]);
                    if a < alpha {
                        alpha = a;
                    }
                }
            }
            for &j in &idx {
                x[j] += alpha * (z[j] - x[j]);
                if x[j] <= 1e-15 * scale.max(1.0) || z[j] <= 0.0 && x[j] <= 0.0 {
                    x[j] = 0.0;
                    passive[j] = false;
                }
            }
            // The variable that reached the bound first leaves the passive set even if rounding
            // left it slightly positive.
            if let Some(&j) = idx
                .iter()
                .filter(|&&j| passive[j] && z[j] <= 0.0)
                .min_by(|&&a, &&b| x[a].total_cmp(&x[b]))
                && x[j] <= 1e-12 * (1.0 + x.amax())
            {
                x[j] = 0.0;
                passive[j] = false;
            }
        }
    }
    x
}

/// Solve `G[idx, idx] z = b[idx]` (Cholesky, falling back to a pseudo-inverse when singular).
fn solve_sub(g: &DMatrix<f64>, b: &DVector<f64>, idx: &[usize]) -> DVector<f64> {
    let k = idx.len();
    let gs = DMatrix::from_fn(k, k, |r, c| g[(idx[r], idx[c])]);
    let bs = DVector::from_fn(k, |r, _| b[idx[r]]);
    if !(crate::stiffness::all_finite(&gs) && bs.iter().all(|v| v.is_finite())) {
        // No decomposition on non-finite input (an SVD on NaN may not terminate).
        return DVector::zeros(k);
    }
    if let Some(ch) = gs.clone().cholesky() {
        return ch.solve(&bs);
    }
    let svd = gs.svd(true, true);
    svd.solve(&bs, 1e-12 * svd.singular_values.amax())
        .unwrap_or_else(|_| DVector::zeros(k))
}
