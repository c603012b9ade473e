//! Errors of the model crate.

use thiserror::Error;

/// Anything that can go wrong when parsing or using a robot description.
#[derive(Debug, Error)]
pub enum ModelError {
    /// The text of a robot description (a TOML, or the URDF it names through a
    /// [`crate::UrdfResolver`]) could not be obtained by whoever supplies it: the model reads no
    /// file, so this is the supplier's own error (e.g. `deflex_app::load::RobotFileError` when
    /// a file cannot be read), shown as it is.
    #[error(transparent)]
    TextUnavailable(Box<dyn std::error::Error + Send + Sync>),
    /// The robot file is not valid TOML or does not follow the schema (unknown key, bad number).
    #[error("{path}: {message}")]
    Parse {
        /// The file (or `builtin:NAME`).
        path: String,
        /// What the parser said, with line and column.
        message: String,
    },
    /// A field has a value that is syntactically fine but physically wrong.
    #[error("{path}: {field}: {message}")]
    Invalid {
        /// The file.
        path: String,
        /// The field, e.g. `joint[3].stiffness.x`.
        field: String,
        /// What was expected.
        message: String,
    },
    /// A DH joint of a robot file does not state one of its required fields (`alpha`, `a`, `d`,
    /// `theta_offset`): a value left out is not silently taken as 0.
    #[error(
        "{path}: {joint}: missing `{field}` ({}); every DH [[joint]] states alpha, a, d and theta_offset (write 0.0 for a zero)",
        dh_field_unit(field)
    )]
    MissingDhField {
        /// The file (or `builtin:NAME`).
        path: String,
        /// The joint, e.g. `joint[2] (joint_2)`.
        joint: String,
        /// The missing key.
        field: &'static str,
    },
    /// The number of joint values does not match the robot.
    #[error(transparent)]
    QLength(#[from] QLengthError),
    /// Inverse kinematics did not converge to the requested pose from the given seed (the pose
    /// may still be reachable from another seed: see [`crate::Robot::inverse_kinematics_search`]).
    #[error(
        "pose unreachable from this seed: after {iterations} iterations the remaining error is {position_error_m:.3e} m and {orientation_error_rad:.3e} rad"
    )]
    Unreachable {
        /// Iterations used.
        iterations: usize,
        /// Remaining position error norm (m).
        position_error_m: f64,
        /// Remaining orientation error norm (rad).
        orientation_error_rad: f64,
    },
    /// The target position lies farther from the first joint than the arm can reach.
    #[error(
        "pose out of reach: the target is {distance_m:.4} m from joint 1, the arm reaches at most {reach_m:.4} m"
    )]
    OutOfReach {
        /// Distance of the target from joint 1's frame origin (m).
        distance_m: f64,
        /// Sum of the link lengths beyond joint 1, tool included (m): an upper bound on the reach.
        reach_m: f64,
    },
    /// Inverse kinematics converged from none of the seeds tried, though the target lies within
    /// the arm's length: the orientation or the joint limits may forbid it, or it lies at the
    /// edge of the workspace.
    #[error(
        "pose not reached from {seeds} seeds (within the arm's length, {distance_m:.4} m of {reach_m:.4} m): best remaining error {position_error_m:.3e} m and {orientation_error_rad:.3e} rad; the orientation or the joint limits may forbid it"
    )]
    NotConverged {
        /// Seeds tried.
        seeds: usize,
        /// Distance of the target from joint 1 (m).
        distance_m: f64,
        /// Upper bound on the reach (m).
        reach_m: f64,
        /// Best remaining position error (m).
        position_error_m: f64,
        /// Orientation error of that best attempt (rad).
        orientation_error_rad: f64,
    },
}

/// The unit of a DH key: lengths `a`, `d` in m, angles in rad.
fn dh_field_unit(field: &str) -> &'static str {
    match field {
        "a" | "d" => "m",
        _ => "rad",
    }
}

/// The joint vector does not have one value per motorised joint. Small and `Copy` so the hot
/// path can return it without allocating.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Error)]
#[error("expected {expected} joint values, got {got}")]
pub struct QLengthError {
    /// Number of joints of the robot.
    pub expected: usize,
    /// Number of values given.
    pub got: usize,
}
