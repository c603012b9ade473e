//! # deflex-files
//!
//! Outputs are written whole or not at all: every file goes to a temporary sibling first and is
//! renamed over the destination only once it is complete and flushed, so a failure (an error, a
//! panic, a killed process) never leaves half a file and never clobbers an older one. Folders of
//! outputs (a validation report, a demo) are built in a temporary sibling folder and swapped in
//! at the end.
//!
//! Depends on nothing but `std`; every deflex crate that writes files uses it.

#![warn(missing_docs)]

use std::fs::{self, File};
use std::io::{self, BufWriter, Write};
use std::path::{Path, PathBuf};
use std::sync::atomic::{AtomicU64, Ordering};

/// A unique suffix for temporary names: process id and a per-process counter.
fn unique_suffix() -> String {
    static COUNTER: AtomicU64 = AtomicU64::new(0);
    let n = COUNTER.fetch_add(1, Ordering::Relaxed);
    format!("{}-{n}", std::process::id())
}

/// The temporary sibling of `path` in the same folder (so rename is atomic):
/// `.<name>.tmp-<pid>-<n>`, or `.<stem>.tmp-<pid>-<n>.<ext>` with `keep_extension` (for writers
/// that choose the format from the extension).
fn temporary_sibling(path: &Path, keep_extension: bool) -> io::Result<PathBuf> {
    let base = if keep_extension {
        path.file_stem()
    } else {
        path.file_name()
    };
    let base = base.ok_or_else(|| {
        io::Error::new(
            io::ErrorKind::InvalidInput,
            format!("{}: not a file name", path.display()),
        )
    })?;
    let mut name = std::ffi::OsString::from(".");
    name.push(base);
    name.push(format!(".tmp-{}", unique_suffix()));
    if let (true, Some(extension)) = (keep_extension, path.extension()) {
        name.push(".");
        name.push(extension);
    }
    Ok(path.with_file_name(name))
}

/// Let `write` produce the file `path` through a temporary sibling with the same extension (for
/// writers that take a path, such as image encoders), renamed over `path` when `write`
/// succeeds and removed when it fails. `io_error` turns a rename failure into the caller's
/// error type.
pub fn write_through<T, E>(
    path: impl AsRef<Path>,
    write: impl FnOnce(&Path) -> Result<T, E>,
    io_error: impl FnOnce(io::Error) -> E,
) -> Result<T, E> {
    let path = path.as_ref();
    let temporary = match temporary_sibling(path, true) {
        Ok(t) => t,
        Err(e) => return Err(io_error(e)),
    };
    match write(&temporary) {
        Ok(value) => match fs::rename(&temporary, path) {
            Ok(()) => Ok(value),
            Err(e) => {
                let _ = fs::remove_file(&temporary);
                Err(io_error(e))
            }
        },
        Err(e) => {
            let _ = fs::remove_file(&temporary);
            Err(e)
        }
    }
}

/// Write `contents` to `path` whole or not at all (temporary sibling, flush, rename). The parent
/// folder must exist.
pub fn write_atomic(path: impl AsRef<Path>, contents: impl AsRef<[u8]>) -> io::Result<()> {
    let mut file = AtomicFile::create(path)?;
    file.write_all(contents.as_ref())?;
    file.commit()
}

/// A file being written: it appears at its destination only on [`AtomicFile::commit`]. Dropped
/// without a commit (error, panic), the temporary file is removed and the destination is left
/// as it was.
pub struct AtomicFile {
    destination: PathBuf,
    temporary: PathBuf,
    writer: Option<BufWriter<File>>,
}

impl AtomicFile {
    /// Start writing `path` (through a temporary sibling). The parent folder must exist.
    pub fn create(path: impl AsRef<Path>) -> io::Result<AtomicFile> {
        let destination = path.as_ref().to_path_buf();
        let temporary = temporary_sibling(&destination, false)?;
        let file = File::create(&temporary)?;
        Ok(AtomicFile {
            destination,
            temporary,
            writer: Some(BufWriter::new(file)),
        })
    }

    /// Where the file will appear.
    pub fn destination(&self) -> &Path {
        &self.destination
    }

    /// Flush, sync and rename over the destination.
    pub fn commit(mut self) -> io::Result<()> {
        let writer = self.writer.take().expect("writer present until commit");
        let file = writer.into_inner().map_err(|e| e.into_error())?;
        file.sync_all()?;
        drop(file);
        fs::rename(&self.temporary, &self.destination)
    }
}

impl Write for AtomicFile {
    fn write(&mut self, buf: &[u8]) -> io::Result<usize> {
        self.writer
            .as_mut()
            .expect("writer present until commit")
            .write(buf)
    }

    fn flush(&mut self) -> io::Result<()> {
        self.writer
            .as_mut()
            .expect("writer present until commit")
            .flush()
    }
}

impl Drop for AtomicFile {
    fn drop(&mut self) {
        if self.writer.take().is_some() {
            let _ = fs::remove_file(&self.temporary);
        }
    }
}

/// A folder of outputs built in a temporary sibling and swapped in on
/// [`AtomicDir::commit`]: readers see the old folder (or none) until the new one is complete.
/// Dropped without a commit, the temporary folder is removed and an existing folder is kept.
pub struct AtomicDir {
    destination: PathBuf,
    temporary: PathBuf,
    committed: bool,
}

impl AtomicDir {
    /// Start building folder `path`. Its parent is created if missing.
    pub fn create(path: impl AsRef<Path>) -> io::Result<AtomicDir> {
        let destination = path.as_ref().to_path_buf();
        if let Some(parent) = destination.parent()
            && !parent.as_os_str().is_empty()
        {
            fs::create_dir_all(parent)?;
        }
        if destination.exists() && !destination.is_dir() {
            return Err(io::Error::new(
                io::ErrorKind::AlreadyExists,
                format!("{}: exists and is not a folder", destination.display()),
            ));
        }
        let temporary = temporary_sibling(&destination, false)?;
        fs::create_dir(&temporary)?;
        Ok(AtomicDir {
            destination,
            temporary,
            committed: false,
        })
    }

    /// The folder to write into now (the temporary one).
    pub fn path(&self) -> &Path {
        &self.temporary
    }

    /// Where the folder will appear.
    pub fn destination(&self) -> &Path {
        &self.destination
    }

    /// Swap the finished folder in. An existing folder at the destination is moved aside first
    /// and removed once the new one is in place; files in it that the new folder does not have
    /// are not kept.
    pub fn commit(mut self) -> io::Result<()> {
        let old = if self.destination.exists() {
            let aside = temporary_sibling(&self.destination, false)?;
            fs::rename(&self.destination, &aside)?;
            Some(aside)
        } else {
            None
        };
        if let Err(e) = fs::rename(&self.temporary, &self.destination) {
            if let Some(aside) = &old {
                let _ = fs::rename(aside, &self.destination);
            }
            return Err(e);
        }
        self.committed = true;
        if let Some(aside) = old {
            let _ = fs::remove_dir_all(aside);
        }
        Ok(())
    }
}

impl Drop for AtomicDir {
    fn drop(&mut self) {
        if !self.committed {
            let _ = fs::remove_dir_all(&self.temporary);
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn scratch(name: &str) -> PathBuf {
        let dir = std::env::temp_dir().join(format!("deflex-files-{name}-{}", unique_suffix()));
        fs::create_dir_all(&dir).unwrap();
        dir
    }

    fn entries(dir: &Path) -> Vec<String> {
        let mut names: Vec<String> = fs::read_dir(dir)
            .unwrap()
            .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
            .collect();
        names.sort();
        names
    }

    #[test]
    fn a_file_appears_only_on_commit_and_an_abandoned_one_keeps_the_old() {
        let dir = scratch("file");
        let path = dir.join("log.csv");
        fs::write(&path, "old").unwrap();
        {
            let mut file = AtomicFile::create(&path).unwrap();
            file.write_all(b"half").unwrap();
            assert_eq!(fs::read_to_string(&path).unwrap(), "old");
            // dropped without commit: a failed run
        }
        assert_eq!(fs::read_to_string(&path).unwrap(), "old");
        assert_eq!(entries(&dir), vec!["log.csv"], "no temporary left behind");
        write_atomic(&path, "new").unwrap();
        assert_eq!(fs::read_to_string(&path).unwrap(), "new");
        assert_eq!(entries(&dir), vec!["log.csv"]);
        fs::remove_dir_all(dir).unwrap();
    }

    #[test]
    fn a_folder_is_swapped_in_whole_and_an_abandoned_one_keeps_the_old() {
        let dir = scratch("dir");
        let out = dir.join("report");
        fs::create_dir(&out).unwrap();
        fs::write(out.join("a.csv"), "old").unwrap();
        {
            let building = AtomicDir::create(&out).unwrap();
            fs::write(building.path().join("a.csv"), "half").unwrap();
            // dropped: a failed validation
        }
        assert_eq!(fs::read_to_string(out.join("a.csv")).unwrap(), "old");
        assert_eq!(entries(&dir), vec!["report"]);
        let building = AtomicDir::create(&out).unwrap();
        fs::write(building.path().join("b.csv"), "new").unwrap();
        building.commit().unwrap();
        assert_eq!(entries(&out), vec!["b.csv"]);
        assert_eq!(entries(&dir), vec!["report"]);
        fs::remove_dir_all(dir).unwrap();
    }

    #[test]
    fn write_through_keeps_the_extension_and_cleans_up_on_failure() {
        let dir = scratch("through");
        let path = dir.join("plot.png");
        fs::write(&path, "old").unwrap();
        let failed: io::Result<()> = write_through(
            &path,
            |tmp| {
                assert_eq!(tmp.extension().unwrap(), "png");
                fs::write(tmp, "half").unwrap();
                Err(io::Error::other("drawing failed"))
            },
            |e| e,
        );
        assert!(failed.is_err());
        assert_eq!(fs::read_to_string(&path).unwrap(), "old");
        assert_eq!(entries(&dir), vec!["plot.png"]);
        write_through(&path, |tmp| fs::write(tmp, "new"), |e| e).unwrap();
        assert_eq!(fs::read_to_string(&path).unwrap(), "new");
        assert_eq!(entries(&dir), vec!["plot.png"]);
        fs::remove_dir_all(dir).unwrap();
    }

    #[test]
    fn a_path_without_a_file_name_is_an_error() {
        assert!(write_atomic("/", "x").is_err());
    }
}
