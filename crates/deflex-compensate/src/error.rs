//! Errors of the compensation crate. Points that cannot be compensated are *not* errors: they are
//! reported per point ([`crate::PointFailure`]); these are the failures of a whole run.

use thiserror::Error;

/// A tool path that cannot be used.
#[derive(Debug, Error, PartialEq)]
pub enum PathError {
    /// Fewer than two points.
    #[error("path \"{name}\": {points} point(s); at least 2 are needed")]
    TooFewPoints {
        /// Path name.
        name: String,
        /// Points given.
        points: usize,
    },
    /// More points than [`crate::MAX_PATH_POINTS`].
    #[error("path \"{name}\": more than {max} points")]
    TooManyPoints {
        /// Path name.
        name: String,
        /// The bound.
        max: usize,
    },
    /// A position is not finite or farther than [`crate::path::MAX_COORDINATE_M`] from the origin.
    #[error("path \"{name}\": point {index}: {field} = {value} is not finite or beyond ±{limit} m")]
    BadPosition {
        /// Path name.
        name: String,
        /// Point index (0-based).
        index: usize,
        /// `x_m`, `y_m` or `z_m`.
        field: &'static str,
        /// The value.
        value: f64,
        /// The bound (m).
        limit: f64,
    },
    /// A rotation is not a rotation (non-finite or not orthonormal).
    #[error("path \"{name}\": point {index}: the orientation is not a rotation matrix")]
    BadRotation {
        /// Path name.
        name: String,
        /// Point index.
        index: usize,
    },
    /// A feed rate is not a positive finite speed of at most 10 m/s.
    #[error("path \"{name}\": point {index}: feed {value} m/s is not within (0, 10]")]
    BadFeed {
        /// Path name.
        name: String,
        /// Point index.
        index: usize,
        /// The value (m/s).
        value: f64,
    },
}

/// A process model could not produce a wrench.
#[derive(Debug, Error, PartialEq)]
#[error("process model \"{model}\" at point {index}: {message}")]
pub struct ProcessError {
    /// The model's name.
    pub model: String,
    /// Path point (0-based).
    pub index: usize,
    /// What went wrong.
    pub message: String,
}

/// Something that stops a compensation run.
#[derive(Debug, Error)]
pub enum CompensateError {
    /// The path.
    #[error(transparent)]
    Path(#[from] PathError),
    /// The process model.
    #[error(transparent)]
    Process(#[from] ProcessError),
    /// An option is out of its range.
    #[error("compensation option {option}: {message}")]
    Option {
        /// The option's field name.
        option: &'static str,
        /// What was expected.
        message: String,
    },
    /// The seed has the wrong number of joints or the first point cannot be reached from it.
    #[error("start of the path: {0}")]
    Start(#[from] deflex_model::ModelError),
    /// Fixed wrenches do not match the path.
    #[error("{got} wrenches for a path of {expected} points")]
    WrenchCount {
        /// Path points.
        expected: usize,
        /// Wrenches given.
        got: usize,
    },
    /// A fixed wrench is not finite.
    #[error("wrench of point {index} is not finite")]
    BadWrench {
        /// Point index.
        index: usize,
    },
}

/// A log that cannot serve as the wrench source of a path (reading the log is the caller's:
/// its errors are the log reader's).
#[derive(Debug, Error, PartialEq)]
pub enum LogError {
    /// No usable row lies near the path.
    #[error("{file}: none of the {rows} usable rows lies within {max_offset_mm} mm of the path")]
    NoRowNearPath {
        /// The file.
        file: String,
        /// Usable rows.
        rows: usize,
        /// The distance bound (mm).
        max_offset_mm: f64,
    },
    /// The log covers only part of the path.
    #[error(
        "{file}: the log covers arc length {from_mm:.1} … {to_mm:.1} mm of the path's {length_mm:.1} mm; points {first_uncovered}… have no force"
    )]
    PartialCoverage {
        /// The file.
        file: String,
        /// First covered arc length (mm).
        from_mm: f64,
        /// Last covered arc length (mm).
        to_mm: f64,
        /// Path length (mm).
        length_mm: f64,
        /// First path point outside the coverage.
        first_uncovered: usize,
    },
}
