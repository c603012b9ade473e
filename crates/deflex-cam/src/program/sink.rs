//! Where an exporter's files go, part by part: in memory ([`MemorySink`], what [`crate::program::export`]
//! returns) or straight to a folder ([`DirectorySink`]), so that a million-point program is never
//! held whole: each part file is written as soon as it is complete, and a file that holds every
//! point (the VAL3 data file) is written in pieces as its parts are made.

use crate::program::ProgramFile;
use crate::program::common::check_lines;
use crate::program::error::ProgramError;
use std::io::Write as _;
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
        Err(ProgramError::Io {
            path: path.to_string(),
            message: "not a plain relative path".into(),
        })
    } else {
        Ok(())
    }
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
            None => Err(ProgramError::Io {
                path: "(memory)".into(),
                message: "write without an open file".into(),
            }),
        }
    }

    fn end(&mut self) -> Result<(), ProgramError> {
        match self.open.take() {
            Some(file) => {
                self.files.push(file);
                Ok(())
            }
            None => Err(ProgramError::Io {
                path: "(memory)".into(),
                message: "end without an open file".into(),
            }),
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
        ProgramError::Io {
            path: self.open.as_ref().map_or_else(
                || self.dir.display().to_string(),
                |f| f.destination().display().to_string(),
            ),
            message: error.to_string(),
        }
    }
}

impl ProgramSink for DirectorySink {
    fn begin(&mut self, path: &str) -> Result<(), ProgramError> {
        plain(path)?;
        let full = self.dir.join(path);
        if let Some(parent) = full.parent() {
            std::fs::create_dir_all(parent).map_err(|e| ProgramError::Io {
                path: parent.display().to_string(),
                message: e.to_string(),
            })?;
        }
        let file = deflex_files::AtomicFile::create(&full).map_err(|e| ProgramError::Io {
            path: full.display().to_string(),
            message: e.to_string(),
        })?;
        self.open = Some(file);
        self.files.push(path.to_string());
        Ok(())
    }

    fn write(&mut self, text: &str) -> Result<(), ProgramError> {
        let result = match &mut self.open {
            Some(file) => file.write_all(text.as_bytes()),
            None => {
                return Err(ProgramError::Io {
                    path: self.dir.display().to_string(),
                    message: "write without an open file".into(),
                });
            }
        };
        result.map_err(|e| self.io(e))?;
        self.bytes += text.len() as u64;
        Ok(())
    }

    fn end(&mut self) -> Result<(), ProgramError> {
        match self.open.take() {
            Some(file) => {
                let path = file.destination().display().to_string();
                file.commit().map_err(|e| ProgramError::Io {
                    path,
                    message: e.to_string(),
                })
            }
            None => Err(ProgramError::Io {
                path: self.dir.display().to_string(),
                message: "end without an open file".into(),
            }),
        }
    }
}
