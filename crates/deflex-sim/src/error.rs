//! Errors of the twin. Every message says what was wrong and where.

use thiserror::Error;

/// Something the twin could not do.
#[derive(Debug, Error)]
pub enum SimError {
    /// A configuration value is out of its physical range.
    #[error("cell configuration: {field}: {message}")]
    Config {
        /// The offending field (`sensor.rate_hz`, …).
        field: String,
        /// What is wrong.
        message: String,
    },
    /// A tool path could not be built or read.
    #[error("tool path: {0}")]
    Path(String),
    /// A G-code file has a problem on a given line.
    #[error("{file}:{line}: {message}")]
    Gcode {
        /// File name (or `<text>`).
        file: String,
        /// 1-based line number.
        line: usize,
        /// What is wrong.
        message: String,
    },
    /// A pose of the path or of a campaign is out of the robot's reach.
    #[error("{what}: inverse kinematics failed: {source}")]
    Unreachable {
        /// Which pose.
        what: String,
        /// Model error.
        source: deflex_model::ModelError,
    },
    /// Robot model problem.
    #[error(transparent)]
    Model(#[from] deflex_model::ModelError),
    /// Measurement/plan file problem.
    #[error(transparent)]
    Data(Box<deflex_calibrate::measurements::DataError>),
    /// The run was stopped before the end of its path (an observer asked, e.g. on Ctrl-C).
    #[error("stopped at {time_s:.1} s of simulated time, before the end of the path")]
    Stopped {
        /// Simulated time when it stopped (s).
        time_s: f64,
    },
    /// A robot spec that is not a built-in robot, given where the twin cannot read the file (it
    /// reads no file: `crate::twin::cell_for_robot` reads robot files).
    #[error(
        "part.robot: `{spec}` is not a built-in robot ({}); a robot file is read by the caller (deflex_app::cell::twin_cell_file::cell_for_robot)",
        builtin_names()
    )]
    NotBuiltin {
        /// The spec given.
        spec: String,
    },
}

impl From<deflex_calibrate::measurements::DataError> for SimError {
    fn from(error: deflex_calibrate::measurements::DataError) -> Self {
        SimError::Data(Box::new(error))
    }
}

impl SimError {
    pub(crate) fn config(field: &str, message: impl Into<String>) -> Self {
        SimError::Config {
            field: field.to_string(),
            message: message.into(),
        }
    }
}

fn builtin_names() -> String {
    deflex_model::BUILTIN_ROBOTS
        .iter()
        .map(|(n, _)| *n)
        .collect::<Vec<_>>()
        .join(", ")
}
