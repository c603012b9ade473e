//! The model checked against the robot: where the robot's protocol reports the controller's own
//! TCP pose (KUKA RSI `RIst`, ABB EGM `feedBack.cartesian`), that pose is compared with the
//! model's rigid forward kinematics at the reported joints (robot file, `[tool]`, no deflection),
//! both in the robot base frame. Both are computed from the same measured joints, so the
//! correction the robot applies and the deflection under load cancel out: what remains is the
//! difference between the controller's kinematics and the model's — a calibration's tenths of
//! a millimetre when the model is the robot in the cell, tens of millimetres for a wrong tool,
//! another robot's file or a file in millimetres.
//!
//! The runtime checks the first telegram before the first correction (a refusal naming the
//! difference and its likely causes) and the controller checks every cycle
//! ([`crate::Controller::cycle_input`]): a difference above the tolerance latches
//! [`deflex_telemetry::FaultKind::ModelMismatch`] with the usual ramp-out. Allocation-free.

use deflex_model::{Data, Pose, QLengthError, Robot};

/// Tolerance of the check and whether it is made.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ModelCheckConfig {
    /// Compare the reported TCP pose with the model's (when the protocol reports one).
    pub enabled: bool,
    /// Largest distance between the reported TCP and the model's (m).
    pub position_tolerance_m: f64,
    /// Largest rotation between the reported TCP orientation and the model's (rad).
    pub orientation_tolerance_rad: f64,
}

impl Default for ModelCheckConfig {
    /// On, 5 mm and 10 mrad: about 25 times the difference between the twin's controller
    /// kinematics (its geometry errors, 0.2 mm) and the nominal model, above what a geometric
    /// calibration changes (tenths of a millimetre, a few tenths of a mrad), and a twelfth of a
    /// 60 mm tool error.
    fn default() -> Self {
        ModelCheckConfig {
            enabled: true,
            position_tolerance_m: 0.005,
            orientation_tolerance_rad: 0.010,
        }
    }
}

/// How far the robot's reported TCP pose is from the model's at the same joints.
#[derive(Clone, Copy, Debug, PartialEq, Default)]
pub struct PoseMismatch {
    /// Distance between the two TCP positions (m).
    pub position_m: f64,
    /// Angle of the rotation between the two TCP orientations (rad).
    pub orientation_rad: f64,
    /// Reported minus model TCP position, robot base axes (m).
    pub offset_m: [f64; 3],
}

impl PoseMismatch {
    /// True when either difference is above its tolerance (or not finite).
    pub fn exceeds(&self, config: &ModelCheckConfig) -> bool {
        !(self.position_m <= config.position_tolerance_m
            && self.orientation_rad <= config.orientation_tolerance_rad)
    }

    /// The larger of two mismatches, component by component (a session's largest).
    pub fn max(&self, other: &PoseMismatch) -> PoseMismatch {
        PoseMismatch {
            position_m: self.position_m.max(other.position_m),
            orientation_rad: self.orientation_rad.max(other.orientation_rad),
            offset_m: if other.position_m > self.position_m {
                other.offset_m
            } else {
                self.offset_m
            },
        }
    }
}

/// The model's TCP in the robot base frame from `data` (forward kinematics already done):
/// base⁻¹ · T_tcp.
pub fn model_tcp_in_base(robot: &Robot, data: &Data) -> Pose {
    robot.base.inverse() * data.tcp
}

/// The mismatch between `reported` (the controller's TCP pose, robot base frame) and the
/// model's TCP in `data` (forward kinematics of the same joints already done).
pub fn pose_mismatch(robot: &Robot, data: &Data, reported: &Pose) -> PoseMismatch {
    let model = model_tcp_in_base(robot, data);
    let d = reported.translation.vector - model.translation.vector;
    let rotation = model.rotation.inverse() * reported.rotation;
    PoseMismatch {
        position_m: d.norm(),
        orientation_rad: rotation.angle(),
        offset_m: [d.x, d.y, d.z],
    }
}

/// The mismatch between the robot's reported TCP pose `reported` (robot base frame) and the
/// model's rigid forward kinematics at the reported joints `q` (base, joints, flange, tool; no
/// deflection), into the scratch `data`: `|p_rep − p_model|` and the angle of
/// `R_modelᵀ R_rep`. Allocation-free.
pub fn tcp_pose_mismatch(
    robot: &Robot,
    data: &mut Data,
    q: &[f64],
    reported: &Pose,
) -> Result<PoseMismatch, QLengthError> {
    robot.forward_kinematics(data, q)?;
    Ok(pose_mismatch(robot, data, reported))
}
