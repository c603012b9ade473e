//! Whole-or-nothing outputs: files through a temporary sibling and a rename, folders built aside
//! and exchanged with the old one in a single step.
//!
//! Names used beside an output `NAME` (all hidden, all in `NAME`'s own folder so that renames are
//! atomic):
//!
//! * `.NAME.tmp-PID-N` (or `.STEM.tmp-PID-N.EXT`): the file or folder being written by process
//!   `PID`. A file one whose process no longer runs is removed by the next write of `NAME`; a
//!   folder one is removed by the next run that holds the lock;
//! * `.NAME.old-PID-N`: the previous folder while it is being replaced on a file system that
//!   cannot exchange two names; if a kill left `NAME` missing, the next run renames it back;
//! * `.NAME.lock`: the lock a folder output is written under (kept: removing a lock file races
//!   with the next run opening it). A second run on the same folder is refused with the holder's
//!   process id.

use crate::input::FileKind;
use crate::output::{MARKER, OutputKind, OutputProblem, check_output, process_alive};
use std::ffi::{OsStr, OsString};
use std::fs::{self, File};
use std::io::{self, BufWriter, Read, Seek, Write};
use std::os::unix::ffi::OsStrExt;
use std::os::unix::fs::OpenOptionsExt;
use std::path::{Path, PathBuf};
use std::sync::atomic::{AtomicU64, Ordering};

/// A unique suffix for temporary names: process id and a per-process counter.
fn unique_suffix() -> String {
    static COUNTER: AtomicU64 = AtomicU64::new(0);
    let n = COUNTER.fetch_add(1, Ordering::Relaxed);
    format!("{}-{n}", std::process::id())
}

fn file_name(path: &Path) -> io::Result<&OsStr> {
    path.file_name().ok_or_else(|| {
        io::Error::new(
            io::ErrorKind::InvalidInput,
            format!("{}: not a file name", crate::shown_path(path)),
        )
    })
}

/// The sibling `.BASE.TAG-PID-N[.EXT]` of `path`.
fn sibling(path: &Path, tag: &str, keep_extension: bool) -> io::Result<PathBuf> {
    file_name(path)?;
    let base = if keep_extension {
        path.file_stem()
    } else {
        path.file_name()
    }
    .unwrap_or_default();
    let mut name = OsString::from(".");
    name.push(base);
    name.push(format!(".{tag}-{}", unique_suffix()));
    if let (true, Some(extension)) = (keep_extension, path.extension()) {
        name.push(".");
        name.push(extension);
    }
    Ok(path.with_file_name(name))
}

/// If `entry` is `.BASE.TAG-PID-N[.EXT]` for `path`, the PID.
fn leftover_pid(entry: &OsStr, path: &Path, tag: &str, keep_extension: bool) -> Option<u32> {
    let base = if keep_extension {
        path.file_stem()?
    } else {
        path.file_name()?
    };
    let mut prefix = b".".to_vec();
    prefix.extend_from_slice(base.as_bytes());
    prefix.extend_from_slice(format!(".{tag}-").as_bytes());
    let mut rest = entry.as_bytes().strip_prefix(prefix.as_slice())?;
    if let (true, Some(extension)) = (keep_extension, path.extension()) {
        let mut suffix = b".".to_vec();
        suffix.extend_from_slice(extension.as_bytes());
        rest = rest.strip_suffix(suffix.as_slice())?;
    }
    let text = std::str::from_utf8(rest).ok()?;
    let (pid, n) = text.split_once('-')?;
    let digits = |s: &str| !s.is_empty() && s.len() <= 20 && s.bytes().all(|b| b.is_ascii_digit());
    if !digits(pid) || !digits(n) {
        return None;
    }
    pid.parse().ok()
}

/// The leftovers `.BASE.TAG-PID-N[.EXT]` of `path` in its folder, with their process ids.
fn leftovers(path: &Path, tag: &str, keep_extension: bool) -> Vec<(PathBuf, u32)> {
    let folder = match path.parent() {
        Some(p) if !p.as_os_str().is_empty() => p,
        _ => Path::new("."),
    };
    let Ok(entries) = fs::read_dir(folder) else {
        return Vec::new();
    };
    entries
        .filter_map(Result::ok)
        .filter_map(|e| {
            let pid = leftover_pid(&e.file_name(), path, tag, keep_extension)?;
            Some((e.path(), pid))
        })
        .collect()
}

/// Remove the temporary files of `path` left by processes that no longer run.
fn clean_file_leftovers(path: &Path, keep_extension: bool) {
    for (leftover, pid) in leftovers(path, "tmp", keep_extension) {
        let is_file = fs::symlink_metadata(&leftover).is_ok_and(|m| m.file_type().is_file());
        if is_file && !process_alive(pid) {
            let _ = fs::remove_file(leftover);
        }
    }
}

fn sync_parent(path: &Path) {
    if let Some(parent) = path.parent() {
        let parent = if parent.as_os_str().is_empty() {
            Path::new(".")
        } else {
            parent
        };
        if let Ok(dir) = File::open(parent) {
            let _ = dir.sync_all();
        }
    }
}

fn create_new(path: &Path) -> io::Result<File> {
    fs::OpenOptions::new()
        .write(true)
        .create_new(true)
        .custom_flags(libc::O_CLOEXEC | libc::O_NOFOLLOW)
        .open(path)
}

/// Let `write` produce the file `path` through a temporary sibling with the same extension (for
/// writers that take a path, such as image encoders), renamed over `path` when `write`
/// succeeds and removed when it fails. `io_error` turns a refusal or rename failure into the
/// caller's error type.
pub fn write_through<T, E>(
    path: impl AsRef<Path>,
    write: impl FnOnce(&Path) -> Result<T, E>,
    io_error: impl FnOnce(io::Error) -> E,
) -> Result<T, E> {
    let prepared = check_output(path.as_ref(), OutputKind::File).and_then(|destination| {
        clean_file_leftovers(&destination, true);
        let temporary = sibling(&destination, "tmp", true)?;
        Ok((destination, temporary))
    });
    let (destination, temporary) = match prepared {
        Ok(p) => p,
        Err(e) => return Err(io_error(e)),
    };
    match write(&temporary) {
        Ok(value) => {
            let renamed = check_output(&destination, OutputKind::File)
                .and_then(|_| fs::rename(&temporary, &destination));
            match renamed {
                Ok(()) => {
                    sync_parent(&destination);
                    Ok(value)
                }
                Err(e) => {
                    let _ = fs::remove_file(&temporary);
                    Err(io_error(e))
                }
            }
        }
        Err(e) => {
            let _ = fs::remove_file(&temporary);
            Err(e)
        }
    }
}

/// Write `contents` to `path` whole or not at all (temporary sibling, sync, rename). The parent
/// folder must exist.
pub fn write_atomic(path: impl AsRef<Path>, contents: impl AsRef<[u8]>) -> io::Result<()> {
    let mut file = AtomicFile::create(path)?;
    file.write_all(contents.as_ref())?;
    file.commit()
}

/// A file being written: it appears at its destination only on [`AtomicFile::commit`]. Dropped
/// without a commit (error, panic), the temporary file is removed and the destination is left
/// as it was. Refused at creation when the destination is not a file deflex may replace
/// ([`check_output`]).
pub struct AtomicFile {
    destination: PathBuf,
    temporary: PathBuf,
    writer: Option<BufWriter<File>>,
}

impl AtomicFile {
    /// Start writing `path` (through a temporary sibling). The parent folder must exist.
    pub fn create(path: impl AsRef<Path>) -> io::Result<AtomicFile> {
        let destination = check_output(path.as_ref(), OutputKind::File)?;
        clean_file_leftovers(&destination, false);
        let temporary = sibling(&destination, "tmp", false)?;
        let file = create_new(&temporary)?;
        Ok(AtomicFile {
            destination,
            temporary,
            writer: Some(BufWriter::new(file)),
        })
    }

    /// Where the file will appear (a symbolic link given at creation resolved).
    pub fn destination(&self) -> &Path {
        &self.destination
    }

    /// Flush, sync and rename over the destination (checked again: it must still be a file
    /// deflex may replace).
    pub fn commit(mut self) -> io::Result<()> {
        let Some(writer) = self.writer.take() else {
            return Err(io::Error::other("file already committed"));
        };
        let result = writer
            .into_inner()
            .map_err(|e| e.into_error())
            .and_then(|file| file.sync_all())
            .and_then(|()| check_output(&self.destination, OutputKind::File))
            .and_then(|_| fs::rename(&self.temporary, &self.destination));
        if result.is_err() {
            let _ = fs::remove_file(&self.temporary);
        } else {
            sync_parent(&self.destination);
        }
        result
    }
}

impl Write for AtomicFile {
    fn write(&mut self, buf: &[u8]) -> io::Result<usize> {
        match self.writer.as_mut() {
            Some(w) => w.write(buf),
            None => Err(io::Error::other("file already committed")),
        }
    }

    fn flush(&mut self) -> io::Result<()> {
        match self.writer.as_mut() {
            Some(w) => w.flush(),
            None => Ok(()),
        }
    }
}

impl Drop for AtomicFile {
    fn drop(&mut self) {
        if self.writer.take().is_some() {
            let _ = fs::remove_file(&self.temporary);
        }
    }
}

/// The lock a folder output is written under: `.NAME.lock`, held with `flock` for the life of
/// the value (released by the system when the process ends, killed or not).
struct FolderLock {
    _file: File,
}

impl FolderLock {
    fn acquire(destination: &Path) -> io::Result<FolderLock> {
        let mut name = OsString::from(".");
        name.push(file_name(destination)?);
        name.push(".lock");
        let path = destination.with_file_name(name);
        let mut file = fs::OpenOptions::new()
            .read(true)
            .write(true)
            .create(true)
            .truncate(false)
            .custom_flags(libc::O_CLOEXEC | libc::O_NOFOLLOW | libc::O_NONBLOCK)
            .open(&path)?;
        let kind = FileKind::of(&file.metadata()?);
        if kind != FileKind::Regular {
            return Err(OutputProblem::NotAFile { kind }.into_io());
        }
        use std::os::fd::AsRawFd;
        // SAFETY: flock on a descriptor we own.
        if unsafe { libc::flock(file.as_raw_fd(), libc::LOCK_EX | libc::LOCK_NB) } != 0 {
            let error = io::Error::last_os_error();
            if error.raw_os_error() != Some(libc::EWOULDBLOCK) {
                return Err(error);
            }
            let mut text = String::new();
            let _ = (&file).take(32).read_to_string(&mut text);
            let holder = match text.trim().parse::<u32>() {
                Ok(pid) => format!("process {pid}, lock {}", crate::shown_path(&path)),
                Err(_) => format!("lock {}", crate::shown_path(&path)),
            };
            return Err(OutputProblem::InUse { holder }.into_io());
        }
        file.set_len(0)?;
        file.rewind()?;
        writeln!(file, "{}", std::process::id())?;
        Ok(FolderLock { _file: file })
    }
}

/// Swap the names `from` and `to` in one step (Linux `renameat2(RENAME_EXCHANGE)`); `Ok(false)`
/// when the file system cannot.
fn exchange(from: &Path, to: &Path) -> io::Result<bool> {
    #[cfg(target_os = "linux")]
    {
        use std::ffi::CString;
        let c = |p: &Path| {
            CString::new(p.as_os_str().as_bytes())
                .map_err(|_| io::Error::new(io::ErrorKind::InvalidInput, "NUL in a path"))
        };
        let (from_c, to_c) = (c(from)?, c(to)?);
        // SAFETY: two valid NUL-terminated paths relative to the working directory.
        let r = unsafe {
            libc::renameat2(
                libc::AT_FDCWD,
                from_c.as_ptr(),
                libc::AT_FDCWD,
                to_c.as_ptr(),
                libc::RENAME_EXCHANGE,
            )
        };
        if r == 0 {
            return Ok(true);
        }
        let error = io::Error::last_os_error();
        match error.raw_os_error() {
            Some(libc::EINVAL) | Some(libc::ENOSYS) | Some(libc::EOPNOTSUPP) => Ok(false),
            _ => Err(error),
        }
    }
    #[cfg(not(target_os = "linux"))]
    {
        let _ = (from, to);
        Ok(false)
    }
}

/// A folder of outputs built in a temporary sibling and swapped in on [`AtomicDir::commit`]:
/// readers see the old folder (or none) until the new one is complete, and at no instant is
/// the folder missing (one exchange of two names). Dropped without a commit, the temporary
/// folder is removed and an existing folder is kept. Refused at creation when the destination
/// is not a folder deflex may replace ([`check_output`]) or is being written by another run.
pub struct AtomicDir {
    destination: PathBuf,
    temporary: PathBuf,
    committed: bool,
    _lock: FolderLock,
}

impl AtomicDir {
    /// Start building folder `path`. Its parent is created if missing.
    pub fn create(path: impl AsRef<Path>) -> io::Result<AtomicDir> {
        let given = path.as_ref();
        file_name(given)?;
        if let Some(parent) = given.parent()
            && !parent.as_os_str().is_empty()
        {
            fs::create_dir_all(parent)?;
        }
        let destination = check_output(given, OutputKind::Folder)?;
        let lock = FolderLock::acquire(&destination)?;
        recover_interrupted_swap(&destination);
        check_output(&destination, OutputKind::Folder)?;
        for (leftover, _) in leftovers(&destination, "tmp", false) {
            // We hold the lock: every temporary folder of this output is a killed run's.
            if fs::symlink_metadata(&leftover).is_ok_and(|m| m.is_dir()) {
                let _ = fs::remove_dir_all(leftover);
            }
        }
        let temporary = sibling(&destination, "tmp", false)?;
        fs::create_dir(&temporary)?;
        let building = AtomicDir {
            destination,
            temporary,
            committed: false,
            _lock: lock,
        };
        fs::write(
            building.temporary.join(MARKER),
            "written by deflex: the next run writing this folder replaces it whole\n",
        )?;
        Ok(building)
    }

    /// The folder to write into now (the temporary one).
    pub fn path(&self) -> &Path {
        &self.temporary
    }

    /// Where the folder will appear.
    pub fn destination(&self) -> &Path {
        &self.destination
    }

    /// Swap the finished folder in: exchanged with the old one in one step, the old one then
    /// removed. Files of the old folder that the new one does not have are not kept.
    pub fn commit(mut self) -> io::Result<()> {
        if let Ok(dir) = File::open(&self.temporary) {
            let _ = dir.sync_all();
        }
        check_output(&self.destination, OutputKind::Folder)?;
        let exists = fs::symlink_metadata(&self.destination).is_ok();
        if !exists {
            fs::rename(&self.temporary, &self.destination)?;
        } else if exchange(&self.temporary, &self.destination)? {
            // The temporary name now holds the old folder.
            let _ = fs::remove_dir_all(&self.temporary);
        } else {
            // No exchange on this file system: old aside, new in, old removed. A kill between
            // the two renames is repaired by the next run (`recover_interrupted_swap`).
            let aside = sibling(&self.destination, "old", false)?;
            fs::rename(&self.destination, &aside)?;
            if let Err(e) = fs::rename(&self.temporary, &self.destination) {
                let _ = fs::rename(&aside, &self.destination);
                return Err(e);
            }
            let _ = fs::remove_dir_all(aside);
        }
        self.committed = true;
        sync_parent(&self.destination);
        Ok(())
    }
}

/// After a kill between the two renames of a swap without exchange: the old folder back under
/// its name; `.old` leftovers of completed swaps removed. Called with the lock held.
fn recover_interrupted_swap(destination: &Path) {
    let mut olds = leftovers(destination, "old", false);
    if olds.is_empty() {
        return;
    }
    if fs::symlink_metadata(destination).is_err() {
        olds.sort();
        if let Some((latest, _)) = olds.pop()
            && fs::rename(&latest, destination).is_err()
        {
            return;
        }
    }
    for (old, _) in olds {
        if fs::symlink_metadata(&old).is_ok_and(|m| m.is_dir()) {
            let _ = fs::remove_dir_all(old);
        }
    }
}

impl Drop for AtomicDir {
    fn drop(&mut self) {
        if !self.committed {
            let _ = fs::remove_dir_all(&self.temporary);
        }
    }
}
