//! URDF reader for the geometry of a serial chain of revolute joints. Internally every joint is
//! a fixed placement followed by a rotation about local z; a URDF joint with origin `T` and axis
//! `a` becomes placement `T · R_a` (R_a takes z onto a) and the next placement starts with
//! `R_a⁻¹`, so that frames follow the URDF's link frames exactly.
//!
//! Link inertials (`<inertial><mass>`, `<origin xyz>`) of the chain's links are summed per moving
//! body: a revolute joint's child link plus every link fixed to it, up to the next revolute
//! joint. Links off the chain and links fixed to the base are ignored.
//!
//! Hostile input is bounded: the document's nesting depth is checked before the XML parser (which
//! recurses) sees it, the node count is capped, link cycles are reported instead of walked
//! forever, and the chain is found with hash maps in linear time.

use crate::error::ModelError;
use crate::robot::{AxisStiffness, Joint, LinkInertia};
use crate::spatial::{Pose, pose_from_xyz_rpy};
use nalgebra::{Rotation3, Translation3, Unit, Vector3};
use std::collections::{HashMap, HashSet};

/// Deepest element nesting accepted (a URDF is 3–4 levels deep).
pub const MAX_URDF_DEPTH: usize = 64;
/// Most XML nodes accepted.
pub const MAX_URDF_NODES: u32 = 4_000_000;

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
    let values: Vec<&str> = text.split_whitespace().take(4).collect();
    let parse = |s: &str| s.parse::<f64>().ok().filter(|v| v.is_finite());
    match values.as_slice() {
        [a, b, c] => match (parse(a), parse(b), parse(c)) {
            (Some(a), Some(b), Some(c)) => Ok([a, b, c]),
            _ => Err(invalid(
                path,
                field,
                format!("expected three finite numbers, got \"{}\"", shorten(text)),
            )),
        },
        _ => Err(invalid(
            path,
            field,
            format!("expected three numbers, got \"{}\"", shorten(text)),
        )),
    }
}

fn shorten(text: &str) -> String {
    if text.chars().count() > 60 {
        format!("{}…", text.chars().take(60).collect::<String>())
    } else {
        text.to_string()
    }
}

fn invalid(path: &str, field: &str, message: String) -> ModelError {
    ModelError::Invalid {
        path: path.to_string(),
        field: field.to_string(),
        message,
    }
}

/// Deepest element nesting of an XML text, by a linear scan that skips comments, CDATA,
/// processing instructions, declarations and quoted attribute values. Returns as soon as
/// `limit` is exceeded.
fn nesting_depth(xml: &str, limit: usize) -> usize {
    let bytes = xml.as_bytes();
    let (mut i, mut depth, mut deepest) = (0usize, 0usize, 0usize);
    let skip_to = |from: usize, end: &[u8]| -> usize {
        bytes[from..]
            .windows(end.len())
            .position(|w| w == end)
            .map_or(bytes.len(), |p| from + p + end.len())
    };
    while i < bytes.len() {
        if bytes[i] != b'<' {
            i += 1;
            continue;
        }
        let rest = &bytes[i..];
        if rest.starts_with(b"<!--") {
            i = skip_to(i + 4, b"-->");
        } else if rest.starts_with(b"<![CDATA[") {
            i = skip_to(i + 9, b"]]>");
        } else if rest.starts_with(b"<?") {
            i = skip_to(i + 2, b"?>");
        } else if rest.starts_with(b"<!") {
            i = skip_to(i + 2, b">");
        } else if rest.starts_with(b"</") {
            depth = depth.saturating_sub(1);
            i = skip_to(i + 2, b">");
        } else {
            // A start tag: find its end outside quotes; `/>` closes it at once.
            let mut j = i + 1;
            let mut quote = None;
            let mut self_closing = false;
            while j < bytes.len() {
                let c = bytes[j];
                match quote {
                    Some(q) if c == q => quote = None,
                    Some(_) => {}
                    None if c == b'"' || c == b'\'' => quote = Some(c),
                    None if c == b'>' => {
                        self_closing = bytes[j - 1] == b'/';
                        break;
                    }
                    None => {}
                }
                j += 1;
            }
            if !self_closing {
                depth += 1;
                deepest = deepest.max(depth);
                if deepest > limit {
                    return deepest;
                }
            }
            i = j + 1;
        }
    }
    deepest
}

/// Read the chain from `base_link` (default: the root link) to `tip_link` (default: the single
/// leaf reached by following the only child at every link).
pub(crate) fn parse_chain(
    xml: &str,
    path: &str,
    base_link: Option<&str>,
    tip_link: Option<&str>,
) -> Result<UrdfChain, ModelError> {
    let document = parse_document(xml, path)?;
    let robot = document.root_element();
    let inertials = read_inertials(robot, path)?;
    let joints = robot
        .children()
        .filter(|n| n.has_tag_name("joint"))
        .map(|node| read_joint(node, path))
        .collect::<Result<Vec<_>, _>>()?;
    check_names(robot, &joints, path)?;
    let tree = JointTree::new(&joints, path)?;
    let root = match base_link {
        Some(b) => b.to_string(),
        None => tree.root(&joints, path)?,
    };
    let tip = match tip_link {
        Some(t) => t.to_string(),
        None => tree.leaf(&joints, &root, path)?,
    };
    let chain = tree.chain(&joints, &root, &tip, path)?;
    let (out, tip_offset) = assemble(&joints, &chain, &inertials, path)?;
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
        tip_offset,
    })
}

/// Link and joint names unique, and every joint's parent and child a declared `<link>`: a
/// duplicated name or a dangling link is an error, not a chain silently built from the first.
fn check_names(robot: roxmltree::Node, joints: &[UrdfJoint], path: &str) -> Result<(), ModelError> {
    let mut links: std::collections::HashSet<&str> = std::collections::HashSet::new();
    for link in robot.children().filter(|n| n.has_tag_name("link")) {
        let name = link.attribute("name").unwrap_or("");
        if !links.insert(name) {
            return Err(invalid(
                path,
                "link",
                format!("link name \"{name}\" appears twice"),
            ));
        }
    }
    let mut names: std::collections::HashSet<&str> = std::collections::HashSet::new();
    for joint in joints {
        if !names.insert(joint.name.as_str()) {
            return Err(invalid(
                path,
                "joint",
                format!("joint name \"{}\" appears twice", joint.name),
            ));
        }
        for (role, link) in [("parent", &joint.parent), ("child", &joint.child)] {
            if !links.contains(link.as_str()) {
                return Err(invalid(
                    path,
                    &format!("joint \"{}\" <{role}>", joint.name),
                    format!("link \"{link}\" is not declared by a <link>"),
                ));
            }
        }
    }
    Ok(())
}

/// The XML document, its nesting depth bounded before the (recursive) parser sees it, with a
/// `<robot>` root.
fn parse_document<'x>(xml: &'x str, path: &str) -> Result<roxmltree::Document<'x>, ModelError> {
    let depth = nesting_depth(xml, MAX_URDF_DEPTH);
    if depth > MAX_URDF_DEPTH {
        return Err(ModelError::Parse {
            path: path.to_string(),
            message: format!(
                "elements are nested more than {MAX_URDF_DEPTH} levels deep; a URDF needs 4"
            ),
        });
    }
    let options = roxmltree::ParsingOptions {
        allow_dtd: false,
        nodes_limit: MAX_URDF_NODES,
    };
    let document =
        roxmltree::Document::parse_with_options(xml, options).map_err(|e| ModelError::Parse {
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
    Ok(document)
}

/// The mass and centre of mass (link frame) of every link with an `<inertial><mass>`.
fn read_inertials(
    robot: roxmltree::Node,
    path: &str,
) -> Result<HashMap<String, LinkInertia>, ModelError> {
    let mut inertials: HashMap<String, LinkInertia> = HashMap::new();
    for link in robot.children().filter(|n| n.has_tag_name("link")) {
        let name = link.attribute("name").unwrap_or("?");
        let Some(inertial) = link.children().find(|c| c.has_tag_name("inertial")) else {
            continue;
        };
        let field = format!("link \"{name}\" <inertial>");
        let mass = match inertial
            .children()
            .find(|c| c.has_tag_name("mass"))
            .and_then(|m| m.attribute("value"))
        {
            Some(text) => text
                .trim()
                .parse::<f64>()
                .ok()
                .filter(|m| m.is_finite() && *m >= 0.0)
                .ok_or_else(|| {
                    invalid(
                        path,
                        &format!("{field} <mass value>"),
                        format!(
                            "expected a non-negative mass in kg, got \"{}\"",
                            shorten(text)
                        ),
                    )
                })?,
            None => continue,
        };
        let com = parse_triplet(
            inertial
                .children()
                .find(|c| c.has_tag_name("origin"))
                .and_then(|o| o.attribute("xyz")),
            path,
            &format!("{field} <origin xyz>"),
        )?;
        inertials.insert(
            name.to_string(),
            LinkInertia {
                mass_kg: mass,
                com: Vector3::from(com),
            },
        );
    }
    Ok(inertials)
}

/// One `<joint>`: its links, origin (bounded before any trigonometry), axis and limits.
fn read_joint(node: roxmltree::Node, path: &str) -> Result<UrdfJoint, ModelError> {
    let name = node.attribute("name").unwrap_or("?").to_string();
    let field = |f: &str| format!("joint \"{name}\" {f}");
    let kind = node.attribute("type").unwrap_or("").to_string();
    let child_attr = |tag: &str| {
        node.children()
            .find(|c| c.has_tag_name(tag))
            .and_then(|c| c.attribute("link"))
            .map(str::to_string)
            .ok_or_else(|| invalid(path, &field(&format!("<{tag} link=...>")), "missing".into()))
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
    if let Some(bad) = xyz
        .iter()
        .find(|v| v.abs() > crate::robot::bounds::MAX_LENGTH_M)
        .or_else(|| {
            rpy.iter()
                .find(|v| v.abs() > crate::robot::bounds::MAX_ANGLE_RAD)
        })
    {
        return Err(invalid(
            path,
            &field("<origin>"),
            format!(
                "{bad} is out of range (lengths within ±{} m, angles within ±{} rad)",
                crate::robot::bounds::MAX_LENGTH_M,
                crate::robot::bounds::MAX_ANGLE_RAD
            ),
        ));
    }
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
    Ok(UrdfJoint {
        name,
        kind,
        parent,
        child,
        origin: pose_from_xyz_rpy(xyz, rpy),
        axis,
        limits,
    })
}

/// The joints indexed by child and by parent link (hash maps: linear time on any input).
struct JointTree<'j> {
    by_child: HashMap<&'j str, usize>,
    by_parent: HashMap<&'j str, Vec<usize>>,
}

impl<'j> JointTree<'j> {
    /// Index `joints`; a link that is the child of two joints is refused (a URDF is a tree).
    fn new(joints: &'j [UrdfJoint], path: &str) -> Result<JointTree<'j>, ModelError> {
        let mut by_child: HashMap<&str, usize> = HashMap::with_capacity(joints.len());
        let mut by_parent: HashMap<&str, Vec<usize>> = HashMap::with_capacity(joints.len());
        for (i, joint) in joints.iter().enumerate() {
            if by_child.insert(joint.child.as_str(), i).is_some() {
                return Err(invalid(
                    path,
                    &format!("joint \"{}\" <child>", joint.name),
                    format!(
                        "link \"{}\" is the child of two joints; a URDF is a tree",
                        joint.child
                    ),
                ));
            }
            by_parent.entry(joint.parent.as_str()).or_default().push(i);
        }
        Ok(JointTree {
            by_child,
            by_parent,
        })
    }

    /// The one link that is no joint's child.
    fn root(&self, joints: &[UrdfJoint], path: &str) -> Result<String, ModelError> {
        let roots: Vec<&str> = joints
            .iter()
            .map(|j| j.parent.as_str())
            .filter(|p| !self.by_child.contains_key(p))
            .collect::<std::collections::BTreeSet<_>>()
            .into_iter()
            .take(5)
            .collect();
        match roots.as_slice() {
            [one] => Ok(one.to_string()),
            [] => Err(invalid(
                path,
                "base_link",
                "every link has a parent: the joints form a cycle".into(),
            )),
            _ => Err(invalid(
                path,
                "base_link",
                format!(
                    "cannot tell the root link (candidates include: {roots:?}); set base_link in the TOML"
                ),
            )),
        }
    }

    /// The leaf reached from `root` by following the only child at every link.
    fn leaf(&self, joints: &[UrdfJoint], root: &str, path: &str) -> Result<String, ModelError> {
        let mut link = root;
        let mut visited = HashSet::new();
        loop {
            if !visited.insert(link) {
                return Err(cycle(path, link));
            }
            match self.by_parent.get(link).map(Vec::as_slice) {
                None | Some([]) => return Ok(link.to_string()),
                Some([one]) => link = joints[*one].child.as_str(),
                Some(_) => {
                    return Err(invalid(
                        path,
                        "tip_link",
                        format!("link \"{link}\" branches; set tip_link in the TOML"),
                    ));
                }
            }
        }
    }

    /// The joints from `root` down to `tip`, in order: walked from the tip up (a chain visits
    /// each joint at most once, so a longer walk is a cycle).
    fn chain(
        &self,
        joints: &[UrdfJoint],
        root: &str,
        tip: &str,
        path: &str,
    ) -> Result<Vec<usize>, ModelError> {
        let mut chain = Vec::new();
        let mut link = tip;
        while link != root {
            let Some(&index) = self.by_child.get(link) else {
                return Err(invalid(
                    path,
                    "tip_link",
                    format!("link \"{tip}\" is not below \"{root}\""),
                ));
            };
            if chain.len() > joints.len() {
                return Err(cycle(path, link));
            }
            chain.push(index);
            link = joints[index].parent.as_str();
        }
        chain.reverse();
        Ok(chain)
    }
}

fn cycle(path: &str, link: &str) -> ModelError {
    invalid(
        path,
        "joint",
        format!("the joints form a cycle through link \"{link}\"; a URDF is a tree"),
    )
}

/// The model's joints along `chain`: each revolute joint is a placement `T · R_a` (the
/// fixed joints before it folded in) and a rotation about local z; every body's links are
/// summed into its inertia. Returns the joints and the fixed placement from the last one to the
/// tip.
fn assemble(
    joints: &[UrdfJoint],
    chain: &[usize],
    inertials: &HashMap<String, LinkInertia>,
    path: &str,
) -> Result<(Vec<Joint>, Pose), ModelError> {
    let mut pending = Pose::identity();
    let mut out: Vec<Joint> = Vec::new();
    // Mass-weighted sum of the current body's centres of mass (joint frame) and its mass.
    let mut body = (Vector3::zeros(), 0.0);
    let flush_body = |out: &mut Vec<Joint>, body: &mut (Vector3<f64>, f64)| {
        if let Some(last) = out.last_mut()
            && body.1 > 0.0
        {
            last.inertia = Some(LinkInertia {
                mass_kg: body.1,
                com: body.0 / body.1,
            });
        }
        *body = (Vector3::zeros(), 0.0);
    };
    for &index in chain {
        let joint = &joints[index];
        match joint.kind.as_str() {
            "fixed" => pending *= joint.origin,
            "revolute" | "continuous" => {
                flush_body(&mut out, &mut body);
                let align_pose = axis_alignment(joint, path)?;
                out.push(Joint {
                    name: joint.name.clone(),
                    placement: pending * joint.origin * align_pose,
                    theta_offset: 0.0,
                    limits: joint.limits,
                    center_shift: 0.0,
                    stiffness: AxisStiffness::RIGID,
                    dh: None,
                    inertia: None,
                    link_frame: align_pose.inverse(),
                });
                pending = align_pose.inverse();
            }
            other => {
                return Err(invalid(
                    path,
                    &format!("joint \"{}\" type", joint.name),
                    format!(
                        "only revolute, continuous and fixed joints are supported, got \"{}\"",
                        shorten(other)
                    ),
                ));
            }
        }
        // The joint's child link is now `pending` in the last revolute joint's frame.
        if !out.is_empty()
            && let Some(inertia) = inertials.get(&joint.child)
        {
            let com = pending.transform_point(&inertia.com.into()).coords;
            body.0 += com * inertia.mass_kg;
            body.1 += inertia.mass_kg;
        }
    }
    flush_body(&mut out, &mut body);
    Ok((out, pending))
}

/// `R_a` as a pose: the rotation taking z onto the joint's (non-zero) axis `a`.
fn axis_alignment(joint: &UrdfJoint, path: &str) -> Result<Pose, ModelError> {
    let norm = joint.axis.norm();
    if norm.is_nan() || norm <= 1e-9 {
        return Err(invalid(
            path,
            &format!("joint \"{}\" <axis xyz>", joint.name),
            "axis must be non-zero".into(),
        ));
    }
    let axis = Unit::new_normalize(joint.axis);
    let align = Rotation3::rotation_between(&Vector3::z(), &axis)
        .unwrap_or_else(|| Rotation3::from_axis_angle(&Vector3::x_axis(), std::f64::consts::PI));
    Ok(Pose::from_parts(Translation3::identity(), align))
}
