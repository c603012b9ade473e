//! The CSV log written from the telemetry stream ([`deflex_record::csv_log`]).

use deflex_control::CycleOutput;
use deflex_record::csv_log::{Plain, spawn_writer};
use deflex_record::run_log::cycle_sample;
use deflex_telemetry::CycleSample;
use deflex_telemetry::Flags;

/// An in-memory file for a log writer: every clone writes into the same bytes.
#[derive(Clone, Default)]
struct SharedBuffer(std::sync::Arc<std::sync::Mutex<Vec<u8>>>);

impl SharedBuffer {
    /// What was written so far, as text.
    fn text(&self) -> String {
        String::from_utf8(self.0.lock().unwrap().clone()).unwrap()
    }
}

impl std::io::Write for SharedBuffer {
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
    let buf = SharedBuffer::default();
    let (mut publisher, ring) = deflex_telemetry::broadcast::<CycleSample>(16);
    let writer = spawn_writer(ring.subscribe(), 6, Box::new(Plain(buf.clone()))).unwrap();
    let mut out = CycleOutput::default();
    out.flags.set(Flags::SENSOR_TIMEOUT | Flags::LATCHED);
    for k in 0..10_000 {
        out.time_s = k as f64;
        publisher.publish(&cycle_sample(&[0.1; 6], &[1.0; 6], &out, 1.0));
    }
    drop(publisher);
    let report = writer.finish(true).unwrap();
    assert_eq!(report.written + report.dropped, 10_000);
    let text = buf.text();
    let mut lines = text.lines();
    let header = lines.next().unwrap();
    let n = header.split(',').count();
    assert_eq!(n, 1 + 6 + 18 + 24 + 5);
    let row = lines.next().unwrap();
    assert_eq!(row.split(',').count(), n);
    assert!(row.ends_with("sensor_timeout|latched"));
}

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
        let (mut publisher, ring) = deflex_telemetry::broadcast::<CycleSample>(64);
        let writer = spawn_writer(ring.subscribe(), 6, Box::new(file)).unwrap();
        let sample = cycle_sample(&[0.0; 6], &[0.0; 6], &CycleOutput::default(), 1.0);
        publisher.publish(&sample);
        drop(publisher);
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
