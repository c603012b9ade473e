//! The choices of `CELL.toml` as enums. Those that are the law's or a protocol's own types
//! (safe action, runaway action, feed-forward mode and index, RSI correction mode and joint
//! element, EGM frame) are deserialised straight into them through serde's remote definitions
//! below, so the file and the code cannot disagree on a name; the others are the runtime's.

use deflex_control::{FeedForwardMode, PathIndex, RunawayAction, SafeAction};
use deflex_io::egm::EgmFrame;
use deflex_io::rsi::{CorrectionMode, JointTag};
use serde::Deserialize;

pub use deflex_io::RobotKind;
pub use deflex_telemetry::ros::{Ros2Qos, Ros2Topic};

/// Sensor protocol (`sensor.kind`).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Deserialize)]
#[serde(rename_all = "kebab-case")]
pub enum SensorKind {
    /// ATI Net F/T RDT over UDP.
    Netft,
    /// A `geometry_msgs/WrenchStamped` topic on the ROS 2 graph (`sensor.topic`, the DDS
    /// settings of `[ros2]`): any ROS 2 F/T driver. Opened by the `deflex-ros2` bridge.
    Ros2,
    /// A Universal Robots arm's own flange sensor over RTDE (`ft_raw_wrench`, e-Series and
    /// UR-Series): `sensor.address` is the controller's RTDE address (port 30004).
    UrRtde,
}

impl SensorKind {
    /// The name in `CELL.toml` (`netft`, `ros2`, `ur-rtde`).
    pub fn key(self) -> &'static str {
        match self {
            SensorKind::Netft => "netft",
            SensorKind::Ros2 => "ros2",
            SensorKind::UrRtde => "ur-rtde",
        }
    }
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
pub enum CorrectionAxis {
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

impl CorrectionAxis {
    /// In ξ order.
    pub const ALL: [CorrectionAxis; 6] = [
        CorrectionAxis::X,
        CorrectionAxis::Y,
        CorrectionAxis::Z,
        CorrectionAxis::Rx,
        CorrectionAxis::Ry,
        CorrectionAxis::Rz,
    ];

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
