//! What an output may replace: the checks made before anything is written.
//!
//! An output path that exists must be what deflex would write there: a regular file for a file
//! output; for a folder output an empty folder or one deflex wrote (it holds [`MARKER`]). A
//! symbolic link is followed and its target checked (the link itself is kept: the file is
//! written where it points). Devices, FIFOs, sockets, dangling links and foreign folders are
//! refused, and so is an output that is one of the files this process read
//! ([`crate::track_inputs`]) or a folder output holding one.

use crate::errors::FileIoError;
use crate::input::{FileKind, read_inputs};
use std::io;
use std::os::unix::fs::MetadataExt;
use std::path::{Path, PathBuf};
use thiserror::Error;

/// The file every folder deflex writes holds, so that a later run knows the folder is deflex's
/// to replace.
pub const MARKER: &str = ".deflex-output";

/// A file output or a folder output.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum OutputKind {
    /// One file, replaced whole.
    File,
    /// A folder of files, replaced whole.
    Folder,
}

/// Why an output path is refused (the path itself is named by the error holding this).
#[derive(Clone, Debug, PartialEq, Error)]
pub enum OutputProblem {
    /// Something that is not a file deflex may replace.
    #[error(
        "is {kind}, not a regular file: deflex replaces only regular files; nothing was written"
    )]
    NotAFile {
        /// What it is.
        kind: FileKind,
    },
    /// Something that is not a folder, given as a folder output.
    #[error("is {kind}, not a folder: nothing was written")]
    NotAFolder {
        /// What it is.
        kind: FileKind,
    },
    /// A folder deflex did not write and that is not empty.
    #[error(
        "is a folder deflex did not write (it has files and no {MARKER}); a folder output replaces the whole folder, so give a new or empty folder; nothing was written"
    )]
    ForeignFolder,
    /// A symbolic link whose target does not exist.
    #[error("is a symbolic link to nothing ({target}); nothing was written")]
    DanglingLink {
        /// Where it points.
        target: String,
    },
    /// The output is one of the command's inputs.
    #[error(
        "is also an input of this command ({input}); give another output path; nothing was written"
    )]
    IsAnInput {
        /// The input, as it was named.
        input: String,
    },
    /// A folder output holding one of the command's inputs.
    #[error(
        "holds an input of this command ({input}), and a folder output replaces the whole folder; give another folder; nothing was written"
    )]
    HoldsAnInput {
        /// The input, as it was named.
        input: String,
    },
    /// Another process is writing the same folder output.
    #[error(
        "is being written by another deflex run ({holder}); wait for it to end; nothing was written"
    )]
    InUse {
        /// Who holds the lock (`process 1234`).
        holder: String,
    },
}

impl OutputProblem {
    /// As an `io::Error` (kind `AlreadyExists`, or `ResourceBusy` for [`OutputProblem::InUse`]),
    /// the typed problem inside.
    pub fn into_io(self) -> io::Error {
        let kind = match self {
            OutputProblem::InUse { .. } => io::ErrorKind::ResourceBusy,
            _ => io::ErrorKind::AlreadyExists,
        };
        io::Error::new(kind, self)
    }
}

/// An output path refused, with the flag that named it: `FLAG PATH: WHY`.
#[derive(Debug, Error)]
#[error("{flag} {error}")]
pub struct OutputError {
    /// The flag (`--out`, `[log] path`).
    pub flag: String,
    /// The path, and why: an [`OutputProblem`] inside the `io::Error`, or the system's error.
    #[source]
    pub error: FileIoError,
}

/// The typed problem inside an `io::Error` made by this crate, if it is one.
pub fn problem_of(error: &io::Error) -> Option<&OutputProblem> {
    error.get_ref()?.downcast_ref::<OutputProblem>()
}

/// Check, without touching anything, that `path` may be written as an output of `kind`:
/// returns the path to write (a symbolic link resolved to its target) or why not.
pub fn check_output(path: &Path, kind: OutputKind) -> io::Result<PathBuf> {
    let target = resolve_links(path)?;
    match std::fs::symlink_metadata(&target) {
        Err(e) if e.kind() == io::ErrorKind::NotFound => {}
        Err(e) => return Err(e),
        Ok(metadata) => {
            let found = FileKind::of(&metadata);
            match (kind, found) {
                (OutputKind::File, FileKind::Regular) => {
                    refuse_if_input(&metadata)?;
                }
                (OutputKind::File, other) => {
                    return Err(OutputProblem::NotAFile { kind: other }.into_io());
                }
                (OutputKind::Folder, FileKind::Folder) => {
                    if !is_deflex_folder(&target)? {
                        return Err(OutputProblem::ForeignFolder.into_io());
                    }
                }
                (OutputKind::Folder, other) => {
                    return Err(OutputProblem::NotAFolder { kind: other }.into_io());
                }
            }
        }
    }
    if kind == OutputKind::Folder {
        refuse_if_holds_input(&target)?;
    }
    Ok(target)
}

/// `check_output` naming the flag in its error.
pub fn check_output_flag(
    flag: &str,
    path: &Path,
    kind: OutputKind,
) -> Result<PathBuf, OutputError> {
    check_output(path, kind).map_err(|source| OutputError {
        flag: flag.to_string(),
        error: FileIoError::new(path, source),
    })
}

/// `path` with symbolic links followed to what they name (at most 40 deep); an error for a
/// link to nothing.
fn resolve_links(path: &Path) -> io::Result<PathBuf> {
    let mut current = path.to_path_buf();
    for _ in 0..40 {
        match std::fs::symlink_metadata(&current) {
            Ok(m) if m.file_type().is_symlink() => {
                let link = std::fs::read_link(&current)?;
                let next = match current.parent() {
                    Some(parent) if link.is_relative() => parent.join(&link),
                    _ => link,
                };
                if !next.exists() {
                    return Err(OutputProblem::DanglingLink {
                        target: crate::shown_path(&next),
                    }
                    .into_io());
                }
                current = next;
            }
            _ => return Ok(current),
        }
    }
    Err(io::Error::other("too many levels of symbolic links"))
}

/// An empty folder, or one holding [`MARKER`].
fn is_deflex_folder(path: &Path) -> io::Result<bool> {
    if path.join(MARKER).is_file() {
        return Ok(true);
    }
    Ok(std::fs::read_dir(path)?.next().is_none())
}

fn refuse_if_input(metadata: &std::fs::Metadata) -> io::Result<()> {
    if let Some(input) = read_inputs().into_iter().find(|i| {
        i.device == metadata.dev()
                && i.inode == metadata.ino()
                // Still the file that was read: an input deleted since (its inode free to be
                // given to a new file, as tmpfs does at once) is no longer one.
                && std::fs::metadata(&i.path)
                    .is_ok_and(|m| m.dev() == i.device && m.ino() == i.inode)
    }) {
        return Err(OutputProblem::IsAnInput {
            input: crate::shown_path(&input.path),
        }
        .into_io());
    }
    Ok(())
}

fn refuse_if_holds_input(folder: &Path) -> io::Result<()> {
    let Ok(resolved) = std::fs::canonicalize(folder) else {
        return Ok(()); // not there yet: it holds nothing
    };
    if let Some(input) = read_inputs().into_iter().find(|i| {
        i.resolved
            .as_ref()
            .is_some_and(|r| r.starts_with(&resolved))
    }) {
        return Err(OutputProblem::HoldsAnInput {
            input: crate::shown_path(&input.path),
        }
        .into_io());
    }
    Ok(())
}

/// Whether process `pid` still runs (a leftover of a process that does not is stale).
pub(crate) fn process_alive(pid: u32) -> bool {
    let Ok(pid) = libc::pid_t::try_from(pid) else {
        return false;
    };
    if pid <= 0 {
        return false;
    }
    // SAFETY: kill with signal 0 only checks that the process exists.
    let r = unsafe { libc::kill(pid, 0) };
    r == 0 || io::Error::last_os_error().raw_os_error() == Some(libc::EPERM)
}
