//! The control thread of a real session allocates nothing per cycle with the ROS 2 parts on:
//! the wrench comes from a `WrenchStamped` topic through [`Ros2SensorLink`] and, in the second
//! run, the telemetry stream is published by a [`Ros2Bridge`] (every topic at the control
//! rate, a DDS subscriber reading). Measured in the control thread itself, as the runtime's no-allocation
//! session does without ROS 2 (`no_alloc::runtime`): the clock that paces that thread reads the thread's allocation
//! count (the counting allocator counts per thread) each time it sleeps until the next cycle.
//! The robot is a KUKA RSI endpoint on loopback. The control cycle's statistics of the runs with
//! the bridge off and on are printed (`--nocapture`), not asserted (timing on a shared machine
//! is not a test).

use super::cycle_counter::CycleCounter;
use deflex_control::{Controller, ControllerConfig};
use deflex_io::RobotSideLink;
use deflex_io::rsi::{CorrectionMode, RsiConfig, RsiLink, RsiRobotEndpoint};
use deflex_ros2::{
    BridgeReport, BridgeSettings, Ros2Bridge, Ros2SensorLink, SensorSettings, join, message_type,
    qos_profile, ros_name,
};
use deflex_runtime::session::{RuntimeOptions, spawn};
use deflex_runtime::telemetry::{Source, session_info};
use deflex_runtime::{Clock, RunSummary, Telemetry, WallClock};
use deflex_telemetry::ros::{
    Header, JointState, Ros2Qos, Ros2Topic, Vector3, Wrench, WrenchStamped,
};
use ros2_client::{Node, Publisher, Subscription};
use std::sync::Arc;
use std::sync::atomic::{AtomicBool, Ordering};
use std::time::{Duration, Instant};

/// Wall time that records, at every `sleep_until` (called by the control thread only, once per
/// cycle), the allocations its caller made since the previous call (from the third call on: the
/// first two include the thread's start).
#[derive(Clone)]
struct CountingClock {
    inner: WallClock,
    counter: Arc<CycleCounter<1>>,
}

impl Clock for CountingClock {
    fn now(&self) -> f64 {
        self.inner.now()
    }
    fn sleep_until(&self, t_s: f64) {
        self.counter.cycle(0);
        self.inner.sleep_until(t_s)
    }
}

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
    let driver = publisher::<WrenchStamped>(&mut driver_node, "/ati/wrench", Ros2Qos::SensorData);
    let counts = sensor.counts_handle();
    // The driver is discovered before the session starts (the sensor must not time out).
    wait_until("the driver discovered", || {
        driver.publish(wrench("ati_ft", now_ns(), -50.0)).unwrap();
        std::thread::sleep(Duration::from_millis(5));
        counts.counts().accepted > 0
    });
    let telemetry = Telemetry::new(session_info(&ctrl, Source::Runtime, "test", 0.004), 1024);
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
            subscriber::<JointState>(&mut node, "/deflex_alloc/joint_states", Ros2Qos::Reliable);
        listener = Some((node, sub));
        b
    });
    let link = RsiLink::bind("127.0.0.1:0", RsiConfig::default()).unwrap();
    let link_addr = link.local_addr().unwrap();
    let driving = Arc::new(AtomicBool::new(true));
    let robot = {
        let driving = driving.clone();
        std::thread::spawn(move || {
            let mut ep =
                RsiRobotEndpoint::new("127.0.0.1:0", link_addr, CorrectionMode::Absolute).unwrap();
            let mut next = Instant::now();
            let mut sent = 0u64;
            while driving.load(Ordering::Acquire) {
                let state = deflex_io::RobotState {
                    cycle_id: sent + 1,
                    ..deflex_io::RobotState::with_joints(&q)
                };
                ep.send_state(&state).unwrap();
                sent += 1;
                next += Duration::from_millis(4);
                let wait = next.saturating_duration_since(Instant::now());
                let _ = ep.receive_correction(wait.max(Duration::from_micros(100)));
                std::thread::sleep(next.saturating_duration_since(Instant::now()));
            }
        })
    };
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
    let clock = CountingClock {
        inner: WallClock::new(),
        counter: Arc::new(CycleCounter::new(2)),
    };
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
    robot.join().unwrap();
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

// The DDS helpers of deflex-ros2's own loopback tests.

/// A DDS domain of this test process alone (other processes on the machine may use DDS), below
/// 100: their RTPS ports (7400 + 250 d + …) then lie under Linux's ephemeral range (32768 on),
/// where the other tests' port-0 sockets live. `offset` (0–7) per session; deflex-ros2's own
/// tests use the offsets 0–3 of their process.
fn domain(offset: u16) -> u16 {
    20 + (std::process::id() % 10) as u16 * 8 + offset
}

const DISCOVERY: Duration = Duration::from_secs(20);

fn wait_until(what: &str, mut done: impl FnMut() -> bool) {
    let start = Instant::now();
    while !done() {
        assert!(
            start.elapsed() < DISCOVERY,
            "{what}: not within {DISCOVERY:?}"
        );
        std::thread::sleep(Duration::from_millis(5));
    }
}

fn subscriber<T: deflex_telemetry::ros::RosMessage + 'static>(
    node: &mut Node,
    topic: &str,
    qos: Ros2Qos,
) -> Subscription<T> {
    let q = qos_profile(qos, 200);
    let t = node
        .create_topic(&ros_name(topic).unwrap(), message_type::<T>(), &q)
        .unwrap();
    node.create_subscription(&t, Some(q)).unwrap()
}

fn publisher<T: deflex_telemetry::ros::RosMessage>(
    node: &mut Node,
    topic: &str,
    qos: Ros2Qos,
) -> Publisher<T> {
    let q = qos_profile(qos, 200);
    let t = node
        .create_topic(&ros_name(topic).unwrap(), message_type::<T>(), &q)
        .unwrap();
    node.create_publisher(&t, Some(q)).unwrap()
}

fn wrench(frame: &str, stamp_ns: u64, fz: f64) -> WrenchStamped {
    WrenchStamped {
        header: Header {
            stamp: deflex_telemetry::ros::Time::from_nanos(stamp_ns),
            frame_id: frame.into(),
        },
        wrench: Wrench {
            force: Vector3 {
                x: 1.0,
                y: -2.0,
                z: fz,
            },
            torque: Vector3 {
                x: 0.1,
                y: 0.2,
                z: 0.3,
            },
        },
    }
}

fn now_ns() -> u64 {
    std::time::SystemTime::now()
        .duration_since(std::time::UNIX_EPOCH)
        .unwrap()
        .as_nanos() as u64
}

fn sensor_settings(d: u16, depth: usize, qos: Ros2Qos) -> SensorSettings {
    SensorSettings {
        domain_id: d,
        namespace: "/deflex_test".into(),
        node_name: "ft".into(),
        qos,
        topic: "/ati/wrench".into(),
        frame_id: "ati_ft".into(),
        max_age: Duration::from_millis(500),
        queue_depth: depth,
    }
}
