//! Errors of the engine layer: every failure of a deflex crate, plus the checks the bindings do
//! on arrays and options, with the text the CLI prints. [`ErrorKind`] picks the Python exception
//! class (`deflex.InputError`, `deflex.ModelError`, …).

use thiserror::Error;

/// Which Python exception an [`Error`](enum@Error) becomes (the classes of `deflex/_errors.py`).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum ErrorKind {
    /// A bad argument: shape, NaN, a value out of its range, an unknown choice.
    Input,
    /// A robot description that cannot be read or used, or an unreachable pose.
    Model,
    /// A measurement, log, G-code or table file (or in-memory table) that cannot be used.
    Data,
    /// A calibration that cannot be done with the data given.
    Calibration,
    /// An offline compensation that failed or left points uncompensated.
    Compensation,
    /// A robot program that cannot be written.
    Program,
    /// The digital twin could not run.
    Simulation,
    /// A file could not be written.
    Io,
    /// A bug in deflex (a panic caught at the boundary).
    Internal,
}

/// Anything the engine layer can fail with.
#[derive(Debug, Error)]
pub enum Error {
    /// An array has the wrong shape.
    #[error("{name}: expected shape {expected}, got {got}")]
    Shape {
        /// Argument name.
        name: &'static str,
        /// Expected shape, in words (`(6,) or (N, 6)`).
        expected: String,
        /// Shape given, as Python prints it.
        got: String,
    },
    /// An array holds NaN or an infinity.
    #[error("{name}[{index}] is {value}: every value must be a finite number")]
    NonFinite {
        /// Argument name.
        name: &'static str,
        /// Index of the value, as Python writes it (`3, 2`).
        index: String,
        /// The value.
        value: f64,
    },
    /// An option or argument value is not acceptable.
    #[error("{name}: {message}")]
    Invalid {
        /// Argument name (the Python keyword).
        name: String,
        /// What was expected and what was given.
        message: String,
    },
    /// A row of an in-memory table (DataFrame or mapping of columns) is bad.
    #[error("{origin} row {row}: {message}")]
    TableRow {
        /// What the table is (`DataFrame`, `table`).
        origin: String,
        /// 0-based row index.
        row: u64,
        /// What is wrong, naming the column.
        message: String,
    },
    /// Robot description or kinematics.
    #[error(transparent)]
    Model(#[from] deflex_model::ModelError),
    /// Measurement file: loaded displacements, a plan, absolute readings.
    #[error(transparent)]
    Data(#[from] deflex_calibrate::measurements::DataError),
    /// Stiffness identification or validation.
    #[error(transparent)]
    Calib(#[from] deflex_calibrate::stiffness::CalibError),
    /// A stiffness calibration that identified nothing (the CLI's refusal).
    #[error(
        "{data}: no eDoF could be identified from this data (every compliance is at its bound or not observable); nothing written"
    )]
    NothingIdentified {
        /// The data, as named to the user.
        data: String,
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
    /// A points file (the points a measurement plan measures) that cannot be used.
    #[error(transparent)]
    Points(#[from] deflex_calibrate::measurements::points::PointsError),
    /// An error about a given input (a file, or a front end's option and its value), named
    /// first.
    #[error("{context}: {source}")]
    In {
        /// The input (`--data m.csv`, `--points`).
        context: String,
        /// What went wrong with it.
        source: Box<Error>,
    },
    /// Elasto-geometric campaign.
    #[error(transparent)]
    Campaign(#[from] deflex_calibrate::geometry::campaign::CampaignError),
    /// Elasto-geometric fit.
    #[error(transparent)]
    Fit(#[from] deflex_calibrate::geometry::fit::FitError),
    /// Elasto-geometric prediction.
    #[error(transparent)]
    Predict(#[from] deflex_calibrate::geometry::predict::PredictError),
    /// UR10 tracker data import.
    #[error(transparent)]
    Import(#[from] deflex_calibrate::geometry::ur10_tracker::ImportError),
    /// A report (page, plots, tables) that could not be written.
    #[cfg(feature = "report")]
    #[error(transparent)]
    Report(#[from] crate::report::PageError),
    /// A set-up registration.
    #[error(transparent)]
    Register(#[from] deflex_calibrate::geometry::register::RegisterError),
    /// Readings that do not say which set-up or target to register.
    #[error(transparent)]
    RegisterInput(#[from] crate::calibrate_geometry::RegisterInputError),
    /// A model step or loss not known (`--steps`, `--loss`; `steps=`, `loss=`).
    #[error("{option}: {source}")]
    Choice {
        /// The option, as the front end names it.
        option: String,
        /// What is wrong with its value.
        source: deflex_calibrate::geometry::fit::ChoiceError,
    },
    /// A fit whose readings the calibrated robot still misses by centimetres: another robot's
    /// data. Nothing is written.
    #[error(
        "{files}: robot \"{robot}\" leaves the fitted readings {rms_mm:.1} mm RMS from its prediction after calibration (more than {limit_mm:.0} mm): these are not this robot's readings (another robot's data? give it with {robot_option}); nothing written"
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
        /// How to give the robot (`--robot`, `robot=`).
        robot_option: String,
    },
    /// A fit that moves the robot's geometry further than a calibration does (bounds of
    /// [`deflex_calibrate::geometry::plausible`]): another robot's or another target's readings.
    #[error(
        "{files}: the fit reshapes robot \"{robot}\" beyond what a calibration changes ({count} parameter(s): {changes}): these readings look like another robot or another target (check {} and the targets); a robot file that is only a rough first guess is allowed with {}; nothing written",
        .names.give("robot"),
        .names.switch("allow_large_changes")
    )]
    LargeChanges {
        /// The data files.
        files: String,
        /// The robot given.
        robot: String,
        /// How many parameters exceed their bound.
        count: usize,
        /// The largest ones, with their changes and bounds (`J2.d +925 mm (bound ±44 mm)`).
        changes: String,
        /// The front end's words for the robot (`--robot`, `robot=`) and the switch that allows
        /// the changes (`--allow-large-changes`, `allow_large_changes=True`).
        names: crate::OptionNames,
    },
    /// A registration that moves a known set-up beyond the arm's working volume or puts a
    /// target further from the flange than a probe sits
    /// ([`deflex_calibrate::geometry::plausible::large_registration_moves`]).
    #[error(
        "{data}: the registration puts {changes}: these readings look like another robot, another target or another set-up's; a deliberate move is allowed with {}; nothing written",
        .names.switch("allow_large_changes")
    )]
    LargeRegistration {
        /// The data.
        data: String,
        /// What moved, by how much, and the bound (`setup[A] moved +2400 mm (bound ±1543 mm)`).
        changes: String,
        /// The front end's words for the switch that allows it (`--allow-large-changes`,
        /// `allow_large_changes=True`).
        names: crate::OptionNames,
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
    /// A label the tracker import would not read back the same.
    #[error(
        "{option} \"{label}\": {problem}; import refuses it (labels are not rewritten): give a label of 1 to {max_bytes} bytes without control characters, outer white space or a leading `#`"
    )]
    ImportLabel {
        /// The option (`--setup` or `--target`; `setup`, `target`).
        option: String,
        /// The label, shown with its control characters escaped.
        label: String,
        /// What is wrong with it.
        problem: deflex_calibrate::geometry::data::LabelProblem,
        /// Longest label accepted (bytes).
        max_bytes: usize,
    },
    /// A tracker series folder without exactly one measurement file.
    #[error("{folder}: expected one measurements_*.csv, found {found}")]
    SeriesFiles {
        /// The folder.
        folder: String,
        /// Measurement files found.
        found: usize,
    },
    /// An input file that cannot be read (special file, too large, not UTF-8, …).
    #[error(transparent)]
    Input(#[from] deflex_files::InputError),
    /// An output that could not be put into its format (a table or JSON text).
    #[error("{what} could not be written: {reason}")]
    Serialise {
        /// The output (`the prediction CSV`).
        what: &'static str,
        /// Why.
        reason: String,
    },
    /// A calibration's terms file that cannot be used.
    #[error("{path}: {source}")]
    Terms {
        /// The terms file.
        path: String,
        /// Why.
        source: deflex_calibrate::geometry::terms::TermsError,
    },
    /// A file larger than its reader accepts (`PATH: more than the N bytes a table may have
    /// …`).
    #[error(transparent)]
    TooLarge(#[from] deflex_files::FileTooLarge),
    /// Offline compensation.
    #[error(transparent)]
    Compensate(#[from] deflex_compensate::CompensateError),
    /// A log used as a wrench source: its rows.
    #[error(transparent)]
    WrenchLog(#[from] crate::load::WrenchLogError),
    /// A log used as a wrench source: its coverage of the path.
    #[error(transparent)]
    Log(#[from] deflex_compensate::LogError),
    /// A tool path.
    #[error(transparent)]
    Path(#[from] deflex_compensate::PathError),
    /// A robot (built-in name or file) named by a front end's option that cannot be read.
    #[error("{flag} {spec}: {source}")]
    RobotSpec {
        /// The option (`--robot`, `--nominal`).
        flag: &'static str,
        /// As given.
        spec: String,
        /// Why.
        source: deflex_model::ModelError,
    },
    /// The robot's twin cell (or the twin file over it) for a compensation.
    #[error("the twin cell of {robot}: {source}")]
    TwinCellOf {
        /// The robot, as given.
        robot: String,
        /// Why.
        source: Box<crate::cell::twin_cell_file::TwinCellFileError>,
    },
    /// A tool path (built-in or G-code file) that cannot be read or placed.
    #[error("{flag} {spec}: {source}")]
    PathSpec {
        /// The option (`--path`, `path`).
        flag: String,
        /// As given.
        spec: String,
        /// Why.
        source: Box<deflex_sim::SimError>,
    },
    /// The seed configuration holds the tool off the path's tool axis.
    #[error(
        "the seed configuration ({seed}) deg holds the tool {angle_deg:.1}° off the path's tool axis (−Z of the part frame{frame}): the programs would tilt the tool. Give {seed_flag} with the tool pointing along it (within {}°); the cell's seed is printed by `deflex sim robot --robot {robot}`",
        crate::compensate::MAX_TOOL_AXIS_DEG
    )]
    ToolAxis {
        /// The seed (deg, comma-separated).
        seed: String,
        /// The angle (deg).
        angle_deg: f64,
        /// ` G54` when named.
        frame: String,
        /// The seed's option (`--seed-deg`, `seed_q`).
        seed_flag: String,
        /// The robot, as given.
        robot: String,
    },
    /// Path points beyond the arm's reach.
    #[error(
        "{count} of {points} path points lie beyond the arm's reach ({reach_mm:.0} mm from joint 1), the first point {first} at {distance_mm:.1} mm, with the part frame at ({x:.1}, {y:.1}, {z:.1}) mm: move the part with {part_flag} x,y,z (deflex sim robot --robot R prints the robot's cell)"
    )]
    OutOfReach {
        /// Points out of reach.
        count: usize,
        /// Path points.
        points: usize,
        /// The first.
        first: usize,
        /// Its distance (mm).
        distance_mm: f64,
        /// The reach (mm).
        reach_mm: f64,
        /// Part origin (mm).
        x: f64,
        /// Part origin (mm).
        y: f64,
        /// Part origin (mm).
        z: f64,
        /// The part origin's option (`--part-xyz-mm`, `part_xyz_m`).
        part_flag: String,
    },
    /// The twin's process model cannot be built.
    #[error("the twin's process model: {0}")]
    ProcessModel(deflex_sim::SimError),
    /// Points could not be compensated: no program (the CLI still writes the table and the
    /// summaries).
    #[error(
        "{count} of {points} points cannot be compensated (status column of compensated_path.csv); no robot program written:\n{list}\n{hint}"
    )]
    PointsNotCompensated {
        /// How many.
        count: usize,
        /// Path points.
        points: usize,
        /// The first ones, one per line.
        list: String,
        /// What to try.
        hint: String,
    },
    /// The compensation did not converge: no program (the CLI still writes the table and the
    /// summaries).
    #[error(
        "the compensation did not converge in {iterations} iterations (last change {change_mm:.4} mm, {change_mrad:.4} mrad, tolerance {tolerance_mm:.4} mm); no robot program written"
    )]
    NotConverged {
        /// Iterations run.
        iterations: usize,
        /// Last change (mm).
        change_mm: f64,
        /// Last change (mrad).
        change_mrad: f64,
        /// The tolerance (mm).
        tolerance_mm: f64,
    },
    /// A program's clearance point that the arm does not reach.
    #[error(
        "the clearance point above the {which} of the path is not reachable ({source}): lower program.clearance_mm in {} or move the part with {}",
        .names.name("settings"),
        .names.name("part_xyz_m")
    )]
    Clearance {
        /// `start` or `end`.
        which: &'static str,
        /// The front end's words for the template's option (`--program-config`, `settings`)
        /// and the part origin's (`--part-xyz-mm`, `part_xyz_m`).
        names: crate::OptionNames,
        /// Why.
        source: deflex_model::ModelError,
    },
    /// A program read back differs from the path (a bug: nothing is written then).
    #[error("{format}: read back {what}")]
    Readback {
        /// The format.
        format: &'static str,
        /// What differs.
        what: String,
    },
    /// A calibrated robot that a format cannot hold, or whose file did not read back.
    #[error(transparent)]
    Export(#[from] deflex_cam::export::ExportError),
    /// An exported URDF that does not load.
    #[error("the written URDF does not read back: {0}")]
    UrdfReadback(deflex_model::ModelError),
    /// An exported file whose kinematics differ from the model's.
    #[error(
        "{format}: the file read back is {error_m:.3e} m from the model (bound 1e-6 m); nothing written"
    )]
    ExportMismatch {
        /// The format.
        format: &'static str,
        /// Largest TCP position difference (m).
        error_m: f64,
    },
    /// Robot programs.
    #[error(transparent)]
    Program(#[from] deflex_cam::program::ProgramError),
    /// The digital twin.
    #[error(transparent)]
    Sim(#[from] deflex_sim::SimError),
    /// The twin's cell file.
    #[error(transparent)]
    Cell(#[from] crate::cell::twin_cell_file::TwinCellFileError),
    /// A cell file (`CELL.toml`) that cannot be read or used.
    #[error(transparent)]
    CellFile(Box<crate::cell::config::ConfigError>),
    /// An output a `CELL.toml` names (`[log] path`) that deflex may not replace, named with the
    /// file.
    #[error("{origin}: {source}")]
    CellOutput {
        /// The `CELL.toml`, as shown.
        origin: String,
        /// Why the output is refused.
        source: deflex_files::OutputError,
    },
    /// A `deflex run` session that could not start (model, feed-forward, links, log, threads).
    #[error(transparent)]
    CellStart(Box<crate::cell::cell_run::StartError>),
    /// The run log's writer thread failed.
    #[error("log writer: {0}")]
    LogWriter(std::io::Error),
    /// The MCAP recording of a session could not be started.
    #[error(transparent)]
    Record(#[from] deflex_record::RecordError),
    /// The ends of the simulated cell could not be made from a `CELL.toml`.
    #[error(transparent)]
    CellSides(#[from] crate::cell::links::CellSidesError),
    /// The simulated cell could not serve its session.
    #[error(transparent)]
    CellServe(Box<deflex_sim::twin::cell_server::CellServeError>),
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
    /// The twin with the correction controller (closed loop).
    #[error(transparent)]
    Twin(#[from] deflex_sim::twin::TwinError),
    /// A twin workflow that could not be set up (the correction's model, the identification
    /// from the twin's campaign).
    #[error(transparent)]
    TwinSetup(#[from] crate::twin::TwinSetupError),
    /// Options of a forming run on the twin that do not go together, named in the words of the
    /// front end.
    #[error("{}", .conflict.describe(*.names))]
    FormConflict {
        /// Which options.
        conflict: crate::twin::FormConflict,
        /// The front end's words.
        names: crate::OptionNames,
    },
    /// The paper's study on the twin (`deflex demo`), or a part of it.
    #[error(transparent)]
    Demo(#[from] crate::study::DemoError),
    /// A deflection map none of whose nodes the arm reaches: nothing written.
    #[error("no grid node is reachable; check --plane, --center and --size")]
    NoReachableNode,
    /// A run log or recording that cannot be read for its plots.
    #[error(transparent)]
    Trace(#[from] deflex_record::trace::TraceError),
    /// A plot or page that could not be drawn or written (the file named first).
    #[cfg(feature = "report")]
    #[error(transparent)]
    Plot(#[from] crate::report::DrawError),
    /// A report or figure asked of a build without them (deflex-app's `report` feature, off):
    /// refused before anything is computed or written ([`crate::report::require`]).
    #[error(
        "{what} needs deflex built with reports (the `report` feature of deflex-app, on in the command line and in the Python package as pip builds it); nothing written"
    )]
    ReportsNotBuilt {
        /// What was asked for, as the front ends name it.
        what: &'static str,
    },
    /// A file (or folder) that could not be written, or read where no input error says more
    /// (`PATH: ERROR`).
    #[error(transparent)]
    Io(#[from] deflex_files::FileIoError),
    /// A CSV table (log) that cannot be read.
    #[error("{origin}:{line}: {message}")]
    Table {
        /// File or origin.
        origin: String,
        /// 1-based line.
        line: u64,
        /// What is wrong.
        message: String,
    },
    /// A panic caught at the boundary: a bug in deflex.
    #[error("internal error (a bug in deflex; please report it with the call that caused it): {0}")]
    Panic(String),
}

impl Error {
    /// The Python exception class this error becomes.
    pub fn kind(&self) -> ErrorKind {
        match self {
            Error::Shape { .. } | Error::NonFinite { .. } | Error::Invalid { .. } => {
                ErrorKind::Input
            }
            Error::Model(_) => ErrorKind::Model,
            Error::Data(_)
            | Error::TableRow { .. }
            | Error::Import(_)
            | Error::Log(_)
            | Error::WrenchLog(_)
            | Error::Table { .. }
            | Error::TooLarge(_)
            | Error::Points(_)
            | Error::SeriesFiles { .. }
            | Error::Input(_) => ErrorKind::Data,
            Error::RegisterInput(_) | Error::Choice { .. } | Error::ImportLabel { .. } => {
                ErrorKind::Input
            }
            Error::Calib(_)
            | Error::NothingIdentified { .. }
            | Error::CouplingNotInStructure { .. }
            | Error::Campaign(_)
            | Error::Fit(_)
            | Error::Predict(_)
            | Error::Register(_)
            | Error::ImplausibleFit { .. }
            | Error::LargeChanges { .. }
            | Error::LargeRegistration { .. }
            | Error::TooFewReadings { .. }
            | Error::Terms { .. } => ErrorKind::Calibration,
            Error::Compensate(_) | Error::Path(_) => ErrorKind::Compensation,
            Error::RobotSpec { .. }
            | Error::Export(_)
            | Error::UrdfReadback(_)
            | Error::ExportMismatch { .. } => ErrorKind::Model,
            Error::TwinCellOf { .. } => ErrorKind::Data,
            Error::PathSpec { .. } | Error::ProcessModel(_) => ErrorKind::Simulation,
            Error::ToolAxis { .. } => ErrorKind::Input,
            Error::OutOfReach { .. }
            | Error::PointsNotCompensated { .. }
            | Error::NotConverged { .. } => ErrorKind::Compensation,
            Error::Clearance { .. } | Error::Readback { .. } => ErrorKind::Program,
            Error::Program(_) => ErrorKind::Program,
            Error::Sim(_) | Error::Twin(_) | Error::TwinSetup(_) | Error::Demo(_) => {
                ErrorKind::Simulation
            }
            Error::NoReachableNode => ErrorKind::Model,
            Error::FormConflict { .. } => ErrorKind::Input,
            Error::Trace(_) => ErrorKind::Data,
            #[cfg(feature = "report")]
            Error::Plot(_) => ErrorKind::Io,
            Error::ReportsNotBuilt { .. } => ErrorKind::Input,
            Error::Cell(_) => ErrorKind::Data,
            Error::CellFile(_) => ErrorKind::Data,
            Error::CellOutput { .. }
            | Error::CellStart(_)
            | Error::LogWriter(_)
            | Error::Record(_) => ErrorKind::Io,
            Error::CellSides(_) | Error::CellServe(_) | Error::SimCellNeedsNetFt { .. } => {
                ErrorKind::Simulation
            }
            Error::Io(_) | Error::Serialise { .. } => ErrorKind::Io,
            #[cfg(feature = "report")]
            Error::Report(_) => ErrorKind::Io,
            Error::Panic(_) => ErrorKind::Internal,
            Error::In { source, .. } => source.kind(),
        }
    }

    /// An error about `context` (a file, or an option and its value), named first.
    pub fn in_context(context: impl Into<String>) -> impl FnOnce(Error) -> Error {
        let context = context.into();
        move |source| Error::In {
            context,
            source: Box::new(source),
        }
    }

    /// An I/O failure on `path` (writing it, or reading where no input error says more), as a
    /// `map_err` argument: `.map_err(Error::io_on(path))`.
    pub fn io_on(path: &std::path::Path) -> impl Fn(std::io::Error) -> Error + Copy + '_ {
        move |source| Error::Io(deflex_files::FileIoError::new(path, source))
    }

    /// An invalid option value.
    pub fn invalid(name: impl Into<String>, message: impl Into<String>) -> Error {
        Error::Invalid {
            name: name.into(),
            message: message.into(),
        }
    }
}

impl From<crate::cell::config::ConfigError> for Error {
    fn from(error: crate::cell::config::ConfigError) -> Self {
        Error::CellFile(Box::new(error))
    }
}

impl From<crate::cell::cell_run::StartError> for Error {
    fn from(error: crate::cell::cell_run::StartError) -> Self {
        Error::CellStart(Box::new(error))
    }
}

impl From<deflex_sim::twin::cell_server::CellServeError> for Error {
    fn from(error: deflex_sim::twin::cell_server::CellServeError) -> Self {
        Error::CellServe(Box::new(error))
    }
}

/// Result of the engine layer.
pub type Result<T, E = Error> = std::result::Result<T, E>;

/// Run `f`, turning a panic into [`Error::Panic`]: no panic crosses into Python.
pub fn guard<T>(f: impl FnOnce() -> Result<T>) -> Result<T> {
    match std::panic::catch_unwind(std::panic::AssertUnwindSafe(f)) {
        Ok(result) => result,
        Err(payload) => {
            let text = payload
                .downcast_ref::<&str>()
                .map(|s| s.to_string())
                .or_else(|| payload.downcast_ref::<String>().cloned())
                .unwrap_or_else(|| "a panic without a message".into());
            Err(Error::Panic(text))
        }
    }
}

/// A number within `[lo, hi]` (NaN and infinities refused), or the CLI's message naming the
/// option (`check_flag` of the CLI, with the Python keyword).
pub fn bounded(name: &str, value: f64, lo: f64, hi: f64, unit: &str) -> Result<f64> {
    if value >= lo && value <= hi {
        Ok(value)
    } else {
        Err(Error::invalid(name, out_of_range(value, lo, hi, unit)))
    }
}

/// What a number outside `[lo, hi]` is told, after the option's name: `expected a number from
/// LO to HI UNIT, got VALUE` (the numbers [`compact`]; no unit when `unit` is empty). The CLI's
/// range errors say the same.
pub fn out_of_range(value: f64, lo: f64, hi: f64, unit: &str) -> String {
    let unit = if unit.is_empty() {
        String::new()
    } else {
        format!(" {unit}")
    };
    format!(
        "expected a number from {} to {}{unit}, got {}",
        compact(lo),
        compact(hi),
        compact(value)
    )
}

/// A number for a message: plain when readable, in exponent form when very large or small.
pub fn compact(value: f64) -> String {
    let magnitude = value.abs();
    if value.is_finite() && value != 0.0 && !(1e-3..1e6).contains(&magnitude) {
        format!("{value:e}")
    } else {
        format!("{value}")
    }
}
