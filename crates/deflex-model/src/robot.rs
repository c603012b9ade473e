//! The read-only robot model: geometry plus the VJM elastic structure (Section 2.2).

use crate::MAX_JOINTS;
use crate::error::ModelError;
use crate::spatial::Pose;
use serde::{Deserialize, Serialize};

/// An axis of a joint frame R_i (or of the base frame R0) about which a torsional spring acts.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, PartialOrd, Ord, Serialize, Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum Axis {
    /// x_i
    X,
    /// y_i
    Y,
    /// z_i: the motorised axis for a joint.
    Z,
}

impl Axis {
    /// All three axes, in order.
    pub const ALL: [Axis; 3] = [Axis::X, Axis::Y, Axis::Z];

    /// Column index in a rotation matrix (0, 1, 2).
    #[inline]
    pub fn index(self) -> usize {
        match self {
            Axis::X => 0,
            Axis::Y => 1,
            Axis::Z => 2,
        }
    }

    /// Lower-case letter used in files and tables.
    pub fn letter(self) -> char {
        match self {
            Axis::X => 'x',
            Axis::Y => 'y',
            Axis::Z => 'z',
        }
    }
}

/// Torsional stiffnesses (N·m/rad) about x, y, z of one frame; `None` means rigid about that axis.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct AxisStiffness(pub [Option<f64>; 3]);

impl AxisStiffness {
    /// No eDoF at all (rigid).
    pub const RIGID: AxisStiffness = AxisStiffness([None; 3]);

    /// Stiffness about one axis.
    #[inline]
    pub fn get(&self, axis: Axis) -> Option<f64> {
        self.0[axis.index()]
    }

    /// Set (or clear with `None`) the stiffness about one axis.
    pub fn set(&mut self, axis: Axis, stiffness: Option<f64>) {
        self.0[axis.index()] = stiffness;
    }

    /// Number of elastic axes.
    pub fn count(&self) -> usize {
        self.0.iter().filter(|k| k.is_some()).count()
    }
}

/// Modified Denavit–Hartenberg (Craig) parameters of a joint, kept for display and for writing
/// the robot back to TOML.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct DhParams {
    /// Twist about x_{i-1} (rad).
    pub alpha: f64,
    /// Length along x_{i-1} (m).
    pub a: f64,
    /// Offset along z_i (m).
    pub d: f64,
}

/// One motorised revolute joint: a fixed placement in the previous joint frame followed by a
/// rotation `q + theta_offset` about the local z axis. Modified DH and URDF are two ways to write
/// the placement.
#[derive(Clone, Debug, PartialEq)]
pub struct Joint {
    /// Joint name (`joint_1`… for DH robots, the URDF joint name otherwise).
    pub name: String,
    /// Placement of frame R_i (at zero joint angle, before `theta_offset`) in frame R_{i-1}.
    pub placement: Pose,
    /// Constant offset added to the joint value (rad).
    pub theta_offset: f64,
    /// Joint limits `[min, max]` in rad, if any.
    pub limits: Option<[f64; 2]>,
    /// The eDoF centre O_i slides this far along z_i from the frame origin (m): the paper's δr.
    pub center_shift: f64,
    /// Torsional stiffness about x_i, y_i, z_i (N·m/rad).
    pub stiffness: AxisStiffness,
    /// DH parameters when the joint was written in modified DH.
    pub dh: Option<DhParams>,
}

/// Where a robot's geometry came from when it was read from a URDF.
#[derive(Clone, Debug, PartialEq)]
pub struct UrdfSource {
    /// Absolute or TOML-relative path of the URDF file.
    pub path: String,
    /// Root link of the chain.
    pub base_link: String,
    /// Last link of the chain (the flange).
    pub tip_link: String,
}

/// Where an eDoF sits.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, PartialOrd, Ord)]
pub enum EdofSite {
    /// The base (baseplate tilt), about R0's axes at its origin.
    Base,
    /// Joint `i` (1-based, as in the paper).
    Joint(usize),
}

impl EdofSite {
    /// 0 for the base, `i` for joint `i`: the eDoF moves links with index ≥ this.
    #[inline]
    pub fn link_index(self) -> usize {
        match self {
            EdofSite::Base => 0,
            EdofSite::Joint(i) => i,
        }
    }
}

impl std::fmt::Display for EdofSite {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            EdofSite::Base => write!(f, "base"),
            EdofSite::Joint(i) => write!(f, "J{i}"),
        }
    }
}

/// One elastic degree of freedom: a torsional spring (eq. 8).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Edof {
    /// Base or joint.
    pub site: EdofSite,
    /// Axis of the site's frame.
    pub axis: Axis,
    /// Stiffness k_θ (N·m/rad).
    pub stiffness: f64,
}

impl Edof {
    /// Label as in the paper: `kθ3,x` → `J3.x`; base → `base.x`.
    pub fn label(&self) -> String {
        format!("{}.{}", self.site, self.axis.letter())
    }
}

/// A serial robot with its elastic structure. Read-only on the hot path; pair it with a
/// [`crate::Data`].
#[derive(Clone, Debug, PartialEq)]
pub struct Robot {
    /// Human-readable name.
    pub name: String,
    /// World → R0 placement.
    pub base: Pose,
    /// Base eDoFs about R0's axes at its origin (baseplate tilt).
    pub base_stiffness: AxisStiffness,
    /// Motorised joints, base to flange.
    pub joints: Vec<Joint>,
    /// Flange frame R_m → TCP frame R_t.
    pub tool: Pose,
    /// Set when the geometry was read from a URDF.
    pub urdf: Option<UrdfSource>,
}

impl Robot {
    /// Number of motorised joints.
    #[inline]
    pub fn joint_count(&self) -> usize {
        self.joints.len()
    }

    /// All eDoFs in a fixed order: base x, y, z, then joint 1 x, y, z, … (absent axes skipped).
    /// This is the column order of the eDoF Jacobian (eq. 13) and of K_θ (eq. 11).
    pub fn edofs(&self) -> impl Iterator<Item = Edof> + '_ {
        let base = Axis::ALL.into_iter().filter_map(|axis| {
            self.base_stiffness.get(axis).map(|stiffness| Edof {
                site: EdofSite::Base,
                axis,
                stiffness,
            })
        });
        let joints = self.joints.iter().enumerate().flat_map(|(i, joint)| {
            Axis::ALL.into_iter().filter_map(move |axis| {
                joint.stiffness.get(axis).map(|stiffness| Edof {
                    site: EdofSite::Joint(i + 1),
                    axis,
                    stiffness,
                })
            })
        });
        base.chain(joints)
    }

    /// Number of eDoFs.
    pub fn edof_count(&self) -> usize {
        self.base_stiffness.count()
            + self
                .joints
                .iter()
                .map(|j| j.stiffness.count())
                .sum::<usize>()
    }

    /// Stiffness of one eDoF, `None` when that axis is rigid.
    pub fn stiffness(&self, site: EdofSite, axis: Axis) -> Option<f64> {
        match site {
            EdofSite::Base => self.base_stiffness.get(axis),
            EdofSite::Joint(i) => self.joints.get(i.wrapping_sub(1))?.stiffness.get(axis),
        }
    }

    /// Set (or clear) the stiffness of one eDoF. Panics if `site` names a joint that does not
    /// exist (a programming error, not user input).
    pub fn set_stiffness(&mut self, site: EdofSite, axis: Axis, stiffness: Option<f64>) {
        match site {
            EdofSite::Base => self.base_stiffness.set(axis, stiffness),
            EdofSite::Joint(i) => self.joints[i - 1].stiffness.set(axis, stiffness),
        }
    }

    /// Check the invariants every other function relies on: 1..=[`MAX_JOINTS`] joints, finite
    /// geometry, positive finite stiffnesses, ordered limits. `origin` names the file in errors.
    pub fn validate(&self, origin: &str) -> Result<(), ModelError> {
        let invalid = |field: String, message: String| ModelError::Invalid {
            path: origin.to_string(),
            field,
            message,
        };
        if self.joints.is_empty() || self.joints.len() > MAX_JOINTS {
            return Err(invalid(
                "joint".into(),
                format!(
                    "a robot needs 1 to {MAX_JOINTS} motorised joints, found {}",
                    self.joints.len()
                ),
            ));
        }
        check_stiffness(&self.base_stiffness, "base.stiffness", &invalid)?;
        check_pose(&self.base, "base", &invalid)?;
        check_pose(&self.tool, "tool", &invalid)?;
        for (i, joint) in self.joints.iter().enumerate() {
            let field = |name: &str| format!("joint[{}] ({}).{name}", i + 1, joint.name);
            check_stiffness(&joint.stiffness, &field("stiffness"), &invalid)?;
            check_pose(&joint.placement, &field("placement"), &invalid)?;
            if !joint.theta_offset.is_finite() {
                return Err(invalid(
                    field("theta_offset"),
                    "must be a finite angle in rad".into(),
                ));
            }
            if !joint.center_shift.is_finite() {
                return Err(invalid(
                    field("center_shift"),
                    "must be a finite length in m".into(),
                ));
            }
            if let Some([lo, hi]) = joint.limits
                && !(lo.is_finite() && hi.is_finite() && lo < hi)
            {
                return Err(invalid(
                    field("limits"),
                    format!("expected [min, max] in rad with min < max, got [{lo}, {hi}]"),
                ));
            }
        }
        Ok(())
    }
}

fn check_stiffness(
    stiffness: &AxisStiffness,
    field: &str,
    invalid: &dyn Fn(String, String) -> ModelError,
) -> Result<(), ModelError> {
    for axis in Axis::ALL {
        if let Some(k) = stiffness.get(axis)
            && !(k.is_finite() && k > 0.0)
        {
            return Err(invalid(
                format!("{field}.{}", axis.letter()),
                format!(
                    "stiffness must be a positive finite number in N·m/rad (omit the axis for a rigid one), got {k}"
                ),
            ));
        }
    }
    Ok(())
}

fn check_pose(
    pose: &Pose,
    field: &str,
    invalid: &dyn Fn(String, String) -> ModelError,
) -> Result<(), ModelError> {
    let finite = pose.translation.vector.iter().all(|v| v.is_finite())
        && pose.rotation.matrix().iter().all(|v| v.is_finite());
    if finite {
        Ok(())
    } else {
        Err(invalid(
            field.to_string(),
            "must contain only finite numbers".into(),
        ))
    }
}
