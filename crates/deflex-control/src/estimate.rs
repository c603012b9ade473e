//! The deflection estimate of eq. 15, the step between the measured wrench and the PID: what the
//! calibrated model says the TCP has moved under the environment's push.
//!
//! δŝ = C(q) w with C(q) = J(q) K_θ⁻¹ J(q)ᵀ (eq. 15): `J` the Jacobian of the virtual joints at
//! the TCP, `K_θ` their stiffnesses, `q` the joint values the robot reports (motor encoders: the
//! commanded configuration, which is where the model is linearised) and `w` the environment
//! wrench at the TCP (eq. 2). The model computes it in world axes ([`Robot::tcp_deflection`]);
//! the loop works in the robot's **base** axes, the axes of ξ that the robot controllers take,
//! so both w and δŝ are rotated there: `v_base = R_baseᵀ v_world` for each 3-vector (force,
//! moment, δp, δφ). Allocation-free.

use deflex_model::{Data, Displacement, Robot, Wrench};
use nalgebra::Vector3;

/// The environment wrench at the TCP and the deflection it causes, both in the robot's base
/// axes.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct DeflectionEstimate {
    /// Environment wrench `w` at the TCP (eq. 2), base axes: [f (N); m about the TCP (N·m)].
    pub wrench_tcp: Wrench,
    /// Estimated deflection δŝ = J K_θ⁻¹ Jᵀ w (eq. 15), base axes: [δp (m); δφ (rad)].
    pub deflection: Displacement,
}

/// Eq. 15 in the robot's base axes: δŝ = J(q) K_θ⁻¹ J(q)ᵀ w for the wrench `wrench_tcp_world`
/// (at the TCP, world axes, moment about the TCP), with `data` holding the forward kinematics of
/// `robot` at the reported joint values q. Returns w and δŝ rotated into base axes.
#[inline]
pub fn tcp_deflection_in_base(
    robot: &Robot,
    data: &Data,
    wrench_tcp_world: &Wrench,
) -> DeflectionEstimate {
    let ds = robot.tcp_deflection(data, wrench_tcp_world);
    let r_t = robot.base.rotation.matrix().transpose();
    // (`Wrench` and `Displacement` are both `Vector6<f64>`.)
    let to_base = |v: &Wrench, at: usize| r_t * Vector3::new(v[at], v[at + 1], v[at + 2]);
    let (f, m) = (to_base(wrench_tcp_world, 0), to_base(wrench_tcp_world, 3));
    let (dp, dphi) = (to_base(&ds, 0), to_base(&ds, 3));
    DeflectionEstimate {
        wrench_tcp: Wrench::new(f.x, f.y, f.z, m.x, m.y, m.z),
        deflection: Displacement::new(dp.x, dp.y, dp.z, dphi.x, dphi.y, dphi.z),
    }
}
