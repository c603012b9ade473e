//! Where an exporter's files go, part by part: in memory ([`MemorySink`], what [`crate::program::export`]
//! returns) or straight to a folder ([`DirectorySink`]), so that a million-point program is never
//! held whole: each part file is written as soon as it is complete, and a file that holds every
//! point (the VAL3 data file) is written in pieces as its parts are made.

use crate::program::ProgramFile;
use crate::program::common::check_lines;
use crate::program::error::ProgramError;
use deflex_files::FileIoError;
use std::io::{ErrorKind, Write as _};
use std::path::{Path, PathBuf};

/// Receives the files of a program, one at a time: [`ProgramSink::begin`], any number of
/// [`ProgramSink::write`]s of whole lines, [`ProgramSink::end`].
pub trait ProgramSink {
    /// Start the file at `path` (relative, forward slashes).
    fn begin(&mut self, path: &str) -> Result<(), ProgramError>;
    /// Append whole lines to the open file.
    fn write(&mut self, text: &str) -> Result<(), ProgramError>;
    /// Complete the open file.
    fn end(&mut self) -> Result<(), ProgramError>;
}

/// Check a piece of a file's text (whole lines) and write it to the sink.
pub(crate) fn put(
    sink: &mut dyn ProgramSink,
    format: &'static str,
    text: &str,
) -> Result<(), ProgramError> {
    check_lines(format, text)?;
    sink.write(text)
}

/// A whole (small) file to the sink.
pub(crate) fn emit(
    sink: &mut dyn ProgramSink,
    format: &'static str,
    path: &str,
    text: &str,
) -> Result<(), ProgramError> {
    sink.begin(path)?;
    put(sink, format, text)?;
    sink.end()
}

/// A relative path with neither empty parts nor `..`.
fn plain(path: &str) -> Result<(), ProgramError> {
    if path.split('/').any(|part| part.is_empty() || part == "..") {
        Err(FileIoError::other(path, ErrorKind::InvalidInput, "not a plain relative path").into())
    } else {
        Ok(())
    }
}

/// A sink's `write` or `end` called with no file open (a bug of the exporter, reported rather
/// than written somewhere): `PATH: write without an open file`.
fn without_open_file(path: impl Into<PathBuf>, message: &'static str) -> ProgramError {
    FileIoError::other(path, ErrorKind::Other, message).into()
}

/// Collects the files in memory.
#[derive(Debug, Default)]
pub struct MemorySink {
    /// The completed files, in the order they were written.
    pub files: Vec<ProgramFile>,
    open: Option<ProgramFile>,
}

impl ProgramSink for MemorySink {
    fn begin(&mut self, path: &str) -> Result<(), ProgramError> {
        plain(path)?;
        self.open = Some(ProgramFile {
            path: path.to_string(),
            contents: String::new(),
        });
        Ok(())
    }

    fn write(&mut self, text: &str) -> Result<(), ProgramError> {
        match &mut self.open {
            Some(file) => {
                file.contents.push_str(text);
                Ok(())
            }
            None => Err(without_open_file("(memory)", "write without an open file")),
        }
    }

    fn end(&mut self) -> Result<(), ProgramError> {
        match self.open.take() {
            Some(file) => {
                self.files.push(file);
                Ok(())
            }
            None => Err(without_open_file("(memory)", "end without an open file")),
        }
    }
}

/// Writes the files under a folder (which must exist; sub-folders are created), each through a
/// temporary sibling renamed over it when complete ([`deflex_files::AtomicFile`]): a failed run
/// leaves no half file.
pub struct DirectorySink {
    dir: PathBuf,
    open: Option<deflex_files::AtomicFile>,
    /// Bytes written.
    pub bytes: u64,
    /// The files written, in order.
    pub files: Vec<String>,
}

impl DirectorySink {
    /// A sink writing under `dir`.
    pub fn new(dir: &Path) -> DirectorySink {
        DirectorySink {
            dir: dir.to_path_buf(),
            open: None,
            bytes: 0,
            files: Vec::new(),
        }
    }

    fn io(&self, error: std::io::Error) -> ProgramError {
        let path = self
            .open
            .as_ref()
            .map_or(self.dir.as_path(), |f| f.destination());
        FileIoError::new(path, error).into()
    }
}

impl ProgramSink for DirectorySink {
    fn begin(&mut self, path: &str) -> Result<(), ProgramError> {
        plain(path)?;
        let full = self.dir.join(path);
        if let Some(parent) = full.parent() {
            std::fs::create_dir_all(parent).map_err(|e| FileIoError::new(parent, e))?;
        }
        let file =
            deflex_files::AtomicFile::create(&full).map_err(|e| FileIoError::new(&full, e))?;
        self.open = Some(file);
        self.files.push(path.to_string());
        Ok(())
    }

    fn write(&mut self, text: &str) -> Result<(), ProgramError> {
        let result = match &mut self.open {
            Some(file) => file.write_all(text.as_bytes()),
            None => return Err(without_open_file(&self.dir, "write without an open file")),
        };
        result.map_err(|e| self.io(e))?;
        self.bytes += text.len() as u64;
        Ok(())
    }

    fn end(&mut self) -> Result<(), ProgramError> {
        match self.open.take() {
            Some(file) => {
                let path = file.destination().to_path_buf();
                file.commit().map_err(|e| FileIoError::new(path, e).into())
            }
            None => Err(without_open_file(&self.dir, "end without an open file")),
        }
    }
}
