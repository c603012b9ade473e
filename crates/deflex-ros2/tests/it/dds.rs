//! The DDS helpers of the loopback tests: this process's own domains, a bounded wait for
//! discovery, a publisher and a subscriber at deflex's QoS profiles, a driver's `WrenchStamped`,
//! the sensor link's settings.
//!
//! The facade's no-allocation session with the ROS 2 parts (crates/deflex/tests/it/no_alloc)
//! compiles this file too, by `#[path]`: it uses nothing of this binary beyond this file.
#![allow(dead_code)]

use deflex_ros2::{SensorSettings, message_type, qos_profile, ros_name};
use deflex_telemetry::ros::{
    HeaderMsg, Ros2Qos, RosMessage, TimeMsg, Vector3Msg, WrenchMsg, WrenchStampedMsg,
};
use ros2_client::{Node, Publisher, Subscription};
use std::time::{Duration, Instant};

/// A DDS domain of this test process alone (other processes on the machine may use DDS), below
/// 100: their RTPS ports (7400 + 250 d + …) then lie under Linux's ephemeral range (32768 on),
/// where the other tests' port-0 sockets live. `offset` (0–7) per session: deflex-ros2's own
/// tests use the offsets 0–3, the facade's no-allocation sessions 4–7, so that the two test
/// processes never share a domain even where their process ids agree modulo 10.
pub fn domain(offset: u16) -> u16 {
    20 + (std::process::id() % 10) as u16 * 8 + offset
}

/// How long discovery may take on a loaded machine.
pub const DISCOVERY: Duration = Duration::from_secs(20);

/// Polls `done` every 5 ms until it holds; fails the test after [`DISCOVERY`].
pub fn wait_until(what: &str, mut done: impl FnMut() -> bool) {
    let start = Instant::now();
    while !done() {
        assert!(
            start.elapsed() < DISCOVERY,
            "{what}: not within {DISCOVERY:?}"
        );
        std::thread::sleep(Duration::from_millis(5));
    }
}

/// A subscription of `node` to `topic` at `qos` (history 200).
pub fn subscriber<T: RosMessage + 'static>(
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

/// A publisher of `node` on `topic` at `qos` (history 200).
pub fn publisher<T: RosMessage>(node: &mut Node, topic: &str, qos: Ros2Qos) -> Publisher<T> {
    let q = qos_profile(qos, 200);
    let t = node
        .create_topic(&ros_name(topic).unwrap(), message_type::<T>(), &q)
        .unwrap();
    node.create_publisher(&t, Some(q)).unwrap()
}

/// A driver's reading in `frame`, stamped `stamp_ns`: force (1, −2, `fz`) N, torque
/// (0.1, 0.2, 0.3) N·m.
pub fn wrench(frame: &str, stamp_ns: u64, fz: f64) -> WrenchStampedMsg {
    WrenchStampedMsg {
        header: HeaderMsg {
            stamp: TimeMsg::from_nanos(stamp_ns),
            frame_id: frame.into(),
        },
        wrench: WrenchMsg {
            force: Vector3Msg {
                x: 1.0,
                y: -2.0,
                z: fz,
            },
            torque: Vector3Msg {
                x: 0.1,
                y: 0.2,
                z: 0.3,
            },
        },
    }
}

/// Now, in nanoseconds since the Unix epoch (the stamps' clock).
pub fn now_ns() -> u64 {
    std::time::SystemTime::now()
        .duration_since(std::time::UNIX_EPOCH)
        .unwrap()
        .as_nanos() as u64
}

/// The sensor link on domain `d` reading `/ati/wrench` in frame `ati_ft` (readings older than
/// 0.5 s refused), with a queue of `depth` at `qos`.
pub fn sensor_settings(d: u16, depth: usize, qos: Ros2Qos) -> SensorSettings {
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
