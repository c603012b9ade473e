//! Inverse kinematics by damped least squares with joint limits, seeded from a reference
//! configuration so that successive poses of a path stay on one branch.

use crate::error::ModelError;
use crate::kinematics::Data;
use crate::robot::Robot;
use crate::spatial::{Pose, orientation_error};
use nalgebra::{DMatrix, DVector, Vector6};

/// Settings of [`Robot::inverse_kinematics`].
#[derive(Clone, Copy, Debug)]
pub struct IkOptions {
    /// Converged when the position error is below this (m).
    pub position_tolerance_m: f64,
    /// Converged when the orientation error is below this (rad).
    pub orientation_tolerance_rad: f64,
    /// Iteration budget.
    pub max_iterations: usize,
    /// Initial damping λ of `Δq = Jᵀ (J Jᵀ + λ² I)⁻¹ e` (adapted during the solve).
    pub damping: f64,
    /// Largest joint step per iteration (rad), keeps the solve on the seed's branch.
    pub max_step_rad: f64,
    /// Length (m) that scales orientation errors against position errors.
    pub orientation_weight_m: f64,
}

impl Default for IkOptions {
    fn default() -> Self {
        IkOptions {
            position_tolerance_m: 1e-9,
            orientation_tolerance_rad: 1e-9,
            max_iterations: 200,
            damping: 1e-3,
            max_step_rad: 0.3,
            orientation_weight_m: 0.5,
        }
    }
}

/// A converged IK solution.
#[derive(Clone, Debug)]
pub struct IkSolution {
    /// Joint values (rad).
    pub q: Vec<f64>,
    /// Iterations used.
    pub iterations: usize,
    /// Final position error (m).
    pub position_error_m: f64,
    /// Final orientation error (rad).
    pub orientation_error_rad: f64,
}

impl Robot {
    /// Joint values that put the TCP at `target` (world), starting from `seed` (rad). Damped least
    /// squares with an adaptive damping (Levenberg–Marquardt style), steps clamped to
    /// `max_step_rad` and to the joint limits. Returns [`ModelError::Unreachable`] when the pose
    /// cannot be reached within tolerance (out of reach or outside the limits).
    pub fn inverse_kinematics(
        &self,
        target: &Pose,
        seed: &[f64],
        options: &IkOptions,
    ) -> Result<IkSolution, ModelError> {
        let n = self.joint_count();
        let mut data = Data::new();
        let mut q: Vec<f64> = seed.to_vec();
        self.clamp_to_limits(&mut q);
        // Also checks that the seed has one value per joint.
        self.forward_kinematics(&mut data, &q)?;
        let weight = options.orientation_weight_m;
        let pose_error = |data: &Data| -> Vector6<f64> {
            let dp = target.translation.vector - data.tcp.translation.vector;
            let dr = orientation_error(&data.tcp.rotation, &target.rotation);
            Vector6::new(
                dp.x,
                dp.y,
                dp.z,
                dr.x * weight,
                dr.y * weight,
                dr.z * weight,
            )
        };
        let mut error = pose_error(&data);
        let mut lambda = options.damping;
        let mut trial = vec![0.0; n];
        for iteration in 0..options.max_iterations {
            let position_error = error.fixed_rows::<3>(0).norm();
            let orientation_error = error.fixed_rows::<3>(3).norm() / weight;
            if position_error < options.position_tolerance_m
                && orientation_error < options.orientation_tolerance_rad
            {
                return Ok(IkSolution {
                    q,
                    iterations: iteration,
                    position_error_m: position_error,
                    orientation_error_rad: orientation_error,
                });
            }
            let mut jacobian = self.geometric_jacobian(&data, &data.tcp_position());
            for mut row in jacobian.rows_mut(3, 3).row_iter_mut() {
                row *= weight;
            }
            let jjt = &jacobian * jacobian.transpose();
            let e = DVector::from_column_slice(error.as_slice());
            let mut improved = false;
            for _ in 0..12 {
                let damped = &jjt + DMatrix::identity(6, 6) * (lambda * lambda);
                let Some(solved) = damped.cholesky().map(|c| c.solve(&e)) else {
                    lambda *= 10.0;
                    continue;
                };
                let mut step = jacobian.transpose() * solved;
                let largest = step.amax();
                if largest > options.max_step_rad {
                    step *= options.max_step_rad / largest;
                }
                for i in 0..n {
                    trial[i] = q[i] + step[i];
                }
                self.clamp_to_limits(&mut trial);
                self.forward_kinematics(&mut data, &trial)?;
                let trial_error = pose_error(&data);
                if trial_error.norm() < error.norm() {
                    q.copy_from_slice(&trial);
                    error = trial_error;
                    lambda = (lambda * 0.3).max(1e-9);
                    improved = true;
                    break;
                }
                lambda *= 10.0;
            }
            if !improved {
                break;
            }
        }
        let position_error = error.fixed_rows::<3>(0).norm();
        let orientation_error = error.fixed_rows::<3>(3).norm() / weight;
        // Accept a solution that stalled at numerical precision.
        if position_error < 1e-7 && orientation_error < 1e-7 {
            return Ok(IkSolution {
                q,
                iterations: options.max_iterations,
                position_error_m: position_error,
                orientation_error_rad: orientation_error,
            });
        }
        Err(ModelError::Unreachable {
            iterations: options.max_iterations,
            position_error_m: position_error,
            orientation_error_rad: orientation_error,
        })
    }

    /// Clamp joint values into their limits (joints without limits are left alone).
    pub fn clamp_to_limits(&self, q: &mut [f64]) {
        for (value, joint) in q.iter_mut().zip(&self.joints) {
            if let Some([lo, hi]) = joint.limits {
                *value = value.clamp(lo, hi);
            }
        }
    }
}
