//! Inverse kinematics that follows a path: Newton steps by damped least squares from the joint
//! values of a nearby pose (the previous point, or the same point's previous iterate), with
//! fixed-size nalgebra types only, so a compensation pass allocates nothing per point.
//!
//! Joint limits are checked *after* convergence, not clamped during it: a compensated pose that
//! needs a joint beyond its limit is reported as such ([`IkFailure::JointLimit`]), distinct from
//! a pose the solver cannot reach ([`IkFailure::NotConverged`]).

use deflex_model::spatial::orientation_error;
use deflex_model::{Data, MAX_JOINTS, Pose, Robot, damped_least_squares_step};
use nalgebra::Vector6;

/// Settings of [`track`].
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct TrackingIkOptions {
    /// Converged when the position error is below this (m).
    pub position_tolerance_m: f64,
    /// Converged when the orientation error is below this (rad).
    pub orientation_tolerance_rad: f64,
    /// Newton steps at most.
    pub max_iterations: usize,
    /// Damping λ of `Δq = Jᵀ (J Jᵀ + λ² I)⁻¹ e` (m): regularises singular configurations.
    pub damping: f64,
    /// Largest joint step per iteration (rad).
    pub max_step_rad: f64,
    /// Length (m) that weighs orientation errors against position errors.
    pub orientation_weight_m: f64,
}

impl Default for TrackingIkOptions {
    fn default() -> Self {
        TrackingIkOptions {
            position_tolerance_m: 1e-9,
            orientation_tolerance_rad: 1e-9,
            max_iterations: 30,
            damping: 1e-6,
            max_step_rad: 0.2,
            orientation_weight_m: 0.5,
        }
    }
}

/// Why a pose could not be given joint values.
#[derive(Clone, Copy, Debug, PartialEq, thiserror::Error)]
pub enum IkFailure {
    /// The solver did not converge (out of reach, or across a singularity).
    #[error(
        "not reached: remaining error {:.3} mm and {:.3} mrad",
        position_error_m * 1e3,
        orientation_error_rad * 1e3
    )]
    NotConverged {
        /// Remaining position error (m).
        position_error_m: f64,
        /// Remaining orientation error (rad).
        orientation_error_rad: f64,
    },
    /// The target lies beyond the arm's reach (multi-seed search of the start point).
    #[error("out of reach: {:.1} mm from joint 1, the arm reaches {:.1} mm", distance_m * 1e3, reach_m * 1e3)]
    OutOfReach {
        /// Distance from joint 1 (m).
        distance_m: f64,
        /// Reach bound (m).
        reach_m: f64,
    },
    /// The pose is reached with a joint outside its limits.
    #[error(
        "joint {joint} at {value_rad:.4} rad is outside its limits [{lower_rad:.4}, {upper_rad:.4}] rad"
    )]
    JointLimit {
        /// Joint number (1-based).
        joint: usize,
        /// Its value (rad).
        value_rad: f64,
        /// Lower limit (rad).
        lower_rad: f64,
        /// Upper limit (rad).
        upper_rad: f64,
    },
}

impl IkFailure {
    /// A short machine-readable code (`not_reached`, `out_of_reach`, `joint_limit:J3`).
    pub fn code(&self) -> String {
        match self {
            IkFailure::NotConverged { .. } => "not_reached".into(),
            IkFailure::OutOfReach { .. } => "out_of_reach".into(),
            IkFailure::JointLimit { joint, .. } => format!("joint_limit:J{joint}"),
        }
    }
}

/// The first joint outside its limits, if any.
pub fn limit_violation(robot: &Robot, q: &[f64]) -> Option<IkFailure> {
    robot
        .joints
        .iter()
        .zip(q)
        .enumerate()
        .find_map(|(i, (joint, &value))| match joint.limits {
            Some([lo, hi]) if !(lo - 1e-12..=hi + 1e-12).contains(&value) => {
                Some(IkFailure::JointLimit {
                    joint: i + 1,
                    value_rad: value,
                    lower_rad: lo,
                    upper_rad: hi,
                })
            }
            _ => None,
        })
}

/// Move `q` (the first `robot.joint_count()` entries; a nearby solution on entry) until the TCP
/// reaches `target`; `data` is scratch space and holds the forward kinematics of the result.
/// Returns the Newton steps used. Allocation-free.
pub fn track(
    robot: &Robot,
    data: &mut Data,
    target: &Pose,
    q: &mut [f64; MAX_JOINTS],
    options: &TrackingIkOptions,
) -> Result<usize, IkFailure> {
    let n = robot.joint_count();
    let weight = options.orientation_weight_m;
    let mut last_error = (f64::INFINITY, f64::INFINITY);
    for iteration in 0..=options.max_iterations {
        robot
            .forward_kinematics(data, &q[..n])
            .expect("q holds one value per joint");
        let dp = target.translation.vector - data.tcp.translation.vector;
        let dr = orientation_error(&data.tcp.rotation, &target.rotation);
        let (position_error, orientation_error_rad) = (dp.norm(), dr.norm());
        last_error = (position_error, orientation_error_rad);
        if position_error < options.position_tolerance_m
            && orientation_error_rad < options.orientation_tolerance_rad
        {
            return match limit_violation(robot, &q[..n]) {
                Some(failure) => Err(failure),
                None => Ok(iteration),
            };
        }
        if iteration == options.max_iterations || !(position_error.is_finite()) {
            break;
        }
        let error = Vector6::new(
            dp.x,
            dp.y,
            dp.z,
            dr.x * weight,
            dr.y * weight,
            dr.z * weight,
        );
        let mut columns = robot.geometric_jacobian_columns(data, &data.tcp_position());
        for column in columns.iter_mut().take(n) {
            for r in 3..6 {
                column[r] *= weight;
            }
        }
        let Some(step) = damped_least_squares_step(&columns[..n], &error, options.damping) else {
            break;
        };
        let largest = step[..n].iter().fold(0.0_f64, |m, s| m.max(s.abs()));
        let scale = if largest > options.max_step_rad {
            options.max_step_rad / largest
        } else {
            1.0
        };
        for (value, s) in q.iter_mut().zip(step).take(n) {
            *value += s * scale;
        }
    }
    Err(IkFailure::NotConverged {
        position_error_m: last_error.0,
        orientation_error_rad: last_error.1,
    })
}
