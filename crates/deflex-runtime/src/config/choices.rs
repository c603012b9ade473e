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
