//! The CSV log of `deflex run`, a sink of the telemetry stream (the runtime's
//! `deflex_runtime::telemetry`): a writer thread reads the session's [`CycleSample`]s through its
//! own [`Subscriber`] and writes one row per control cycle in the run log's format
//! ([`crate::run_log::RunLogFormat::cell`]: every column, SI units). The control thread never
//! waits for it, never allocates for it and never touches the file; if the writer falls more
//! than the ring's capacity behind, the oldest cycles are lost to it and counted
//! ([`LogReport::dropped`]).
//!
//! The writer streams into a [`LogTarget`]; for `deflex run` that is a
//! [`deflex_files::AtomicFile`], so the log appears at its path only when
//! [`LogWriter::finish`] commits it: a run that fails keeps the log a previous run left there.

use crate::run_log::RunLogFormat;
use deflex_telemetry::{CycleSample, Subscriber};
use std::io::Write;
use std::sync::{Arc, OnceLock};
use std::thread::JoinHandle;

/// Where the writer thread streams the CSV: written as it goes, made visible (or kept) only by
/// [`LogTarget::commit`].
pub trait LogTarget: Write + Send {
    /// Flushes and makes the file appear at its destination.
    fn commit(self: Box<Self>) -> std::io::Result<()>;
}

impl LogTarget for deflex_files::AtomicFile {
    fn commit(self: Box<Self>) -> std::io::Result<()> {
        deflex_files::AtomicFile::commit(*self)
    }
}

/// Any writer as a [`LogTarget`] whose commit is a flush (tests, stdout).
pub struct Plain<W: Write + Send>(pub W);

impl<W: Write + Send> Write for Plain<W> {
    fn write(&mut self, buf: &[u8]) -> std::io::Result<usize> {
        self.0.write(buf)
    }
    fn flush(&mut self) -> std::io::Result<()> {
        self.0.flush()
    }
}

impl<W: Write + Send> LogTarget for Plain<W> {
    fn commit(mut self: Box<Self>) -> std::io::Result<()> {
        self.0.flush()
    }
}

type WriterResult = (Box<dyn LogTarget>, std::io::Result<(u64, u64)>);

/// The writer thread; [`LogWriter::finish`] waits for it once the stream has ended.
pub struct LogWriter {
    handle: JoinHandle<WriterResult>,
    failure: Arc<OnceLock<String>>,
}

/// What the writer did.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct LogReport {
    /// Rows written.
    pub written: u64,
    /// Control cycles the writer lost (overwritten in the ring before it read them).
    pub dropped: u64,
    /// The file was committed (it is at its destination).
    pub committed: bool,
}

/// Writes every sample of `stream` to `out` until the stream ends (its publisher is dropped);
/// returns (rows written, samples lost).
fn write_stream(
    stream: &mut Subscriber<CycleSample>,
    joint_count: usize,
    out: &mut dyn Write,
) -> std::io::Result<(u64, u64)> {
    let format = RunLogFormat::cell(joint_count);
    let mut w = std::io::BufWriter::new(out);
    writeln!(w, "{}", format.header())?;
    let mut written = 0u64;
    let mut row = String::with_capacity(512);
    loop {
        let mut any = false;
        while let Some(sample) = stream.try_next() {
            row.clear();
            format.write_row(&sample, &mut row);
            writeln!(w, "{row}")?;
            written += 1;
            any = true;
        }
        if stream.is_finished() {
            break;
        }
        if !any {
            w.flush()?;
            std::thread::sleep(std::time::Duration::from_millis(20));
        }
    }
    w.flush()?;
    Ok((written, stream.lost()))
}

/// Starts the writer thread: it reads `stream` (subscribe it before the session starts to log
/// every cycle) and writes the CSV for `joint_count` joints to `out`.
pub fn spawn_writer(
    mut stream: Subscriber<CycleSample>,
    joint_count: usize,
    out: Box<dyn LogTarget>,
) -> Result<LogWriter, std::io::Error> {
    let failure = Arc::new(OnceLock::new());
    let failed = Arc::clone(&failure);
    let handle = std::thread::Builder::new()
        .name("deflex-log".into())
        .spawn(move || -> WriterResult {
            let mut out = out;
            let result = write_stream(&mut stream, joint_count, &mut out);
            if let Err(e) = &result {
                // Seen at once by whoever polls `failure` (a full disk, a removed folder).
                let _ = failed.set(e.to_string());
            }
            (out, result)
        })?;
    Ok(LogWriter { handle, failure })
}

impl LogWriter {
    /// The write error that stopped the writer, as soon as it happened (`None` while it
    /// writes): the session's owner polls it to report a full disk during the run, not after.
    pub fn failure(&self) -> Option<&str> {
        self.failure.get().map(String::as_str)
    }

    /// Waits for the writer (the stream must end: the session's publisher dropped) and, when
    /// `commit`, makes the file appear at its destination; otherwise the partial file is
    /// discarded (an [`deflex_files::AtomicFile`] leaves whatever was at the destination
    /// untouched).
    pub fn finish(self, commit: bool) -> std::io::Result<LogReport> {
        let (target, result) = self
            .handle
            .join()
            .map_err(|_| std::io::Error::other("log writer thread panicked"))?;
        let (written, dropped) = result?;
        if commit {
            target.commit()?;
        }
        Ok(LogReport {
            written,
            dropped,
            committed: commit,
        })
    }
}
