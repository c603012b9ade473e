//! What a command can fail with: the libraries' typed errors, and the usage errors of the command
//! line (naming the flag, what it takes and what it was given). Only `main` turns them into text.

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
    /// A robot description that cannot be read or used.
    #[error(transparent)]
    Model(#[from] deflex_model::ModelError),
    /// A measurement file that cannot be used: loaded displacements, a plan, absolute
    /// (tracker) readings.
    #[error(transparent)]
    Data(#[from] deflex_calibrate::measurements::DataError),
    /// A points file that cannot be used.
    #[error(transparent)]
    Points(#[from] deflex_calibrate::measurements::points::PointsError),
    /// A point given on the command line that cannot be used.
    #[error(transparent)]
    Point(#[from] deflex_calibrate::measurements::points::PointProblem),
    /// Calibration, planning or validation refused the data.
    #[error(transparent)]
    Calib(#[from] deflex_calibrate::stiffness::CalibError),
    /// The twin refused its settings or a path.
    #[error(transparent)]
    Sim(#[from] deflex_sim::SimError),
    /// A twin settings file that cannot be read or used.
    #[error(transparent)]
    TwinCellFile(#[from] deflex_app::cell::twin_cell_file::TwinCellFileError),
    /// The controller could not drive the twin.
    #[error(transparent)]
    Twin(#[from] deflex_sim::twin::TwinError),
    /// A twin workflow could not be set up.
    #[error(transparent)]
    TwinSetup(#[from] deflex_app::twin::TwinSetupError),
    /// The ends of the simulated cell could not be made.
    #[error(transparent)]
    CellSides(#[from] deflex_app::cell::links::CellSidesError),
    /// The study could not be run.
    #[error(transparent)]
    Demo(#[from] deflex_app::study::DemoError),
    /// A report could not be written.
    #[error(transparent)]
    Page(#[from] deflex_app::report::PageError),
    /// A plot or page could not be written.
    #[error(transparent)]
    Report(#[from] deflex_plot::PlotError),
    /// The live view could not be served.
    #[error(transparent)]
    View(#[from] deflex_view::ViewError),
    /// The MCAP recording could not be written.
    #[error(transparent)]
    Record(#[from] deflex_record::RecordError),
    /// A run log or recording that cannot be plotted.
    #[error(transparent)]
    Trace(#[from] deflex_record::trace::TraceError),
    /// A run stopped before its end (Ctrl-C with a live view): its outputs are not written.
    #[error("{source}: nothing written ({} keeps what it held)", .out.display())]
    Stopped {
        /// The output folder, left as it was.
        out: PathBuf,
        /// Where the run stopped.
        source: Box<deflex_sim::SimError>,
    },
    /// A file or folder could not be written.
    #[error("{}: {source}", .path.display())]
    Write {
        /// The file or folder.
        path: PathBuf,
        /// The operating system's error.
        source: std::io::Error,
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
    /// A deflection map none of whose nodes the arm reaches.
    #[error("no grid node is reachable; check --plane, --center and --size")]
    NoReachableNode,
    /// A calibration that identified nothing.
    #[error(
        "{}: no eDoF could be identified from this data (every compliance is at its bound or not observable); nothing written",
        .data.display()
    )]
    NothingIdentified {
        /// The measurement file.
        data: PathBuf,
    },
    /// A coupling asked for (`calibrate --couplings`) with an end the identified structure has
    /// no eDoF for.
    #[error(
        "--couplings {pair}: {edof} is not an eDoF of the identified structure `{structure}` (a coupling joins two eDoFs the calibration identified: choose them from the structure, or make the search keep them with --structure fixed and a start model that has them); nothing written"
    )]
    CouplingNotInStructure {
        /// The pair as given (`J2.z:J3.y`).
        pair: String,
        /// The end that is missing (`J3.y`).
        edof: String,
        /// The identified structure's label.
        structure: String,
    },
    /// A `deflex run` session that did not end well.
    #[error(transparent)]
    Run(#[from] RunFailure),
    /// An output path refused, or that could not be written, named with its flag.
    #[error(transparent)]
    Output(#[from] deflex_files::OutputError),
    /// An offline compensation that could not be made or written.
    #[error(transparent)]
    Compensate(#[from] crate::cmd_compensate::CompensateCommandError),
    /// An input file that cannot be read (special file, too large, not UTF-8, …).
    #[error(transparent)]
    Input(#[from] deflex_files::InputError),
    /// A folder that cannot be listed.
    #[error("{}: {source}", .path.display())]
    Read {
        /// The folder.
        path: PathBuf,
        /// The operating system's error.
        source: std::io::Error,
    },
    /// A series folder without exactly one measurement file.
    #[error("{}: expected one measurements_*.csv, found {found}", .folder.display())]
    SeriesFiles {
        /// The folder.
        folder: PathBuf,
        /// Measurement files found.
        found: usize,
    },
    /// A tracker series that cannot be imported.
    #[error(transparent)]
    Import(#[from] deflex_calibrate::geometry::ur10_tracker::ImportError),
    /// A campaign the elasto-geometric calibration cannot use.
    #[error(transparent)]
    Campaign(#[from] deflex_calibrate::geometry::campaign::CampaignError),
    /// An elasto-geometric fit that failed.
    #[error(transparent)]
    Fit(#[from] deflex_calibrate::geometry::fit::FitError),
    /// A prediction that failed.
    #[error(transparent)]
    Predict(#[from] deflex_calibrate::geometry::predict::PredictError),
    /// Readings that do not say which set-up or target to register.
    #[error(transparent)]
    RegisterInput(#[from] crate::cmd_register::RegisterInputError),
    /// A registration that failed.
    #[error(transparent)]
    Register(#[from] deflex_calibrate::geometry::register::RegisterError),
    /// A calibration terms file that cannot be used.
    #[error(transparent)]
    Terms(#[from] deflex_calibrate::geometry::terms::TermsError),
    /// A model step or loss not known (`--steps`, `--loss`).
    #[error(transparent)]
    Choice(#[from] deflex_calibrate::geometry::fit::ChoiceError),
    /// A fit whose readings the calibrated robot still misses by centimetres: another robot's
    /// data. Nothing is written.
    #[error(
        "{files}: robot \"{robot}\" leaves the fitted readings {rms_mm:.1} mm RMS from its prediction after calibration (more than {limit_mm:.0} mm): these are not this robot's readings (another robot's data? give it with --robot); nothing written"
    )]
    ImplausibleFit {
        /// The data files.
        files: String,
        /// The robot given.
        robot: String,
        /// RMS of the fitted readings' residuals (mm).
        rms_mm: f64,
        /// The limit (mm).
        limit_mm: f64,
    },
    /// Fewer independent equations than parameters: the data cannot determine them.
    #[error(
        "{files}: {distinct} distinct reading(s) of {readings} give {equations} equations for {parameters} parameters: the data cannot determine them; measure more configurations (nothing written)"
    )]
    TooFewReadings {
        /// The data files.
        files: String,
        /// Distinct readings.
        distinct: usize,
        /// Readings fitted.
        readings: usize,
        /// Equations they give (3 per distinct reading).
        equations: usize,
        /// Parameters to determine.
        parameters: usize,
    },
    /// A label `import` would not read back the same.
    #[error(
        "{flag} \"{label}\": {problem}; import refuses it (labels are not rewritten): give a label of 1 to {max_bytes} bytes without control characters, outer white space or a leading `#`"
    )]
    ImportLabel {
        /// `--setup` or `--target`.
        flag: &'static str,
        /// The label, shown with its control characters escaped.
        label: String,
        /// What is wrong with it.
        problem: deflex_calibrate::geometry::data::LabelProblem,
        /// Longest label accepted (bytes).
        max_bytes: usize,
    },
    /// A cell file (`CELL.toml`) that cannot be read or used.
    #[error(transparent)]
    Config(#[from] deflex_app::cell::config::ConfigError),
    /// A `deflex run` session that could not start (links, sensor, threads).
    #[error(transparent)]
    Start(#[from] deflex_app::cell::cell_run::StartError),
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
    /// The simulated cell could not serve its session.
    #[error(transparent)]
    CellServe(#[from] deflex_sim::twin::cell_server::CellServeError),
    /// The run log's writer thread failed.
    #[error("log writer: {0}")]
    LogWriter(std::io::Error),
    /// `cell --sim` given a cell whose sensor is a ROS 2 topic.
    #[error(
        "{origin}: sensor.kind = \"ros2\": the simulated cell plays the robot and an ATI Net F/T; \
         give `deflex cell --sim` a CELL.toml with sensor.kind = \"netft\" and relay its \
         readings onto the WrenchStamped topic (as crates/deflex-ros2/tests/python does)"
    )]
    SimCellNeedsNetFt {
        /// The cell file.
        origin: String,
    },
    /// A calibrated robot that could not be exported.
    #[error(transparent)]
    Export(#[from] crate::cmd_export::ExportCommandError),
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

    /// A write to `path` failed.
    pub fn write(path: impl Into<PathBuf>) -> impl FnOnce(std::io::Error) -> CliError {
        let path = path.into();
        move |source| CliError::Write { path, source }
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
        "the log {} could not be written: {message}; the session was stopped when it happened and the correction ramped out",
        .path.display()
    )]
    Log {
        /// The log's path.
        path: PathBuf,
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
        "{flag}: expected a number from {} to {}{}, got {}",
        compact(*.lo),
        compact(*.hi),
        unit_suffix(.unit),
        compact(*.got)
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

/// A number for a message: plain when readable, in exponent form when very large or small
/// (`1e308`, not three hundred digits).
pub fn compact(value: f64) -> String {
    let magnitude = value.abs();
    if value.is_finite() && value != 0.0 && !(1e-3..1e6).contains(&magnitude) {
        format!("{value:e}")
    } else {
        format!("{value}")
    }
}

fn unit_suffix(unit: &str) -> String {
    if unit.is_empty() {
        String::new()
    } else {
        format!(" {unit}")
    }
}
