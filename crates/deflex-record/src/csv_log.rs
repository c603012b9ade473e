//! The CSV log, a sink of the telemetry stream (the runtime's `deflex_runtime::telemetry`): a
//! writer thread reads the session's [`CycleSample`]s through its own [`Subscriber`] and writes
//! one row per control cycle with unit-named columns. The control thread never waits for it,
//! never allocates for it and never touches the file; if the writer falls more than the ring's
//! capacity behind, the oldest cycles are lost to it and counted ([`LogReport::dropped`]).
//!
//! Columns: `time_s`, `q1_rad…qN_rad`, the raw reading `raw_fx_n…raw_mz_nm` (sensor frame), the
//! compensated reading `ws_fx_n…ws_mz_nm` (sensor frame), the TCP wrench `w_fx_n…w_mz_nm` (eq. 2,
//! base axes), δŝ `ds_x_m…ds_rz_rad` (eq. 15), ξ `xi_x_m…xi_rz_rad` (eq. 7), ε `eps_x_m…eps_rz_rad`
//! (eq. 5), the feed-forward's prior `ff_x_m…ff_rz_rad` and the arc length `path_s_m` (empty
//! without a table or while acquiring; [`deflex_control::feedforward`]), `loop_gain` (the runaway
//! guard's estimate, empty when unknown), `cycle_us`, `flags`
//! (integer) and `status` (the flags and the latched fault by name).
//!
//! The writer streams into a [`LogTarget`]; for `deflex run` that is a
//! [`deflex_files::AtomicFile`], so the log appears at its path only when
//! [`LogWriter::finish`] commits it: a run that fails keeps the log a previous run left there.

use deflex_control::{CycleOutput, RecordCycle};
use deflex_telemetry::Flags;
use deflex_telemetry::{CycleSample, Subscriber};
use std::io::Write;
use std::sync::{Arc, OnceLock};
use std::thread::JoinHandle;

/// One row of the log: a telemetry sample as the log writes it.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct LogRecord(pub CycleSample);

impl LogRecord {
    /// The row of a control cycle given its joint values `q`, raw reading `raw` (sensor frame),
    /// output `out` and computation time `cycle_us` (µs), without a controller at hand (the
    /// runtime fills whole samples; this is for tools and tests that write logs).
    pub fn new(q: &[f64], raw: &[f64; 6], out: &CycleOutput, cycle_us: f64) -> Self {
        let mut sample = CycleSample::default();
        sample.set_q(q);
        sample.wrench_raw = *raw;
        sample.record_output(out);
        sample.cycle_time_s = cycle_us * 1e-6;
        LogRecord(sample)
    }
}

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

const SUFFIXES: [&str; 6] = ["x_m", "y_m", "z_m", "rx_rad", "ry_rad", "rz_rad"];
const WRENCH: [&str; 6] = ["fx_n", "fy_n", "fz_n", "mx_nm", "my_nm", "mz_nm"];

/// CSV header for `joint_count` joints.
pub fn csv_header(joint_count: usize) -> String {
    let mut cols = vec!["time_s".to_string()];
    cols.extend((1..=joint_count).map(|i| format!("q{i}_rad")));
    for prefix in ["raw", "ws", "w"] {
        cols.extend(WRENCH.iter().map(|s| format!("{prefix}_{s}")));
    }
    for prefix in ["ds", "xi", "eps", "ff"] {
        cols.extend(SUFFIXES.iter().map(|s| format!("{prefix}_{s}")));
    }
    cols.extend(["path_s_m", "loop_gain", "cycle_us", "flags", "status"].map(String::from));
    cols.join(",")
}

/// One CSV row (allocates: writer thread only).
pub fn csv_row(record: &LogRecord) -> String {
    use std::fmt::Write as _;
    let r = &record.0;
    let mut s = String::with_capacity(512);
    let _ = write!(s, "{:.6}", r.time_s);
    for q in r.q() {
        let _ = write!(s, ",{q:.9}");
    }
    for block in [&r.wrench_raw, &r.wrench_sensor, &r.wrench_tcp] {
        for v in block {
            let _ = write!(s, ",{v:.4}");
        }
    }
    for block in [&r.deflection, &r.correction, &r.error, &r.feedforward] {
        for v in block {
            let _ = write!(s, ",{v:.9}");
        }
    }
    if r.path_s_m.is_finite() {
        let _ = write!(s, ",{:.6}", r.path_s_m);
    } else {
        s.push(',');
    }
    if r.loop_gain.is_finite() {
        let _ = write!(s, ",{:.4}", r.loop_gain);
    } else {
        s.push(',');
    }
    let _ = write!(
        s,
        ",{:.2},{},{}",
        r.cycle_time_s * 1e6,
        r.flags,
        Flags(r.flags).describe()
    );
    s
}

/// Writes every sample of `stream` to `out` until the stream ends (its publisher is dropped);
/// returns (rows written, samples lost).
fn write_stream(
    stream: &mut Subscriber<CycleSample>,
    joint_count: usize,
    out: &mut dyn Write,
) -> std::io::Result<(u64, u64)> {
    let mut w = std::io::BufWriter::new(out);
    writeln!(w, "{}", csv_header(joint_count))?;
    let mut written = 0u64;
    loop {
        let mut any = false;
        while let Some(sample) = stream.try_next() {
            writeln!(w, "{}", csv_row(&LogRecord(sample)))?;
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
