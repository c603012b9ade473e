//! The two failures every file reader and writer of deflex shares, defined once: an I/O failure
//! on a named file ([`FileIoError`]) and a file larger than its reader accepts
//! ([`FileTooLarge`]). A crate's error enum holds them as a variant's payload
//! (`#[error(transparent)] Io(#[from] FileIoError)`) instead of repeating a `path` and a
//! `source` of its own.
//!
//! Both name the file with its control characters escaped ([`crate::shown_path`]).

use crate::shown::shown_path;
use std::io;
use std::path::{Path, PathBuf};
use thiserror::Error;

/// Reading or writing a named file failed: the operating system's error (or a refusal carried
/// in one, such as [`crate::InputProblem`] inside [`crate::InputError::into_io`]).
///
/// Shown as `PATH: ERROR`, or `PATH: CONTEXT: ERROR` with a context
/// ([`FileIoError::context`]: `cannot start the recording`).
#[derive(Debug, Error)]
#[error("{}: {}{source}", shown_path(.path), .context.map(|c| format!("{c}: ")).unwrap_or_default())]
pub struct FileIoError {
    /// The file (or folder).
    pub path: PathBuf,
    /// What was being done, shown between the path and the error (`cannot read file`); none
    /// for the plain `PATH: ERROR`.
    pub context: Option<&'static str>,
    /// The operating system's error.
    #[source]
    pub source: io::Error,
}

impl FileIoError {
    /// `source` on `path`, shown as `PATH: ERROR`.
    pub fn new(path: impl Into<PathBuf>, source: io::Error) -> FileIoError {
        FileIoError {
            path: path.into(),
            context: None,
            source,
        }
    }

    /// The same error shown as `PATH: CONTEXT: ERROR` (`context`: what was being done, such as
    /// `cannot read file`).
    pub fn context(mut self, context: &'static str) -> FileIoError {
        self.context = Some(context);
        self
    }

    /// An error on `path` that is not the system's (a path refused before any I/O, a sink used
    /// out of order): `message` as an `io::Error` of `kind`, shown as `PATH: MESSAGE`.
    pub fn other(path: impl Into<PathBuf>, kind: io::ErrorKind, message: &'static str) -> Self {
        FileIoError::new(path, io::Error::new(kind, message))
    }

    /// The file.
    pub fn path(&self) -> &Path {
        &self.path
    }
}

/// A file larger than its reader accepts, found by reading (the reading stopped one byte past
/// the limit, or at the end of the line that passed it), not from the metadata.
///
/// Shown as `PATH: more than the LIMIT bytes WHAT may have (stopped reading after READ)`, where
/// `WHAT` says which kind of file the reader reads (`a measurement file`, `a log`).
#[derive(Clone, Debug, PartialEq, Eq, Error)]
#[error(
    "{}: more than the {limit} bytes {what} may have (stopped reading after {read})",
    shown_path(.path)
)]
pub struct FileTooLarge {
    /// The file.
    pub path: PathBuf,
    /// What the file is, with its article, as the message says it (`a measurement file`,
    /// `a robot description`, `a log`).
    pub what: &'static str,
    /// The most bytes the reader accepts.
    pub limit: u64,
    /// Bytes read before stopping (more than `limit`).
    pub read: u64,
}

impl FileTooLarge {
    /// `path`, a file of the kind `what`, read past its `limit` (`read` bytes).
    pub fn new(path: impl Into<PathBuf>, what: &'static str, limit: u64, read: u64) -> Self {
        FileTooLarge {
            path: path.into(),
            what,
            limit,
            read,
        }
    }
}
