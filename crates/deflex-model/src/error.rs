//! Errors of the model crate.

use thiserror::Error;

/// Anything that can go wrong when reading or using a robot description.
#[derive(Debug, Error)]
pub enum ModelError {
    /// A robot file (TOML or URDF) could not be read.
    #[error("{path}: cannot read file: {source}")]
    Io {
        /// The file.
        path: String,
        /// The operating-system error.
        source: std::io::Error,
    },
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
    /// The number of joint values does not match the robot.
    #[error(transparent)]
    QLength(#[from] QLengthError),
    /// Inverse kinematics did not converge to the requested pose.
    #[error(
        "pose unreachable: after {iterations} iterations the remaining error is {position_error_m:.3e} m and {orientation_error_rad:.3e} rad"
    )]
    Unreachable {
        /// Iterations used.
        iterations: usize,
        /// Remaining position error norm (m).
        position_error_m: f64,
        /// Remaining orientation error norm (rad).
        orientation_error_rad: f64,
    },
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
