//! Logging off the cycle path: the control thread pushes fixed-size [`LogRecord`]s into a
//! lock-free single-producer ring buffer (rtrb, pre-allocated); a writer thread drains it into a
//! CSV file with unit-named columns. A full buffer drops the record and counts it; the cycle
//! never blocks, allocates or touches the file.
//!
//! Columns: `time_s`, `q1_rad…qN_rad`, the raw reading `raw_fx_n…raw_mz_nm` (sensor frame), the
//! compensated reading `ws_fx_n…ws_mz_nm` (sensor frame), the TCP wrench `w_fx_n…w_mz_nm` (eq. 2,
//! base axes), δŝ `ds_x_m…ds_rz_rad` (eq. 15), ξ `xi_x_m…xi_rz_rad` (eq. 7), ε `eps_x_m…eps_rz_rad`
//! (eq. 5), the feed-forward's prior `ff_x_m…ff_rz_rad` and the arc length `path_s_m` (empty
//! without a table or while acquiring; [`crate::feedforward`]), `loop_gain` (the runaway
//! guard's estimate, empty when unknown), `cycle_us`, `flags`
//! (integer) and `status` (the flags and the latched fault by name).
//!
//! The writer streams into a [`LogTarget`]; for `deflex run` that is a
//! [`deflex_files::AtomicFile`], so the log appears at its path only when
//! [`LogWriter::finish`] commits it: a run that fails keeps the log a previous run left there.

use crate::controller::CycleOutput;
use crate::safety::Flags;
use deflex_model::MAX_JOINTS;
use std::io::Write;
use std::sync::Arc;
use std::sync::atomic::{AtomicU64, Ordering};
use std::thread::JoinHandle;

/// One logged control cycle (plain data, `Copy`).
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct LogRecord {
    /// Joint values (rad), first `joint_count` used.
    pub q_rad: [f64; MAX_JOINTS],
    /// Number of joints.
    pub joint_count: u8,
    /// Raw reading, sensor frame.
    pub raw_wrench: [f64; 6],
    /// Controller output of the cycle.
    pub out: CycleOutput,
    /// Duration of the cycle computation (µs).
    pub cycle_us: f64,
}

impl LogRecord {
    /// Builds a record (allocation-free).
    #[inline]
    pub fn new(q: &[f64], raw: &[f64; 6], out: &CycleOutput, cycle_us: f64) -> Self {
        let mut q_rad = [0.0; MAX_JOINTS];
        let n = q.len().min(MAX_JOINTS);
        q_rad[..n].copy_from_slice(&q[..n]);
        LogRecord {
            q_rad,
            joint_count: n as u8,
            raw_wrench: *raw,
            out: *out,
            cycle_us,
        }
    }
}

/// Producer end held by the control thread.
pub struct LogSink {
    producer: rtrb::Producer<LogRecord>,
    dropped: Arc<AtomicU64>,
}

impl LogSink {
    /// Pushes a record; if the ring is full the record is dropped and counted. Never blocks.
    #[inline]
    pub fn push(&mut self, record: LogRecord) {
        if self.producer.push(record).is_err() {
            self.dropped.fetch_add(1, Ordering::Relaxed);
        }
    }
    /// Records dropped so far.
    pub fn dropped(&self) -> u64 {
        self.dropped.load(Ordering::Relaxed)
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

type WriterResult = (Box<dyn LogTarget>, std::io::Result<u64>);

/// The writer thread; [`LogWriter::finish`] waits for it after the sink is dropped.
pub struct LogWriter {
    handle: JoinHandle<WriterResult>,
    dropped: Arc<AtomicU64>,
}

/// What the writer did.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct LogReport {
    /// Rows written.
    pub written: u64,
    /// Records dropped because the ring was full.
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
pub fn csv_row(r: &LogRecord) -> String {
    use std::fmt::Write as _;
    let mut s = String::with_capacity(512);
    let _ = write!(s, "{:.6}", r.out.time_s);
    for q in &r.q_rad[..usize::from(r.joint_count)] {
        let _ = write!(s, ",{q:.9}");
    }
    for block in [&r.raw_wrench, &r.out.wrench_sensor, &r.out.wrench_tcp] {
        for v in block {
            let _ = write!(s, ",{v:.4}");
        }
    }
    for block in [
        &r.out.delta_s_hat,
        &r.out.xi,
        &r.out.epsilon,
        &r.out.feedforward,
    ] {
        for v in block {
            let _ = write!(s, ",{v:.9}");
        }
    }
    if r.out.path_s_m.is_finite() {
        let _ = write!(s, ",{:.6}", r.out.path_s_m);
    } else {
        s.push(',');
    }
    if r.out.loop_gain.is_finite() {
        let _ = write!(s, ",{:.4}", r.out.loop_gain);
    } else {
        s.push(',');
    }
    let _ = write!(
        s,
        ",{:.2},{},{}",
        r.cycle_us,
        r.out.flags.0,
        Flags(r.out.flags.0).describe()
    );
    s
}

/// Creates the ring (`capacity` records, at least 16) and starts the writer thread on `out`.
pub fn spawn_writer(
    capacity: usize,
    joint_count: usize,
    out: Box<dyn LogTarget>,
) -> Result<(LogSink, LogWriter), std::io::Error> {
    let (producer, mut consumer) = rtrb::RingBuffer::<LogRecord>::new(capacity.max(16));
    let dropped = Arc::new(AtomicU64::new(0));
    let handle = std::thread::Builder::new()
        .name("deflex-log".into())
        .spawn(move || -> WriterResult {
            let mut out = out;
            let result = (|| -> std::io::Result<u64> {
                let mut w = std::io::BufWriter::new(&mut out);
                writeln!(w, "{}", csv_header(joint_count))?;
                let mut written = 0u64;
                loop {
                    let mut any = false;
                    while let Ok(record) = consumer.pop() {
                        writeln!(w, "{}", csv_row(&record))?;
                        written += 1;
                        any = true;
                    }
                    if consumer.is_abandoned() && consumer.is_empty() {
                        break;
                    }
                    if !any {
                        w.flush()?;
                        std::thread::sleep(std::time::Duration::from_millis(20));
                    }
                }
                w.flush()?;
                Ok(written)
            })();
            (out, result)
        })?;
    Ok((
        LogSink {
            producer,
            dropped: dropped.clone(),
        },
        LogWriter { handle, dropped },
    ))
}

impl LogWriter {
    /// Waits for the writer (drop the [`LogSink`] first) and, when `commit`, makes the file
    /// appear at its destination; otherwise the partial file is discarded (an
    /// [`deflex_files::AtomicFile`] leaves whatever was at the destination untouched).
    pub fn finish(self, commit: bool) -> std::io::Result<LogReport> {
        let (target, result) = self
            .handle
            .join()
            .map_err(|_| std::io::Error::other("log writer thread panicked"))?;
        let written = result?;
        if commit {
            target.commit()?;
        }
        Ok(LogReport {
            written,
            dropped: self.dropped.load(Ordering::Relaxed),
            committed: commit,
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::sync::Mutex;

    #[derive(Clone, Default)]
    struct Shared(Arc<Mutex<Vec<u8>>>);
    impl Write for Shared {
        fn write(&mut self, b: &[u8]) -> std::io::Result<usize> {
            self.0.lock().unwrap().extend_from_slice(b);
            Ok(b.len())
        }
        fn flush(&mut self) -> std::io::Result<()> {
            Ok(())
        }
    }

    #[test]
    fn rows_match_header_and_drops_are_counted() {
        let buf = Shared::default();
        let (mut sink, writer) = spawn_writer(16, 6, Box::new(Plain(buf.clone()))).unwrap();
        let mut out = CycleOutput::default();
        out.flags.set(Flags::SENSOR_TIMEOUT | Flags::LATCHED);
        for k in 0..10_000 {
            out.time_s = k as f64;
            sink.push(LogRecord::new(&[0.1; 6], &[1.0; 6], &out, 1.0));
        }
        let dropped = sink.dropped();
        drop(sink);
        let report = writer.finish(true).unwrap();
        assert_eq!(report.written + report.dropped, 10_000);
        assert_eq!(report.dropped, dropped);
        let text = String::from_utf8(buf.0.lock().unwrap().clone()).unwrap();
        let mut lines = text.lines();
        let header = lines.next().unwrap();
        let n = header.split(',').count();
        assert_eq!(n, 1 + 6 + 18 + 24 + 5);
        let row = lines.next().unwrap();
        assert_eq!(row.split(',').count(), n);
        assert!(row.ends_with("sensor_timeout|latched"));
    }
}

#[cfg(test)]
mod atomic_tests {
    use super::*;

    /// A run that fails (no commit) leaves the previous log as it was; a finished run replaces
    /// it whole.
    #[test]
    fn uncommitted_log_keeps_the_previous_file() {
        let dir = std::env::temp_dir().join(format!("deflex-log-atomic-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        let path = dir.join("run.csv");
        std::fs::write(&path, "previous session\n").unwrap();
        let write = |commit: bool| {
            let file = deflex_files::AtomicFile::create(&path).unwrap();
            let (mut sink, writer) = spawn_writer(64, 6, Box::new(file)).unwrap();
            sink.push(LogRecord::new(
                &[0.0; 6],
                &[0.0; 6],
                &CycleOutput::default(),
                1.0,
            ));
            drop(sink);
            writer.finish(commit).unwrap()
        };
        let report = write(false);
        assert_eq!((report.written, report.committed), (1, false));
        assert_eq!(
            std::fs::read_to_string(&path).unwrap(),
            "previous session\n"
        );
        // No temporary file is left behind.
        assert_eq!(std::fs::read_dir(&dir).unwrap().count(), 1);
        write(true);
        let text = std::fs::read_to_string(&path).unwrap();
        assert!(
            text.starts_with("time_s,q1_rad") && text.lines().count() == 2,
            "{text}"
        );
        let _ = std::fs::remove_dir_all(&dir);
    }
}
