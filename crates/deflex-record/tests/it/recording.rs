//! Recording and reading back: values, schemas, bounds and failures.

use deflex_record::{
    MIN_MAX_BYTES, McapRecorder, McapSink, ReadError, RecordError, RecordOptions, RecordStats,
    SessionRecord, channels, for_each_cycle,
};
use deflex_telemetry::CycleSample;
use deflex_telemetry::ros::{
    DiagnosticArrayMsg, JointStateMsg, PoseStampedMsg, RosMessage, TwistStampedMsg,
    Vector3StampedMsg, WrenchStampedMsg,
};
use deflex_telemetry::synthetic::SyntheticCell;
use std::io::{Cursor, Write};
use std::path::PathBuf;

fn temp_dir(name: &str) -> PathBuf {
    let dir = std::env::temp_dir().join(format!("deflex-record-{name}-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(&dir).unwrap();
    dir
}

fn record(samples: &[CycleSample], twin: bool, options: RecordOptions) -> (Vec<u8>, RecordStats) {
    let info = SyntheticCell::new(0.01, 1, twin).session_info();
    let mut sink = McapSink::new(Vec::new(), "memory", &info, options).unwrap();
    for s in samples {
        sink.write(s).unwrap();
    }
    sink.finish().unwrap()
}

fn synthetic(n: usize, twin: bool) -> Vec<CycleSample> {
    let mut cell = SyntheticCell::new(0.01, 7, twin);
    (0..n).map(|_| cell.next_sample()).collect()
}

fn close(a: f64, b: f64, tol: f64) -> bool {
    (a - b).abs() <= tol || (a.is_nan() && b.is_nan())
}

#[test]
fn cycles_read_back_as_written() {
    let samples = synthetic(600, true);
    let options = RecordOptions {
        start_unix_ns: Some(1_700_000_000_000_000_000),
        ..RecordOptions::default()
    };
    let (bytes, stats) = record(&samples, true, options);
    assert_eq!(stats.recorded, 600);
    let dir = temp_dir("roundtrip");
    let path = dir.join("run.mcap");
    std::fs::write(&path, &bytes).unwrap();
    let mut back = Vec::new();
    let summary = for_each_cycle(&path, |s| back.push(*s)).unwrap();
    assert_eq!(summary.cycles, 600);
    assert!(summary.path_error_known);
    let session = summary.session.unwrap();
    assert_eq!(session.label, "SIMULATED");
    assert_eq!(session.start_unix_ns, 1_700_000_000_000_000_000);
    assert_eq!(session.joint_names.len(), 6);
    let mut diagnostics_rows = 0;
    for (w, r) in samples.iter().zip(&back) {
        assert_eq!(w.cycle, r.cycle);
        // The log time is integer nanoseconds.
        assert!(close(w.time_s, r.time_s, 1e-9), "{} {}", w.time_s, r.time_s);
        assert_eq!(w.q(), r.q());
        for (a, b) in [
            (&w.wrench_raw, &r.wrench_raw),
            (&w.wrench_sensor, &r.wrench_sensor),
            (&w.wrench_tcp, &r.wrench_tcp),
            (&w.deflection, &r.deflection),
            (&w.correction, &r.correction),
            (&w.error, &r.error),
            (&w.feedforward, &r.feedforward),
        ] {
            assert_eq!(a, b);
        }
        assert_eq!(w.tcp_position_m, r.tcp_position_m);
        assert_eq!(w.truth_error_m, r.truth_error_m);
        for i in 0..3 {
            for j in 0..3 {
                assert!(close(w.tcp_rotation[i][j], r.tcp_rotation[i][j], 1e-12));
            }
        }
        assert_eq!(w.phase_code, r.phase_code);
        assert_eq!(w.flags, r.flags);
        if r.cycle_time_s.is_finite() {
            diagnostics_rows += 1;
            assert_eq!(w.cycle_time_s, r.cycle_time_s);
            assert_eq!(w.late_answers, r.late_answers);
            assert!(close(w.path_s_m, r.path_s_m, 0.0));
        }
    }
    // 6 s at 10 Hz, plus the changes of state (taring → running, saturation on and off).
    assert!(diagnostics_rows >= 60, "{diagnostics_rows}");
    let _ = std::fs::remove_dir_all(dir);
}

#[test]
fn channels_have_the_ros2_schemas_and_encodings() {
    let (bytes, _) = record(&synthetic(50, true), true, RecordOptions::default());
    let summary = mcap::Summary::read(&bytes)
        .unwrap()
        .expect("summary written");
    let expected: [(&str, &str, &str); 12] = [
        (
            channels::JOINT_STATES,
            JointStateMsg::NAME,
            JointStateMsg::DEFINITION,
        ),
        (
            channels::WRENCH_RAW,
            WrenchStampedMsg::NAME,
            WrenchStampedMsg::DEFINITION,
        ),
        (
            channels::WRENCH_SENSOR,
            WrenchStampedMsg::NAME,
            WrenchStampedMsg::DEFINITION,
        ),
        (
            channels::WRENCH_TCP,
            WrenchStampedMsg::NAME,
            WrenchStampedMsg::DEFINITION,
        ),
        (
            channels::TCP_POSE,
            PoseStampedMsg::NAME,
            PoseStampedMsg::DEFINITION,
        ),
        (
            channels::PROGRAM_POSE,
            PoseStampedMsg::NAME,
            PoseStampedMsg::DEFINITION,
        ),
        (
            channels::DEFLECTION,
            TwistStampedMsg::NAME,
            TwistStampedMsg::DEFINITION,
        ),
        (
            channels::CORRECTION,
            TwistStampedMsg::NAME,
            TwistStampedMsg::DEFINITION,
        ),
        (
            channels::ERROR,
            TwistStampedMsg::NAME,
            TwistStampedMsg::DEFINITION,
        ),
        (
            channels::FEEDFORWARD,
            TwistStampedMsg::NAME,
            TwistStampedMsg::DEFINITION,
        ),
        (
            channels::PATH_ERROR,
            Vector3StampedMsg::NAME,
            Vector3StampedMsg::DEFINITION,
        ),
        (
            channels::DIAGNOSTICS,
            DiagnosticArrayMsg::NAME,
            DiagnosticArrayMsg::DEFINITION,
        ),
    ];
    for (topic, name, definition) in expected {
        let channel = summary
            .channels
            .values()
            .find(|c| c.topic == topic)
            .unwrap_or_else(|| panic!("{topic} missing"));
        assert_eq!(channel.message_encoding, "cdr", "{topic}");
        let schema = channel.schema.as_ref().unwrap();
        assert_eq!(schema.name, name, "{topic}");
        assert_eq!(schema.encoding, "ros2msg", "{topic}");
        assert_eq!(&schema.data[..], definition.as_bytes(), "{topic}");
    }
    let session = summary
        .channels
        .values()
        .find(|c| c.topic == channels::SESSION)
        .unwrap();
    assert_eq!(session.message_encoding, "json");
    assert_eq!(session.schema.as_ref().unwrap().encoding, "jsonschema");
    // Each message decodes as its channel's type; one message per channel per cycle.
    let stats = summary.stats.as_ref().unwrap();
    let per_channel = |topic: &str| {
        let id = summary
            .channels
            .values()
            .find(|c| c.topic == topic)
            .unwrap()
            .id;
        stats.channel_message_counts[&id]
    };
    assert_eq!(per_channel(channels::WRENCH_TCP), 50);
    assert_eq!(per_channel(channels::PATH_ERROR), 50);
    assert!(per_channel(channels::DIAGNOSTICS) >= 5);
    for message in mcap::MessageStream::new(&bytes).unwrap() {
        let message = message.unwrap();
        let data = &message.data[..];
        let ok = match message.channel.schema.as_ref().map(|s| s.name.as_str()) {
            Some(JointStateMsg::NAME) => {
                deflex_telemetry::ros::decode::<JointStateMsg>(data).is_ok()
            }
            Some(WrenchStampedMsg::NAME) => {
                deflex_telemetry::ros::decode::<WrenchStampedMsg>(data).is_ok()
            }
            Some(PoseStampedMsg::NAME) => {
                deflex_telemetry::ros::decode::<PoseStampedMsg>(data).is_ok()
            }
            Some(TwistStampedMsg::NAME) => {
                deflex_telemetry::ros::decode::<TwistStampedMsg>(data).is_ok()
            }
            Some(Vector3StampedMsg::NAME) => {
                deflex_telemetry::ros::decode::<Vector3StampedMsg>(data).is_ok()
            }
            Some(DiagnosticArrayMsg::NAME) => {
                deflex_telemetry::ros::decode::<DiagnosticArrayMsg>(data).is_ok()
            }
            _ => serde_json::from_slice::<SessionRecord>(data).is_ok(),
        };
        assert!(ok, "{}", message.channel.topic);
    }
}

#[test]
fn a_real_cell_recording_has_no_path_error() {
    let (bytes, _) = record(&synthetic(20, false), false, RecordOptions::default());
    let summary = mcap::Summary::read(&bytes).unwrap().unwrap();
    let stats = summary.stats.unwrap();
    let id = summary
        .channels
        .values()
        .find(|c| c.topic == channels::PATH_ERROR)
        .unwrap()
        .id;
    assert_eq!(
        stats.channel_message_counts.get(&id).copied().unwrap_or(0),
        0
    );
}

#[test]
fn the_file_stops_growing_at_its_cap_and_stays_readable() {
    let options = RecordOptions {
        max_bytes: MIN_MAX_BYTES,
        compress: false,
        ..RecordOptions::default()
    };
    let info = SyntheticCell::new(0.01, 1, true).session_info();
    let mut sink = McapSink::new(Vec::new(), "memory", &info, options).unwrap();
    let mut cell = SyntheticCell::new(0.01, 3, true);
    let mut written = 0u64;
    for _ in 0..40_000 {
        if sink.write(&cell.next_sample()).unwrap() {
            written += 1;
        }
    }
    assert!(sink.is_capped());
    let (bytes, stats) = sink.finish().unwrap();
    assert!((bytes.len() as u64) <= MIN_MAX_BYTES, "{}", bytes.len());
    assert_eq!(stats.recorded, written);
    assert_eq!(stats.recorded + stats.after_cap, 40_000);
    assert!(stats.after_cap > 0);
    let dir = temp_dir("cap");
    let path = dir.join("capped.mcap");
    std::fs::write(&path, &bytes).unwrap();
    let summary = for_each_cycle(&path, |_| {}).unwrap();
    assert_eq!(summary.cycles, written);
    let _ = std::fs::remove_dir_all(dir);
}

/// A writer on a disk that fills up after `room` bytes.
struct FullDisk {
    room: usize,
}

impl Write for FullDisk {
    fn write(&mut self, buf: &[u8]) -> std::io::Result<usize> {
        if self.room == 0 {
            return Err(std::io::Error::from(std::io::ErrorKind::StorageFull));
        }
        let n = buf.len().min(self.room);
        self.room -= n;
        Ok(n)
    }
    fn flush(&mut self) -> std::io::Result<()> {
        Ok(())
    }
}

#[test]
fn a_full_disk_is_a_clear_error() {
    let info = SyntheticCell::new(0.01, 1, true).session_info();
    let mut sink = McapSink::new(
        FullDisk { room: 300_000 },
        "/data/run.mcap",
        &info,
        RecordOptions::default(),
    )
    .unwrap();
    let mut cell = SyntheticCell::new(0.01, 3, true);
    let mut failure = None;
    for _ in 0..100_000 {
        if let Err(e) = sink.write(&cell.next_sample()) {
            failure = Some(e);
            break;
        }
    }
    let failure = match failure {
        Some(e) => e,
        None => sink.finish().map(|_| ()).unwrap_err(),
    };
    let text = failure.to_string();
    assert!(matches!(failure, RecordError::DiskFull { .. }), "{text}");
    assert!(
        text.contains("/data/run.mcap") && text.contains("disk full"),
        "{text}"
    );
}

#[test]
fn the_recorder_thread_records_every_sample_and_replaces_the_file_only_at_the_end() {
    let dir = temp_dir("thread");
    let path = dir.join("session.mcap");
    std::fs::write(&path, b"earlier recording").unwrap();
    let (mut publisher, ring) = deflex_telemetry::broadcast::<CycleSample>(100_000);
    let cell = SyntheticCell::new(0.01, 5, false);
    let info = std::sync::Arc::new(cell.session_info());
    let recorder = McapRecorder::spawn(&path, &ring, info).unwrap();
    let mut cell = cell;
    for _ in 0..2_000 {
        publisher.publish(&cell.next_sample());
    }
    // Still recording: the earlier file is untouched.
    assert_eq!(std::fs::read(&path).unwrap(), b"earlier recording");
    drop(publisher);
    let report = recorder.finish().unwrap();
    assert_eq!(report.stats.recorded, 2_000);
    assert_eq!(report.lost, 0);
    let summary = for_each_cycle(&path, |_| {}).unwrap();
    assert_eq!(summary.cycles, 2_000);
    assert!(!summary.path_error_known);
    // No temporary file is left beside it.
    let names: Vec<_> = std::fs::read_dir(&dir)
        .unwrap()
        .map(|e| e.unwrap().file_name())
        .collect();
    assert_eq!(names.len(), 1, "{names:?}");
    let _ = std::fs::remove_dir_all(dir);
}

#[test]
fn foreign_and_damaged_files_are_named_errors() {
    let dir = temp_dir("foreign");
    let text = dir.join("log.csv");
    std::fs::write(&text, "time_s,q1_rad\n0,0\n").unwrap();
    let e = for_each_cycle(&text, |_| {}).unwrap_err();
    assert!(matches!(e, ReadError::NotMcap { .. }), "{e}");
    assert!(e.to_string().contains("log.csv"));

    // An MCAP file of someone else's.
    let mut other = mcap::Writer::new(Cursor::new(Vec::new())).unwrap();
    let id = other
        .add_channel(0, "/camera/image", "raw", &Default::default())
        .unwrap();
    other
        .write_to_known_channel(
            &mcap::records::MessageHeader {
                channel_id: id,
                sequence: 1,
                log_time: 1,
                publish_time: 1,
            },
            &[1, 2, 3],
        )
        .unwrap();
    other.finish().unwrap();
    let foreign = dir.join("camera.mcap");
    std::fs::write(&foreign, other.into_inner().into_inner()).unwrap();
    let e = for_each_cycle(&foreign, |_| {}).unwrap_err();
    assert!(e.to_string().contains("/camera/image"), "{e}");

    // A recording cut short.
    let (bytes, _) = record(&synthetic(300, true), true, RecordOptions::default());
    let cut = dir.join("cut.mcap");
    std::fs::write(&cut, &bytes[..bytes.len() / 2]).unwrap();
    let e = for_each_cycle(&cut, |_| {}).unwrap_err();
    assert!(matches!(e, ReadError::Mcap { .. }), "{e}");
    assert!(e.to_string().contains("cut.mcap"));
    let _ = std::fs::remove_dir_all(dir);
}

/// A failed session discards its recording: the earlier file stays whole and nothing is left
/// beside it, also when the stream ended before `finish_with` was called.
#[test]
fn a_discarded_recording_leaves_the_earlier_file_whole() {
    let dir = temp_dir("discard");
    let path = dir.join("session.mcap");
    std::fs::write(&path, b"earlier recording").unwrap();
    let (mut publisher, ring) = deflex_telemetry::broadcast::<CycleSample>(10_000);
    let mut cell = SyntheticCell::new(0.01, 5, false);
    let info = std::sync::Arc::new(cell.session_info());
    let recorder = McapRecorder::spawn(&path, &ring, info).unwrap();
    for _ in 0..500 {
        publisher.publish(&cell.next_sample());
    }
    drop(publisher);
    // The stream has ended; the recorder waits for the verdict.
    std::thread::sleep(std::time::Duration::from_millis(150));
    assert!(!recorder.is_finished());
    assert_eq!(std::fs::read(&path).unwrap(), b"earlier recording");
    let report = recorder.finish_with(false).unwrap();
    assert_eq!(report.stats.recorded, 500);
    assert_eq!(std::fs::read(&path).unwrap(), b"earlier recording");
    let names: Vec<_> = std::fs::read_dir(&dir).unwrap().collect();
    assert_eq!(names.len(), 1, "a temporary file was left behind");
    let _ = std::fs::remove_dir_all(dir);
}

/// A twin-cell stream (the twin's own, no controller) names the cell's state in `/diagnostics`
/// and reads back with it.
#[test]
fn twin_cell_states_are_named_and_read_back() {
    use deflex_telemetry::{CellState, StreamSource};
    let mut info = SyntheticCell::new(0.02, 1, true).session_info();
    info.source = StreamSource::TwinCell;
    let mut sink = McapSink::new(Vec::new(), "memory", &info, RecordOptions::default()).unwrap();
    let states = [CellState::Waiting, CellState::Forming, CellState::Finished];
    for (k, state) in states.iter().enumerate() {
        let s = CycleSample {
            time_s: k as f64,
            cycle: k as u64 + 1,
            phase_code: state.code(),
            ..CycleSample::default()
        };
        sink.write(&s).unwrap();
    }
    let (bytes, _) = sink.finish().unwrap();
    let dir = temp_dir("twincell");
    let path = dir.join("cell.mcap");
    std::fs::write(&path, &bytes).unwrap();
    let mut back = Vec::new();
    let summary = for_each_cycle(&path, |s| back.push(s.phase_code)).unwrap();
    assert_eq!(summary.session.unwrap().source, "twin-cell");
    assert_eq!(back, states.map(CellState::code).to_vec());
    assert_eq!(StreamSource::TwinCell.phase_name(back[1]), "forming");
    let _ = std::fs::remove_dir_all(dir);
}
