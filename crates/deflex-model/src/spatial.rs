//! Spatial types and small helpers: poses, wrenches, displacement screws, tool loads,
//! roll–pitch–yaw. The vendors' orientation conventions are in [`crate::conventions`].

use nalgebra::{IsometryMatrix3, Rotation3, Translation3, Vector3, Vector6};

/// A rigid placement (rotation matrix + translation). `pose * p` maps a point from the local
/// frame to the parent frame.
pub type Pose = IsometryMatrix3<f64>;

/// A wrench `[fx, fy, fz, mx, my, mz]` in N and N·m (eq. 2), expressed in world axes, the moment
/// taken about the point of application unless stated otherwise.
pub type Wrench = Vector6<f64>;

/// A small displacement screw `δs = [δp; δφ]` in m and rad (eq. 3), world axes.
pub type Displacement = Vector6<f64>;

/// The load of a tool: its mass and its centre of mass. The frame the centre of mass is given
/// in is said by the field that holds the load (`tool_in_sensor` for the controller's gravity
/// compensation, `tool_load_in_flange` for a program's declared load).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ToolLoad {
    /// Mass (kg).
    pub mass_kg: f64,
    /// Centre of mass (m), in the frame named by the field holding this load.
    pub centre_of_mass_m: Vector3<f64>,
}

impl ToolLoad {
    /// No load: zero mass at the frame's origin.
    pub const NONE: ToolLoad = ToolLoad {
        mass_kg: 0.0,
        centre_of_mass_m: Vector3::new(0.0, 0.0, 0.0),
    };
}

/// Rotation from roll–pitch–yaw in rad: `R = Rz(yaw) · Ry(pitch) · Rx(roll)`.
pub fn rotation_from_rpy(rpy: [f64; 3]) -> Rotation3<f64> {
    Rotation3::from_euler_angles(rpy[0], rpy[1], rpy[2])
}

/// Roll–pitch–yaw (rad) of a rotation, inverse of [`rotation_from_rpy`].
pub fn rpy_from_rotation(rotation: &Rotation3<f64>) -> [f64; 3] {
    let (roll, pitch, yaw) = rotation.euler_angles();
    [roll, pitch, yaw]
}

/// A pose from a position (m) and roll–pitch–yaw angles (rad).
pub fn pose_from_xyz_rpy(xyz: [f64; 3], rpy: [f64; 3]) -> Pose {
    Pose::from_parts(
        Translation3::new(xyz[0], xyz[1], xyz[2]),
        rotation_from_rpy(rpy),
    )
}

/// Pure rotation about the local z axis by `angle` (rad).
#[inline]
pub fn rot_z(angle: f64) -> Pose {
    Pose::from_parts(
        Translation3::identity(),
        Rotation3::from_axis_angle(&Vector3::z_axis(), angle),
    )
}

/// The rotation vector (axis × angle, rad) that takes orientation `from` to `to`, in the parent
/// frame: `to = exp(ω) · from`.
pub fn orientation_error(from: &Rotation3<f64>, to: &Rotation3<f64>) -> Vector3<f64> {
    rotation_log(&(to * from.inverse()))
}

/// Rotation vector (axis × angle, rad) of a rotation matrix, accurate for small angles too
/// (`atan2` of the skew and symmetric parts instead of `acos` of the trace).
pub fn rotation_log(rotation: &Rotation3<f64>) -> Vector3<f64> {
    let m = rotation.matrix();
    let skew = Vector3::new(
        m[(2, 1)] - m[(1, 2)],
        m[(0, 2)] - m[(2, 0)],
        m[(1, 0)] - m[(0, 1)],
    );
    let sin_norm = 0.5 * skew.norm();
    let cos = 0.5 * (m.trace() - 1.0);
    if cos < -0.99 {
        // Near π the skew part vanishes; nalgebra's eigen-based extraction is accurate there.
        return rotation.scaled_axis();
    }
    let angle = sin_norm.atan2(cos);
    if sin_norm < 1e-300 {
        return Vector3::zeros();
    }
    skew * (0.5 * angle / sin_norm)
}

/// Column of the eDoF Jacobian of eq. 13 for a spring of axis `v` (unit, world) centred at `c`,
/// evaluated at world point `p`: `[v × (p − c); v]`. The same screw maps the spring's small
/// rotation to the displacement of `p`, and (transposed) a wrench at `p` to the spring torque
/// (eq. 14).
#[inline]
pub fn edof_screw(
    axis: &Vector3<f64>,
    center: &Vector3<f64>,
    point: &Vector3<f64>,
) -> Vector6<f64> {
    let linear = axis.cross(&(point - center));
    Vector6::new(linear.x, linear.y, linear.z, axis.x, axis.y, axis.z)
}
