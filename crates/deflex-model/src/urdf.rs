//! URDF reader for the geometry of a serial chain of revolute joints. Internally every joint is
//! a fixed placement followed by a rotation about local z; a URDF joint with origin `T` and axis
//! `a` becomes placement `T · R_a` (R_a takes z onto a) and the next placement starts with
//! `R_a⁻¹`, so that frames follow the URDF's link frames exactly.

use crate::error::ModelError;
use crate::robot::{AxisStiffness, Joint};
use crate::spatial::{Pose, pose_from_xyz_rpy};
use nalgebra::{Rotation3, Translation3, Unit, Vector3};
use std::collections::HashMap;

/// The serial chain read from a URDF.
pub(crate) struct UrdfChain {
    pub joints: Vec<Joint>,
    pub base_link: String,
    pub tip_link: String,
    /// Fixed placement from the last revolute joint frame to the tip link.
    pub tip_offset: Pose,
}

struct UrdfJoint {
    name: String,
    kind: String,
    parent: String,
    child: String,
    origin: Pose,
    axis: Vector3<f64>,
    limits: Option<[f64; 2]>,
}

fn parse_triplet(text: Option<&str>, path: &str, field: &str) -> Result<[f64; 3], ModelError> {
    let Some(text) = text else {
        return Ok([0.0; 3]);
    };
    let values: Vec<&str> = text.split_whitespace().collect();
    let parse = |s: &str| s.parse::<f64>().ok().filter(|v| v.is_finite());
    match values.as_slice() {
        [a, b, c] => match (parse(a), parse(b), parse(c)) {
            (Some(a), Some(b), Some(c)) => Ok([a, b, c]),
            _ => Err(invalid(
                path,
                field,
                format!("expected three finite numbers, got \"{text}\""),
            )),
        },
        _ => Err(invalid(
            path,
            field,
            format!("expected three numbers, got \"{text}\""),
        )),
    }
}

fn invalid(path: &str, field: &str, message: String) -> ModelError {
    ModelError::Invalid {
        path: path.to_string(),
        field: field.to_string(),
        message,
    }
}

/// Read the chain from `base_link` (default: the root link) to `tip_link` (default: the single
/// leaf reached by following the only child at every link).
pub(crate) fn parse_chain(
    xml: &str,
    path: &str,
    base_link: Option<&str>,
    tip_link: Option<&str>,
) -> Result<UrdfChain, ModelError> {
    let document = roxmltree::Document::parse(xml).map_err(|e| ModelError::Parse {
        path: path.to_string(),
        message: format!("not valid XML: {e}"),
    })?;
    let robot = document.root_element();
    if robot.tag_name().name() != "robot" {
        return Err(invalid(
            path,
            "<robot>",
            format!("the root element is <{}>", robot.tag_name().name()),
        ));
    }
    let mut joints = Vec::new();
    for node in robot.children().filter(|n| n.has_tag_name("joint")) {
        let name = node.attribute("name").unwrap_or("?").to_string();
        let field = |f: &str| format!("joint \"{name}\" {f}");
        let kind = node.attribute("type").unwrap_or("").to_string();
        let child_attr = |tag: &str| {
            node.children()
                .find(|c| c.has_tag_name(tag))
                .and_then(|c| c.attribute("link"))
                .map(str::to_string)
                .ok_or_else(|| {
                    invalid(path, &field(&format!("<{tag} link=...>")), "missing".into())
                })
        };
        let parent = child_attr("parent")?;
        let child = child_attr("child")?;
        let origin_node = node.children().find(|c| c.has_tag_name("origin"));
        let xyz = parse_triplet(
            origin_node.and_then(|o| o.attribute("xyz")),
            path,
            &field("<origin xyz>"),
        )?;
        let rpy = parse_triplet(
            origin_node.and_then(|o| o.attribute("rpy")),
            path,
            &field("<origin rpy>"),
        )?;
        let axis_node = node.children().find(|c| c.has_tag_name("axis"));
        let axis = match axis_node.and_then(|a| a.attribute("xyz")) {
            Some(text) => Vector3::from(parse_triplet(Some(text), path, &field("<axis xyz>"))?),
            None => Vector3::x(),
        };
        let limits = match node.children().find(|c| c.has_tag_name("limit")) {
            Some(limit) if kind == "revolute" => {
                let read = |attr: &str| -> Result<f64, ModelError> {
                    limit
                        .attribute(attr)
                        .unwrap_or("0")
                        .parse::<f64>()
                        .ok()
                        .filter(|v| v.is_finite())
                        .ok_or_else(|| {
                            invalid(
                                path,
                                &field(&format!("<limit {attr}>")),
                                "expected a finite number in rad".into(),
                            )
                        })
                };
                Some([read("lower")?, read("upper")?])
            }
            _ => None,
        };
        joints.push(UrdfJoint {
            name,
            kind,
            parent,
            child,
            origin: pose_from_xyz_rpy(xyz, rpy),
            axis,
            limits,
        });
    }
    let by_child: HashMap<&str, usize> = joints
        .iter()
        .enumerate()
        .map(|(i, j)| (j.child.as_str(), i))
        .collect();
    let root = match base_link {
        Some(b) => b.to_string(),
        None => {
            let roots: Vec<&str> = joints
                .iter()
                .map(|j| j.parent.as_str())
                .filter(|p| !by_child.contains_key(p))
                .collect::<std::collections::BTreeSet<_>>()
                .into_iter()
                .collect();
            match roots.as_slice() {
                [one] => one.to_string(),
                _ => {
                    return Err(invalid(
                        path,
                        "base_link",
                        format!(
                            "cannot tell the root link (candidates: {roots:?}); set base_link in the TOML"
                        ),
                    ));
                }
            }
        }
    };
    let tip = match tip_link {
        Some(t) => t.to_string(),
        None => {
            let mut link = root.clone();
            loop {
                let children: Vec<&UrdfJoint> =
                    joints.iter().filter(|j| j.parent == link).collect();
                match children.as_slice() {
                    [] => break link,
                    [one] => link = one.child.clone(),
                    _ => {
                        return Err(invalid(
                            path,
                            "tip_link",
                            format!("link \"{link}\" branches; set tip_link in the TOML"),
                        ));
                    }
                }
            }
        }
    };
    // Walk from the tip up to the root.
    let mut chain = Vec::new();
    let mut link = tip.clone();
    while link != root {
        let Some(&index) = by_child.get(link.as_str()) else {
            return Err(invalid(
                path,
                "tip_link",
                format!("link \"{tip}\" is not below \"{root}\""),
            ));
        };
        chain.push(index);
        link = joints[index].parent.clone();
    }
    chain.reverse();
    let mut pending = Pose::identity();
    let mut out = Vec::new();
    for index in chain {
        let joint = &joints[index];
        match joint.kind.as_str() {
            "fixed" => pending *= joint.origin,
            "revolute" | "continuous" => {
                let norm = joint.axis.norm();
                if norm.is_nan() || norm <= 1e-9 {
                    return Err(invalid(
                        path,
                        &format!("joint \"{}\" <axis xyz>", joint.name),
                        "axis must be non-zero".into(),
                    ));
                }
                let axis = Unit::new_normalize(joint.axis);
                let align =
                    Rotation3::rotation_between(&Vector3::z(), &axis).unwrap_or_else(|| {
                        Rotation3::from_axis_angle(&Vector3::x_axis(), std::f64::consts::PI)
                    });
                let align_pose = Pose::from_parts(Translation3::identity(), align);
                out.push(Joint {
                    name: joint.name.clone(),
                    placement: pending * joint.origin * align_pose,
                    theta_offset: 0.0,
                    limits: joint.limits,
                    center_shift: 0.0,
                    stiffness: AxisStiffness::RIGID,
                    dh: None,
                });
                pending = align_pose.inverse();
            }
            other => {
                return Err(invalid(
                    path,
                    &format!("joint \"{}\" type", joint.name),
                    format!(
                        "only revolute, continuous and fixed joints are supported, got \"{other}\""
                    ),
                ));
            }
        }
    }
    if out.is_empty() {
        return Err(invalid(
            path,
            "joint",
            format!("no revolute joint between \"{root}\" and \"{tip}\""),
        ));
    }
    Ok(UrdfChain {
        joints: out,
        base_link: root,
        tip_link: tip,
        tip_offset: pending,
    })
}
