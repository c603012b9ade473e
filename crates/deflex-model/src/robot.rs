//! The read-only robot model: geometry plus the VJM elastic structure (Section 2.2).

use crate::MAX_JOINTS;
use crate::error::ModelError;
use crate::spatial::Pose;
use nalgebra::Vector3;
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

/// Which Denavit–Hartenberg convention a robot file uses.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum DhConvention {
    /// Modified DH (Craig): `T(i-1,i) = RotX(α_i)·RotY(β_i)·TransX(a_i)·TransZ(d_i)·RotZ(q_i+θ_i)`.
    #[default]
    Modified,
    /// Standard DH (as UR and most datasheets publish it):
    /// `T(i-1,i) = RotZ(q_i+θ_i)·TransZ(d_i)·TransX(a_i)·RotX(α_i)·RotY(β_i)`.
    Standard,
}

impl DhConvention {
    /// The word used in robot files (`modified`, `standard`).
    pub fn name(self) -> &'static str {
        match self {
            DhConvention::Modified => "modified",
            DhConvention::Standard => "standard",
        }
    }
}

/// Denavit–Hartenberg parameters of one joint's row, in the robot's [`DhConvention`], with
/// Hayati's β (a rotation about y) for consecutive axes that are (nearly) parallel, where the
/// classic parameters jump under a small tilt. β is 0 in every nominal table; calibration may
/// identify it. Kept for display, for writing the robot back to TOML and for geometric
/// calibration, which changes these and rebuilds the placements ([`Robot::rebuild_dh_geometry`]).
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct DhParams {
    /// Twist α (rad).
    pub alpha: f64,
    /// Length a (m).
    pub a: f64,
    /// Offset d along the joint axis (m).
    pub d: f64,
    /// Hayati tilt β about y (rad).
    pub beta: f64,
}

/// Mass and centre of mass of the body a joint moves (its link plus everything rigidly attached
/// up to the next joint), for gravity-induced deflection.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct LinkInertia {
    /// Mass (kg).
    pub mass_kg: f64,
    /// Centre of mass in the joint frame R_i (m).
    pub com: Vector3<f64>,
}

/// A named rigid placement (a tracker set-up: the robot's world frame in the tracker frame).
#[derive(Clone, Debug, PartialEq)]
pub struct NamedPose {
    /// Label (the measurement file's `setup` column).
    pub name: String,
    /// `p_tracker = pose · p_world`.
    pub pose: Pose,
}

/// A named point on the flange (a tracker target, a probe tip), in the flange frame (m).
#[derive(Clone, Debug, PartialEq)]
pub struct NamedPoint {
    /// Label (the measurement file's `target` column).
    pub name: String,
    /// Position in the flange frame (m).
    pub position: Vector3<f64>,
    /// Orientation of the target's own frame in the flange frame, when known (a 6-DoF probe
    /// whose orientation the tracker measures); written as `rpy` in the robot file.
    pub rotation: Option<nalgebra::Rotation3<f64>>,
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
    /// DH row when the geometry was written as a DH table (see [`Robot::dh_convention`]).
    pub dh: Option<DhParams>,
    /// Mass and centre of mass of the body this joint moves, if known.
    pub inertia: Option<LinkInertia>,
    /// R_i → the frame in which the robot file writes this link's centre of mass: identity for
    /// modified DH, `L_i` for standard DH (the DH frame at the end of the link), the child
    /// link's frame for a URDF.
    pub link_frame: Pose,
}

/// Where a robot's geometry came from when it was read from a URDF.
#[derive(Clone, Debug, PartialEq)]
pub struct UrdfSource {
    /// The URDF path as the robot file wrote it (absolute, or relative to the robot file).
    pub path: String,
    /// The path the URDF was read from (the robot file's folder joined with `path`); used to
    /// rewrite `path` when the robot is written to another folder.
    pub resolved: std::path::PathBuf,
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

/// An off-diagonal joint compliance between two eDoFs (rad/(N·m)): the torque on one turns the
/// other, `θ_a += c τ_b`, `θ_b += c τ_a`, so `K_θ⁻¹` is no longer diagonal (eq. 11 generalised).
/// A counterbalance or a shared casting couples a robot's two pitch joints this way; no diagonal
/// `K_θ` represents it. The joint compliance stays positive definite: `c² < c_a c_b`
/// ([`Robot::validate`]). The deflection stays linear in `c`, so it is identified by the same
/// weighted least squares as the eDoF compliances.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ComplianceCoupling {
    /// The first eDoF (site and axis; the robot must have a stiffness there).
    pub a: (EdofSite, Axis),
    /// The second eDoF.
    pub b: (EdofSite, Axis),
    /// Off-diagonal compliance `c` (rad/(N·m)), either sign.
    pub compliance: f64,
}

impl ComplianceCoupling {
    /// Label `J2.z–J3.z`.
    pub fn label(&self) -> String {
        format!(
            "{}.{}–{}.{}",
            self.a.0,
            self.a.1.letter(),
            self.b.0,
            self.b.1.letter()
        )
    }

    /// The correlation `c / √(c_a c_b)` with the robot's eDoF compliances (|ρ| < 1), if both
    /// eDoFs have a stiffness.
    pub fn correlation(&self, robot: &Robot) -> Option<f64> {
        let ka = robot.stiffness(self.a.0, self.a.1)?;
        let kb = robot.stiffness(self.b.0, self.b.1)?;
        Some(self.compliance * (ka * kb).sqrt())
    }
}

/// Most couplings a robot may have.
pub const MAX_COUPLINGS: usize = 8;

/// A serial robot with its elastic structure. Read-only on the hot path; pair it with a
/// [`crate::Data`].
#[derive(Clone, Debug, PartialEq)]
pub struct Robot {
    /// Human-readable name.
    pub name: String,
    /// World → R0 placement.
    pub base: Pose,
    /// Base eDoFs about R0's axes through [`Robot::base_pivot`] (baseplate tilt).
    pub base_stiffness: AxisStiffness,
    /// Centre of the base eDoFs in R0 (m): where the baseplate tilts. R0's origin by default; a
    /// baseplate bolted to the floor tilts about a point near the floor, which for a robot whose
    /// R0 sits at shoulder height is well below R0 (the TX200's baseplate is 0.642 m below).
    pub base_pivot: Vector3<f64>,
    /// Motorised joints, base to flange.
    pub joints: Vec<Joint>,
    /// Last joint frame R_N → flange frame R_m (identity for modified DH; `TransX(a_N)·RotX(α_N)·
    /// RotY(β_N)` for standard DH; the fixed joints after the last revolute one in a URDF).
    pub flange: Pose,
    /// The robot file's `[flange]`: an extra fixed placement after the DH table's last frame,
    /// for arms whose flange frame is not the last DH frame (KUKA's A6 axis points into the
    /// wrist while `$FLANGE` z points out). Included in `flange`; kept to rebuild it.
    pub flange_offset: Pose,
    /// Flange frame R_m → TCP frame R_t.
    pub tool: Pose,
    /// Set when the geometry was read from a URDF.
    pub urdf: Option<UrdfSource>,
    /// Set when the geometry was written as a DH table (every joint then has `dh`).
    pub dh_convention: Option<DhConvention>,
    /// Gravity in world axes (m/s²), for gravity-induced deflection. Default `[0, 0, −9.81]`.
    pub gravity: Vector3<f64>,
    /// Payload carried at the flange, if any: mass and centre of mass in the flange frame.
    pub payload: Option<LinkInertia>,
    /// Tracker set-ups known to the model (calibrated registrations), by name.
    pub setups: Vec<NamedPose>,
    /// Targets on the flange known to the model (calibrated probe/reflector offsets), by name.
    pub targets: Vec<NamedPoint>,
    /// Off-diagonal joint compliances (none in the paper's model).
    pub couplings: Vec<ComplianceCoupling>,
}

/// Standard gravity (m/s²) pointing down the world z axis.
pub const STANDARD_GRAVITY: Vector3<f64> = Vector3::new(0.0, 0.0, -9.80665);

impl Robot {
    /// Whether the model carries a tool of its own: a flange → TCP other than the identity (a
    /// model without one has its TCP at the flange, and a cell gives it the cell's tool).
    pub fn has_tool(&self) -> bool {
        self.tool != Pose::identity()
    }

    /// The couplings' invariants: at most [`MAX_COUPLINGS`], between two distinct eDoFs the
    /// robot has, each pair once, `|c| < √(c_a c_b)` (a positive definite joint compliance).
    fn check_couplings(
        &self,
        invalid: &dyn Fn(String, String) -> ModelError,
    ) -> Result<(), ModelError> {
        if self.couplings.len() > MAX_COUPLINGS {
            return Err(invalid(
                "coupling".into(),
                format!(
                    "at most {MAX_COUPLINGS} couplings, found {}",
                    self.couplings.len()
                ),
            ));
        }
        let mut pairs = std::collections::BTreeSet::new();
        for (i, c) in self.couplings.iter().enumerate() {
            let field = format!("coupling[{}] ({})", i + 1, c.label());
            for (end, (site, axis)) in [("a", c.a), ("b", c.b)] {
                if let EdofSite::Joint(j) = site
                    && (j == 0 || j > self.joints.len())
                {
                    return Err(invalid(
                        format!("{field}.{end}"),
                        format!("the robot has joints 1 to {}, not {j}", self.joints.len()),
                    ));
                }
                if self.stiffness(site, axis).is_none() {
                    return Err(invalid(
                        format!("{field}.{end}"),
                        format!(
                            "{site}.{} has no stiffness: a coupling joins two eDoFs of the model",
                            axis.letter()
                        ),
                    ));
                }
            }
            if c.a == c.b {
                return Err(invalid(
                    field,
                    "a coupling joins two different eDoFs".into(),
                ));
            }
            let key = if c.a <= c.b { (c.a, c.b) } else { (c.b, c.a) };
            if !pairs.insert(key) {
                return Err(invalid(field, "this pair is coupled twice".into()));
            }
            let rho = c.correlation(self).unwrap_or(f64::NAN);
            if !(c.compliance.is_finite() && rho.abs() < 1.0) {
                return Err(invalid(
                    format!("{field}.compliance"),
                    format!(
                        "expected |c| < √(c_a c_b) (a positive definite joint compliance), got c = {:e} rad/(N·m), correlation {rho:.3}",
                        c.compliance
                    ),
                ));
            }
        }
        Ok(())
    }

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
    /// geometry within [`bounds`], stiffnesses, masses and limits within their bounds. `origin`
    /// names the file in errors.
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
        check_vector(
            &self.base_pivot,
            "base.pivot",
            bounds::MAX_LENGTH_M,
            "m",
            &invalid,
        )?;
        check_pose(&self.flange, "flange", &invalid)?;
        check_pose(&self.flange_offset, "flange", &invalid)?;
        check_pose(&self.tool, "tool", &invalid)?;
        check_vector(
            &self.gravity,
            "gravity",
            bounds::MAX_GRAVITY_M_S2,
            "m/s²",
            &invalid,
        )?;
        if let Some(payload) = &self.payload {
            check_inertia(payload, "payload", &invalid)?;
        }
        for (i, joint) in self.joints.iter().enumerate() {
            let field = |name: &str| format!("joint[{}] ({}).{name}", i + 1, joint.name);
            check_stiffness(&joint.stiffness, &field("stiffness"), &invalid)?;
            check_pose(&joint.placement, &field("placement"), &invalid)?;
            check_scalar(
                joint.theta_offset,
                &field("theta_offset"),
                bounds::MAX_ANGLE_RAD,
                "rad",
                &invalid,
            )?;
            check_scalar(
                joint.center_shift,
                &field("center_shift"),
                bounds::MAX_LENGTH_M,
                "m",
                &invalid,
            )?;
            if let Some([lo, hi]) = joint.limits {
                let within = |v: f64| v.is_finite() && v.abs() <= bounds::MAX_JOINT_LIMIT_RAD;
                if !(within(lo) && within(hi) && lo < hi) {
                    return Err(invalid(
                        field("limits"),
                        format!(
                            "expected [min, max] in rad with min < max, each within ±{}, got [{lo}, {hi}]",
                            bounds::MAX_JOINT_LIMIT_RAD
                        ),
                    ));
                }
            }
            if let Some(dh) = &joint.dh {
                check_dh_row(dh, &format!("joint[{}] ({})", i + 1, joint.name), &invalid)?;
            }
            if let Some(inertia) = &joint.inertia {
                check_inertia(inertia, &field(""), &invalid)?;
            }
        }
        self.check_couplings(&invalid)?;
        let mut names = std::collections::BTreeSet::new();
        for (i, setup) in self.setups.iter().enumerate() {
            check_pose(
                &setup.pose,
                &format!("setup[{}] ({})", i + 1, setup.name),
                &invalid,
            )?;
            if !names.insert(("setup", setup.name.as_str())) {
                return Err(invalid(
                    format!("setup[{}].name", i + 1),
                    format!("set-up `{}` is listed twice", setup.name),
                ));
            }
        }
        for (i, target) in self.targets.iter().enumerate() {
            let field = format!("target[{}] ({}).xyz", i + 1, target.name);
            check_vector(
                &target.position,
                &field,
                bounds::MAX_LENGTH_M,
                "m",
                &invalid,
            )?;
            if !names.insert(("target", target.name.as_str())) {
                return Err(invalid(
                    format!("target[{}].name", i + 1),
                    format!("target `{}` is listed twice", target.name),
                ));
            }
        }
        Ok(())
    }
}

/// Bounds on robot-file values. A value outside is refused at load with the field named: it
/// would make every result meaningless (a stiffness of 5e-324 N·m/rad is an infinite compliance,
/// a twist of 1e308 rad has no meaningful sine).
pub mod bounds {
    /// Largest length (m): link lengths, offsets, centre shifts, tool and base translations.
    pub const MAX_LENGTH_M: f64 = 100.0;
    /// Largest fixed angle (rad): twists, offsets, roll–pitch–yaw (two turns).
    pub const MAX_ANGLE_RAD: f64 = 4.0 * std::f64::consts::PI;
    /// Largest joint limit magnitude (rad), generous for multi-turn joints.
    pub const MAX_JOINT_LIMIT_RAD: f64 = 100.0;
    /// Smallest torsional stiffness (N·m/rad).
    pub const MIN_STIFFNESS: f64 = 1e-2;
    /// Largest torsional stiffness (N·m/rad); beyond it, leave the axis out (rigid).
    pub const MAX_STIFFNESS: f64 = 1e13;
    /// Largest link or payload mass (kg).
    pub const MAX_MASS_KG: f64 = 1e5;
    /// Largest gravity magnitude (m/s²).
    pub const MAX_GRAVITY_M_S2: f64 = 100.0;
}

/// A DH row within [`bounds`]; `joint_field` is e.g. `joint[3] (joint_3)`.
pub(crate) fn check_dh_row(
    row: &DhParams,
    joint_field: &str,
    invalid: &dyn Fn(String, String) -> ModelError,
) -> Result<(), ModelError> {
    let field = |name: &str| format!("{joint_field}.{name}");
    check_scalar(
        row.alpha,
        &field("alpha"),
        bounds::MAX_ANGLE_RAD,
        "rad",
        invalid,
    )?;
    check_scalar(
        row.beta,
        &field("beta"),
        bounds::MAX_ANGLE_RAD,
        "rad",
        invalid,
    )?;
    check_scalar(row.a, &field("a"), bounds::MAX_LENGTH_M, "m", invalid)?;
    check_scalar(row.d, &field("d"), bounds::MAX_LENGTH_M, "m", invalid)
}

fn check_scalar(
    value: f64,
    field: &str,
    limit: f64,
    unit: &str,
    invalid: &dyn Fn(String, String) -> ModelError,
) -> Result<(), ModelError> {
    if value.is_finite() && value.abs() <= limit {
        Ok(())
    } else {
        Err(invalid(
            field.to_string(),
            format!("expected a finite value within ±{limit} {unit}, got {value}"),
        ))
    }
}

fn check_vector(
    value: &Vector3<f64>,
    field: &str,
    limit: f64,
    unit: &str,
    invalid: &dyn Fn(String, String) -> ModelError,
) -> Result<(), ModelError> {
    for (c, v) in ["x", "y", "z"].iter().zip(value.iter()) {
        check_scalar(*v, &format!("{field}.{c}"), limit, unit, invalid)?;
    }
    Ok(())
}

fn check_inertia(
    inertia: &LinkInertia,
    field: &str,
    invalid: &dyn Fn(String, String) -> ModelError,
) -> Result<(), ModelError> {
    let mass = inertia.mass_kg;
    if !(mass.is_finite() && (0.0..=bounds::MAX_MASS_KG).contains(&mass)) {
        return Err(invalid(
            format!("{field}mass"),
            format!(
                "expected a mass in kg within [0, {}], got {mass}",
                bounds::MAX_MASS_KG
            ),
        ));
    }
    check_vector(
        &inertia.com,
        &format!("{field}com"),
        bounds::MAX_LENGTH_M,
        "m",
        invalid,
    )
}

fn check_stiffness(
    stiffness: &AxisStiffness,
    field: &str,
    invalid: &dyn Fn(String, String) -> ModelError,
) -> Result<(), ModelError> {
    for axis in Axis::ALL {
        if let Some(k) = stiffness.get(axis)
            && !(k.is_finite() && (bounds::MIN_STIFFNESS..=bounds::MAX_STIFFNESS).contains(&k))
        {
            return Err(invalid(
                format!("{field}.{}", axis.letter()),
                format!(
                    "stiffness must be a positive finite number in N·m/rad within [{:e}, {:e}] (omit the axis for a rigid one), got {k}",
                    bounds::MIN_STIFFNESS,
                    bounds::MAX_STIFFNESS
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
    let finite = pose
        .translation
        .vector
        .iter()
        .all(|v| v.is_finite() && v.abs() <= bounds::MAX_LENGTH_M)
        && pose.rotation.matrix().iter().all(|v| v.is_finite());
    if finite {
        Ok(())
    } else {
        Err(invalid(
            field.to_string(),
            format!(
                "must contain only finite numbers, translations within ±{} m",
                bounds::MAX_LENGTH_M
            ),
        ))
    }
}
