//! Lawson–Hanson NNLS against brute force over every active set, its KKT conditions, and a
//! zero column that stays at zero.

use deflex_calibrate::stiffness::nnls::nnls;
use nalgebra::{DMatrix, DVector};
use rand::{Rng, SeedableRng};

/// Objective value.
fn objective(g: &DMatrix<f64>, b: &DVector<f64>, x: &DVector<f64>) -> f64 {
    0.5 * (x.transpose() * g * x)[0] - b.dot(x)
}

/// Brute force: every active set, unconstrained solve on the free part, keep feasible
/// solutions, return the best objective.
fn brute_force(g: &DMatrix<f64>, b: &DVector<f64>) -> f64 {
    let p = b.len();
    let mut best = 0.0; // x = 0
    for mask in 1u32..(1 << p) {
        let idx: Vec<usize> = (0..p).filter(|j| mask & (1 << j) != 0).collect();
        let z = solve_sub(g, b, &idx);
        if z.iter().all(|v| *v >= 0.0) {
            let mut x = DVector::zeros(p);
            for (k, &j) in idx.iter().enumerate() {
                x[j] = z[k];
            }
            best = f64::min(best, objective(g, b, &x));
        }
    }
    best
}

/// Unconstrained solve on a subset: `G[idx, idx] z = b[idx]` (Cholesky, falling back to a
/// pseudo-inverse when singular).
fn solve_sub(g: &DMatrix<f64>, b: &DVector<f64>, idx: &[usize]) -> DVector<f64> {
    let k = idx.len();
    let gs = DMatrix::from_fn(k, k, |r, c| g[(idx[r], idx[c])]);
    let bs = DVector::from_fn(k, |r, _| b[idx[r]]);
    if let Some(ch) = gs.clone().cholesky() {
        return ch.solve(&bs);
    }
    let svd = gs.svd(true, true);
    svd.solve(&bs, 1e-12 * svd.singular_values.amax())
        .unwrap_or_else(|_| DVector::zeros(k))
}

#[test]
fn matches_brute_force_on_random_problems() {
    let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(7);
    for trial in 0..300 {
        let p = rng.gen_range(1..=6);
        let m = rng.gen_range(p..=p + 8);
        let a = DMatrix::from_fn(m, p, |_, _| rng.gen_range(-1.0..1.0));
        let y = DVector::from_fn(m, |_, _| rng.gen_range(-1.0..1.0));
        let g = a.tr_mul(&a);
        let b = a.tr_mul(&y);
        let x = nnls(&g, &b);
        assert!(x.iter().all(|v| *v >= 0.0), "trial {trial}: negative");
        let got = objective(&g, &b, &x);
        let want = brute_force(&g, &b);
        assert!(
            (got - want).abs() <= 1e-9 * (1.0 + want.abs()),
            "trial {trial}: nnls {got} vs brute force {want}"
        );
        // KKT: gradient ≥ 0 on the bound, ≈ 0 on the free set.
        let w = &b - &g * &x;
        for j in 0..p {
            if x[j] > 0.0 {
                assert!(w[j].abs() < 1e-8, "trial {trial}: free gradient {}", w[j]);
            } else {
                assert!(w[j] < 1e-8, "trial {trial}: bound gradient {}", w[j]);
            }
        }
    }
}

#[test]
fn zero_column_stays_zero() {
    let g = DMatrix::from_row_slice(2, 2, &[1.0, 0.0, 0.0, 0.0]);
    let b = DVector::from_row_slice(&[2.0, 0.0]);
    let x = nnls(&g, &b);
    assert_eq!(x[1], 0.0);
    assert!((x[0] - 2.0).abs() < 1e-12);
}
