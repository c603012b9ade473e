//! The plant's settings (`[cell.plant]`): stiffnesses, centre shifts, base tilt and its pivot,
//! coupling, lost motion, geometry errors; their documented defaults are the table of
//! [`crate::plant`].

use crate::chain::{GeometryErrors, JOINTS, MAX_SPRINGS, SpringSpec};
use crate::error::SimError;
use deflex_model::{AxisStiffness, Robot};
use serde::{Deserialize, Serialize};

/// Largest stiffness accepted (N·m/rad); above it an axis is as good as rigid (use 0).
pub const MAX_STIFFNESS: f64 = 1e12;
/// Smallest non-zero stiffness accepted (N·m/rad): a 1 N load at 1 m would turn a softer spring
/// by more than 10 mrad.
pub const MIN_STIFFNESS: f64 = 1e2;

/// The plant's elasticity and geometry errors (hidden truth). Stiffness 0 means rigid about
/// that axis. See the module documentation for the defaults and their sources.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct PlantConfig {
    /// Torsional stiffness about x_i, y_i, z_i of joints 1..6 (N·m/rad; 0 = rigid).
    pub joint_stiffness: [[f64; 3]; JOINTS],
    /// Shift of each joint's spring centre along its z axis (m), the paper's δr.
    pub center_shift_m: [f64; JOINTS],
    /// Base tilt stiffness about x0, y0, z0 (N·m/rad; 0 = rigid).
    pub base_stiffness: [f64; 3],
    /// Point about which the base tilts, in R0 (m): where the baseplate meets the floor.
    pub base_pivot_m: [f64; 3],
    /// Correlation ρ of the J2.z and J3.z compliances (off-diagonal `ρ/√(k2 k3)`), |ρ| < 1.
    pub j2_j3_coupling: f64,
    /// Lost motion half-width of the J4, J5, J6 reducers (rad).
    pub wrist_lost_motion_rad: [f64; 3],
    /// Torque over which the lost motion is taken up (N·m).
    pub wrist_takeup_torque_nm: f64,
    /// Half-width of the friction hysteresis band of the wrist reducers (N·m).
    pub wrist_hysteresis_nm: f64,
    /// Residual joint offsets of the calibrated robot (rad), added to the description's offsets.
    /// Applied when `[cell.errors] geometry` is on.
    pub joint_offset_error_rad: [f64; JOINTS],
    /// Residual placement (link-length) errors (m), added to each joint placement's translation
    /// in the previous joint frame. Applied when `[cell.errors] geometry` is on.
    pub link_error_m: [[f64; 3]; JOINTS],
    /// Tool error (m, flange frame). Applied when `[cell.errors] geometry` is on.
    pub tool_error_m: [f64; 3],
    /// Finite-rotation equilibrium with the torques taken in the deformed configuration (the
    /// geometric stiffness); `false`: the first-order VJM assumptions.
    pub large_rotation: bool,
}

impl Default for PlantConfig {
    fn default() -> Self {
        PlantConfig {
            joint_stiffness: [
                [15e6, 15e6, 2.10e6],
                [10e6, 10e6, 1.55e6],
                [1.30e6, 6e6, 1.80e6],
                [1.2e6, 1.2e6, 0.085e6],
                [0.25e6, 0.25e6, 0.040e6],
                [0.2e6, 0.2e6, 0.030e6],
            ],
            center_shift_m: [0.0, 0.0, 0.4, 0.0, 0.0, 0.0],
            base_stiffness: [8.0e6, 4.5e6, 0.0],
            base_pivot_m: [0.0, 0.0, -0.642],
            j2_j3_coupling: 0.1,
            wrist_lost_motion_rad: [0.15e-3, 0.20e-3, 0.20e-3],
            wrist_takeup_torque_nm: 25.0,
            wrist_hysteresis_nm: 6.0,
            joint_offset_error_rad: [0.05e-3, -0.08e-3, 0.06e-3, -0.10e-3, 0.12e-3, -0.05e-3],
            link_error_m: [
                [0.03e-3, -0.02e-3, 0.04e-3],
                [-0.05e-3, 0.03e-3, 0.02e-3],
                [0.06e-3, -0.03e-3, -0.02e-3],
                [-0.02e-3, 0.04e-3, -0.05e-3],
                [0.03e-3, 0.02e-3, 0.03e-3],
                [-0.03e-3, -0.02e-3, 0.04e-3],
            ],
            tool_error_m: [0.0, 0.0, 0.05e-3],
            large_rotation: true,
        }
    }
}

fn stiffness_in_range(field: &str, k: f64) -> Result<(), SimError> {
    if k == 0.0 || (k.is_finite() && (MIN_STIFFNESS..=MAX_STIFFNESS).contains(&k)) {
        Ok(())
    } else {
        Err(SimError::config(
            field,
            format!(
                "must be 0 (rigid) or within {MIN_STIFFNESS:e}..{MAX_STIFFNESS:e} N·m/rad, got {k}"
            ),
        ))
    }
}

impl PlantConfig {
    /// Check ranges; every message names the field.
    pub fn validate(&self) -> Result<(), SimError> {
        use crate::range_check::bounded;
        for (i, joint) in self.joint_stiffness.iter().enumerate() {
            for (a, k) in joint.iter().enumerate() {
                stiffness_in_range(&format!("plant.joint_stiffness[{i}][{a}]"), *k)?;
            }
        }
        for (a, k) in self.base_stiffness.iter().enumerate() {
            stiffness_in_range(&format!("plant.base_stiffness[{a}]"), *k)?;
        }
        for (i, v) in self.center_shift_m.iter().enumerate() {
            bounded(&format!("plant.center_shift_m[{i}]"), *v, -2.0, 2.0, "m")?;
        }
        for (i, v) in self.base_pivot_m.iter().enumerate() {
            bounded(&format!("plant.base_pivot_m[{i}]"), *v, -5.0, 5.0, "m")?;
        }
        if self.j2_j3_coupling.is_nan() || self.j2_j3_coupling.abs() >= 1.0 {
            return Err(SimError::config(
                "plant.j2_j3_coupling",
                format!("must be within (−1, 1), got {}", self.j2_j3_coupling),
            ));
        }
        for (i, b) in self.wrist_lost_motion_rad.iter().enumerate() {
            bounded(
                &format!("plant.wrist_lost_motion_rad[{i}]"),
                *b,
                0.0,
                0.01,
                "rad",
            )?;
        }
        bounded(
            "plant.wrist_takeup_torque_nm",
            self.wrist_takeup_torque_nm,
            1e-3,
            1e5,
            "N·m",
        )?;
        bounded(
            "plant.wrist_hysteresis_nm",
            self.wrist_hysteresis_nm,
            0.0,
            1e5,
            "N·m",
        )?;
        for (i, v) in self.joint_offset_error_rad.iter().enumerate() {
            bounded(
                &format!("plant.joint_offset_error_rad[{i}]"),
                *v,
                -0.01,
                0.01,
                "rad",
            )?;
        }
        for (i, joint) in self.link_error_m.iter().enumerate() {
            for (a, v) in joint.iter().enumerate() {
                bounded(
                    &format!("plant.link_error_m[{i}][{a}]"),
                    *v,
                    -0.01,
                    0.01,
                    "m",
                )?;
            }
        }
        for (a, v) in self.tool_error_m.iter().enumerate() {
            bounded(&format!("plant.tool_error_m[{a}]"), *v, -0.01, 0.01, "m")?;
        }
        Ok(())
    }

    /// The linear, VJM-representable part of the plant as a `deflex_model::Robot` on the
    /// nominal geometry (for documentation and the report's "plant" column: what an ideal VJM
    /// calibration could at best find). Not representable and left out: the floor pivot of the
    /// base tilt (the model's base eDoFs turn about R0), the coupling, the lost motion, the
    /// geometric stiffness and the geometry errors.
    pub fn linear_robot(&self, nominal: &Robot) -> Result<Robot, SimError> {
        check_six_joints(nominal)?;
        let mut robot = nominal.clone();
        robot.name = format!("{} — twin plant (SIMULATED truth)", nominal.name);
        let opt = |k: f64| if k > 0.0 { Some(k) } else { None };
        robot.base_stiffness = AxisStiffness(self.base_stiffness.map(opt));
        for ((joint, k), shift) in robot
            .joints
            .iter_mut()
            .zip(&self.joint_stiffness)
            .zip(self.center_shift_m)
        {
            joint.stiffness = AxisStiffness(k.map(opt));
            joint.center_shift = shift;
        }
        robot.validate("plant")?;
        Ok(robot)
    }

    /// The springs of the plant's chain ([`crate::chain::Chain::new`]'s `springs`), in chain
    /// order (base x, y, z, then joints 1..6, each x, y, z), each with its stiffness (N·m/rad):
    /// one for every non-zero stiffness of this configuration.
    pub fn springs(&self) -> Vec<(SpringSpec, f64)> {
        let mut out = Vec::with_capacity(MAX_SPRINGS);
        for (axis, k) in self.base_stiffness.iter().enumerate() {
            if *k > 0.0 {
                out.push((SpringSpec { link: 0, axis }, *k));
            }
        }
        for (i, joint) in self.joint_stiffness.iter().enumerate() {
            for (axis, k) in joint.iter().enumerate() {
                if *k > 0.0 {
                    out.push((SpringSpec { link: i + 1, axis }, *k));
                }
            }
        }
        out
    }

    pub(super) fn geometry_errors(&self) -> GeometryErrors {
        GeometryErrors {
            joint_offset_rad: self.joint_offset_error_rad,
            placement_m: self.link_error_m,
            tool_m: self.tool_error_m,
        }
    }
}

pub(crate) fn check_six_joints(robot: &Robot) -> Result<(), SimError> {
    if robot.joint_count() != JOINTS {
        return Err(SimError::config(
            "part.robot",
            format!(
                "the twin needs a 6-joint robot, \"{}\" has {}",
                robot.name,
                robot.joint_count()
            ),
        ));
    }
    Ok(())
}
