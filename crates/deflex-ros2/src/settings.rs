//! The bridge's and the sensor link's settings (a `CELL.toml`'s `[ros2]` and `[sensor]`, read by
//! `deflex-app`).

use deflex_telemetry::ros::{Ros2Qos, Ros2Topic};
use ros2_client::qos::{Durability, History, Liveliness, Reliability, WhenFull};
use ros2_client::ros2::QosProfile;
use std::time::Duration;

/// What [`crate::Ros2Bridge`] publishes, and where.
#[derive(Clone, Debug, PartialEq)]
pub struct BridgeSettings {
    /// DDS domain.
    pub domain_id: u16,
    /// Namespace (absolute, `/` for none).
    pub namespace: String,
    /// Node name.
    pub node_name: String,
    /// QoS profile.
    pub qos: Ros2Qos,
    /// History depth.
    pub depth: usize,
    /// Rate of the cycle topics (Hz).
    pub publish_rate_hz: f64,
    /// Rate of the diagnostics between changes of state (Hz).
    pub diagnostics_rate_hz: f64,
    /// Topics published.
    pub topics: Vec<Ros2Topic>,
}

/// What [`crate::Ros2SensorLink`] takes, and what it refuses.
#[derive(Clone, Debug, PartialEq)]
pub struct SensorSettings {
    /// DDS domain.
    pub domain_id: u16,
    /// Namespace of the link's node.
    pub namespace: String,
    /// The link's node name.
    pub node_name: String,
    /// QoS profile.
    pub qos: Ros2Qos,
    /// The `WrenchStamped` topic (absolute).
    pub topic: String,
    /// The frame id the messages must carry.
    pub frame_id: String,
    /// Oldest (and farthest ahead) stamp accepted, against this machine's clock.
    pub max_age: Duration,
    /// Depth of the handover queue and of the subscription's history.
    pub queue_depth: usize,
}

/// The ROS 2 QoS of `qos` with history depth `depth`: `SensorDataQoS` (best effort) or the
/// default profile (reliable), both volatile with automatic liveliness. A reliable writer never
/// waits for a slow reader: a full send window fails the write (counted), it does not block.
pub fn qos_profile(qos: Ros2Qos, depth: usize) -> QosProfile {
    QosProfile {
        reliability: match qos {
            Ros2Qos::SensorData => Reliability::BestEffort,
            Ros2Qos::Reliable => Reliability::Reliable {
                when_full: WhenFull::Fail,
            },
        },
        durability: Durability::Volatile,
        history: History::KeepLast {
            depth: depth.max(1),
        },
        deadline: None,
        lifespan: None,
        liveliness: Liveliness::Automatic,
        liveliness_lease: None,
    }
}
