//! The topics of a session on the ROS 2 graph and the QoS profile they are published with:
//! the names `CELL.toml`'s `[ros2]` section chooses from (`ros2.topics`, `ros2.qos`), shared by
//! the configuration, the bridge and the MCAP channels.

use serde::Deserialize;

/// A topic the ROS 2 bridge publishes (`ros2.topics`), named as under the namespace.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum Ros2Topic {
    /// `sensor_msgs/JointState`: the joint values the robot reported.
    JointStates,
    /// `geometry_msgs/WrenchStamped`: raw F/T reading, sensor frame.
    WrenchRaw,
    /// `geometry_msgs/WrenchStamped`: bias and tool gravity removed, filtered, sensor frame.
    WrenchSensor,
    /// `geometry_msgs/WrenchStamped`: the environment's wrench at the TCP, base frame.
    WrenchTcp,
    /// `geometry_msgs/PoseStamped`: the corrected TCP, base frame.
    TcpPose,
    /// `geometry_msgs/PoseStamped`: the program's TCP, base frame.
    ProgramPose,
    /// `geometry_msgs/TwistStamped`: the estimated deflection δŝ (a displacement), base frame.
    Deflection,
    /// `geometry_msgs/TwistStamped`: the applied correction ξ, base frame.
    Correction,
    /// `geometry_msgs/TwistStamped`: the tracking error ε, base frame.
    Error,
    /// `geometry_msgs/TwistStamped`: the feed-forward prior, base frame.
    Feedforward,
    /// `geometry_msgs/Vector3Stamped`: twin only, true minus desired TCP.
    PathError,
    /// `diagnostic_msgs/DiagnosticArray`: phase, fault, flags, counters, timing.
    Diagnostics,
}

impl Ros2Topic {
    /// Every topic, in publishing order.
    pub const ALL: [Ros2Topic; 12] = [
        Ros2Topic::JointStates,
        Ros2Topic::WrenchRaw,
        Ros2Topic::WrenchSensor,
        Ros2Topic::WrenchTcp,
        Ros2Topic::TcpPose,
        Ros2Topic::ProgramPose,
        Ros2Topic::Deflection,
        Ros2Topic::Correction,
        Ros2Topic::Error,
        Ros2Topic::Feedforward,
        Ros2Topic::PathError,
        Ros2Topic::Diagnostics,
    ];

    /// The name under the namespace (`joint_states`, …).
    pub fn name(self) -> &'static str {
        match self {
            Ros2Topic::JointStates => "joint_states",
            Ros2Topic::WrenchRaw => "wrench_raw",
            Ros2Topic::WrenchSensor => "wrench_sensor",
            Ros2Topic::WrenchTcp => "wrench_tcp",
            Ros2Topic::TcpPose => "tcp_pose",
            Ros2Topic::ProgramPose => "program_pose",
            Ros2Topic::Deflection => "deflection",
            Ros2Topic::Correction => "correction",
            Ros2Topic::Error => "error",
            Ros2Topic::Feedforward => "feedforward",
            Ros2Topic::PathError => "path_error",
            Ros2Topic::Diagnostics => "diagnostics",
        }
    }
}

/// The QoS profile of the bridge's topics (`ros2.qos`).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Deserialize)]
#[serde(rename_all = "kebab-case")]
pub enum Ros2Qos {
    /// ROS 2's `SensorDataQoS`: best effort, volatile, keep last `ros2.depth`.
    SensorData,
    /// ROS 2's default (`rclcpp::QoS(depth)`): reliable, volatile, keep last `ros2.depth`.
    Reliable,
}
