//! Bounded inputs: every read capped by the bytes actually read, only regular files read.
//!
//! The size a file's metadata reports is not a bound: `/dev/zero` and `/dev/urandom` report 0
//! bytes and never end, a pipe (a process substitution `<(…)`) reports nothing, and opening a
//! FIFO for reading waits for a writer for ever. So an input is opened without blocking
//! (`O_NONBLOCK`: a FIFO opens at once), its type is checked on the open descriptor (not on the
//! name, which could change in between), anything but a regular file is refused, and the read
//! is `Read::take(limit + 1)`: one byte more than allowed proves the file too large without
//! reading the rest.
//!
//! When [`track_inputs`] was called (the command-line tool does), every file opened here is
//! remembered by device and inode, so that an output naming one of them is refused
//! ([`crate::output`]).

use crate::errors::{FileIoError, FileTooLarge};
use crate::shown::shown_path;
use std::fs::{File, Metadata};
use std::io::{self, Read};
use std::os::unix::fs::{FileTypeExt, MetadataExt, OpenOptionsExt};
use std::path::{Path, PathBuf};
use std::sync::Mutex;
use thiserror::Error;

/// What a path names when it is not a regular file.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum FileKind {
    /// A regular file.
    Regular,
    /// A folder.
    Folder,
    /// A character device (`/dev/null`, `/dev/zero`, a terminal).
    CharDevice,
    /// A block device (a disk).
    BlockDevice,
    /// A FIFO or a pipe (a process substitution).
    Fifo,
    /// A Unix socket.
    Socket,
    /// A symbolic link (as seen without following it).
    Symlink,
}

impl FileKind {
    /// The kind of file `metadata` describes.
    pub fn of(metadata: &Metadata) -> FileKind {
        let t = metadata.file_type();
        if t.is_file() {
            FileKind::Regular
        } else if t.is_dir() {
            FileKind::Folder
        } else if t.is_char_device() {
            FileKind::CharDevice
        } else if t.is_block_device() {
            FileKind::BlockDevice
        } else if t.is_fifo() {
            FileKind::Fifo
        } else if t.is_socket() {
            FileKind::Socket
        } else {
            FileKind::Symlink
        }
    }
}

impl std::fmt::Display for FileKind {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(match self {
            FileKind::Regular => "a regular file",
            FileKind::Folder => "a folder",
            FileKind::CharDevice => "a character device",
            FileKind::BlockDevice => "a block device",
            FileKind::Fifo => "a FIFO or pipe",
            FileKind::Socket => "a socket",
            FileKind::Symlink => "a symbolic link",
        })
    }
}

/// Why an input file was refused (the path is named by the [`InputError`] holding this).
#[derive(Clone, Debug, PartialEq, Error)]
pub enum InputProblem {
    /// Not a regular file: refused before reading a byte.
    #[error(
        "is {kind}, not a regular file (deflex reads its inputs from regular files only; copy the data to a file first)"
    )]
    NotAFile {
        /// What it is.
        kind: FileKind,
    },
    /// More bytes than allowed (found by reading, not from the metadata).
    /// The message words it as [`FileTooLarge`] does (a reader that knows what it reads names
    /// it there: [`InputError::reported_as`]).
    #[error(
        "more than the {limit} bytes this kind of file may have (stopped reading after {read})"
    )]
    TooLarge {
        /// The limit.
        limit: u64,
        /// Bytes read before stopping (limit + 1).
        read: u64,
    },
    /// Text expected, bytes found that are not UTF-8.
    #[error("not UTF-8 text (invalid byte at offset {offset})")]
    NotText {
        /// Offset of the first invalid byte.
        offset: usize,
    },
}

/// Why an input file could not be read.
#[derive(Debug, Error)]
pub enum InputError {
    /// The operating system's error (missing file, no permission, …).
    #[error(transparent)]
    Io(#[from] FileIoError),
    /// Refused: not a regular file, too large, not text.
    #[error("{}: {problem}", shown_path(.path))]
    Refused {
        /// The file.
        path: PathBuf,
        /// Why.
        problem: InputProblem,
    },
}

impl InputError {
    fn refused(path: &Path, problem: InputProblem) -> InputError {
        InputError::Refused {
            path: path.to_path_buf(),
            problem,
        }
    }

    /// The file the error is about.
    pub fn path(&self) -> &Path {
        match self {
            InputError::Io(error) => &error.path,
            InputError::Refused { path, .. } => path,
        }
    }

    /// Why it was refused, if it was.
    pub fn problem(&self) -> Option<&InputProblem> {
        match self {
            InputError::Refused { problem, .. } => Some(problem),
            InputError::Io(_) => None,
        }
    }

    /// The same error as an `io::Error` without the path (for callers whose error type names
    /// the path and wraps an `io::Error`): the system's error, or the [`InputProblem`] inside
    /// one of kind `InvalidData`.
    pub fn into_io(self) -> io::Error {
        match self {
            InputError::Io(error) => error.source,
            InputError::Refused { problem, .. } => {
                io::Error::new(io::ErrorKind::InvalidData, problem)
            }
        }
    }

    /// The same error as a [`FileIoError`] naming the file: the system's error, or the
    /// [`InputProblem`] inside an `io::Error` of kind `InvalidData` ([`InputError::into_io`]).
    pub fn into_file_io(self) -> FileIoError {
        match self {
            InputError::Io(error) => error,
            InputError::Refused { path, problem } => {
                FileIoError::new(path, io::Error::new(io::ErrorKind::InvalidData, problem))
            }
        }
    }

    /// This error as a reader of one kind of file reports it, `what` saying which (with its
    /// article: `a measurement file`): a file over the limit as [`FileTooLarge`], any other
    /// failure (the system's error, a refusal) as [`FileIoError`]
    /// ([`InputError::into_file_io`]). `E` is the reader's error type, which holds both:
    ///
    /// ```
    /// # use deflex_files::{FileIoError, FileTooLarge, read_bounded};
    /// #[derive(Debug, thiserror::Error)]
    /// enum NotesError {
    ///     #[error(transparent)]
    ///     Io(#[from] FileIoError),
    ///     #[error(transparent)]
    ///     TooLarge(#[from] FileTooLarge),
    /// }
    /// let dir = std::env::temp_dir().join(format!("deflex-notes-{}", std::process::id()));
    /// std::fs::create_dir_all(&dir).unwrap();
    /// let path = dir.join("notes.txt");
    /// std::fs::write(&path, "0123456789").unwrap();
    /// let e = read_bounded(&path, 4)
    ///     .map_err(|e| e.reported_as::<NotesError>("a notes file"))
    ///     .unwrap_err();
    /// assert!(e.to_string().ends_with(
    ///     "notes.txt: more than the 4 bytes a notes file may have (stopped reading after 5)"
    /// ));
    /// assert!(matches!(
    ///     read_bounded(&dir.join("missing"), 4).map_err(|e| e.reported_as::<NotesError>("a notes file")),
    ///     Err(NotesError::Io(_))
    /// ));
    /// # std::fs::remove_dir_all(dir).unwrap();
    /// ```
    pub fn reported_as<E: From<FileIoError> + From<FileTooLarge>>(self, what: &'static str) -> E {
        match self {
            InputError::Refused {
                path,
                problem: InputProblem::TooLarge { limit, read },
            } => FileTooLarge::new(path, what, limit, read).into(),
            other => other.into_file_io().into(),
        }
    }
}

/// A file deflex read, by identity (device and inode) and by resolved path.
#[derive(Clone, Debug)]
pub(crate) struct ReadInput {
    pub(crate) device: u64,
    pub(crate) inode: u64,
    pub(crate) path: PathBuf,
    pub(crate) resolved: Option<PathBuf>,
}

static INPUTS: Mutex<Option<Vec<ReadInput>>> = Mutex::new(None);

/// Remember, from now on in this process, every file opened by [`open_input`] (and so by
/// [`read_bounded`]), so that writing an output over one of them is refused. Called once by a
/// command-line tool at start; a library used inside a long-lived process does not call it.
pub fn track_inputs() {
    let mut inputs = INPUTS.lock().unwrap_or_else(|e| e.into_inner());
    if inputs.is_none() {
        *inputs = Some(Vec::new());
    }
}

/// The inputs read so far (empty when not tracking).
pub(crate) fn read_inputs() -> Vec<ReadInput> {
    INPUTS
        .lock()
        .unwrap_or_else(|e| e.into_inner())
        .clone()
        .unwrap_or_default()
}

fn remember(path: &Path, metadata: &Metadata) {
    let mut inputs = INPUTS.lock().unwrap_or_else(|e| e.into_inner());
    if let Some(list) = inputs.as_mut()
        && list.len() < 100_000
        && !list
            .iter()
            .any(|i| i.device == metadata.dev() && i.inode == metadata.ino())
    {
        list.push(ReadInput {
            device: metadata.dev(),
            inode: metadata.ino(),
            path: path.to_path_buf(),
            resolved: std::fs::canonicalize(path).ok(),
        });
    }
}

/// Open `path` for reading when it is a regular file: opened without blocking (a FIFO cannot
/// make this wait), its type checked on the open file, anything else refused with
/// [`InputProblem::NotAFile`].
pub fn open_input(path: &Path) -> Result<File, InputError> {
    let io_error = |source| InputError::Io(FileIoError::new(path, source));
    let file = std::fs::OpenOptions::new()
        .read(true)
        .custom_flags(libc::O_NONBLOCK | libc::O_NOCTTY)
        .open(path)
        .map_err(io_error)?;
    let metadata = file.metadata().map_err(io_error)?;
    let kind = FileKind::of(&metadata);
    if kind != FileKind::Regular {
        return Err(InputError::refused(path, InputProblem::NotAFile { kind }));
    }
    remember(path, &metadata);
    Ok(file)
}

/// The bytes of `path`, a regular file of at most `limit` bytes (counted while reading).
pub fn read_bounded_bytes(path: &Path, limit: u64) -> Result<Vec<u8>, InputError> {
    let file = open_input(path)?;
    let mut bytes = Vec::new();
    file.take(limit.saturating_add(1))
        .read_to_end(&mut bytes)
        .map_err(|source| FileIoError::new(path, source))?;
    if bytes.len() as u64 > limit {
        let read = bytes.len() as u64;
        return Err(InputError::refused(
            path,
            InputProblem::TooLarge { limit, read },
        ));
    }
    Ok(bytes)
}

/// The UTF-8 text of `path`, a regular file of at most `limit` bytes (counted while reading).
pub fn read_bounded(path: &Path, limit: u64) -> Result<String, InputError> {
    let bytes = read_bounded_bytes(path, limit)?;
    String::from_utf8(bytes).map_err(|e| {
        let offset = e.utf8_error().valid_up_to();
        InputError::refused(path, InputProblem::NotText { offset })
    })
}
