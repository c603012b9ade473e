//! The control thread of a real session allocates nothing per cycle with the ROS 2 parts on:
//! the wrench comes from a `WrenchStamped` topic through [`Ros2SensorLink`] and, in the second
//! run, the telemetry stream is published by a [`Ros2Bridge`] (every topic at the control
//! rate, a DDS subscriber reading). Measured in the control thread itself, as the runtime's no-allocation
//! session does without ROS 2 (`no_alloc::runtime`): the clock that paces that thread reads the thread's allocation
//! count (the counting allocator counts per thread) each time it sleeps until the next cycle.
//! The robot is a KUKA RSI endpoint on loopback. The control cycle's statistics of the runs with
//! the bridge off and on are printed (`--nocapture`), not asserted (timing on a shared machine
//! is not a test).

use super::cycle_counter::CountingClock;
use super::setup::kuka_robot;
use dds::{domain, now_ns, publisher, sensor_settings, subscriber, wait_until, wrench};
use deflex_control::{Controller, ControllerConfig};
use deflex_io::rsi::{RsiConfig, RsiLink};
use deflex_ros2::{BridgeReport, BridgeSettings, Ros2Bridge, Ros2SensorLink, join};
use deflex_runtime::session::{RuntimeOptions, spawn};
use deflex_runtime::telemetry::{StreamSource, session_info};
use deflex_runtime::{RunSummary, Telemetry};
use deflex_telemetry::ros::{JointStateMsg, Ros2Qos, Ros2Topic, WrenchStampedMsg};
use std::sync::Arc;
use std::sync::atomic::{AtomicBool, Ordering};
use std::time::{Duration, Instant};

/// deflex-ros2's DDS test helpers (its tests' `dds` module), compiled here by `#[path]`, not
/// copied: the domains of this process (offsets 4–7 here, 0–3 there), the bounded wait for
/// discovery, publishers and subscribers at deflex's QoS, a driver's `WrenchStamped`.
#[path = "../../../../deflex-ros2/tests/it/dds.rs"]
mod dds;

/// What one session gave: its summary, the control thread's allocations in the measured
/// cycles, the number of those cycles, and the bridge's report.
struct Measured {
    summary: RunSummary,
    allocations: u64,
    measured: u64,
    bridge: Option<BridgeReport>,
}

/// One session on DDS domain `d`: the robot sends joint values every 4 ms, a driver publishes a
/// wrench every 2 ms; after 150 control cycles the session is stopped, the correction ramps out
/// while both still stream, then they stop. With `bridge`, the stream is published on domain
/// `d + 1` to a subscriber.
fn session(d: u16, bridge: bool) -> Measured {
    let q = deflex_model::TX200_FORMING_Q_DEG.map(f64::to_radians);
    let config = ControllerConfig {
        bias: Some([0.0; 6]),
        ..ControllerConfig::default()
    };
    let ctrl = Controller::new(deflex_model::builtin("tx200").unwrap(), config).unwrap();
    let mut settings = sensor_settings(d, 16, Ros2Qos::SensorData);
    settings.max_age = Duration::from_secs(1);
    let sensor = Ros2SensorLink::open(&settings).unwrap();
    let mut driver_node = join(d, "/", "driver").unwrap();
    let driver =
        publisher::<WrenchStampedMsg>(&mut driver_node, "/ati/wrench", Ros2Qos::SensorData);
    let counts = sensor.counts_handle();
    // The driver is discovered before the session starts (the sensor must not time out).
    wait_until("the driver discovered", || {
        driver.publish(wrench("ati_ft", now_ns(), -50.0)).unwrap();
        std::thread::sleep(Duration::from_millis(5));
        counts.counts().accepted > 0
    });
    let telemetry = Telemetry::new(
        session_info(&ctrl, StreamSource::Runtime, "test", 0.004),
        1024,
    );
    let mut listener = None;
    let bridge = bridge.then(|| {
        let settings = BridgeSettings {
            domain_id: d + 1,
            namespace: "/deflex_alloc".into(),
            node_name: "bridge".into(),
            qos: Ros2Qos::Reliable,
            depth: 100,
            publish_rate_hz: 100.0,
            diagnostics_rate_hz: 10.0,
            topics: Ros2Topic::ALL.to_vec(),
        };
        let b =
            Ros2Bridge::spawn(&settings, telemetry.subscribe(), telemetry.info().clone()).unwrap();
        let mut node = join(d + 1, "/", "listener").unwrap();
        let sub =
            subscriber::<JointStateMsg>(&mut node, "/deflex_alloc/joint_states", Ros2Qos::Reliable);
        listener = Some((node, sub));
        b
    });
    let link = RsiLink::bind("127.0.0.1:0", RsiConfig::default()).unwrap();
    let robot = kuka_robot(link.local_addr().unwrap(), q, f64::INFINITY);
    let driving = Arc::new(AtomicBool::new(true));
    let publishing = {
        let driving = driving.clone();
        std::thread::spawn(move || {
            while driving.load(Ordering::Acquire) {
                let _ = driver.publish(wrench("ati_ft", now_ns(), -50.0));
                std::thread::sleep(Duration::from_millis(2));
            }
            drop(driver_node);
        })
    };
    let clock = CountingClock::new();
    let options = RuntimeOptions {
        realtime: false,
        lock_memory: false,
        startup_timeout_s: 5.0,
        // The session ends by a stop request; the backstop.
        idle_exit_s: Some(0.3),
        ..RuntimeOptions::default()
    };
    let runtime = spawn(
        ctrl,
        Box::new(link),
        Box::new(sensor),
        clock.clone(),
        telemetry,
        options,
    )
    .unwrap();
    wait_until("150 control cycles", || runtime.status().cycles >= 150);
    // Stopped while the robot and the driver still stream: the correction ramps out and the
    // link sends its last answer (a robot that fell silent first would latch robot_link_lost
    // and leave the link waiting to send it).
    runtime.request_stop();
    let deadline = Instant::now() + Duration::from_secs(30);
    while !runtime.is_finished() && Instant::now() < deadline {
        std::thread::sleep(Duration::from_millis(20));
    }
    let summary = runtime.join();
    driving.store(false, Ordering::Release);
    robot.join();
    publishing.join().unwrap();
    let bridge = bridge.map(|b| b.finish().unwrap());
    drop(listener);
    Measured {
        summary,
        allocations: clock.counter.allocations(0),
        measured: clock.counter.cycles(0),
        bridge,
    }
}

#[test]
fn control_thread_allocates_nothing_with_the_ros2_sensor_and_the_bridge() {
    for (bridge, d) in [(false, domain(4)), (true, domain(6))] {
        let m = session(d, bridge);
        let (s, c) = (&m.summary, &m.summary.control);
        eprintln!(
            "bridge {}: {} allocations in {} measured cycles of {}; control cycle p50 {} µs, \
             p99 {} µs, max {} µs; {} sensor samples; fault {:?}; bridge {:?}",
            if bridge { "on" } else { "off" },
            m.allocations,
            m.measured,
            s.cycles,
            c.p50_us,
            c.p99_us,
            c.max_us,
            s.samples,
            s.fault.map(|f| f.kind),
            m.bridge,
        );
        assert_eq!(s.error, None);
        assert!(m.measured > 100, "{} cycles measured", m.measured);
        assert!(s.samples > 100, "{} sensor samples", s.samples);
        if let Some(r) = &m.bridge {
            assert!(r.cycles_published > 100, "{r:?}");
        }
        assert_eq!(
            m.allocations, 0,
            "bridge {bridge}: {} allocations in {} cycles",
            m.allocations, m.measured
        );
    }
}
