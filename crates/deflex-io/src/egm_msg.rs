//! Hand-written prost messages: the subset of ABB `egm.proto` that deflex
//! uses, with the same field numbers (tags) and proto2 labels.

/// Message header.
#[derive(Clone, PartialEq, prost::Message)]
pub struct EgmHeader {
    /// Sequence number.
    #[prost(uint32, optional, tag = "1")]
    pub seqno: Option<u32>,
    /// Sender time stamp in ms.
    #[prost(uint32, optional, tag = "2")]
    pub tm: Option<u32>,
    /// Message type (2 = DATA, 4 = PATH_CORRECTION).
    #[prost(int32, optional, tag = "3")]
    pub mtype: Option<i32>,
}
/// Cartesian position in mm.
#[derive(Clone, Copy, PartialEq, prost::Message)]
pub struct EgmCartesian {
    /// x (mm).
    #[prost(double, required, tag = "1")]
    pub x: f64,
    /// y (mm).
    #[prost(double, required, tag = "2")]
    pub y: f64,
    /// z (mm).
    #[prost(double, required, tag = "3")]
    pub z: f64,
}
/// Unit quaternion `u0 + u1 i + u2 j + u3 k`.
#[derive(Clone, Copy, PartialEq, prost::Message)]
pub struct EgmQuaternion {
    /// Scalar part.
    #[prost(double, required, tag = "1")]
    pub u0: f64,
    /// i.
    #[prost(double, required, tag = "2")]
    pub u1: f64,
    /// j.
    #[prost(double, required, tag = "3")]
    pub u2: f64,
    /// k.
    #[prost(double, required, tag = "4")]
    pub u3: f64,
}
/// ZYX Euler angles in degrees (`Rz(z) Ry(y) Rx(x)`).
#[derive(Clone, Copy, PartialEq, prost::Message)]
pub struct EgmEuler {
    /// About x (deg).
    #[prost(double, required, tag = "1")]
    pub x: f64,
    /// About y (deg).
    #[prost(double, required, tag = "2")]
    pub y: f64,
    /// About z (deg).
    #[prost(double, required, tag = "3")]
    pub z: f64,
}
/// Pose.
#[derive(Clone, Copy, PartialEq, prost::Message)]
pub struct EgmPose {
    /// Position.
    #[prost(message, optional, tag = "1")]
    pub pos: Option<EgmCartesian>,
    /// Orientation as quaternion.
    #[prost(message, optional, tag = "2")]
    pub orient: Option<EgmQuaternion>,
    /// Orientation as Euler angles.
    #[prost(message, optional, tag = "3")]
    pub euler: Option<EgmEuler>,
}
/// Joint values in degrees.
#[derive(Clone, PartialEq, prost::Message)]
pub struct EgmJoints {
    /// Joint values (deg), not packed (proto2).
    #[prost(double, repeated, packed = "false", tag = "1")]
    pub joints: Vec<f64>,
}
/// Controller clock.
#[derive(Clone, Copy, PartialEq, prost::Message)]
pub struct EgmClock {
    /// Seconds.
    #[prost(uint64, required, tag = "1")]
    pub sec: u64,
    /// Microseconds.
    #[prost(uint64, required, tag = "2")]
    pub usec: u64,
}
/// Feedback (measured) or planned data.
#[derive(Clone, PartialEq, prost::Message)]
pub struct EgmFeedBack {
    /// Joints (deg).
    #[prost(message, optional, tag = "1")]
    pub joints: Option<EgmJoints>,
    /// TCP pose.
    #[prost(message, optional, tag = "2")]
    pub cartesian: Option<EgmPose>,
    /// External axes.
    #[prost(message, optional, tag = "3")]
    pub external_joints: Option<EgmJoints>,
    /// Time stamp.
    #[prost(message, optional, tag = "4")]
    pub time: Option<EgmClock>,
}
/// Robot → sensor message.
#[derive(Clone, PartialEq, prost::Message)]
pub struct EgmRobot {
    /// Header.
    #[prost(message, optional, tag = "1")]
    pub header: Option<EgmHeader>,
    /// Measured state.
    #[prost(message, optional, tag = "2")]
    pub feed_back: Option<EgmFeedBack>,
    /// Planned state (same layout as feedback).
    #[prost(message, optional, tag = "3")]
    pub planned: Option<EgmFeedBack>,
    /// `utilizationRate` (percent of the EGM cycle used).
    #[prost(double, optional, tag = "10")]
    pub utilization_rate: Option<f64>,
}
/// Path correction payload.
#[derive(Clone, Copy, PartialEq, prost::Message)]
pub struct EgmPathCorr {
    /// Correction in mm, sensor (path) frame.
    #[prost(message, required, tag = "1")]
    pub pos: EgmCartesian,
    /// Age of the measurement in ms.
    #[prost(uint32, required, tag = "2")]
    pub age: u32,
}
/// Sensor → robot path correction message.
#[derive(Clone, PartialEq, prost::Message)]
pub struct EgmSensorPathCorr {
    /// Header.
    #[prost(message, optional, tag = "1")]
    pub header: Option<EgmHeader>,
    /// Correction.
    #[prost(message, optional, tag = "2")]
    pub path_corr: Option<EgmPathCorr>,
}
