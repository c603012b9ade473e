//! Robot description files: the TOML schema (documented in the README), built-in robots, and
//! writing a robot back to TOML (the calibration output).

use crate::error::ModelError;
use crate::robot::{Axis, AxisStiffness, DhParams, Joint, Robot, UrdfSource};
use crate::spatial::{mdh_placement, pose_from_xyz_rpy, rpy_from_rotation};
use serde::Deserialize;
use std::fmt::Write as _;
use std::path::Path;

/// Built-in robots, selectable by name wherever a robot file is accepted: `(name, TOML text)`.
pub const BUILTIN_ROBOTS: &[(&str, &str)] = &[
    ("tx200", include_str!("../../../robots/tx200.toml")),
    (
        "tx200-1edof",
        include_str!("../../../robots/tx200-1edof.toml"),
    ),
];

/// A built-in robot by name (`tx200`, `tx200-1edof`).
pub fn builtin(name: &str) -> Option<Robot> {
    BUILTIN_ROBOTS
        .iter()
        .find(|(n, _)| *n == name)
        .map(|(n, text)| {
            robot_from_toml_str(text, &format!("builtin:{n}"), None)
                .expect("built-in robot files are valid (checked by tests)")
        })
}

/// Load a robot from a built-in name or a TOML file path. A URDF named in the TOML is resolved
/// relative to the TOML file's folder.
pub fn load_robot(spec: &str) -> Result<Robot, ModelError> {
    if let Some(robot) = builtin(spec) {
        return Ok(robot);
    }
    let path = Path::new(spec);
    let text = std::fs::read_to_string(path).map_err(|source| ModelError::Io {
        path: if source.kind() == std::io::ErrorKind::NotFound {
            // Say what else the argument could have been.
            let names: Vec<&str> = BUILTIN_ROBOTS.iter().map(|(n, _)| *n).collect();
            format!("{spec} (not a built-in robot: {})", names.join(", "))
        } else {
            spec.to_string()
        },
        source,
    })?;
    robot_from_toml_str(&text, spec, path.parent())
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct RobotFile {
    name: String,
    urdf: Option<String>,
    base_link: Option<String>,
    tip_link: Option<String>,
    base: Option<BaseSection>,
    #[serde(default, rename = "joint")]
    joints: Vec<JointSection>,
    tool: Option<PoseSection>,
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct BaseSection {
    xyz: Option<[f64; 3]>,
    rpy: Option<[f64; 3]>,
    stiffness: Option<StiffnessSection>,
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct PoseSection {
    xyz: Option<[f64; 3]>,
    rpy: Option<[f64; 3]>,
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct JointSection {
    name: Option<String>,
    alpha: Option<f64>,
    a: Option<f64>,
    d: Option<f64>,
    theta_offset: Option<f64>,
    limits: Option<[f64; 2]>,
    center_shift: Option<f64>,
    stiffness: Option<StiffnessSection>,
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

/// Parse a robot TOML. `origin` names the file in error messages; `base_dir` resolves a relative
/// `urdf` path.
pub fn robot_from_toml_str(
    text: &str,
    origin: &str,
    base_dir: Option<&Path>,
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
    let base = pose_from_xyz_rpy(
        base_section.and_then(|b| b.xyz).unwrap_or([0.0; 3]),
        base_section.and_then(|b| b.rpy).unwrap_or([0.0; 3]),
    );
    let base_stiffness = base_section
        .and_then(|b| b.stiffness.as_ref())
        .map(StiffnessSection::to_axes)
        .unwrap_or_default();
    let tool = file
        .tool
        .as_ref()
        .map(|t| pose_from_xyz_rpy(t.xyz.unwrap_or([0.0; 3]), t.rpy.unwrap_or([0.0; 3])))
        .unwrap_or_else(crate::Pose::identity);

    let (joints, urdf) = match &file.urdf {
        None => {
            if file.base_link.is_some() || file.tip_link.is_some() {
                return Err(invalid(
                    "base_link".into(),
                    "base_link/tip_link are only meaningful with `urdf = \"...\"`".into(),
                ));
            }
            let mut joints = Vec::with_capacity(file.joints.len());
            for (i, section) in file.joints.iter().enumerate() {
                let alpha = section.alpha.unwrap_or(0.0);
                let a = section.a.unwrap_or(0.0);
                let d = section.d.unwrap_or(0.0);
                joints.push(Joint {
                    name: section
                        .name
                        .clone()
                        .unwrap_or_else(|| format!("joint_{}", i + 1)),
                    placement: mdh_placement(alpha, a, d),
                    theta_offset: section.theta_offset.unwrap_or(0.0),
                    limits: section.limits,
                    center_shift: section.center_shift.unwrap_or(0.0),
                    stiffness: section
                        .stiffness
                        .as_ref()
                        .map(StiffnessSection::to_axes)
                        .unwrap_or_default(),
                    dh: Some(DhParams { alpha, a, d }),
                });
            }
            (joints, None)
        }
        Some(urdf_path) => {
            let resolved = match base_dir {
                Some(dir) if Path::new(urdf_path).is_relative() => dir.join(urdf_path),
                _ => Path::new(urdf_path).to_path_buf(),
            };
            let resolved_str = resolved.display().to_string();
            let xml = std::fs::read_to_string(&resolved).map_err(|source| ModelError::Io {
                path: resolved_str.clone(),
                source,
            })?;
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
                    || section.theta_offset.is_some()
                {
                    return Err(invalid(
                        field,
                        "alpha/a/d/theta_offset come from the URDF; remove them from the TOML"
                            .into(),
                    ));
                }
                if section.limits.is_some() {
                    joint.limits = section.limits;
                }
                joint.center_shift = section.center_shift.unwrap_or(0.0);
                joint.stiffness = section
                    .stiffness
                    .as_ref()
                    .map(StiffnessSection::to_axes)
                    .unwrap_or_default();
            }
            let source = UrdfSource {
                path: urdf_path.clone(),
                base_link: chain.base_link,
                tip_link: chain.tip_link,
            };
            // The URDF's fixed joints after the last revolute joint belong to the flange side.
            let tool = chain.tip_offset * tool;
            return finish(
                Robot {
                    name: file.name,
                    base,
                    base_stiffness,
                    joints,
                    tool,
                    urdf: Some(source),
                },
                origin,
            );
        }
    };
    finish(
        Robot {
            name: file.name,
            base,
            base_stiffness,
            joints,
            tool,
            urdf,
        },
        origin,
    )
}

fn finish(robot: Robot, origin: &str) -> Result<Robot, ModelError> {
    robot.validate(origin)?;
    Ok(robot)
}

/// Write a robot as TOML in the same schema (the calibration result is a drop-in robot file).
pub fn robot_to_toml(robot: &Robot) -> String {
    let mut out = String::new();
    let _ = writeln!(
        out,
        "# deflex robot description (SI units: m, rad, N·m/rad)"
    );
    let _ = writeln!(out, "name = {}", toml_string(&robot.name));
    if let Some(urdf) = &robot.urdf {
        let _ = writeln!(out, "urdf = {}", toml_string(&urdf.path));
        let _ = writeln!(out, "base_link = {}", toml_string(&urdf.base_link));
        let _ = writeln!(out, "tip_link = {}", toml_string(&urdf.tip_link));
    }
    let base_xyz = robot.base.translation.vector;
    let base_rpy = rpy_from_rotation(&robot.base.rotation);
    if base_xyz.norm() > 0.0
        || base_rpy.iter().any(|v| *v != 0.0)
        || robot.base_stiffness.count() > 0
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
    }
    for joint in &robot.joints {
        let _ = writeln!(out, "\n[[joint]]");
        let _ = writeln!(out, "name = {}", toml_string(&joint.name));
        if robot.urdf.is_none() {
            let dh = joint.dh.unwrap_or(DhParams {
                alpha: 0.0,
                a: 0.0,
                d: 0.0,
            });
            let _ = writeln!(out, "alpha = {:?}", dh.alpha);
            let _ = writeln!(out, "a = {:?}", dh.a);
            let _ = writeln!(out, "d = {:?}", dh.d);
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
