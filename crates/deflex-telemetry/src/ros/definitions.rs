//! The `.msg` definitions (fields and constants of `ros2/common_interfaces` and
//! `builtin_interfaces`, comments left out), concatenated with their dependencies in the
//! `ros2msg` form: the type's own definition, then for each dependency a line of 80 `=`, a line
//! `MSG: package/Type` and its definition.

macro_rules! sep {
    ($name:literal) => {
        concat!(
            "================================================================================\n",
            "MSG: ",
            $name,
            "\n"
        )
    };
}
macro_rules! time_msg {
    () => {
        "int32 sec\nuint32 nanosec\n"
    };
}
macro_rules! header_msg {
    () => {
        "builtin_interfaces/Time stamp\nstring frame_id\n"
    };
}
macro_rules! vector3_msg {
    () => {
        "float64 x\nfloat64 y\nfloat64 z\n"
    };
}
macro_rules! point_msg {
    () => {
        "float64 x\nfloat64 y\nfloat64 z\n"
    };
}
macro_rules! quaternion_msg {
    () => {
        "float64 x 0\nfloat64 y 0\nfloat64 z 0\nfloat64 w 1\n"
    };
}
macro_rules! pose_msg {
    () => {
        "Point position\nQuaternion orientation\n"
    };
}
macro_rules! wrench_msg {
    () => {
        "Vector3 force\nVector3 torque\n"
    };
}
macro_rules! twist_msg {
    () => {
        "Vector3 linear\nVector3 angular\n"
    };
}
macro_rules! key_value_msg {
    () => {
        "string key\nstring value\n"
    };
}
macro_rules! diagnostic_status_msg {
    () => {
        "byte OK=0\nbyte WARN=1\nbyte ERROR=2\nbyte STALE=3\n\
         byte level\nstring name\nstring message\nstring hardware_id\nKeyValue[] values\n"
    };
}
macro_rules! header_deps {
    () => {
        concat!(
            sep!("std_msgs/Header"),
            header_msg!(),
            sep!("builtin_interfaces/Time"),
            time_msg!()
        )
    };
}

/// `builtin_interfaces/msg/Time`.
pub const TIME_SCHEMA: &str = time_msg!();

/// `std_msgs/msg/Header`.
pub const HEADER_SCHEMA: &str =
    concat!(header_msg!(), sep!("builtin_interfaces/Time"), time_msg!());

/// `geometry_msgs/msg/Vector3`.
pub const VECTOR3_SCHEMA: &str = vector3_msg!();

/// `geometry_msgs/msg/Vector3Stamped`.
pub const VECTOR3_STAMPED_SCHEMA: &str = concat!(
    "std_msgs/Header header\nVector3 vector\n",
    header_deps!(),
    sep!("geometry_msgs/Vector3"),
    vector3_msg!()
);

/// `geometry_msgs/msg/PoseStamped`.
pub const POSE_STAMPED_SCHEMA: &str = concat!(
    "std_msgs/Header header\nPose pose\n",
    header_deps!(),
    sep!("geometry_msgs/Pose"),
    pose_msg!(),
    sep!("geometry_msgs/Point"),
    point_msg!(),
    sep!("geometry_msgs/Quaternion"),
    quaternion_msg!()
);

/// `geometry_msgs/msg/WrenchStamped`.
pub const WRENCH_STAMPED_SCHEMA: &str = concat!(
    "std_msgs/Header header\nWrench wrench\n",
    header_deps!(),
    sep!("geometry_msgs/Wrench"),
    wrench_msg!(),
    sep!("geometry_msgs/Vector3"),
    vector3_msg!()
);

/// `geometry_msgs/msg/TwistStamped`.
pub const TWIST_STAMPED_SCHEMA: &str = concat!(
    "std_msgs/Header header\nTwist twist\n",
    header_deps!(),
    sep!("geometry_msgs/Twist"),
    twist_msg!(),
    sep!("geometry_msgs/Vector3"),
    vector3_msg!()
);

/// `sensor_msgs/msg/JointState`.
pub const JOINT_STATE_SCHEMA: &str = concat!(
    "std_msgs/Header header\nstring[] name\nfloat64[] position\nfloat64[] velocity\n\
     float64[] effort\n",
    header_deps!()
);

/// `diagnostic_msgs/msg/DiagnosticArray`.
pub const DIAGNOSTIC_ARRAY_SCHEMA: &str = concat!(
    "std_msgs/Header header\nDiagnosticStatus[] status\n",
    header_deps!(),
    sep!("diagnostic_msgs/DiagnosticStatus"),
    diagnostic_status_msg!(),
    sep!("diagnostic_msgs/KeyValue"),
    key_value_msg!()
);
