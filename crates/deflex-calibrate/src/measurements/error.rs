//! What can be wrong with a measurement file of any format of this crate (loaded
//! displacements, plans, absolute tracker readings), with the values that explain it: one error
//! type, [`DataError`], whose messages name the file, the line and the column.

use deflex_files::{FileIoError, FileTooLarge};
use thiserror::Error;

/// A bad measurement file (loaded displacements, a plan, absolute tracker readings). Nothing of a
/// file with an error is used.
#[derive(Debug, Error)]
pub enum DataError {
    /// The file could not be read or written (built by the crates that touch the disk).
    #[error(transparent)]
    Io(#[from] FileIoError),
    /// The file is larger than a measurement file may be
    /// ([`crate::measurements::MAX_FILE_BYTES`]; the reader names it `a measurement file`).
    #[error(transparent)]
    TooLarge(#[from] FileTooLarge),
    /// The file was written for a robot with another number of joints
    /// ([`crate::measurements::check_joint_columns`], before the file is read).
    #[error(
        "{path}: the data has {found} joint columns (q1_rad…q{found}_rad) but the robot has {expected} joints"
    )]
    JointColumns {
        /// File.
        path: String,
        /// Joint columns in the file.
        found: usize,
        /// Joints of the robot.
        expected: usize,
    },
    /// A problem with the header (the column names).
    #[error("{path}: header: {problem}")]
    Header {
        /// File.
        path: String,
        /// What is wrong.
        problem: HeaderProblem,
    },
    /// A problem with one row.
    #[error("{path}:{line}: {error}")]
    Row {
        /// File.
        path: String,
        /// 1-based line number in the file.
        line: u64,
        /// What is wrong, and in which column.
        error: RowError,
    },
    /// More rows than the format reads ([`crate::measurements::reader::RowLimit::PerFile`]).
    #[error("{path}: more than {limit} rows")]
    TooManyRows {
        /// File.
        path: String,
        /// The bound.
        limit: usize,
    },
    /// Two rows of one load case hold different joint configurations (rows with the same
    /// `load_case` share configuration and load: the calibration groups them as one loading).
    #[error("{path}: {conflict}")]
    LoadCaseConfigurations {
        /// File.
        path: String,
        /// The load case and the two rows (boxed: every error of the workspace carries this
        /// type, so its size stays that of its common variants).
        conflict: Box<LoadCaseConflict>,
    },
    /// The file has a header but no data row.
    #[error("{path}: no data rows")]
    NoRows {
        /// File.
        path: String,
    },
}

/// Two rows of one load case with different joint values.
#[derive(Debug, Clone, PartialEq, Error)]
#[error(
    "load case `{load_case}` holds two joint configurations: line {first_line} has q{joint}_rad = {first_value}, line {line} has {value}; give each configuration its own load case"
)]
pub struct LoadCaseConflict {
    /// The load case.
    pub load_case: String,
    /// Line of the load case's first row.
    pub first_line: u64,
    /// Line of the row that differs.
    pub line: u64,
    /// The first joint (1-based) whose value differs.
    pub joint: usize,
    /// Its value on the first row (rad).
    pub first_value: f64,
    /// Its value on the differing row (rad).
    pub value: f64,
}

/// What is wrong with a file's column names.
#[derive(Debug, Error)]
pub enum HeaderProblem {
    /// The CSV reader could not read the header line.
    #[error("{0}")]
    Csv(#[source] csv::Error),
    /// A column name appears twice.
    #[error("column `{name}` appears twice")]
    Duplicate {
        /// The column.
        name: String,
    },
    /// A column the format does not have (a typo such as `sigma_mm` would otherwise be
    /// ignored and its values replaced by the default).
    #[error("unknown column `{name}`{}; a column kept on purpose must be named as ignored (`deflex … --ignore-column {name}`)", closest.as_ref().map(|c| format!(" (did you mean `{c}`?)")).unwrap_or_default())]
    Unknown {
        /// The column.
        name: String,
        /// The closest column of the format.
        closest: Option<String>,
    },
    /// A column asked to be ignored is one the format reads: ignoring it would change what the
    /// file means (drop the column from the file instead).
    #[error(
        "column `{name}` is read by the format and cannot be ignored (only columns the format does not know can be)"
    )]
    IgnoredKnown {
        /// The column.
        name: String,
    },
    /// No `q1_rad` column.
    #[error("no joint columns: expected q1_rad, q2_rad, …")]
    NoJointColumns,
    /// The `q1_rad…` columns do not match the robot the file is read for.
    #[error("the file has {found} joint columns (q1_rad…) but the robot has {expected} joints")]
    JointColumns {
        /// `q{i}_rad` columns found (consecutive from 1).
        found: usize,
        /// Robot joints.
        expected: usize,
    },
    /// Required columns are missing.
    #[error("missing column(s) {}", quoted(names))]
    Missing {
        /// The missing columns, in the order of the format.
        names: Vec<String>,
    },
    /// Some but not all columns of a group that goes together.
    #[error("columns {} go together: give all or none", .names.join(", "))]
    PartialGroup {
        /// The columns of the group.
        names: Vec<String>,
    },
}

fn quoted(names: &[String]) -> String {
    names
        .iter()
        .map(|s| format!("`{s}`"))
        .collect::<Vec<_>>()
        .join(", ")
}

/// What is wrong with a row, and the column it is in.
#[derive(Debug, Error)]
#[error("{}{problem}", column.as_ref().map(|c| format!("column `{c}`: ")).unwrap_or_default())]
pub struct RowError {
    /// The column; none (or `-`, for absolute readings) when the problem is the record as a
    /// whole.
    pub column: Option<String>,
    /// What is wrong.
    pub problem: RowProblem,
}

impl RowError {
    /// A problem of the cell in `column`.
    pub fn in_column(column: &str, problem: RowProblem) -> RowError {
        RowError {
            column: Some(column.to_string()),
            problem,
        }
    }
}

/// What is wrong with one row of a file (the column is named by [`RowError`]).
#[derive(Debug, Error)]
pub enum RowProblem {
    /// The CSV reader could not read the line (e.g. an unterminated quote).
    #[error("{0}")]
    Csv(#[source] csv::Error),
    /// The row has another number of fields than the header.
    #[error("expected {expected} fields as in the header, found {found}")]
    FieldCount {
        /// Fields of the header.
        expected: usize,
        /// Fields of the row.
        found: usize,
    },
    /// The file has more rows than a calibration may use
    /// ([`crate::measurements::reader::RowLimit::PerLine`]).
    #[error("more than {max} data rows: split the campaign")]
    TooManyRows {
        /// The limit ([`crate::measurements::MAX_ROWS`]).
        max: usize,
    },
    /// A numeric cell is not a number; the unit is named when the format's messages state it
    /// ([`crate::measurements::reader::Cells::number_in`]).
    #[error("expected a number{}, got \"{text}\"", unit.map(|u| format!(" in {u}")).unwrap_or_default())]
    NotANumber {
        /// The cell (at most 40 characters of it, except where the unit is named).
        text: String,
        /// The unit expected, when named.
        unit: Option<&'static str>,
    },
    /// A numeric cell is NaN or infinite ([`crate::measurements::reader::Cells::number`]).
    #[error("value must be finite, got {text}")]
    NotFinite {
        /// The cell (at most 40 characters of it).
        text: String,
    },
    /// A numeric cell is beyond the physical bound of its column
    /// ([`crate::measurements::reader::Cells::number`]).
    #[error("{value:e} {unit} is beyond the ±{limit:e} {unit} a file may hold")]
    BeyondBound {
        /// The value.
        value: f64,
        /// The bound on its magnitude.
        limit: f64,
        /// Its unit.
        unit: &'static str,
    },
    /// A numeric cell that is NaN, infinite or beyond its bound, told as the range expected
    /// ([`crate::measurements::reader::Cells::number_in`]).
    #[error("expected a finite value within ±{limit} {unit}, got {text}")]
    OutOfRange {
        /// The cell.
        text: String,
        /// The bound.
        limit: f64,
        /// Unit.
        unit: &'static str,
    },
    /// A link cell is not a link index.
    #[error("expected a link index 0..={joint_count}, got \"{text}\"")]
    NotALink {
        /// The cell.
        text: String,
        /// Joints of the file (the last link's index).
        joint_count: usize,
    },
    /// A link index beyond the last link.
    #[error("link {link} does not exist (0 = base … {joint_count} = last link)")]
    NoSuchLink {
        /// The index given.
        link: usize,
        /// Joints of the file (the last link's index).
        joint_count: usize,
    },
    /// An empty label.
    #[error("empty label")]
    EmptyLabel,
    /// A label longer than its format allows.
    #[error("{max}")]
    LabelTooLong {
        /// The limit, in characters or bytes.
        max: LabelLength,
    },
    /// A standard deviation outside its range.
    #[error("must be positive, from {:e} to {} {}, got {value}", .sigma.min(), .sigma.max(), .sigma.unit())]
    Sigma {
        /// Which standard deviation.
        sigma: SigmaColumn,
        /// The value.
        value: f64,
    },
    /// A standard deviation that is zero or negative.
    #[error("must be positive, got {0}")]
    NotPositive(f64),
    /// A negative payload.
    #[error("must not be negative, got {0}")]
    Negative(f64),
    /// A temperature outside its range
    /// ([`crate::geometry::data::limits::TEMPERATURE_RANGE_C`]).
    #[error("expected {}…{} °C, got {value}", .range[0], .range[1])]
    Temperature {
        /// Value.
        value: f64,
        /// Range accepted.
        range: [f64; 2],
    },
}

/// The longest label a format reads, and how it is measured.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Error)]
pub enum LabelLength {
    /// At most this many characters (measurement and plan files).
    #[error("a label of more than {0} characters")]
    Characters(usize),
    /// At most this many UTF-8 bytes (absolute readings).
    #[error("label longer than {0} bytes")]
    Bytes(usize),
}

impl LabelLength {
    /// Whether `text` is longer than the limit.
    pub fn exceeded_by(self, text: &str) -> bool {
        match self {
            LabelLength::Characters(max) => text.chars().count() > max,
            LabelLength::Bytes(max) => text.len() > max,
        }
    }
}

/// The two standard-deviation columns, with their ranges.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum SigmaColumn {
    /// `sigma_m`: [`crate::measurements::MIN_SIGMA_M`] to [`crate::measurements::MAX_SIGMA_M`].
    Position,
    /// `sigma_rad`: [`crate::measurements::MIN_SIGMA_RAD`] to [`crate::measurements::MAX_SIGMA_RAD`].
    Rotation,
}

impl SigmaColumn {
    /// The column name.
    pub fn column(self) -> &'static str {
        match self {
            SigmaColumn::Position => "sigma_m",
            SigmaColumn::Rotation => "sigma_rad",
        }
    }

    /// Smallest value allowed.
    pub fn min(self) -> f64 {
        match self {
            SigmaColumn::Position => crate::measurements::MIN_SIGMA_M,
            SigmaColumn::Rotation => crate::measurements::MIN_SIGMA_RAD,
        }
    }

    /// Largest value allowed.
    pub fn max(self) -> f64 {
        match self {
            SigmaColumn::Position => crate::measurements::MAX_SIGMA_M,
            SigmaColumn::Rotation => crate::measurements::MAX_SIGMA_RAD,
        }
    }

    /// Unit.
    pub fn unit(self) -> &'static str {
        match self {
            SigmaColumn::Position => "m",
            SigmaColumn::Rotation => "rad",
        }
    }

    /// Whether `value` is within the range.
    pub fn accepts(self, value: f64) -> bool {
        (self.min()..=self.max()).contains(&value)
    }
}

/// A value of a row built in code (not read from a file) that a file could not hold:
/// [`crate::measurements::check_row_values`].
#[derive(Clone, Debug, PartialEq, Error)]
pub enum RowValueError {
    /// NaN, infinite or beyond the column's bound.
    #[error("`{column}` = {value:e} {unit} is NaN, infinite or beyond ±{limit:e} {unit}")]
    OutOfBound {
        /// The column the value would be written in.
        column: String,
        /// The value.
        value: f64,
        /// The bound on its magnitude.
        limit: f64,
        /// Its unit.
        unit: &'static str,
    },
    /// A standard deviation outside its range.
    #[error("`{}` = {value:e} {} must be positive, from {:e} to {} {}", .sigma.column(), .sigma.unit(), .sigma.min(), .sigma.max(), .sigma.unit())]
    Sigma {
        /// Which standard deviation.
        sigma: SigmaColumn,
        /// The value.
        value: f64,
    },
}
