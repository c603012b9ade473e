//! What a command can fail with: the application's error (every workflow's failure), the errors
//! of what the command line attaches itself (the live view, ROS 2, a run stopped by Ctrl-C) and
//! checks itself (an output path, a point flag), the usage errors of the command line (naming
//! the flag, what it takes and what it was given), and how a `deflex run` session ended. Only
//! `main` turns them into text.

use std::path::PathBuf;
use thiserror::Error;

/// Result of every command.
pub type CommandResult = Result<(), CliError>;

/// Why a command failed.
#[derive(Debug, Error)]
pub enum CliError {
    /// A flag, or a combination of flags, that cannot be used.
    #[error(transparent)]
    Usage(#[from] UsageError),
    /// A workflow of the application layer failed (its text says what and where).
    #[error(transparent)]
    App(#[from] deflex_app::Error),
    /// A point given on the command line (`--point`) that cannot be used.
    #[error(transparent)]
    Point(#[from] deflex_app::calibrate::plan::PointProblem),
    /// The live view could not be served.
    #[error(transparent)]
    View(#[from] deflex_view::ViewError),
    /// A run stopped before its end (Ctrl-C with a live view): its outputs are not written.
    #[error("{source}: nothing written ({} keeps what it held)", .out.display())]
    Stopped {
        /// The output folder, left as it was.
        out: PathBuf,
        /// Where the run stopped.
        source: Box<deflex_sim::SimError>,
    },
    /// An error about a given file or flag value, named first.
    #[error("{context}: {source}")]
    In {
        /// The file, or the flag and its value (`--model m.toml`, `--points`).
        context: String,
        /// What went wrong with it.
        source: Box<CliError>,
    },
    /// An inverse kinematics that did not reach the target.
    #[error("{source} (target {xyz_mm:?} mm, rpy {rpy_deg:?}°)")]
    Unreachable {
        /// The target position (mm).
        xyz_mm: [f64; 3],
        /// The target orientation (roll, pitch, yaw, degrees).
        rpy_deg: [f64; 3],
        /// Why it was not reached.
        source: deflex_model::ModelError,
    },
    /// A `deflex run` session that did not end well.
    #[error(transparent)]
    Run(#[from] RunFailure),
    /// An output path refused, or that could not be written, named with its flag.
    #[error(transparent)]
    Output(#[from] deflex_files::OutputError),
    /// The ROS 2 sensor link or bridge.
    #[cfg(feature = "ros2")]
    #[error(transparent)]
    Ros2(#[from] deflex_ros2::Ros2Error),
    /// A cell that asks for ROS 2 given to a `deflex` built without it.
    #[cfg(not(feature = "ros2"))]
    #[error(
        "{origin}: {field}: this deflex was built without ROS 2 (the `ros2` cargo feature of \
         deflex-cli); build it with: {} (or run it as cargo run --release -p deflex-cli \
         --features ros2 -- run …)",
        crate::ros2_parts::ros2_build_command!()
    )]
    Ros2NotBuilt {
        /// The cell file.
        origin: String,
        /// The field that asks for ROS 2: `[ros2]` or `sensor.kind = "ros2"`.
        field: &'static str,
    },
}

impl CliError {
    /// The process's exit status for this error (documented in the README, "Reliability"):
    /// 1 an error (bad input, refused output, a session that failed), 3 a `run` session that
    /// ended with a latched fault, 4 a `run` whose log could not be written. (2 is the
    /// command-line parser's: an unknown flag or a missing value.)
    pub fn exit_code(&self) -> u8 {
        match self {
            CliError::Run(failure) => failure.exit_code(),
            _ => 1,
        }
    }

    /// An error about `context` (a file, or a flag with its value), named first.
    pub fn in_context(context: impl Into<String>) -> impl FnOnce(CliError) -> CliError {
        let context = context.into();
        move |source| CliError::In {
            context,
            source: Box::new(source),
        }
    }
}

/// How a `deflex run` session failed.
#[derive(Debug, Error)]
pub enum RunFailure {
    /// The session could not run (no data, a joint-count mismatch, a thread that panicked…).
    #[error("the session failed: {0}")]
    Failed(String),
    /// A fault latched during the session (sensor_timeout, joint_jump, robot_link_lost…).
    #[error(
        "the session ended with a latched fault: {0}; the correction was ramped to its safe value"
    )]
    Faulted(String),
    /// Another connection held the robot link while the robot was served no answers.
    #[error(
        "the session ended faulted: another connection held the robot link while the robot was served no answers (robot_link_starved); the robot may not have received its corrections"
    )]
    Starved,
    /// The log could not be written (a full disk…): the session was stopped when it happened.
    #[error(
        "the log{} could not be written: {message}; the session was stopped when it happened and the correction ramped out",
        .path.as_ref().map(|p| format!(" {}", p.display())).unwrap_or_default()
    )]
    Log {
        /// The log's path (a session has a log error only when it has a log).
        path: Option<PathBuf>,
        /// The system's error.
        message: String,
    },
}

impl RunFailure {
    /// 1 failed, 3 faulted (starved included), 4 log not written.
    pub fn exit_code(&self) -> u8 {
        match self {
            RunFailure::Failed(_) => 1,
            RunFailure::Faulted(_) | RunFailure::Starved => 3,
            RunFailure::Log { .. } => 4,
        }
    }
}

/// A flag, or a combination of flags, that cannot be used.
#[derive(Clone, Debug, PartialEq, Error)]
pub enum UsageError {
    /// A number outside its range (NaN and infinities included).
    #[error(
        "{flag}: {}",
        deflex_app::error::out_of_range(*.got, *.lo, *.hi, .unit)
    )]
    Range {
        /// The flag.
        flag: String,
        /// Smallest value accepted.
        lo: f64,
        /// Largest value accepted.
        hi: f64,
        /// Unit (empty: none).
        unit: &'static str,
        /// The value given.
        got: f64,
    },
    /// A value not of the form the flag takes.
    #[error("{flag}: expected {expected}, got {got}")]
    Invalid {
        /// The flag.
        flag: String,
        /// What it takes.
        expected: String,
        /// What it was given.
        got: String,
    },
    /// Two flags that exclude each other.
    #[error("give {first} or {second}, not both")]
    NotBoth {
        /// One flag.
        first: &'static str,
        /// The other.
        second: &'static str,
    },
    /// A flag that only applies with another setting.
    #[error("{flag}: {applies}")]
    DoesNotApply {
        /// The flag.
        flag: &'static str,
        /// Where it applies (`only with --load cable`).
        applies: &'static str,
    },
    /// Something the command needs and was not given.
    #[error("{what}: {give}")]
    Missing {
        /// What is missing.
        what: &'static str,
        /// How to give it.
        give: &'static str,
    },
    /// A position farther than 100 m (mm values).
    #[error("{flag}: {xyz:?} is farther than 100 m")]
    TooFar {
        /// The flag.
        flag: &'static str,
        /// The position given (mm).
        xyz: [f64; 3],
    },
    /// A flag given with a setting it does not apply to.
    #[error("{flag} is only used with {with}")]
    OnlyWith {
        /// The flag.
        flag: &'static str,
        /// The setting it applies to (`--format dh-table`).
        with: &'static str,
    },
    /// Joint values that do not match the robot.
    #[error("robot \"{robot}\" has {joints} joints, but {given} joint values were given")]
    JointCount {
        /// The robot's name.
        robot: String,
        /// Its joints.
        joints: usize,
        /// Values given.
        given: usize,
    },
}

impl UsageError {
    /// A value not of the form `flag` takes.
    pub fn invalid(
        flag: impl Into<String>,
        expected: impl Into<String>,
        got: impl std::fmt::Display,
    ) -> UsageError {
        UsageError::Invalid {
            flag: flag.into(),
            expected: expected.into(),
            got: got.to_string(),
        }
    }
}
