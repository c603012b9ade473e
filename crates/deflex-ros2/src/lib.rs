//! # deflex-ros2
//!
//! deflex on the ROS 2 graph with no ROS installation: nodes, topics and QoS of
//! [`ros2_client`] on RustDDS (a DDS/RTPS implementation in Rust), the messages and their CDR
//! encoding of [`deflex_telemetry::ros`] (the same structs the MCAP recorder writes, so a recording and
//! the live graph agree).
//!
//! * [`Ros2Bridge`]: a sink thread of the telemetry stream (never the control thread) that
//!   publishes each cycle, decimated to `ros2.publish_rate_hz`, as the standard messages of
//!   [`deflex_telemetry::ros::cycle`] on `<namespace>/<topic>` (DDS topic `rt<namespace>/<topic>`, type
//!   `sensor_msgs::msg::dds_::JointState_` …), and the diagnostics at
//!   `ros2.diagnostics_rate_hz` and on every change of state.
//! * [`Ros2SensorLink`]: `[sensor] kind = "ros2"`, a [`deflex_io::ForceSensorLink`] taking
//!   `geometry_msgs/WrenchStamped` from any ROS 2 F/T driver. A DDS reader thread of its own
//!   takes the messages, refuses and counts those that are malformed, carry a non-finite value,
//!   another frame than `ros2.sensor_frame`, a stamp older (or further ahead) than
//!   `sensor.max_age_s` on this machine's clock or going back; it hands the accepted ones over
//!   through a bounded queue ([`handover`]). The runtime's sensor thread reads that queue as it
//!   reads a Net F/T socket, so timeout, tare (bias), tool gravity, range and faults are handled
//!   by the same code.
//!
//! **Stamps.** Every message of a cycle is stamped with the session time of the cycle mapped to
//! ROS time (ns since the Unix epoch, what `rclcpp::Clock(RCL_SYSTEM_TIME)` gives): the
//! bridge takes the wall clock when it reads the session's first sample minus that sample's
//! session time as the epoch of session time 0, and adds each cycle's session time to it (the
//! offset is fixed for the session; its error is the bridge's reading delay of the first sample,
//! one poll period, ≤ [`bridge::POLL`]). ROS simulated time (`/clock`, `use_sim_time`) is not
//! supported.
//!
//! Layering: model → control law → io → runtime → twin → front ends (**ROS 2**, CLI, …).

#![warn(missing_docs)]
#![forbid(unsafe_code)]

pub mod bridge;
pub mod handover;
pub mod sensor;
mod settings;

pub use bridge::{BridgeReport, Ros2Bridge};
pub use sensor::{Refusal, Ros2SensorLink, SensorCounts};
pub use settings::{BridgeSettings, SensorSettings, qos_profile};

use deflex_telemetry::ros::RosMessage;
use ros2_client::{Context, ContextOptions, MessageTypeName, Name, Node, NodeName, NodeOptions};

/// Why the bridge or the sensor link could not join the graph.
#[derive(Debug, thiserror::Error)]
pub enum Ros2Error {
    /// The DDS participant (domain `domain_id`) could not be created (no usable network
    /// interface, ports taken).
    #[error("ROS 2: cannot join DDS domain {domain_id}: {message}")]
    Participant {
        /// `ros2.domain_id`.
        domain_id: u16,
        /// The DDS stack's message.
        message: String,
    },
    /// The node could not be created.
    #[error("ROS 2: cannot create node {namespace}/{node}: {message}")]
    Node {
        /// `ros2.namespace`.
        namespace: String,
        /// `ros2.node_name`.
        node: String,
        /// The DDS stack's message.
        message: String,
    },
    /// A topic, publisher or subscription could not be created.
    #[error("ROS 2: topic {topic}: {message}")]
    Topic {
        /// The topic's ROS name.
        topic: String,
        /// The DDS stack's message.
        message: String,
    },
    /// The bridge's or the reader's thread could not be started, or it panicked.
    #[error("ROS 2: {what}: {message}")]
    Thread {
        /// Which thread.
        what: &'static str,
        /// Why.
        message: String,
    },
}

/// The ROS 2 package and type of a message (`geometry_msgs/msg/WrenchStamped` →
/// `geometry_msgs`, `WrenchStamped`): DDS type `geometry_msgs::msg::dds_::WrenchStamped_`.
pub fn message_type<T: RosMessage>() -> MessageTypeName {
    let mut parts = T::NAME.split('/');
    let package = parts.next().unwrap_or_default();
    let name = parts.next_back().unwrap_or_default();
    MessageTypeName::new(package, name)
}

/// Nice value of the bridge's thread and of the DDS threads it starts (RustDDS's event loop
/// and discovery threads inherit it): publishing yields the CPU to the runtime's loop threads
/// (nice 0, or SCHED_FIFO with `control.realtime`) instead of competing with them on equal
/// terms. The sensor link's reader is not lowered: it is the force's path (with
/// `control.realtime` the loop threads preempt it anyway).
pub const DDS_NICE: i32 = 10;

/// Lowers the calling thread to [`DDS_NICE`] (Linux: the nice value is per thread, and threads
/// started from it inherit it). Best effort: a refusal leaves the priority as it was.
pub(crate) fn lower_priority() {
    let _ = rustix::process::setpriority_process(None, DDS_NICE);
}

/// A DDS participant on `domain_id` and a node `node` in `namespace` (`/` for none): how the
/// bridge's and the reader's threads join the graph (the bridge's after lowering its priority
/// to [`DDS_NICE`]), and how a test or a tool joins it as another ROS 2 node (a driver
/// publishing `WrenchStamped`, a listener of the bridge).
pub fn join(domain_id: u16, namespace: &str, node: &str) -> Result<Node, Ros2Error> {
    let context =
        Context::with_options(ContextOptions::new().domain_id(domain_id)).map_err(|e| {
            Ros2Error::Participant {
                domain_id,
                message: format!("{e:?}"),
            }
        })?;
    let node_error = |message: String| Ros2Error::Node {
        namespace: namespace.to_string(),
        node: node.to_string(),
        message,
    };
    let name = NodeName::new(namespace, node).map_err(|e| node_error(e.to_string()))?;
    context
        .new_node(name, NodeOptions::new().enable_rosout(false))
        .map_err(|e| node_error(format!("{e:?}")))
}

/// The ROS name of `topic` under `namespace` (`/deflex` + `joint_states`).
pub fn topic_name(namespace: &str, topic: &str) -> String {
    if namespace == "/" {
        format!("/{topic}")
    } else {
        format!("{namespace}/{topic}")
    }
}

/// The [`Name`] of an absolute topic name (`/deflex/joint_states`); a name ROS 2 refuses is a
/// [`Ros2Error::Topic`] naming it.
pub fn ros_name(full: &str) -> Result<Name, Ros2Error> {
    Name::parse(full).map_err(|e| Ros2Error::Topic {
        topic: full.to_string(),
        message: e.to_string(),
    })
}
