//! Inverse kinematics by damped least squares with joint limits, seeded from a reference
//! configuration so that successive poses of a path stay on one branch; and a multi-seed search
//! for a single pose that tells "out of reach" from "not converged".

use crate::MAX_JOINTS;
use crate::error::ModelError;
use crate::kinematics::Data;
use crate::robot::Robot;
use crate::spatial::{Pose, orientation_error};
use nalgebra::{Cholesky, Matrix6, U6, Vector6};

/// `J Jᵀ + λ² I` of the Jacobian `columns` (6-vectors, one per joint), Cholesky-factored:
/// the 6×6 system behind every damped-least-squares solve (IK, path tracking, joint
/// corrections). `None` when it is not positive definite (λ = 0 at a singularity, NaN).
/// Allocation-free.
pub fn damped_gram(columns: &[Vector6<f64>], damping: f64) -> Option<Cholesky<f64, U6>> {
    let mut gram = Matrix6::identity() * (damping * damping);
    for column in columns {
        gram += column * column.transpose();
    }
    gram.cholesky()
}

/// Damped-least-squares step `Δq = Jᵀ (J Jᵀ + λ² I)⁻¹ e` for the Jacobian `columns` (at most
/// [`MAX_JOINTS`]) and the task error `e`: the joint change that best moves the task by `e`,
/// regularised near singularities. Entries past `columns.len()` are 0. Allocation-free.
pub fn damped_least_squares_step(
    columns: &[Vector6<f64>],
    error: &Vector6<f64>,
    damping: f64,
) -> Option<[f64; MAX_JOINTS]> {
    let y = damped_gram(columns, damping)?.solve(error);
    let mut step = [0.0; MAX_JOINTS];
    for (s, column) in step.iter_mut().zip(columns) {
        *s = column.dot(&y);
    }
    Some(step)
}

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
            let mut columns = self.geometric_jacobian_columns(&data, &data.tcp_position());
            for column in columns.iter_mut().take(n) {
                for r in 3..6 {
                    column[r] *= weight;
                }
            }
            let mut improved = false;
            for _ in 0..12 {
                let Some(mut step) = damped_least_squares_step(&columns[..n], &error, lambda)
                else {
                    lambda *= 10.0;
                    continue;
                };
                let largest = step[..n].iter().fold(0.0_f64, |m, v| m.max(v.abs()));
                if largest > options.max_step_rad {
                    for s in &mut step[..n] {
                        *s *= options.max_step_rad / largest;
                    }
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

    /// Upper bound on the distance from joint 1's frame origin that the TCP can reach: the sum of
    /// the link lengths beyond joint 1, flange and tool included (m).
    pub fn reach_bound(&self) -> f64 {
        self.joints
            .iter()
            .skip(1)
            .map(|j| j.placement.translation.vector.norm())
            .sum::<f64>()
            + self.flange.translation.vector.norm()
            + self.tool.translation.vector.norm()
    }

    /// Inverse kinematics from several seeds: `preferred` first (when given), then a fixed,
    /// deterministic spread over the first three joints (wrist bent away from its singularity),
    /// clamped into the limits. Returns the first converged solution. Fails with
    /// [`ModelError::OutOfReach`] when the target position is beyond the sum of the link
    /// lengths, and with [`ModelError::NotConverged`] (best attempt's error) when no seed
    /// converged though the target is within the arm's length.
    pub fn inverse_kinematics_search(
        &self,
        target: &Pose,
        preferred: Option<&[f64]>,
        options: &IkOptions,
    ) -> Result<IkSolution, ModelError> {
        let n = self.joint_count();
        if let Some(seed) = preferred
            && seed.len() != n
        {
            return Err(crate::QLengthError {
                expected: n,
                got: seed.len(),
            }
            .into());
        }
        let mut data = Data::new();
        self.forward_kinematics(&mut data, &vec![0.0; n])?;
        let shoulder = data.joint_frames[0].translation.vector;
        let distance_m = (target.translation.vector - shoulder).norm();
        let reach_m = self.reach_bound();
        if distance_m > reach_m + options.position_tolerance_m.max(1e-9) {
            return Err(ModelError::OutOfReach {
                distance_m,
                reach_m,
            });
        }
        let mut seeds: Vec<Vec<f64>> = preferred.map(|s| vec![s.to_vec()]).unwrap_or_default();
        seeds.extend(spread_seeds(self));
        let mut best: Option<(f64, f64)> = None;
        for seed in &seeds {
            match self.inverse_kinematics(target, seed, options) {
                Ok(solution) => return Ok(solution),
                Err(ModelError::Unreachable {
                    position_error_m,
                    orientation_error_rad,
                    ..
                }) => {
                    if best.is_none_or(|(p, _)| position_error_m < p) {
                        best = Some((position_error_m, orientation_error_rad));
                    }
                }
                Err(other) => return Err(other),
            }
        }
        let (position_error_m, orientation_error_rad) = best.unwrap_or((f64::NAN, f64::NAN));
        Err(ModelError::NotConverged {
            seeds: seeds.len(),
            distance_m,
            reach_m,
            position_error_m,
            orientation_error_rad,
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

/// The multi-seed search's fixed spread: joint 1 at four headings, joints 2 and 3 at three
/// values each around the middle of their ranges, the wrist bent by 0.6 rad on its middle joint
/// (a straight wrist is singular), every value clamped into the limits: 36 seeds for an arm of
/// three or more joints.
fn spread_seeds(robot: &Robot) -> Vec<Vec<f64>> {
    use std::f64::consts::{FRAC_PI_2, PI};
    let n = robot.joint_count();
    let middle = |i: usize| {
        robot
            .joints
            .get(i)
            .and_then(|j| j.limits)
            .map_or(0.0, |[lo, hi]| 0.5 * (lo + hi))
    };
    let headings = [0.0, FRAC_PI_2, -FRAC_PI_2, PI];
    let offsets = [-0.8, 0.0, 0.8];
    let mut seeds = Vec::new();
    for heading in headings {
        for a in offsets {
            for b in offsets {
                let mut q: Vec<f64> = (0..n).map(middle).collect();
                q[0] = middle(0) + heading;
                if n > 1 {
                    q[1] += a;
                }
                if n > 2 {
                    q[2] += 1.5 * b;
                }
                if n > 4 {
                    q[4] += 0.6;
                }
                robot.clamp_to_limits(&mut q);
                seeds.push(q);
            }
        }
    }
    seeds
}
