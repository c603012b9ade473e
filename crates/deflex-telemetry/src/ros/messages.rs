//! The message structs: fields in the order, with the names and the types, of the `.msg` files.
//! Each is named after its ROS 2 message type with the suffix `Msg`, which marks a ROS 2 message
//! type (`geometry_msgs/msg/Wrench` is [`WrenchMsg`]).

use crate::ros::RosMessage;
use crate::ros::definitions as def;
use serde::{Deserialize, Serialize};

/// `builtin_interfaces/msg/Time`: `int32 sec`, `uint32 nanosec`.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Serialize, Deserialize)]
pub struct TimeMsg {
    /// Seconds.
    pub sec: i32,
    /// Nanoseconds past `sec` (0 ≤ nanosec < 10⁹).
    pub nanosec: u32,
}

impl TimeMsg {
    /// The time `nanos` nanoseconds after the epoch (saturating at the `i32` seconds range).
    pub fn from_nanos(nanos: u64) -> TimeMsg {
        let sec = nanos / 1_000_000_000;
        TimeMsg {
            sec: sec.min(i32::MAX as u64) as i32,
            nanosec: (nanos % 1_000_000_000) as u32,
        }
    }

    /// Nanoseconds after the epoch (negative seconds count as zero).
    pub fn to_nanos(self) -> u64 {
        (self.sec.max(0) as u64) * 1_000_000_000 + u64::from(self.nanosec)
    }
}

/// `std_msgs/msg/Header`: `builtin_interfaces/Time stamp`, `string frame_id`.
#[derive(Clone, Debug, Default, PartialEq, Serialize, Deserialize)]
pub struct HeaderMsg {
    /// Time of the data.
    pub stamp: TimeMsg,
    /// Frame the data is expressed in.
    pub frame_id: String,
}

/// `geometry_msgs/msg/Vector3`: `float64 x, y, z`.
#[derive(Clone, Copy, Debug, Default, PartialEq, Serialize, Deserialize)]
pub struct Vector3Msg {
    /// x
    pub x: f64,
    /// y
    pub y: f64,
    /// z
    pub z: f64,
}

impl Vector3Msg {
    /// From the first three values of a slice (zeros where it is shorter).
    pub fn from_slice(v: &[f64]) -> Vector3Msg {
        let at = |i: usize| v.get(i).copied().unwrap_or(0.0);
        Vector3Msg {
            x: at(0),
            y: at(1),
            z: at(2),
        }
    }

    /// `[x, y, z]`.
    pub fn to_array(self) -> [f64; 3] {
        [self.x, self.y, self.z]
    }
}

/// `geometry_msgs/msg/Point`: `float64 x, y, z`.
#[derive(Clone, Copy, Debug, Default, PartialEq, Serialize, Deserialize)]
pub struct PointMsg {
    /// x
    pub x: f64,
    /// y
    pub y: f64,
    /// z
    pub z: f64,
}

/// `geometry_msgs/msg/Quaternion`: `float64 x, y, z, w`.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct QuaternionMsg {
    /// x
    pub x: f64,
    /// y
    pub y: f64,
    /// z
    pub z: f64,
    /// w
    pub w: f64,
}

impl Default for QuaternionMsg {
    /// The identity (the `.msg` default `w = 1`).
    fn default() -> Self {
        QuaternionMsg {
            x: 0.0,
            y: 0.0,
            z: 0.0,
            w: 1.0,
        }
    }
}

/// `geometry_msgs/msg/Pose`: `Point position`, `Quaternion orientation`.
#[derive(Clone, Copy, Debug, Default, PartialEq, Serialize, Deserialize)]
pub struct PoseMsg {
    /// Position.
    pub position: PointMsg,
    /// Orientation.
    pub orientation: QuaternionMsg,
}

/// `geometry_msgs/msg/PoseStamped`: `std_msgs/Header header`, `Pose pose`.
#[derive(Clone, Debug, Default, PartialEq, Serialize, Deserialize)]
pub struct PoseStampedMsg {
    /// Stamp and frame.
    pub header: HeaderMsg,
    /// The pose.
    pub pose: PoseMsg,
}

/// `geometry_msgs/msg/Wrench`: `Vector3 force`, `Vector3 torque`.
#[derive(Clone, Copy, Debug, Default, PartialEq, Serialize, Deserialize)]
pub struct WrenchMsg {
    /// Force (N).
    pub force: Vector3Msg,
    /// Torque (N·m).
    pub torque: Vector3Msg,
}

/// `geometry_msgs/msg/WrenchStamped`: `std_msgs/Header header`, `Wrench wrench`.
#[derive(Clone, Debug, Default, PartialEq, Serialize, Deserialize)]
pub struct WrenchStampedMsg {
    /// Stamp and frame.
    pub header: HeaderMsg,
    /// The wrench.
    pub wrench: WrenchMsg,
}

/// `geometry_msgs/msg/Twist`: `Vector3 linear`, `Vector3 angular`.
#[derive(Clone, Copy, Debug, Default, PartialEq, Serialize, Deserialize)]
pub struct TwistMsg {
    /// Linear part.
    pub linear: Vector3Msg,
    /// Angular part.
    pub angular: Vector3Msg,
}

/// `geometry_msgs/msg/TwistStamped`: `std_msgs/Header header`, `Twist twist`.
#[derive(Clone, Debug, Default, PartialEq, Serialize, Deserialize)]
pub struct TwistStampedMsg {
    /// Stamp and frame.
    pub header: HeaderMsg,
    /// The twist.
    pub twist: TwistMsg,
}

/// `geometry_msgs/msg/Vector3Stamped`: `std_msgs/Header header`, `Vector3 vector`.
#[derive(Clone, Debug, Default, PartialEq, Serialize, Deserialize)]
pub struct Vector3StampedMsg {
    /// Stamp and frame.
    pub header: HeaderMsg,
    /// The vector.
    pub vector: Vector3Msg,
}

/// `sensor_msgs/msg/JointState`: `std_msgs/Header header`, `string[] name`,
/// `float64[] position`, `float64[] velocity`, `float64[] effort`.
#[derive(Clone, Debug, Default, PartialEq, Serialize, Deserialize)]
pub struct JointStateMsg {
    /// Stamp (and frame, usually empty).
    pub header: HeaderMsg,
    /// Joint names.
    pub name: Vec<String>,
    /// Positions (rad for revolute joints).
    pub position: Vec<f64>,
    /// Velocities (empty when unknown).
    pub velocity: Vec<f64>,
    /// Efforts (empty when unknown).
    pub effort: Vec<f64>,
}

/// `diagnostic_msgs/msg/KeyValue`: `string key`, `string value`.
#[derive(Clone, Debug, Default, PartialEq, Serialize, Deserialize)]
pub struct KeyValueMsg {
    /// Key.
    pub key: String,
    /// Value.
    pub value: String,
}

/// `diagnostic_msgs/msg/DiagnosticStatus`: `byte level`, `string name`, `string message`,
/// `string hardware_id`, `KeyValue[] values` (constants `OK = 0`, `WARN = 1`, `ERROR = 2`,
/// `STALE = 3`).
#[derive(Clone, Debug, Default, PartialEq, Serialize, Deserialize)]
pub struct DiagnosticStatusMsg {
    /// One of [`DiagnosticStatusMsg::OK`] … [`DiagnosticStatusMsg::STALE`].
    pub level: u8,
    /// Component name.
    pub name: String,
    /// Human-readable state.
    pub message: String,
    /// Hardware identifier.
    pub hardware_id: String,
    /// Named values.
    pub values: Vec<KeyValueMsg>,
}

impl DiagnosticStatusMsg {
    /// `byte OK=0`.
    pub const OK: u8 = 0;
    /// `byte WARN=1`.
    pub const WARN: u8 = 1;
    /// `byte ERROR=2`.
    pub const ERROR: u8 = 2;
    /// `byte STALE=3`.
    pub const STALE: u8 = 3;

    /// The value of `key`, if present.
    pub fn value(&self, key: &str) -> Option<&str> {
        self.values
            .iter()
            .find(|kv| kv.key == key)
            .map(|kv| kv.value.as_str())
    }
}

/// `diagnostic_msgs/msg/DiagnosticArray`: `std_msgs/Header header`, `DiagnosticStatus[] status`.
#[derive(Clone, Debug, Default, PartialEq, Serialize, Deserialize)]
pub struct DiagnosticArrayMsg {
    /// Stamp.
    pub header: HeaderMsg,
    /// One status per component.
    pub status: Vec<DiagnosticStatusMsg>,
}

macro_rules! ros_message {
    ($ty:ty, $name:literal, $def:expr) => {
        impl RosMessage for $ty {
            const NAME: &'static str = $name;
            const DEFINITION: &'static str = $def;
        }
    };
}

ros_message!(TimeMsg, "builtin_interfaces/msg/Time", def::TIME_SCHEMA);
ros_message!(HeaderMsg, "std_msgs/msg/Header", def::HEADER_SCHEMA);
ros_message!(Vector3Msg, "geometry_msgs/msg/Vector3", def::VECTOR3_SCHEMA);
ros_message!(
    Vector3StampedMsg,
    "geometry_msgs/msg/Vector3Stamped",
    def::VECTOR3_STAMPED_SCHEMA
);
ros_message!(
    PoseStampedMsg,
    "geometry_msgs/msg/PoseStamped",
    def::POSE_STAMPED_SCHEMA
);
ros_message!(
    WrenchStampedMsg,
    "geometry_msgs/msg/WrenchStamped",
    def::WRENCH_STAMPED_SCHEMA
);
ros_message!(
    TwistStampedMsg,
    "geometry_msgs/msg/TwistStamped",
    def::TWIST_STAMPED_SCHEMA
);
ros_message!(
    JointStateMsg,
    "sensor_msgs/msg/JointState",
    def::JOINT_STATE_SCHEMA
);
ros_message!(
    DiagnosticArrayMsg,
    "diagnostic_msgs/msg/DiagnosticArray",
    def::DIAGNOSTIC_ARRAY_SCHEMA
);
