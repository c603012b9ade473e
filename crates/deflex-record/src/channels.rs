//! The channels of a deflex MCAP file: topic names, message types and frames.
//!
//! The messages are those of [`deflex_telemetry::ros::cycle`] (the mapping the ROS 2 bridge shares).
//! Every channel but [`SESSION`] carries ROS 2 messages (schema encoding `ros2msg`, message
//! encoding `cdr`, profile `ros2`), one message per control cycle unless said otherwise. All
//! messages of a cycle share its log time (the recording's start epoch plus the cycle's session
//! time, ns), its header stamp (the same instant) and its MCAP sequence number (the cycle number,
//! modulo 2³²). SI units throughout.
//!
//! | topic | type | frame | content |
//! | --- | --- | --- | --- |
//! | `/joint_states` | `sensor_msgs/msg/JointState` | – | joint values the robot reported (rad), named as the model's joints |
//! | `/deflex/wrench_raw` | `geometry_msgs/msg/WrenchStamped` | sensor | raw F/T reading, cycle mean (N, N·m) |
//! | `/deflex/wrench_sensor` | `geometry_msgs/msg/WrenchStamped` | sensor | bias and tool gravity removed, low-pass filtered |
//! | `/deflex/wrench_tcp` | `geometry_msgs/msg/WrenchStamped` | base | the environment's wrench on the tool, **at the TCP**, base axes (eq. 2) |
//! | `/deflex/tcp_pose` | `geometry_msgs/msg/PoseStamped` | base | the corrected TCP: forward kinematics of the reported joints |
//! | `/deflex/program_pose` | `geometry_msgs/msg/PoseStamped` | base | the program's (desired) TCP: position minus ξ, orientation exp(−ξ_r)·R |
//! | `/deflex/deflection` | `geometry_msgs/msg/TwistStamped` | base | estimated deflection δŝ (eq. 15): `linear` m, `angular` rad — a displacement, not a velocity |
//! | `/deflex/correction` | `geometry_msgs/msg/TwistStamped` | base | applied correction ξ (eq. 7), same convention |
//! | `/deflex/error` | `geometry_msgs/msg/TwistStamped` | base | tracking error ε = −ξ − δŝ (eq. 5), same convention |
//! | `/deflex/feedforward` | `geometry_msgs/msg/TwistStamped` | base | the feed-forward prior (zero without one) |
//! | `/deflex/path_error` | `geometry_msgs/msg/Vector3Stamped` | base | twin only: true TCP minus desired TCP (m); absent on a real cell |
//! | `/diagnostics` | `diagnostic_msgs/msg/DiagnosticArray` | – | every [`crate::RecordOptions::diagnostics_period_s`] and whenever the phase, flags or fault change: one status `deflex/controller` (level OK, WARN when saturated, ramping or holding, ERROR with a latched fault) whose values are the keys of [`diag`] |
//! | `/deflex/session` | JSON (`jsonschema`) | – | one message at the start: the session description ([`crate::SessionRecord`]) |
//!
//! The same session description is also written as an MCAP metadata record named `deflex`.

/// `/joint_states`.
pub const JOINT_STATES: &str = "/joint_states";
/// Raw F/T reading, sensor frame.
pub const WRENCH_RAW: &str = "/deflex/wrench_raw";
/// Compensated F/T reading, sensor frame.
pub const WRENCH_SENSOR: &str = "/deflex/wrench_sensor";
/// Environment wrench at the TCP, base axes.
pub const WRENCH_TCP: &str = "/deflex/wrench_tcp";
/// Corrected TCP pose.
pub const TCP_POSE: &str = "/deflex/tcp_pose";
/// Program (desired) TCP pose.
pub const PROGRAM_POSE: &str = "/deflex/program_pose";
/// δŝ.
pub const DEFLECTION: &str = "/deflex/deflection";
/// ξ.
pub const CORRECTION: &str = "/deflex/correction";
/// ε.
pub const ERROR: &str = "/deflex/error";
/// Feed-forward prior.
pub const FEEDFORWARD: &str = "/deflex/feedforward";
/// Twin only: true minus desired TCP.
pub const PATH_ERROR: &str = "/deflex/path_error";
/// Controller state, faults, counters and timing.
pub const DIAGNOSTICS: &str = "/diagnostics";
/// Session description (JSON).
pub const SESSION: &str = "/deflex/session";

/// Name of the diagnostic status.
pub use deflex_telemetry::ros::cycle::STATUS_NAME;

/// Keys of the `deflex/controller` diagnostic status (values are decimal text, SI units): those
/// of [`deflex_telemetry::ros::cycle::diag`] and the recorder's own count.
pub mod diag {
    pub use deflex_telemetry::ros::cycle::diag::*;
    /// Samples the recorder lost so far (overwritten in the telemetry ring before it read them).
    pub const RECORDER_LOST: &str = "recorder_lost";
}
