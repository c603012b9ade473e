//! Robot description files: the TOML schema (documented in the README), built-in robots, and
//! writing a robot back to TOML (the calibration output).

use crate::dh::{dh_placements, standard_dh_link};
use crate::error::ModelError;
use crate::robot::{
    Axis, AxisStiffness, ComplianceCoupling, DhConvention, DhParams, EdofSite, Joint, LinkInertia,
    NamedPoint, NamedPose, Robot, STANDARD_GRAVITY, UrdfSource, check_dh_row,
};
use crate::spatial::{Pose, pose_from_xyz_rpy, rpy_from_rotation};
use nalgebra::Vector3;
use serde::Deserialize;
use std::fmt::Write as _;
use std::path::PathBuf;

/// Built-in robots, selectable by name wherever a robot file is accepted: `(name, TOML text)`.
pub const BUILTIN_ROBOTS: &[(&str, &str)] = &[
    ("tx200", include_str!("../robots/tx200.toml")),
    ("tx200-1edof", include_str!("../robots/tx200-1edof.toml")),
    ("ur10", include_str!("../robots/ur10.toml")),
    ("ur10e", include_str!("../robots/ur10e.toml")),
    ("kr210-r2700", include_str!("../robots/kr210-r2700.toml")),
    ("irb4600", include_str!("../robots/irb4600.toml")),
    ("r2000ic-165f", include_str!("../robots/r2000ic-165f.toml")),
    ("gp180", include_str!("../robots/gp180.toml")),
];

/// A built-in robot by name (see [`BUILTIN_ROBOTS`]).
pub fn builtin(name: &str) -> Option<Robot> {
    BUILTIN_ROBOTS
        .iter()
        .find(|(n, _)| *n == name)
        .map(|(n, text)| {
            robot_from_toml_str(text, &format!("builtin:{n}"), None)
                .expect("built-in robot files are valid (checked by tests)")
        })
}

/// Supplies the text of the URDF a robot TOML names with `urdf = "…"`: the model reads no file,
/// so whoever gives it a TOML that names a URDF gives it the URDF too (`deflex_app::load` reads
/// it from disk next to the TOML; [`robot_from_toml_and_urdf_str`] takes it as text).
pub trait UrdfResolver {
    /// The URDF the TOML names as `reference`: where it was found and its XML text. A resolver
    /// that cannot supply it returns its own error in [`ModelError::TextUnavailable`].
    fn resolve(&self, reference: &str) -> Result<ResolvedUrdf, ModelError>;
}

/// A URDF as a [`UrdfResolver`] found it.
#[derive(Clone, Debug, PartialEq)]
pub struct ResolvedUrdf {
    /// Where it was read from (named in messages; kept in [`UrdfSource::resolved`] so the robot
    /// can be written to another folder and still name it).
    pub path: PathBuf,
    /// The XML text.
    pub xml: String,
}

/// A URDF given as text: resolves any reference to itself.
struct UrdfText<'a>(&'a str);

impl UrdfResolver for UrdfText<'_> {
    fn resolve(&self, reference: &str) -> Result<ResolvedUrdf, ModelError> {
        Ok(ResolvedUrdf {
            path: PathBuf::from(reference),
            xml: self.0.to_string(),
        })
    }
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct RobotFile {
    name: String,
    dh: Option<DhConvention>,
    urdf: Option<String>,
    base_link: Option<String>,
    tip_link: Option<String>,
    gravity: Option<[f64; 3]>,
    base: Option<BaseSection>,
    #[serde(default, rename = "joint")]
    joints: Vec<JointSection>,
    flange: Option<PoseSection>,
    tool: Option<PoseSection>,
    payload: Option<InertiaSection>,
    #[serde(default, rename = "setup")]
    setups: Vec<NamedPoseSection>,
    #[serde(default, rename = "target")]
    targets: Vec<TargetSection>,
    #[serde(default, rename = "coupling")]
    couplings: Vec<CouplingSection>,
}

/// `[[coupling]] a = "J2.z", b = "J3.z", compliance = 1.2e-8` (rad/(N·m)).
#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct CouplingSection {
    a: String,
    b: String,
    compliance: f64,
}

/// An eDoF's label as robot files and reports write it: `J2.z` → (joint 2, z); `base.x` →
/// (base, x). `None` for anything else.
pub fn parse_edof_label(label: &str) -> Option<(EdofSite, Axis)> {
    let (site, axis) = label.trim().split_once('.')?;
    let axis = match axis {
        "x" => Axis::X,
        "y" => Axis::Y,
        "z" => Axis::Z,
        _ => return None,
    };
    let site = match site {
        "base" => EdofSite::Base,
        joint => EdofSite::Joint(joint.strip_prefix('J')?.parse().ok()?),
    };
    Some((site, axis))
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct BaseSection {
    xyz: Option<[f64; 3]>,
    rpy: Option<[f64; 3]>,
    stiffness: Option<StiffnessSection>,
    pivot: Option<[f64; 3]>,
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct PoseSection {
    xyz: Option<[f64; 3]>,
    rpy: Option<[f64; 3]>,
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct NamedPoseSection {
    name: String,
    xyz: Option<[f64; 3]>,
    rpy: Option<[f64; 3]>,
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct TargetSection {
    name: String,
    xyz: [f64; 3],
    rpy: Option<[f64; 3]>,
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct InertiaSection {
    mass: f64,
    com: Option<[f64; 3]>,
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct JointSection {
    name: Option<String>,
    alpha: Option<f64>,
    a: Option<f64>,
    d: Option<f64>,
    beta: Option<f64>,
    theta_offset: Option<f64>,
    /// Read as a list and checked to hold two values (`[lo, hi]`): a third value is an error,
    /// not ignored.
    limits: Option<Vec<f64>>,
    center_shift: Option<f64>,
    stiffness: Option<StiffnessSection>,
    mass: Option<f64>,
    com: Option<[f64; 3]>,
}

#[derive(Deserialize, Default)]
#[serde(deny_unknown_fields)]
struct StiffnessSection {
    x: Option<f64>,
    y: Option<f64>,
    z: Option<f64>,
}

impl StiffnessSection {
    fn to_axes(&self) -> AxisStiffness {
        AxisStiffness([self.x, self.y, self.z])
    }
}

/// A joint's `limits = [lo, hi]`, exactly two values.
fn limits_of(
    section: &JointSection,
    index: usize,
    invalid: &dyn Fn(String, String) -> ModelError,
) -> Result<Option<[f64; 2]>, ModelError> {
    match section.limits.as_deref() {
        None => Ok(None),
        Some(&[lo, hi]) => Ok(Some([lo, hi])),
        Some(other) => Err(invalid(
            format!("joint[{}].limits", index + 1),
            format!("expected two values [lo, hi] (rad), got {}", other.len()),
        )),
    }
}

/// Bounds checked before any trigonometry: a pose from a file.
fn checked_pose(
    xyz: Option<[f64; 3]>,
    rpy: Option<[f64; 3]>,
    field: &str,
    invalid: &dyn Fn(String, String) -> ModelError,
) -> Result<Pose, ModelError> {
    let xyz = xyz.unwrap_or([0.0; 3]);
    let rpy = rpy.unwrap_or([0.0; 3]);
    for (name, values, limit, unit) in [
        ("xyz", xyz, crate::robot::bounds::MAX_LENGTH_M, "m"),
        ("rpy", rpy, crate::robot::bounds::MAX_ANGLE_RAD, "rad"),
    ] {
        if let Some(bad) = values.iter().find(|v| !(v.is_finite() && v.abs() <= limit)) {
            return Err(invalid(
                format!("{field}.{name}"),
                format!("expected finite values within ±{limit} {unit}, got {bad}"),
            ));
        }
    }
    Ok(pose_from_xyz_rpy(xyz, rpy))
}

/// Parse a robot TOML. `origin` names the file in error messages; `urdf` supplies the URDF the
/// TOML may name (without one, a TOML naming a URDF is refused).
pub fn robot_from_toml_str(
    text: &str,
    origin: &str,
    urdf: Option<&dyn UrdfResolver>,
) -> Result<Robot, ModelError> {
    parse_robot(text, origin, urdf)
}

/// Parse a robot TOML whose `urdf = "…"` names a URDF given here as text (not read from disk):
/// for robot descriptions shipped inside a program, and for fuzzing the URDF reader.
pub fn robot_from_toml_and_urdf_str(
    text: &str,
    urdf_xml: &str,
    origin: &str,
) -> Result<Robot, ModelError> {
    parse_robot(text, origin, Some(&UrdfText(urdf_xml)))
}

fn parse_robot(
    text: &str,
    origin: &str,
    resolver: Option<&dyn UrdfResolver>,
) -> Result<Robot, ModelError> {
    let file: RobotFile = toml::from_str(text).map_err(|e| ModelError::Parse {
        path: origin.to_string(),
        message: e.to_string().trim_end().replace('\n', "\n  "),
    })?;
    let invalid = |field: String, message: String| ModelError::Invalid {
        path: origin.to_string(),
        field,
        message,
    };
    let base_section = file.base.as_ref();
    let base = checked_pose(
        base_section.and_then(|b| b.xyz),
        base_section.and_then(|b| b.rpy),
        "base",
        &invalid,
    )?;
    let base_stiffness = base_section
        .and_then(|b| b.stiffness.as_ref())
        .map(StiffnessSection::to_axes)
        .unwrap_or_default();
    let flange_offset = match &file.flange {
        Some(f) => checked_pose(f.xyz, f.rpy, "flange", &invalid)?,
        None => Pose::identity(),
    };
    let tool = match &file.tool {
        Some(t) => checked_pose(t.xyz, t.rpy, "tool", &invalid)?,
        None => Pose::identity(),
    };
    let setups = file
        .setups
        .iter()
        .enumerate()
        .map(|(i, s)| {
            Ok(NamedPose {
                name: s.name.clone(),
                pose: checked_pose(s.xyz, s.rpy, &format!("setup[{}]", i + 1), &invalid)?,
            })
        })
        .collect::<Result<Vec<_>, ModelError>>()?;
    let targets = file
        .targets
        .iter()
        .enumerate()
        .map(|(i, t)| {
            let pose = checked_pose(Some(t.xyz), t.rpy, &format!("target[{}]", i + 1), &invalid)?;
            Ok(NamedPoint {
                name: t.name.clone(),
                position: Vector3::from(t.xyz),
                rotation: t.rpy.map(|_| pose.rotation),
            })
        })
        .collect::<Result<Vec<_>, ModelError>>()?;
    let mut robot = Robot {
        name: file.name.clone(),
        base,
        base_stiffness,
        base_pivot: Vector3::from(base_section.and_then(|b| b.pivot).unwrap_or([0.0; 3])),
        joints: Vec::new(),
        flange: flange_offset,
        flange_offset,
        tool,
        urdf: None,
        dh_convention: None,
        gravity: file.gravity.map(Vector3::from).unwrap_or(STANDARD_GRAVITY),
        payload: file.payload.as_ref().map(|p| LinkInertia {
            mass_kg: p.mass,
            com: Vector3::from(p.com.unwrap_or([0.0; 3])),
        }),
        setups,
        targets,
        couplings: file
            .couplings
            .iter()
            .enumerate()
            .map(|(i, c)| {
                let edof = |label: &str, end: &str| {
                    parse_edof_label(label).ok_or_else(|| {
                        invalid(
                            format!("coupling[{}].{end}", i + 1),
                            format!(
                                "expected an eDoF such as \"J2.z\" or \"base.x\", got {label:?}"
                            ),
                        )
                    })
                };
                Ok(ComplianceCoupling {
                    a: edof(&c.a, "a")?,
                    b: edof(&c.b, "b")?,
                    compliance: c.compliance,
                })
            })
            .collect::<Result<Vec<_>, ModelError>>()?,
    };

    match &file.urdf {
        None => dh_geometry(&file, &mut robot, flange_offset, origin, &invalid)?,
        Some(urdf_path) => urdf_geometry(
            &file,
            &mut robot,
            flange_offset,
            urdf_path,
            resolver,
            &invalid,
        )?,
    }
    robot.validate(origin)?;
    Ok(robot)
}

/// The robot's joints and flange from the TOML's DH table (modified by default).
fn dh_geometry(
    file: &RobotFile,
    robot: &mut Robot,
    flange_offset: Pose,
    origin: &str,
    invalid: &dyn Fn(String, String) -> ModelError,
) -> Result<(), ModelError> {
    if file.base_link.is_some() || file.tip_link.is_some() {
        return Err(invalid(
            "base_link".into(),
            "base_link/tip_link are only meaningful with `urdf = \"...\"`".into(),
        ));
    }
    let convention = file.dh.unwrap_or_default();
    let mut rows: Vec<DhParams> = Vec::with_capacity(file.joints.len());
    for (i, section) in file.joints.iter().enumerate() {
        let name = section
            .name
            .clone()
            .unwrap_or_else(|| format!("joint_{}", i + 1));
        let joint = format!("joint[{}] ({name})", i + 1);
        // Strict: a DH row states its four numbers (β, the Hayati tilt, is optional and 0 in
        // every published table). A left-out `alpha` read as 0 turns a perpendicular axis into
        // a parallel one without a word.
        let required = |value: Option<f64>, field: &'static str| {
            value.ok_or_else(|| ModelError::MissingDhField {
                path: origin.to_string(),
                joint: joint.clone(),
                field,
            })
        };
        let row = DhParams {
            alpha: required(section.alpha, "alpha")?,
            a: required(section.a, "a")?,
            d: required(section.d, "d")?,
            beta: section.beta.unwrap_or(0.0),
        };
        required(section.theta_offset, "theta_offset")?;
        // Bounds before trigonometry: a twist of 1e308 rad has no meaningful sine.
        check_dh_row(&row, &joint, &invalid)?;
        rows.push(row);
    }
    let (placements, flange) = dh_placements(convention, &rows);
    for (i, ((section, row), placement)) in
        file.joints.iter().zip(&rows).zip(placements).enumerate()
    {
        let link_frame = match convention {
            DhConvention::Modified => Pose::identity(),
            DhConvention::Standard => standard_dh_link(row),
        };
        robot.joints.push(Joint {
            name: section
                .name
                .clone()
                .unwrap_or_else(|| format!("joint_{}", i + 1)),
            placement,
            theta_offset: section.theta_offset.unwrap_or(0.0),
            limits: limits_of(section, i, invalid)?,
            center_shift: section.center_shift.unwrap_or(0.0),
            stiffness: section
                .stiffness
                .as_ref()
                .map(StiffnessSection::to_axes)
                .unwrap_or_default(),
            dh: Some(*row),
            inertia: inertia_in_joint_frame(section, &link_frame, None),
            link_frame,
        });
    }
    robot.flange = flange * flange_offset;
    robot.dh_convention = Some(convention);
    Ok(())
}

/// The robot's joints and flange from the URDF the TOML names (the TOML's `[[joint]]` entries
/// name the URDF's revolute joints in chain order and add what a URDF lacks: stiffness, centre
/// shift, limits, masses).
fn urdf_geometry(
    file: &RobotFile,
    robot: &mut Robot,
    flange_offset: Pose,
    urdf_path: &str,
    resolver: Option<&dyn UrdfResolver>,
    invalid: &dyn Fn(String, String) -> ModelError,
) -> Result<(), ModelError> {
    if file.dh.is_some() {
        return Err(invalid(
            "dh".into(),
            "the geometry comes from the URDF; remove `dh`".into(),
        ));
    }
    let Some(resolver) = resolver else {
        return Err(invalid(
            "urdf".into(),
            format!(
                "names the URDF `{urdf_path}`, but no URDF was supplied with the text (read robot files with deflex_app::load::load_robot)"
            ),
        ));
    };
    let ResolvedUrdf {
        path: resolved,
        xml,
    } = resolver.resolve(urdf_path)?;
    let resolved_str = resolved.display().to_string();
    let chain = crate::urdf::parse_chain(
        &xml,
        &resolved_str,
        file.base_link.as_deref(),
        file.tip_link.as_deref(),
    )?;
    if file.joints.len() != chain.joints.len() {
        return Err(invalid(
            "joint".into(),
            format!(
                "the URDF chain {} → {} has {} revolute joints ({}), but the TOML lists {} [[joint]] entries; give one per URDF joint, by name, in chain order",
                chain.base_link,
                chain.tip_link,
                chain.joints.len(),
                chain
                    .joints
                    .iter()
                    .map(|j| j.name.as_str())
                    .collect::<Vec<_>>()
                    .join(", "),
                file.joints.len()
            ),
        ));
    }
    let mut joints = chain.joints;
    for (i, (joint, section)) in joints.iter_mut().zip(&file.joints).enumerate() {
        let field = format!("joint[{}]", i + 1);
        match &section.name {
            Some(name) if *name == joint.name => {}
            Some(name) => {
                return Err(invalid(
                    format!("{field}.name"),
                    format!(
                        "expected URDF joint `{}` at this position of the chain, got `{name}`",
                        joint.name
                    ),
                ));
            }
            None => {
                return Err(invalid(
                    format!("{field}.name"),
                    format!(
                        "with a URDF every [[joint]] needs `name`; expected `{}`",
                        joint.name
                    ),
                ));
            }
        }
        if section.alpha.is_some()
            || section.a.is_some()
            || section.d.is_some()
            || section.beta.is_some()
            || section.theta_offset.is_some()
        {
            return Err(invalid(
                field,
                "alpha/a/d/beta/theta_offset come from the URDF; remove them from the TOML".into(),
            ));
        }
        if section.limits.is_some() {
            joint.limits = limits_of(section, i, invalid)?;
        }
        joint.center_shift = section.center_shift.unwrap_or(0.0);
        joint.stiffness = section
            .stiffness
            .as_ref()
            .map(StiffnessSection::to_axes)
            .unwrap_or_default();
        joint.inertia = inertia_in_joint_frame(section, &joint.link_frame, joint.inertia);
    }
    robot.joints = joints;
    // The URDF's fixed joints after the last revolute joint lead to the flange (tip link).
    robot.flange = chain.tip_offset * flange_offset;
    robot.urdf = Some(UrdfSource {
        path: urdf_path.to_string(),
        resolved,
        base_link: chain.base_link,
        tip_link: chain.tip_link,
    });
    Ok(())
}

/// The TOML's `mass`/`com` of a joint (com in the description's link frame) in the joint frame,
/// overriding `fallback` (the URDF's inertials). A `com` without a mass is ignored by nothing:
/// it needs a mass.
fn inertia_in_joint_frame(
    section: &JointSection,
    link_frame: &Pose,
    fallback: Option<LinkInertia>,
) -> Option<LinkInertia> {
    match (section.mass, section.com) {
        (Some(mass), com) => Some(LinkInertia {
            mass_kg: mass,
            com: link_frame
                .transform_point(&Vector3::from(com.unwrap_or([0.0; 3])).into())
                .coords,
        }),
        (None, Some(com)) => Some(LinkInertia {
            // Validation refuses NaN: a centre of mass without a mass is an error.
            mass_kg: f64::NAN,
            com: Vector3::from(com),
        }),
        (None, None) => fallback,
    }
}

/// A 64-bit FNV-1a hash of the robot's geometry (base, joint placements and offsets, flange,
/// tool), each number rounded to 0.1 µm / 0.1 µrad first, as 16 hex digits. Plans and
/// measurement files carry it so a file can be matched to the robot it was made for. Stiffness,
/// limits and masses do not enter it.
pub fn geometry_fingerprint(robot: &Robot) -> String {
    let mut hash: u64 = 0xcbf2_9ce4_8422_2325;
    let mut feed = |value: f64| {
        let rounded = (value * 1e7).round() as i64;
        for byte in rounded.to_le_bytes() {
            hash ^= u64::from(byte);
            hash = hash.wrapping_mul(0x0000_0100_0000_01b3);
        }
    };
    let feed_pose = |pose: &Pose, feed: &mut dyn FnMut(f64)| {
        for v in pose.translation.vector.iter() {
            feed(*v);
        }
        for v in pose.rotation.matrix().iter() {
            feed(*v);
        }
    };
    feed(robot.joints.len() as f64);
    feed_pose(&robot.base, &mut feed);
    for joint in &robot.joints {
        feed_pose(&joint.placement, &mut feed);
        feed(joint.theta_offset);
    }
    feed_pose(&robot.flange, &mut feed);
    feed_pose(&robot.tool, &mut feed);
    format!("{hash:016x}")
}

impl Robot {
    /// See [`geometry_fingerprint`].
    pub fn geometry_fingerprint(&self) -> String {
        geometry_fingerprint(self)
    }
}

/// Write a robot as TOML in the same schema (the calibration result is a drop-in robot file).
/// A URDF path is written as the robot file had it; use `deflex_app::load::robot_to_toml_for` when the TOML goes
/// to another folder.
pub fn robot_to_toml(robot: &Robot) -> String {
    robot_to_toml_with_urdf_path(robot, robot.urdf.as_ref().map(|u| u.path.clone()))
}

/// [`robot_to_toml`] naming the URDF as `urdf_path` (e.g. relative to the folder the TOML will
/// be written to: `deflex_app::load::robot_to_toml_for`); `None` leaves the URDF lines out.
pub fn robot_to_toml_with_urdf_path(robot: &Robot, urdf_path: Option<String>) -> String {
    let mut out = String::new();
    let _ = writeln!(
        out,
        "# deflex robot description (SI units: m, rad, N·m/rad, kg)"
    );
    let _ = writeln!(
        out,
        "# geometry fingerprint {}",
        geometry_fingerprint(robot)
    );
    let _ = writeln!(out, "name = {}", toml_string(&robot.name));
    if let (Some(urdf), Some(path)) = (&robot.urdf, urdf_path) {
        let _ = writeln!(out, "urdf = {}", toml_string(&path));
        let _ = writeln!(out, "base_link = {}", toml_string(&urdf.base_link));
        let _ = writeln!(out, "tip_link = {}", toml_string(&urdf.tip_link));
    }
    if let Some(convention) = robot.dh_convention {
        let _ = writeln!(out, "dh = {}", toml_string(convention.name()));
    }
    if robot.gravity != STANDARD_GRAVITY {
        let _ = writeln!(
            out,
            "gravity = {}",
            toml_array(&[robot.gravity.x, robot.gravity.y, robot.gravity.z])
        );
    }
    let base_xyz = robot.base.translation.vector;
    let base_rpy = rpy_from_rotation(&robot.base.rotation);
    if base_xyz.norm() > 0.0
        || base_rpy.iter().any(|v| *v != 0.0)
        || robot.base_stiffness.count() > 0
        || robot.base_pivot != Vector3::zeros()
    {
        let _ = writeln!(out, "\n[base]");
        let _ = writeln!(
            out,
            "xyz = {}",
            toml_array(&[base_xyz.x, base_xyz.y, base_xyz.z])
        );
        let _ = writeln!(out, "rpy = {}", toml_array(&base_rpy));
        if robot.base_stiffness.count() > 0 {
            let _ = writeln!(out, "stiffness = {}", toml_stiffness(&robot.base_stiffness));
        }
        if robot.base_pivot != Vector3::zeros() {
            let p = robot.base_pivot;
            let _ = writeln!(out, "pivot = {}", toml_array(&[p.x, p.y, p.z]));
        }
    }
    for joint in &robot.joints {
        let _ = writeln!(out, "\n[[joint]]");
        let _ = writeln!(out, "name = {}", toml_string(&joint.name));
        if robot.urdf.is_none() {
            let dh = joint.dh.unwrap_or_default();
            let _ = writeln!(out, "alpha = {:?}", dh.alpha);
            let _ = writeln!(out, "a = {:?}", dh.a);
            let _ = writeln!(out, "d = {:?}", dh.d);
            if dh.beta != 0.0 {
                let _ = writeln!(out, "beta = {:?}", dh.beta);
            }
            let _ = writeln!(out, "theta_offset = {:?}", joint.theta_offset);
        }
        if let Some(limits) = joint.limits {
            let _ = writeln!(out, "limits = {}", toml_array(&limits));
        }
        if joint.center_shift != 0.0 {
            let _ = writeln!(out, "center_shift = {:?}", joint.center_shift);
        }
        if joint.stiffness.count() > 0 {
            let _ = writeln!(out, "stiffness = {}", toml_stiffness(&joint.stiffness));
        }
        if let Some(inertia) = &joint.inertia {
            let com = joint
                .link_frame
                .inverse_transform_point(&inertia.com.into())
                .coords;
            let _ = writeln!(out, "mass = {:?}", inertia.mass_kg);
            let _ = writeln!(out, "com = {}", toml_array(&[com.x, com.y, com.z]));
        }
    }
    if robot.flange_offset != Pose::identity() {
        let xyz = robot.flange_offset.translation.vector;
        let _ = writeln!(out, "\n[flange]");
        let _ = writeln!(out, "xyz = {}", toml_array(&[xyz.x, xyz.y, xyz.z]));
        let _ = writeln!(
            out,
            "rpy = {}",
            toml_array(&rpy_from_rotation(&robot.flange_offset.rotation))
        );
    }
    let tool_xyz = robot.tool.translation.vector;
    let _ = writeln!(out, "\n[tool]");
    let _ = writeln!(
        out,
        "xyz = {}",
        toml_array(&[tool_xyz.x, tool_xyz.y, tool_xyz.z])
    );
    let _ = writeln!(
        out,
        "rpy = {}",
        toml_array(&rpy_from_rotation(&robot.tool.rotation))
    );
    if let Some(payload) = &robot.payload {
        let _ = writeln!(out, "\n[payload]");
        let _ = writeln!(out, "mass = {:?}", payload.mass_kg);
        let _ = writeln!(
            out,
            "com = {}",
            toml_array(&[payload.com.x, payload.com.y, payload.com.z])
        );
    }
    for setup in &robot.setups {
        let xyz = setup.pose.translation.vector;
        let _ = writeln!(out, "\n[[setup]]");
        let _ = writeln!(out, "name = {}", toml_string(&setup.name));
        let _ = writeln!(out, "xyz = {}", toml_array(&[xyz.x, xyz.y, xyz.z]));
        let _ = writeln!(
            out,
            "rpy = {}",
            toml_array(&rpy_from_rotation(&setup.pose.rotation))
        );
    }
    for target in &robot.targets {
        let p = target.position;
        let _ = writeln!(out, "\n[[target]]");
        let _ = writeln!(out, "name = {}", toml_string(&target.name));
        let _ = writeln!(out, "xyz = {}", toml_array(&[p.x, p.y, p.z]));
        if let Some(rotation) = &target.rotation {
            let _ = writeln!(out, "rpy = {}", toml_array(&rpy_from_rotation(rotation)));
        }
    }
    for coupling in &robot.couplings {
        let label = |(site, axis): (EdofSite, Axis)| format!("{site}.{}", axis.letter());
        let _ = writeln!(out, "\n[[coupling]]");
        let _ = writeln!(out, "a = {}", toml_string(&label(coupling.a)));
        let _ = writeln!(out, "b = {}", toml_string(&label(coupling.b)));
        let _ = writeln!(out, "compliance = {:e}", coupling.compliance);
    }
    out
}

fn toml_string(s: &str) -> String {
    toml::Value::String(s.to_string()).to_string()
}

fn toml_array(values: &[f64]) -> String {
    let items: Vec<String> = values.iter().map(|v| format!("{v:?}")).collect();
    format!("[{}]", items.join(", "))
}

fn toml_stiffness(stiffness: &AxisStiffness) -> String {
    let items: Vec<String> = Axis::ALL
        .iter()
        .filter_map(|axis| {
            stiffness
                .get(*axis)
                .map(|k| format!("{} = {k:e}", axis.letter()))
        })
        .collect();
    format!("{{ {} }}", items.join(", "))
}
