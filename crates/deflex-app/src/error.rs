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
    #[error(transparent)]
    Report(#[from] crate::report::PageError),
    /// A set-up registration.
    #[error(transparent)]
    Register(#[from] deflex_calibrate::geometry::register::RegisterError),
    /// A calibration's terms file that cannot be used.
    #[error("{path}: {source}")]
    Terms {
        /// The terms file.
        path: String,
        /// Why.
        source: deflex_calibrate::geometry::terms::TermsError,
    },
    /// An input file (or folder) that cannot be read.
    #[error("{path}: {source}")]
    Read {
        /// The file.
        path: String,
        /// The cause.
        source: std::io::Error,
    },
    /// A file larger than deflex reads.
    #[error("{path}: {bytes} bytes is more than the {limit} bytes read")]
    TooLarge {
        /// The file.
        path: String,
        /// Its size.
        bytes: u64,
        /// The limit.
        limit: u64,
    },
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
    /// Points not compensated or an iteration that did not converge (the CLI's refusal).
    #[error("{message}")]
    NotCompensated {
        /// The CLI's text (points and reasons).
        message: String,
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
    /// The twin with the correction controller (closed loop).
    #[error(transparent)]
    Twin(#[from] deflex_sim::twin::TwinError),
    /// A file that could not be read or written.
    #[error("{path}: {source}")]
    Io {
        /// The file.
        path: String,
        /// The cause.
        source: std::io::Error,
    },
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
            | Error::Read { .. }
            | Error::TooLarge { .. } => ErrorKind::Data,
            Error::Calib(_)
            | Error::NothingIdentified { .. }
            | Error::Campaign(_)
            | Error::Fit(_)
            | Error::Predict(_)
            | Error::Register(_)
            | Error::Terms { .. } => ErrorKind::Calibration,
            Error::Compensate(_) | Error::Path(_) | Error::NotCompensated { .. } => {
                ErrorKind::Compensation
            }
            Error::Program(_) => ErrorKind::Program,
            Error::Sim(_) | Error::Twin(_) => ErrorKind::Simulation,
            Error::Cell(_) => ErrorKind::Data,
            Error::Io { .. } | Error::Report(_) => ErrorKind::Io,
            Error::Panic(_) => ErrorKind::Internal,
        }
    }

    /// An invalid option value.
    pub fn invalid(name: impl Into<String>, message: impl Into<String>) -> Error {
        Error::Invalid {
            name: name.into(),
            message: message.into(),
        }
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
        let unit = if unit.is_empty() {
            String::new()
        } else {
            format!(" {unit}")
        };
        Err(Error::invalid(
            name,
            format!(
                "expected a number from {} to {}{unit}, got {}",
                compact(lo),
                compact(hi),
                compact(value)
            ),
        ))
    }
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
