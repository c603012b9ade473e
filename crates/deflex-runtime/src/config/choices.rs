//! The choices of `CELL.toml` as enums. Those that are the law's or a protocol's own types
//! (safe action, runaway action, feed-forward mode and index, RSI correction mode and joint
//! element, EGM frame) are deserialised straight into them through serde's remote definitions
//! below, so the file and the code cannot disagree on a name; the others are the runtime's.

use deflex_control::{FeedForwardMode, PathIndex, RunawayAction, SafeAction};
use deflex_io::egm::EgmFrame;
use deflex_io::rsi::{CorrectionMode, JointTag};
use serde::Deserialize;

/// Robot protocol (`robot.kind`).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Deserialize)]
#[serde(rename_all = "kebab-case")]
pub enum RobotKind {
    /// KUKA RSI, XML over UDP.
    KukaRsi,
    /// ABB EGM path correction.
    AbbEgm,
    /// Stäubli VAL3 `alter` program (deflex binary protocol).
    Staubli,
    /// Text lines over UDP.
    SimpleUdp,
    /// The same text lines over TCP (the controller listens; a UR script connects to it).
    SimpleTcp,
}

impl RobotKind {
    /// The protocol's name for people ("KUKA RSI", "ABB EGM", …).
    pub fn name(self) -> &'static str {
        match self {
            RobotKind::KukaRsi => "KUKA RSI",
            RobotKind::AbbEgm => "ABB EGM",
            RobotKind::Staubli => "Stäubli",
            RobotKind::SimpleUdp => "simple UDP",
            RobotKind::SimpleTcp => "simple TCP",
        }
    }

    /// The name in `CELL.toml` (`kuka-rsi`, …).
    pub fn key(self) -> &'static str {
        match self {
            RobotKind::KukaRsi => "kuka-rsi",
            RobotKind::AbbEgm => "abb-egm",
            RobotKind::Staubli => "staubli",
            RobotKind::SimpleUdp => "simple-udp",
            RobotKind::SimpleTcp => "simple-tcp",
        }
    }

    /// Whether the robot's replies echo its telegram's cycle id (RSI's IPOC, the Stäubli
    /// acknowledgement), so a late reply is never taken for the current one. The other
    /// protocols carry no echo: the first reply after a state is its answer.
    pub fn echoes_cycle(self) -> bool {
        matches!(self, RobotKind::KukaRsi | RobotKind::Staubli)
    }
}

/// Sensor protocol (`sensor.kind`).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Deserialize)]
#[serde(rename_all = "kebab-case")]
pub enum SensorKind {
    /// ATI Net F/T RDT over UDP.
    Netft,
    /// A `geometry_msgs/WrenchStamped` topic on the ROS 2 graph (`sensor.topic`, the DDS
    /// settings of `[ros2]`): any ROS 2 F/T driver. Opened by the `deflex-ros2` bridge.
    Ros2,
}

impl SensorKind {
    /// The name in `CELL.toml` (`netft`, `ros2`).
    pub fn key(self) -> &'static str {
        match self {
            SensorKind::Netft => "netft",
            SensorKind::Ros2 => "ros2",
        }
    }
}

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

/// What RSI answers carry (`robot.rsi_answer`).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Default, Deserialize)]
#[serde(rename_all = "kebab-case")]
pub enum RsiAnswerKind {
    /// The Cartesian correction (`RKorr`).
    #[default]
    Cartesian,
    /// Joint corrections through the model's Jacobian (element `robot.rsi_joint_tag`).
    Joint,
}

/// An axis of ξ (`control.axes`).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Deserialize)]
#[serde(rename_all = "kebab-case")]
pub enum Axis {
    /// Position x.
    X,
    /// Position y.
    Y,
    /// Position z.
    Z,
    /// Rotation about x.
    Rx,
    /// Rotation about y.
    Ry,
    /// Rotation about z.
    Rz,
}

impl Axis {
    /// In ξ order.
    pub const ALL: [Axis; 6] = [Axis::X, Axis::Y, Axis::Z, Axis::Rx, Axis::Ry, Axis::Rz];

    /// Index in ξ.
    pub fn index(self) -> usize {
        self as usize
    }
}

#[derive(Deserialize)]
#[serde(remote = "SafeAction", rename_all = "kebab-case")]
pub(super) enum SafeActionDef {
    Zero,
    Hold,
}

#[derive(Deserialize)]
#[serde(remote = "RunawayAction", rename_all = "kebab-case")]
pub(super) enum RunawayActionDef {
    Withdraw,
    Hold,
    Fault,
}

#[derive(Deserialize)]
#[serde(remote = "FeedForwardMode", rename_all = "kebab-case")]
pub(super) enum FeedForwardModeDef {
    FeedForward,
    Precompensated,
}

#[derive(Deserialize)]
#[serde(remote = "PathIndex", rename_all = "kebab-case")]
pub(super) enum PathIndexDef {
    ArcLength,
    Time,
}

#[derive(Deserialize)]
#[serde(remote = "CorrectionMode", rename_all = "kebab-case")]
pub(super) enum CorrectionModeDef {
    Absolute,
    Relative,
}

#[derive(Deserialize)]
#[serde(remote = "JointTag")]
pub(super) enum JointTagDef {
    #[serde(rename = "AK")]
    Ak,
    #[serde(rename = "AKorr")]
    AKorr,
}

#[derive(Deserialize)]
#[serde(remote = "EgmFrame", rename_all = "kebab-case")]
pub(super) enum EgmFrameDef {
    Tool,
    WorkObject,
    Base,
}
