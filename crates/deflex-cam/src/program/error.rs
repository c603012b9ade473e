//! Errors of the program exporters and readers.

use deflex_files::{FileIoError, FileTooLarge};
use thiserror::Error;

/// What can go wrong when exporting or reading a robot program.
#[derive(Debug, Error)]
pub enum ProgramError {
    /// A settings value is out of range or a name is invalid.
    #[error("{source_name}: {key}: {message}")]
    Settings {
        /// The template file (or `defaults`).
        source_name: String,
        /// The key, e.g. `kuka.tool`.
        key: String,
        /// What was expected.
        message: String,
    },
    /// The path has no point, or more than the settings allow.
    #[error(
        "{format}: the path has {points} points; a program holds 1 ..= {max} (program.max_points)"
    )]
    PointCount {
        /// Output format.
        format: &'static str,
        /// Points given.
        points: usize,
        /// Largest allowed.
        max: usize,
    },
    /// A point has a non-finite or absurd value.
    #[error("{format}: point {index}: {field} = {value} is not finite or beyond ±{limit}")]
    BadValue {
        /// Output format.
        format: &'static str,
        /// Index of the point in the path.
        index: usize,
        /// Which value (`x_m`, `speed_m_s`, …).
        field: &'static str,
        /// The value.
        value: f64,
        /// The bound.
        limit: f64,
    },
    /// The program frame or the tool has a non-finite or absurd value.
    #[error("{format}: {which}: {field} = {value} is not finite or beyond ±{limit}")]
    BadFrame {
        /// Output format.
        format: &'static str,
        /// `frame` or `tool`.
        which: &'static str,
        /// Which value.
        field: &'static str,
        /// The value.
        value: f64,
        /// The bound.
        limit: f64,
    },
    /// Too many distinct speeds for a format that declares one speed datum per speed.
    #[error("{format}: {count} distinct speeds; at most {max} are supported (round the feeds)")]
    TooManySpeeds {
        /// Output format.
        format: &'static str,
        /// Distinct speeds found.
        count: usize,
        /// Largest allowed.
        max: usize,
    },
    /// Per-point data of the wrong length.
    #[error("{format}: {got} {what} for {expected} points")]
    Mismatch {
        /// Output format.
        format: &'static str,
        /// What.
        what: &'static str,
        /// Given.
        got: usize,
        /// Expected.
        expected: usize,
    },
    /// A generated line would exceed the format's line length bound (a bug or an absurd value).
    #[error("{format}: line {line} is {length} characters long, more than {max}")]
    LineTooLong {
        /// Output format.
        format: &'static str,
        /// 1-based line.
        line: usize,
        /// Its length.
        length: usize,
        /// Bound.
        max: usize,
    },
    /// A program being read back has a line that is not what the exporter writes.
    #[error("{file}:{line}: {message}")]
    Read {
        /// File name.
        file: String,
        /// 1-based line number.
        line: usize,
        /// What was expected.
        message: String,
    },
    /// Reading or writing a file failed (or a file path was refused before any I/O: not a plain
    /// relative path, a sink used out of order).
    #[error(transparent)]
    Io(#[from] FileIoError),
    /// A file read is larger than its reader accepts: a program template (1 MiB) or a program
    /// file being read back ([`crate::program::readback::MAX_READ_BYTES`]).
    #[error(transparent)]
    TooLarge(#[from] FileTooLarge),
}
