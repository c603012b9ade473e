//! The control thread's whole per-cycle path allocates nothing, measured **in the control
//! thread of a real session**: the clock that paces it reads that thread's allocation count
//! (the counting allocator counts per thread) every time the thread sleeps until its next
//! cycle, so the difference between two wake-ups is everything one cycle did — reading the
//! joint and wrench messages, the law (eq. 15, 17, limiter, safety, runaway guard), the joint
//! map of RSI `AK` answers, the correction command, the telemetry sample filled and published
//! (with the CSV log and a second sink subscribed) and the bookkeeping. The session runs a KUKA
//! RSI robot and a Net F/T on loopback, first in contact, then with the sensor silent (the fault
//! and the ramp to the safe value are measured too). The per-answer send shaper is measured in
//! the test's own thread.

use super::count;
use super::cycle_counter::CountingClock;
use super::setup::{config, controller, finish, loopback_cell, q0, raw_reading, telemetry};
use deflex_record::csv_log::{Plain, spawn_writer};
use deflex_runtime::send_shaper::{LinkDirective, SendShaper, SendShaperConfig};
use deflex_runtime::session::{RuntimeOptions, spawn};
use deflex_telemetry::Flags;

#[test]
fn control_thread_cycle_and_publish_allocate_nothing() {
    let mut config = config();
    config.wrench.lowpass_hz = Some(30.0);
    config.safety.sensor_timeout_s = 0.2;
    // The fault measured is the sensor's silence: a robot held back 50 ms by a loaded machine
    // must not latch robot_link_lost first (the robot emulator is a thread of this test).
    config.safety.robot_timeout_s = 1.0;
    config.limiter.ramp_out_s = 0.2;
    let ctrl = controller(config);
    let q = q0();
    let raw = raw_reading(&config, &q, [300.0, -200.0, 900.0, 1.0, 2.0, -1.0]);
    let rsi = deflex_io::rsi::RsiConfig {
        answer: deflex_io::rsi::RsiAnswer::Joint(deflex_io::rsi::JointTag::Ak),
        ..Default::default()
    };
    // The robot and the sensor stream until told: the sensor falls silent once the session
    // has run its cycles in contact, the robot streams on until the fault is ramped out.
    let (link, client, peers) = loopback_cell(rsi, raw, q, f64::INFINITY, f64::INFINITY);
    let telemetry = telemetry(&ctrl);
    let log = spawn_writer(telemetry.subscribe(), 6, Box::new(Plain(std::io::sink()))).unwrap();
    let mut other_sink = telemetry.subscribe();
    let clock = CountingClock::new();
    let options = RuntimeOptions {
        realtime: false,
        startup_timeout_s: 5.0,
        // Ended by a stop request once the fault is ramped out; the backstop.
        idle_exit_s: Some(0.3),
        ..RuntimeOptions::default()
    };
    let runtime = spawn(
        ctrl,
        Box::new(link),
        Box::new(client),
        clock.clone(),
        telemetry,
        options,
    )
    .unwrap();
    // 120 cycles (1.2 s) in contact, then the sensor's silence: latched, then ramped to zero.
    wait_for_status(&runtime, "120 cycles", |s| s.cycles >= 120);
    peers.silence_sensor();
    wait_for_status(&runtime, "the fault ramped out", |s| {
        s.flags.has(Flags::LATCHED) && s.xi_m == [0.0; 3] && s.xi_rot_rad == 0.0
    });
    runtime.request_stop();
    let summary = finish(runtime);
    peers.join();
    let report = log.finish(true).unwrap();
    let received = other_sink.drain(|_| {});
    let (allocations, measured) = (clock.counter.allocations(0), clock.counter.cycles(0));
    eprintln!(
        "control thread: {allocations} allocations in {measured} measured cycles of {}; log \
         {} rows; second sink {received} samples; fault {:?}",
        summary.cycles, report.written, summary.fault
    );
    assert_eq!(summary.error, None);
    // The session did the work: cycles in contact, then the sensor's silence latched and was
    // ramped out, and every cycle reached both sinks.
    assert!(measured > 100, "{measured} cycles measured");
    assert_eq!(
        summary.fault.map(|f| f.kind),
        Some(deflex_telemetry::FaultKind::SensorTimeout)
    );
    assert!(summary.max_xi_m > 1e-4, "{}", summary.max_xi_m);
    assert_eq!(report.written + report.dropped, summary.cycles);
    assert_eq!(received as u64 + other_sink.lost(), summary.cycles);
    assert_eq!(
        allocations, 0,
        "{allocations} allocations in {measured} cycles"
    );
}

#[test]
fn send_shaper_allocates_nothing() {
    let mut shaper = SendShaper::new(SendShaperConfig::new([0.02; 6], [0.008; 6], 0.004, 0.5));
    let (_, allocations) = count(|| {
        for k in 0..5000 {
            let target = [(k % 7) as f64 * 1e-3; 6];
            let directive = [
                LinkDirective::Follow,
                LinkDirective::RampOut,
                LinkDirective::Hold,
            ][k / 500 % 3];
            std::hint::black_box(shaper.next(&target, directive));
        }
    });
    assert_eq!(allocations, 0);
}

/// Waits (bounded, 10 s) until `done` holds for the runtime's live status.
fn wait_for_status(
    runtime: &deflex_runtime::Runtime,
    what: &str,
    done: impl Fn(&deflex_runtime::LiveStatus) -> bool,
) {
    let deadline = std::time::Instant::now() + std::time::Duration::from_secs(10);
    loop {
        let status = runtime.status();
        if done(&status) {
            return;
        }
        assert!(
            std::time::Instant::now() < deadline,
            "{what}: not within 10 s ({status:?})"
        );
        std::thread::sleep(std::time::Duration::from_millis(5));
    }
}
