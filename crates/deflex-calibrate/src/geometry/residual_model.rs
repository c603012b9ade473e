//! A residual model on the joint angles: what the parametric model leaves, learnt as a smooth
//! function of the configuration and added to its predictions.
//!
//! **Frame and inputs.** The residual is learnt in joint 1's frame (the frame that turns with
//! the arm), as a function of the joints that shape the arm: an error that comes from the arm's
//! own bending or geometry then follows it round the base, and a series measured with the base
//! joint elsewhere still sees it. On the UR10 data this is what lets a model learnt on the grid
//! of Series A reach Series B at all: B's configurations lie a median 1.2 rad from A's nearest
//! in all six joints, 0.1 rad in joints 2–3.
//!
//! **Model.** A Gaussian process on the joint angles with the kernel
//! `k(q, q') = σ_f² exp(−Σ_j 2 (1 − cos(q_j − q'_j)) / (2 ℓ²))` (a squared exponential on each
//! joint's circle: `2(1 − cos Δ) ≈ Δ²` for small Δ, and a full turn is the same angle), three
//! independent outputs (x, y, z) sharing it. With n ≈ 10⁴ readings an exact GP needs an n × n
//! Cholesky (≈ 10¹² flops, 1 GB); instead the *subset-of-regressors* approximation on m
//! inducing configurations `u` (a random subset of the training ones, m ≤ [`MAX_INDUCING`]):
//! posterior mean `μ(q) = k_u(q)ᵀ (λ K_uu + K_unK_nu)⁻¹ K_un y`, `λ = σ_n²/σ_f²` (Rasmussen &
//! Williams 2006, §8.3.1), O(n m²). Only the mean is used; with a long way to the nearest
//! training configuration it falls back to zero (the parametric model alone).
//!
//! **Hyper-parameters** ℓ and λ are not fitted to the training rows (that would learn the
//! fitted series); the caller picks them from [`HYPER_GRID`] by the held-out protocol across
//! sessions or series ([`crate::geometry::fit`]). Linear algebra: `nalgebra`'s Cholesky.

use nalgebra::{DMatrix, Vector3};
use rand::seq::SliceRandom;
use rand_chacha::ChaCha8Rng;

/// Largest number of inducing configurations.
pub const MAX_INDUCING: usize = 400;

/// Kernel hyper-parameters.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ResidualHyper {
    /// Length scale ℓ on each joint angle (rad).
    pub length_scale_rad: f64,
    /// Ridge λ = σ_n²/σ_f² (dimensionless).
    pub ridge: f64,
    /// Joints the kernel looks at (bit j = joint j + 1).
    pub joints: u16,
}

/// Shoulder and elbow (joints 2, 3): the arm's shape in the plane joint 1 turns.
pub const ARM: u16 = 0b110;
/// Joints 2 to 5.
pub const ARM_AND_WRIST: u16 = 0b11110;
/// Every joint.
pub const ALL_JOINTS: u16 = 0xffff;

/// The candidates tried by cross-validation: the arm's shape (joints 2, 3) or joints 2–5,
/// ℓ 0.3, 0.6, 1.2 rad, λ 1 or 30.
pub const HYPER_GRID: [ResidualHyper; 12] = {
    const fn h(joints: u16, length_scale_rad: f64, ridge: f64) -> ResidualHyper {
        ResidualHyper {
            length_scale_rad,
            ridge,
            joints,
        }
    }
    [
        h(ARM, 0.3, 1.0),
        h(ARM, 0.3, 30.0),
        h(ARM, 0.6, 1.0),
        h(ARM, 0.6, 30.0),
        h(ARM, 1.2, 1.0),
        h(ARM, 1.2, 30.0),
        h(ARM_AND_WRIST, 0.3, 1.0),
        h(ARM_AND_WRIST, 0.3, 30.0),
        h(ARM_AND_WRIST, 0.6, 1.0),
        h(ARM_AND_WRIST, 0.6, 30.0),
        h(ARM_AND_WRIST, 1.2, 1.0),
        h(ARM_AND_WRIST, 1.2, 30.0),
    ]
};

/// A trained residual model.
#[derive(Clone, Debug, PartialEq)]
pub struct ResidualModel {
    /// Hyper-parameters.
    pub hyper: ResidualHyper,
    /// Inducing configurations (rad), each of the robot's joint count.
    pub inducing: Vec<Vec<f64>>,
    /// Weights of each inducing configuration, per world axis (m).
    pub weights: Vec<[f64; 3]>,
}

/// Why a residual model cannot be trained.
#[derive(Debug, thiserror::Error)]
pub enum ResidualModelError {
    /// Too few training readings.
    #[error("a residual model needs at least {minimum} training readings, got {got}")]
    TooFew {
        /// Readings given.
        got: usize,
        /// Needed.
        minimum: usize,
    },
    /// The system was not positive definite.
    #[error(
        "the residual model's normal matrix is not positive definite (ℓ = {length_scale_rad} rad, λ = {ridge})"
    )]
    NotPositiveDefinite {
        /// Length scale.
        length_scale_rad: f64,
        /// Ridge.
        ridge: f64,
    },
    /// Stored weights and inducing configurations disagree.
    #[error("{inducing} inducing configurations but {weights} weights")]
    Shape {
        /// Inducing configurations.
        inducing: usize,
        /// Weight rows.
        weights: usize,
    },
}

fn kernel(a: &[f64], b: &[f64], inv_two_l2: f64, joints: u16) -> f64 {
    let d2: f64 = a
        .iter()
        .zip(b)
        .enumerate()
        .filter(|(j, _)| *j < 16 && joints & (1 << j) != 0)
        .map(|(_, (x, y))| 2.0 * (1.0 - (x - y).cos()))
        .sum();
    (-d2 * inv_two_l2).exp()
}

impl ResidualModel {
    /// Train on configurations `q` and world residuals `y` (same order), `seed` choosing the
    /// inducing subset (module documentation).
    pub fn train(
        q: &[Vec<f64>],
        y: &[Vector3<f64>],
        hyper: ResidualHyper,
        rng: &mut ChaCha8Rng,
    ) -> Result<ResidualModel, ResidualModelError> {
        const MINIMUM: usize = 10;
        if q.len() < MINIMUM || q.len() != y.len() {
            return Err(ResidualModelError::TooFew {
                got: q.len().min(y.len()),
                minimum: MINIMUM,
            });
        }
        let mut order: Vec<usize> = (0..q.len()).collect();
        order.shuffle(rng);
        let mut inducing: Vec<Vec<f64>> = Vec::new();
        for &i in &order {
            if inducing.len() >= MAX_INDUCING {
                break;
            }
            let distinct = inducing
                .iter()
                .all(|u| u.iter().zip(&q[i]).any(|(a, b)| (a - b).abs() > 1e-6));
            if distinct {
                inducing.push(q[i].clone());
            }
        }
        let m = inducing.len();
        let inv = 1.0 / (2.0 * hyper.length_scale_rad.powi(2));
        let mut a = DMatrix::<f64>::zeros(m, m);
        for i in 0..m {
            for j in 0..=i {
                let k = kernel(&inducing[i], &inducing[j], inv, hyper.joints) * hyper.ridge;
                a[(i, j)] = k;
                a[(j, i)] = k;
            }
        }
        let mut b = DMatrix::<f64>::zeros(m, 3);
        let mut column = vec![0.0; m];
        for (qi, yi) in q.iter().zip(y) {
            for (c, u) in column.iter_mut().zip(&inducing) {
                *c = kernel(u, qi, inv, hyper.joints);
            }
            for i in 0..m {
                let ci = column[i];
                if ci == 0.0 {
                    continue;
                }
                for j in 0..=i {
                    a[(i, j)] += ci * column[j];
                }
                for k in 0..3 {
                    b[(i, k)] += ci * yi[k];
                }
            }
        }
        for i in 0..m {
            for j in 0..i {
                a[(j, i)] = a[(i, j)];
            }
            // A jitter relative to the diagonal keeps the factorisation stable when inducing
            // configurations nearly coincide.
            a[(i, i)] *= 1.0 + 1e-10;
        }
        let cholesky = a
            .cholesky()
            .ok_or(ResidualModelError::NotPositiveDefinite {
                length_scale_rad: hyper.length_scale_rad,
                ridge: hyper.ridge,
            })?;
        let w = cholesky.solve(&b);
        let weights = (0..m).map(|i| [w[(i, 0)], w[(i, 1)], w[(i, 2)]]).collect();
        Ok(ResidualModel {
            hyper,
            inducing,
            weights,
        })
    }

    /// Check a stored model's shape.
    pub fn check(&self) -> Result<(), ResidualModelError> {
        if self.inducing.len() != self.weights.len() {
            return Err(ResidualModelError::Shape {
                inducing: self.inducing.len(),
                weights: self.weights.len(),
            });
        }
        Ok(())
    }

    /// The predicted correction at joint values `q` (m, in joint 1's frame: multiply by that
    /// frame's rotation for world axes).
    pub fn predict(&self, q: &[f64]) -> Vector3<f64> {
        let inv = 1.0 / (2.0 * self.hyper.length_scale_rad.powi(2));
        let mut out = Vector3::zeros();
        for (u, w) in self.inducing.iter().zip(&self.weights) {
            let k = kernel(u, q, inv, self.hyper.joints);
            out += Vector3::new(w[0], w[1], w[2]) * k;
        }
        out
    }
}
