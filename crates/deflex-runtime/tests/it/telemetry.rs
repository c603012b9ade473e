//! The telemetry stream of a real session (KUKA RSI and Net F/T on loopback): the CSV log is
//! written from it, one row per control cycle; a sink that joins during the session reads the
//! same samples; a sink that falls behind loses the oldest samples, counted, without slowing the
//! session; the session's description is there for any sink. (The log's row format, the one
//! `deflex run` has always written, is checked in deflex-record's `run_log`.)

use crate::common;
use deflex_record::csv_log::{Plain, spawn_writer};
use deflex_record::run_log::RunLogFormat;
use deflex_runtime::WallClock;
use deflex_runtime::session::{RuntimeOptions, spawn};
use deflex_runtime::telemetry::{StreamSource, Telemetry, session_info};
use deflex_telemetry::Phase;

fn options() -> RuntimeOptions {
    RuntimeOptions {
        realtime: false,
        startup_timeout_s: 5.0,
        // The sessions end by a stop request; the backstop.
        idle_exit_s: Some(0.3),
        ..RuntimeOptions::default()
    }
}

/// What one session with a telemetry ring of `capacity` samples gave its sinks.
struct Sinks {
    summary: deflex_runtime::RunSummary,
    log: deflex_record::csv_log::LogReport,
    log_text: String,
    /// Subscribed before the session, read only at its end.
    idle: deflex_telemetry::Subscriber<deflex_telemetry::CycleSample>,
    /// Subscribed half a second into the session, read at its end.
    late: deflex_telemetry::Subscriber<deflex_telemetry::CycleSample>,
    info: deflex_telemetry::SessionInfo,
    status: deflex_runtime::LiveStatus,
}

fn session(capacity: usize) -> Sinks {
    let config = common::config();
    let ctrl = common::controller(config);
    let q = common::q0();
    let raw = common::raw_reading(&config, &q, [150.0, -80.0, 900.0, 0.0, 0.0, 0.0]);
    // The robot and the sensor stream until the session has ended (by a stop request).
    let (link, client, peers) =
        common::loopback_cell(Default::default(), raw, q, f64::INFINITY, f64::INFINITY);
    let info = session_info(&ctrl, StreamSource::Runtime, "kuka-rsi", 0.004);
    let telemetry = Telemetry::new(info, capacity);
    let log_path = std::env::temp_dir().join(format!(
        "deflex-runtime-telemetry-{capacity}-{}.csv",
        std::process::id()
    ));
    let file = std::fs::File::create(&log_path).unwrap();
    let log = spawn_writer(telemetry.subscribe(), 6, Box::new(Plain(file))).unwrap();
    let idle = telemetry.subscribe();
    let runtime = spawn(
        ctrl,
        Box::new(link),
        Box::new(client),
        WallClock::new(),
        telemetry,
        options(),
    )
    .unwrap();
    let info = (**runtime.session_info()).clone();
    std::thread::sleep(std::time::Duration::from_millis(500));
    let late = runtime.telemetry().subscribe();
    let status = runtime.status();
    // The late sink reads 0.3 s of the session live, then the stop ramps the correction out
    // (0.5 s) while the robot still streams.
    std::thread::sleep(std::time::Duration::from_millis(300));
    runtime.request_stop();
    let summary = common::finish(runtime);
    peers.join();
    let log = log.finish(true).unwrap();
    let log_text = std::fs::read_to_string(&log_path).unwrap();
    let _ = std::fs::remove_file(&log_path);
    Sinks {
        summary,
        log,
        log_text,
        idle,
        late,
        info,
        status,
    }
}

#[test]
fn the_log_is_written_from_the_stream_and_sinks_join_any_time() {
    // A ring larger than the whole session: no sink loses anything.
    let mut s = session(4096);
    assert_eq!(s.summary.error, None);
    let cycles = s.summary.cycles;
    assert!(cycles > 50, "{cycles} cycles");
    // The description is there for any sink.
    assert_eq!(s.info.source, StreamSource::Runtime);
    assert_eq!(s.info.joint_names.len(), 6);
    assert_eq!(s.info.protocol, "kuka-rsi");
    assert_eq!(s.info.control_period_s, common::config().period_s);
    // One row per control cycle.
    assert_eq!((s.log.written, s.log.dropped), (cycles, 0));
    let mut lines = s.log_text.lines();
    assert_eq!(lines.next(), Some(RunLogFormat::cell(6).header().as_str()));
    assert_eq!(lines.count() as u64, cycles);
    // The idle sink has every cycle, in order.
    let mut n = 0;
    s.idle.drain(|sample| {
        n += 1;
        assert_eq!(sample.cycle, n);
    });
    assert_eq!((n, s.idle.lost()), (cycles, 0));
    // The late sink reads what came after it joined, whole, up to the last cycle.
    let mut previous = 0;
    let mut seen = 0u64;
    s.late.drain(|sample| {
        assert!(sample.cycle > previous, "{} after {previous}", sample.cycle);
        assert_eq!(sample.q().len(), 6);
        assert!(sample.tcp_position().norm() > 0.5 && sample.time_s.is_finite());
        previous = sample.cycle;
        seen += 1;
    });
    assert!(
        seen > 0 && previous == cycles,
        "{seen} samples, last {previous}"
    );
    assert!(s.late.is_finished());
    // The live status came from the stream.
    assert!(
        s.status.cycles > 0 && s.status.telegrams > 0 && s.status.phase != Phase::Idle,
        "{:?}",
        s.status
    );
}

#[test]
fn a_sink_that_falls_behind_loses_the_oldest_counted_without_slowing_the_session() {
    let mut s = session(16);
    assert_eq!(s.summary.error, None);
    let cycles = s.summary.cycles;
    assert!(cycles > 50, "{cycles} cycles");
    // The idle sink keeps the ring's last 16 cycles and counts the rest as lost.
    let mut kept = Vec::new();
    s.idle.drain(|sample| kept.push(sample.cycle));
    assert_eq!(kept, ((cycles - 15)..=cycles).collect::<Vec<_>>());
    assert_eq!(s.idle.lost(), cycles - 16);
    // The log, reading as it goes, accounts for every cycle.
    assert_eq!(s.log.written + s.log.dropped, cycles);
    assert_eq!(s.log_text.lines().count() as u64, s.log.written + 1);
}
