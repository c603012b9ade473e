//! # Calibrated geometry out (`deflex_cam::export`)
//!
//! A calibrated robot where controllers and ROS stacks read it (`deflex export`), as text in
//! memory (the caller writes the files):
//!
//! * [`urdf`]: a URDF of the serial chain with the calibrated joint origins (`world` → R0 →
//!   `link_1` … `link_N` → `flange` → `tcp`), revolute joints about their z axes with the
//!   model's limits. Geometry only: the stiffnesses stay in deflex's robot file.
//! * [`ur_calibration`]: Universal Robots' calibration file as `ur_calibration` writes it and
//!   `ur_robot_driver` / `ur_description` read it (`kinematics_params`): a `kinematics:` map of
//!   `shoulder`, `upper_arm`, `forearm`, `wrist_1`, `wrist_2`, `wrist_3`, each the origin of the
//!   URDF joint (`x y z` in m, `roll pitch yaw` in rad, URDF's `R = Rz(yaw)·Ry(pitch)·Rx(roll)`),
//!   and a `hash`. Layout checked against the `default_kinematics.yaml` files of UR's ROS 2
//!   description package.
//! * [`dh_table`]: the DH table as CSV with units in the column names, and with a nominal robot
//!   the corrections (calibrated − nominal) for absolute-accuracy workflows that enter DH
//!   offsets on the controller.
//!
//! Each has a reader ([`read_ur_calibration`], [`read_dh_table`]) for checking; the URDF reads
//! back through deflex's own URDF loader.
//!
//! ## Frames
//!
//! deflex's joint i is `placement_i · RotZ(q_i + θ_i)`; a URDF revolute joint is
//! `origin · RotZ(q)` about `axis 0 0 1`, so `origin_i = placement_i · RotZ(θ_i)`. For a
//! standard-DH robot (UR) `placement_i = TransX(a_{i−1})·RotX(α_{i−1})·RotY(β_{i−1})·TransZ(d_i)`,
//! which is exactly how UR's calibration places its segments (`shoulder z = d₁`, `upper_arm
//! roll = α₁`, `forearm x = a₂`, …); its `tool0` is the `wrist_3_link` frame (ur_description's
//! fixed `flange` and `tool0` rotations multiply to the identity), so the model's flange must be
//! the last joint frame up to a shift and a turn about z, which is folded into `wrist_3`.

#![warn(missing_docs)]

use deflex_model::spatial::{pose_from_xyz_rpy, rpy_from_rotation};
use deflex_model::{DhParams, Pose, Robot};
use nalgebra::{Rotation3, Vector3};
use std::fmt::Write as _;

/// The segments of a UR calibration, in order.
pub const UR_SEGMENTS: [&str; 6] = [
    "shoulder",
    "upper_arm",
    "forearm",
    "wrist_1",
    "wrist_2",
    "wrist_3",
];

/// A robot that cannot be written in a format, or a file that cannot be read back.
#[derive(Debug, thiserror::Error, PartialEq)]
pub enum ExportError {
    /// The format needs something the robot does not have.
    #[error("{format}: {message}")]
    Unsupported {
        /// The format.
        format: &'static str,
        /// What is missing or in the way.
        message: String,
    },
    /// A file being read back.
    #[error("{file}:{line}: {message}")]
    Read {
        /// The file.
        file: String,
        /// 1-based line (0: the whole file).
        line: usize,
        /// What was expected.
        message: String,
    },
}

/// A number written so that it reads back to the same `f64` (shortest round-trip form).
fn number(v: f64) -> String {
    let v = if v == 0.0 { 0.0 } else { v };
    format!("{v:?}")
}

fn xyz_rpy(pose: &Pose) -> ([f64; 3], [f64; 3]) {
    let t = pose.translation.vector;
    ([t.x, t.y, t.z], rpy_from_rotation(&pose.rotation))
}

fn origin_xml(pose: &Pose) -> String {
    let (xyz, rpy) = xyz_rpy(pose);
    format!(
        "<origin xyz=\"{} {} {}\" rpy=\"{} {} {}\"/>",
        number(xyz[0]),
        number(xyz[1]),
        number(xyz[2]),
        number(rpy[0]),
        number(rpy[1]),
        number(rpy[2])
    )
}

/// The URDF joint origins `placement_i · RotZ(θ_i)` (see the crate documentation).
pub fn joint_origins(robot: &Robot) -> Vec<Pose> {
    robot
        .joints
        .iter()
        .map(|j| {
            j.placement
                * Pose::from_parts(
                    nalgebra::Translation3::identity(),
                    Rotation3::from_axis_angle(&Vector3::z_axis(), j.theta_offset),
                )
        })
        .collect()
}

/// Text safe inside an XML comment or attribute.
fn xml_text(text: &str) -> String {
    text.replace('&', "and")
        .replace('<', "[")
        .replace('>', "]")
        .replace("--", "-")
        .replace('"', "'")
}

/// The robot as a URDF (see the crate documentation). `name` is the `<robot name>`.
pub fn urdf(robot: &Robot) -> String {
    let name = xml_text(&robot.name);
    let mut out = String::new();
    let _ = writeln!(out, "<?xml version=\"1.0\"?>");
    let _ = writeln!(
        out,
        "<!-- {name}, geometry {}: written by deflex export. Joint origins are the model's \
         (calibrated) placements; stiffness, masses and limits of effort and velocity are not \
         carried (effort and velocity below are placeholders: set your robot's). -->",
        robot.geometry_fingerprint()
    );
    let _ = writeln!(out, "<robot name=\"{name}\">");
    let n = robot.joint_count();
    let link = |i: usize| {
        if i == 0 {
            "base_link".to_string()
        } else {
            format!("link_{i}")
        }
    };
    let _ = writeln!(out, "  <link name=\"world\"/>");
    for i in 0..=n {
        let _ = writeln!(out, "  <link name=\"{}\"/>", link(i));
    }
    let _ = writeln!(out, "  <link name=\"flange\"/>\n  <link name=\"tcp\"/>");
    let _ = writeln!(
        out,
        "  <joint name=\"base_joint\" type=\"fixed\">\n    <parent link=\"world\"/>\n    <child link=\"base_link\"/>\n    {}\n  </joint>",
        origin_xml(&robot.base)
    );
    for (i, (joint, origin)) in robot.joints.iter().zip(joint_origins(robot)).enumerate() {
        let limit = match joint.limits {
            Some([lo, hi]) => format!(
                "\n    <limit lower=\"{}\" upper=\"{}\" effort=\"10000\" velocity=\"3.14159\"/>",
                number(lo),
                number(hi)
            ),
            None => String::new(),
        };
        let kind = if joint.limits.is_some() {
            "revolute"
        } else {
            "continuous"
        };
        let _ = writeln!(
            out,
            "  <joint name=\"{}\" type=\"{kind}\">\n    <parent link=\"{}\"/>\n    <child link=\"{}\"/>\n    {}\n    <axis xyz=\"0 0 1\"/>{limit}\n  </joint>",
            xml_text(&joint.name),
            link(i),
            link(i + 1),
            origin_xml(&origin)
        );
    }
    for (joint, parent, child, pose) in [
        ("flange_joint", link(n), "flange", &robot.flange),
        ("tcp_joint", "flange".to_string(), "tcp", &robot.tool),
    ] {
        let _ = writeln!(
            out,
            "  <joint name=\"{joint}\" type=\"fixed\">\n    <parent link=\"{parent}\"/>\n    <child link=\"{child}\"/>\n    {}\n  </joint>",
            origin_xml(pose)
        );
    }
    let _ = writeln!(out, "</robot>");
    out
}

/// A robot file (deflex TOML) that reads the URDF written by [`urdf`] as `file`: the chain from
/// `world` to `tcp`, one `[[joint]]` per joint by name with the model's eDoF centre shift and
/// stiffnesses (the URDF carries the geometry, this file the elasticity).
pub fn urdf_robot_toml(robot: &Robot, file: &str) -> String {
    let mut out = String::new();
    let _ = writeln!(
        out,
        "name = \"{} (URDF export)\"\nurdf = \"{file}\"\nbase_link = \"world\"\ntip_link = \"tcp\"",
        robot.name.replace('"', "'")
    );
    for joint in &robot.joints {
        let _ = writeln!(out, "\n[[joint]]\nname = \"{}\"", xml_text(&joint.name));
        if joint.center_shift != 0.0 {
            let _ = writeln!(out, "center_shift = {}", number(joint.center_shift));
        }
        let k = joint.stiffness.0;
        if k.iter().any(Option::is_some) {
            let axes: Vec<String> = ["x", "y", "z"]
                .iter()
                .zip(k)
                .filter_map(|(axis, v)| v.map(|v| format!("{axis} = {}", number(v))))
                .collect();
            let _ = writeln!(out, "stiffness = {{ {} }}", axes.join(", "));
        }
    }
    out
}

/// Universal Robots' calibration file (see the crate documentation). Needs six joints, an
/// identity base and a flange that is the last joint frame up to a shift and a turn about z.
pub fn ur_calibration(robot: &Robot) -> Result<String, ExportError> {
    let unsupported = |message: String| ExportError::Unsupported {
        format: "ur-calibration",
        message,
    };
    if robot.joint_count() != 6 {
        return Err(unsupported(format!(
            "a UR calibration has six segments, the robot has {} joints",
            robot.joint_count()
        )));
    }
    let base = &robot.base;
    if base.translation.vector.norm() > 1e-12 || base.rotation.angle() > 1e-12 {
        return Err(unsupported(
            "the robot file places R0 in a world frame ([base]); UR's calibration is relative to \
             the UR base frame: export a robot without [base], or use --format urdf"
                .into(),
        ));
    }
    let f = &robot.flange;
    let t = f.translation.vector;
    let z = f.rotation * Vector3::z();
    if t.x.hypot(t.y) > 1e-12 || (z - Vector3::z()).norm() > 1e-12 {
        return Err(unsupported(format!(
            "the flange is ({:.6}, {:.6}, {:.6}) m and turned {:.6} rad off the last joint's \
             axis: UR's tool0 is the wrist_3 frame (a shift or a turn about z only); use \
             --format urdf",
            t.x,
            t.y,
            t.z,
            z.angle(&Vector3::z())
        )));
    }
    let mut origins = joint_origins(robot);
    // Fold the flange's shift and turn about z into wrist_3 (they commute with RotZ(q6)).
    origins[5] *= f;
    let mut out = String::new();
    let _ = writeln!(
        out,
        "# {}: written by deflex export (geometry {}), the layout of ur_calibration's output\n\
         # (kinematics_params of ur_robot_driver / ur_description). The hash is deflex's, not the\n\
         # robot's: the driver warns that it differs from the controller's own calibration.",
        robot.name.replace('\n', " "),
        robot.geometry_fingerprint()
    );
    let _ = writeln!(out, "kinematics:");
    for (segment, origin) in UR_SEGMENTS.iter().zip(&origins) {
        let (xyz, rpy) = xyz_rpy(origin);
        let _ = writeln!(out, "  {segment}:");
        for (key, value) in ["x", "y", "z", "roll", "pitch", "yaw"]
            .iter()
            .zip(xyz.iter().chain(rpy.iter()))
        {
            let _ = writeln!(out, "    {key}: {}", number(*value));
        }
    }
    let _ = writeln!(out, "  hash: calib_deflex_{}", robot.geometry_fingerprint());
    Ok(out)
}

/// The six segment origins of a UR calibration file: `[x, y, z, roll, pitch, yaw]` (m, rad).
pub fn read_ur_calibration(text: &str, file: &str) -> Result<[[f64; 6]; 6], ExportError> {
    let error = |line: usize, message: String| ExportError::Read {
        file: file.to_string(),
        line,
        message,
    };
    if text.len() > 1 << 20 {
        return Err(error(0, "larger than 1 MiB".into()));
    }
    let mut values = [[f64::NAN; 6]; 6];
    let mut segment: Option<usize> = None;
    let mut in_kinematics = false;
    for (index, raw) in text.lines().enumerate() {
        let line = index + 1;
        let content = raw.split('#').next().unwrap_or("");
        if content.trim().is_empty() {
            continue;
        }
        let indent = content.len() - content.trim_start().len();
        let (key, value) = content.trim().split_once(':').ok_or_else(|| {
            error(
                line,
                format!("expected `key: value`, got \"{}\"", content.trim()),
            )
        })?;
        let value = value.trim();
        match indent {
            0 => {
                in_kinematics = key == "kinematics";
                segment = None;
            }
            2 if in_kinematics => {
                segment = UR_SEGMENTS.iter().position(|s| *s == key);
                if segment.is_none() && key != "hash" {
                    return Err(error(line, format!("unknown segment \"{key}\"")));
                }
            }
            4 if in_kinematics => {
                let s =
                    segment.ok_or_else(|| error(line, format!("\"{key}\" outside a segment")))?;
                let k = ["x", "y", "z", "roll", "pitch", "yaw"]
                    .iter()
                    .position(|n| *n == key)
                    .ok_or_else(|| error(line, format!("unknown key \"{key}\"")))?;
                values[s][k] = value
                    .parse::<f64>()
                    .ok()
                    .filter(|v| v.is_finite())
                    .ok_or_else(|| {
                        error(line, format!("{key}: expected a number, got \"{value}\""))
                    })?;
            }
            _ => return Err(error(line, format!("unexpected indentation {indent}"))),
        }
    }
    for (s, row) in values.iter().enumerate() {
        if row.iter().any(|v| v.is_nan()) {
            return Err(error(
                0,
                format!("segment {} is incomplete", UR_SEGMENTS[s]),
            ));
        }
    }
    Ok(values)
}

/// Column names of the DH table.
const DH_COLUMNS: [&str; 5] = ["alpha_rad", "a_m", "beta_rad", "d_m", "theta_offset_rad"];

fn dh_values(row: &DhParams, theta: f64) -> [f64; 5] {
    [row.alpha, row.a, row.beta, row.d, theta]
}

/// The DH table as CSV: `joint, convention` and the five parameters (`alpha_rad, a_m,
/// beta_rad, d_m, theta_offset_rad`); with `nominal`, its values (`nominal_…`) and the
/// corrections (`delta_…` = calibrated − nominal). Comment lines (`#`) name the robot, the
/// convention's formula, the flange and the tool.
pub fn dh_table(robot: &Robot, nominal: Option<&Robot>) -> Result<String, ExportError> {
    let unsupported = |message: String| ExportError::Unsupported {
        format: "dh-table",
        message,
    };
    let convention = robot.dh_convention.ok_or_else(|| {
        unsupported("the robot's geometry is not a DH table (a URDF): use --format urdf".into())
    })?;
    let rows: Vec<(DhParams, f64)> = robot
        .joints
        .iter()
        .map(|j| j.dh.map(|d| (d, j.theta_offset)))
        .collect::<Option<_>>()
        .ok_or_else(|| unsupported("a joint has no DH row".into()))?;
    let nominal_rows: Option<Vec<(DhParams, f64)>> = match nominal {
        None => None,
        Some(n) => {
            if n.dh_convention != Some(convention) || n.joint_count() != robot.joint_count() {
                return Err(unsupported(format!(
                    "the nominal robot \"{}\" is not a {} DH table of {} joints",
                    n.name,
                    convention.name(),
                    robot.joint_count()
                )));
            }
            Some(
                n.joints
                    .iter()
                    .map(|j| j.dh.map(|d| (d, j.theta_offset)))
                    .collect::<Option<_>>()
                    .ok_or_else(|| unsupported("a nominal joint has no DH row".into()))?,
            )
        }
    };
    let mut out = String::new();
    let formula = match convention {
        deflex_model::DhConvention::Modified => {
            "T(i-1,i) = RotX(alpha)·RotY(beta)·TransX(a)·TransZ(d)·RotZ(q + theta_offset)"
        }
        deflex_model::DhConvention::Standard => {
            "T(i-1,i) = RotZ(q + theta_offset)·TransZ(d)·TransX(a)·RotX(alpha)·RotY(beta)"
        }
    };
    let _ = writeln!(
        out,
        "# robot: {} (geometry {})",
        robot.name,
        robot.geometry_fingerprint()
    );
    let _ = writeln!(out, "# convention: {} DH, {formula}", convention.name());
    let (fxyz, frpy) = xyz_rpy(&robot.flange_offset);
    let (txyz, trpy) = xyz_rpy(&robot.tool);
    let _ = writeln!(
        out,
        "# flange offset after the table (m, rad xyz rpy): {} {} {} {} {} {}",
        number(fxyz[0]),
        number(fxyz[1]),
        number(fxyz[2]),
        number(frpy[0]),
        number(frpy[1]),
        number(frpy[2])
    );
    let _ = writeln!(
        out,
        "# tool, flange to TCP (m, rad xyz rpy): {} {} {} {} {} {}",
        number(txyz[0]),
        number(txyz[1]),
        number(txyz[2]),
        number(trpy[0]),
        number(trpy[1]),
        number(trpy[2])
    );
    if let Some(n) = nominal {
        let _ = writeln!(
            out,
            "# nominal: {} (geometry {})",
            n.name,
            n.geometry_fingerprint()
        );
    }
    let mut header = vec!["joint".to_string(), "convention".to_string()];
    header.extend(DH_COLUMNS.iter().map(|c| c.to_string()));
    if nominal_rows.is_some() {
        header.extend(DH_COLUMNS.iter().map(|c| format!("nominal_{c}")));
        header.extend(DH_COLUMNS.iter().map(|c| format!("delta_{c}")));
    }
    let _ = writeln!(out, "{}", header.join(","));
    for (i, (row, theta)) in rows.iter().enumerate() {
        let values = dh_values(row, *theta);
        let mut fields = vec![(i + 1).to_string(), convention.name().to_string()];
        fields.extend(values.iter().map(|v| number(*v)));
        if let Some(nominal) = &nominal_rows {
            let (nrow, ntheta) = &nominal[i];
            let nvalues = dh_values(nrow, *ntheta);
            fields.extend(nvalues.iter().map(|v| number(*v)));
            fields.extend(values.iter().zip(&nvalues).map(|(c, n)| number(c - n)));
        }
        let _ = writeln!(out, "{}", fields.join(","));
    }
    Ok(out)
}

/// One row of a DH table read back.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct DhRow {
    /// The parameters.
    pub dh: DhParams,
    /// θ offset (rad).
    pub theta_offset: f64,
    /// The corrections (`delta_…`), when the table has them, in the column order.
    pub delta: Option<[f64; 5]>,
}

/// Read a DH table written by [`dh_table`].
pub fn read_dh_table(text: &str, file: &str) -> Result<Vec<DhRow>, ExportError> {
    let error = |line: usize, message: String| ExportError::Read {
        file: file.to_string(),
        line,
        message,
    };
    let mut lines = text
        .lines()
        .enumerate()
        .filter(|(_, l)| !l.starts_with('#') && !l.trim().is_empty());
    let (_, header) = lines.next().ok_or_else(|| error(0, "no header".into()))?;
    let names: Vec<&str> = header.split(',').map(str::trim).collect();
    let column = |name: &str| {
        names
            .iter()
            .position(|n| *n == name)
            .ok_or_else(|| error(1, format!("missing column {name}")))
    };
    let columns: Vec<usize> = DH_COLUMNS
        .iter()
        .map(|c| column(c))
        .collect::<Result<_, _>>()?;
    let deltas: Option<Vec<usize>> = DH_COLUMNS
        .iter()
        .map(|c| names.iter().position(|n| *n == format!("delta_{c}")))
        .collect();
    let mut out = Vec::new();
    for (index, line) in lines {
        if out.len() >= 64 {
            return Err(error(index + 1, "more than 64 rows".into()));
        }
        let fields: Vec<&str> = line.split(',').map(str::trim).collect();
        let value = |k: usize| {
            fields
                .get(k)
                .and_then(|t| t.parse::<f64>().ok())
                .filter(|v| v.is_finite())
                .ok_or_else(|| error(index + 1, format!("column {}: expected a number", names[k])))
        };
        let v: Vec<f64> = columns
            .iter()
            .map(|k| value(*k))
            .collect::<Result<_, _>>()?;
        let delta = match &deltas {
            Some(d) => {
                let d: Vec<f64> = d.iter().map(|k| value(*k)).collect::<Result<_, _>>()?;
                Some([d[0], d[1], d[2], d[3], d[4]])
            }
            None => None,
        };
        out.push(DhRow {
            dh: DhParams {
                alpha: v[0],
                a: v[1],
                beta: v[2],
                d: v[3],
            },
            theta_offset: v[4],
            delta,
        });
    }
    Ok(out)
}

/// A pose from a UR calibration segment `[x, y, z, roll, pitch, yaw]`.
pub fn segment_pose(segment: &[f64; 6]) -> Pose {
    pose_from_xyz_rpy(
        [segment[0], segment[1], segment[2]],
        [segment[3], segment[4], segment[5]],
    )
}
