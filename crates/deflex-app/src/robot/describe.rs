//! The description of a robot model (`deflex model show`): the joint table, its eDoFs and
//! stiffnesses, as text and as JSON (SI), with the twin cell the commands build around it.

use crate::error::Result;
use deflex_model::Robot;
use deflex_model::spatial::rpy_from_rotation;
use deflex_sim::profile::CellSummary;
use serde_json::json;
use std::fmt::Write as _;

/// A robot and the twin cell `compensate`, `sim` and `demo` use for it (`deflex model show`).
pub struct ModelShow {
    /// The robot.
    pub robot: Robot,
    /// Its twin cell, or why no cell can be built around it (not 6 joints, no reachable part
    /// placement).
    pub cell: std::result::Result<CellSummary, deflex_sim::SimError>,
}

impl ModelShow {
    /// The robot `spec` (a built-in name or a robot file) and its twin cell.
    pub fn load(spec: &str) -> Result<ModelShow> {
        let robot = super::load(spec)?;
        let cell = crate::cell::twin_cell_file::cell_for_robot(spec).and_then(|c| c.summary());
        Ok(ModelShow { robot, cell })
    }

    /// The description and the cell as text.
    pub fn text(&self) -> String {
        let mut out = describe(&self.robot);
        match &self.cell {
            Ok(summary) => {
                let _ = writeln!(out, "{summary}");
            }
            Err(e) => {
                let _ = writeln!(out, "twin cell: none ({e})");
            }
        }
        out
    }

    /// The description and the cell as JSON (SI).
    pub fn to_json(&self) -> serde_json::Value {
        let mut value = describe_json(&self.robot);
        value["cell"] = match &self.cell {
            Ok(summary) => summary.to_json(),
            Err(e) => json!({"error": e.to_string()}),
        };
        value
    }
}

/// A pose as `{xyz_m, rpy_rad}`.
fn pose_json(pose: &deflex_model::Pose) -> serde_json::Value {
    let t = pose.translation.vector;
    json!({"xyz_m": [t.x, t.y, t.z], "rpy_rad": rpy_from_rotation(&pose.rotation)})
}

/// Where the geometry came from, in words.
fn geometry_source(robot: &Robot) -> String {
    match (&robot.urdf, robot.dh_convention) {
        (Some(urdf), _) => format!(
            "URDF {} ({} → {})",
            urdf.resolved.display(),
            urdf.base_link,
            urdf.tip_link
        ),
        (None, Some(convention)) => format!("{} DH", convention.name()),
        (None, None) => "placements".into(),
    }
}

/// The model as JSON (SI): geometry of every joint (DH row or placement), masses, eDoFs.
pub fn describe_json(robot: &Robot) -> serde_json::Value {
    let joints: Vec<_> = robot
        .joints
        .iter()
        .map(|j| {
            json!({
                "name": j.name,
                "dh": j.dh.map(|d| json!({"alpha_rad": d.alpha, "a_m": d.a, "d_m": d.d, "beta_rad": d.beta})),
                "placement": pose_json(&j.placement),
                "theta_offset_rad": j.theta_offset,
                "limits_rad": j.limits,
                "center_shift_m": j.center_shift,
                "stiffness_Nm_per_rad": {"x": j.stiffness.0[0], "y": j.stiffness.0[1], "z": j.stiffness.0[2]},
                "mass_kg": j.inertia.map(|i| i.mass_kg),
                "com_joint_frame_m": j.inertia.map(|i| [i.com.x, i.com.y, i.com.z]),
            })
        })
        .collect();
    let edofs: Vec<_> = robot
        .edofs()
        .map(|e| json!({"edof": e.label(), "stiffness_Nm_per_rad": e.stiffness}))
        .collect();
    json!({
        "name": robot.name,
        "geometry": geometry_source(robot),
        "geometry_fingerprint": robot.geometry_fingerprint(),
        "base": pose_json(&robot.base),
        "flange": pose_json(&robot.flange),
        "tool": pose_json(&robot.tool),
        "gravity_m_s2": [robot.gravity.x, robot.gravity.y, robot.gravity.z],
        "payload": robot.payload.map(|p| json!({"mass_kg": p.mass_kg, "com_flange_m": [p.com.x, p.com.y, p.com.z]})),
        "joints": joints,
        "edofs": edofs,
        "setups": robot.setups.iter().map(|s| json!({"name": s.name, "pose": pose_json(&s.pose)})).collect::<Vec<_>>(),
        "targets": robot.targets.iter().map(|t| json!({"name": t.name, "xyz_flange_m": [t.position.x, t.position.y, t.position.z]})).collect::<Vec<_>>(),
    })
}

/// `x y z mm, r p y °` of a pose.
fn pose_text(pose: &deflex_model::Pose) -> String {
    let t = pose.translation.vector * 1e3;
    let r = rpy_from_rotation(&pose.rotation).map(f64::to_degrees);
    format!(
        "xyz {:.4} {:.4} {:.4} mm, rpy {:.6} {:.6} {:.6}°",
        t.x, t.y, t.z, r[0], r[1], r[2]
    )
}

/// Human-readable joint table and eDoF list.
pub fn describe(robot: &Robot) -> String {
    let mut out = String::new();
    let _ = writeln!(
        out,
        "{}  ({} joints, {} eDoFs)",
        robot.name,
        robot.joint_count(),
        robot.edof_count()
    );
    let _ = writeln!(
        out,
        "geometry: {}  (fingerprint {})",
        geometry_source(robot),
        robot.geometry_fingerprint()
    );
    let width = robot
        .joints
        .iter()
        .map(|j| j.name.chars().count())
        .max()
        .unwrap_or(5)
        .max(5);
    let k = |v: Option<f64>| {
        v.map(|k| format!("{:.3}", k / 1e6))
            .unwrap_or_else(|| "-".into())
    };
    let mass = |joint: &deflex_model::Joint| {
        joint
            .inertia
            .map(|i| format!("{:.2}", i.mass_kg))
            .unwrap_or_else(|| "-".into())
    };
    let limits = |joint: &deflex_model::Joint| {
        joint
            .limits
            .map(|[lo, hi]| format!("[{:.0}, {:.0}]", lo.to_degrees(), hi.to_degrees()))
            .unwrap_or_else(|| "none".into())
    };
    // The geometry columns: a DH row, or the placement for a URDF robot.
    let dh_table = robot.dh_convention.is_some();
    let geometry_header = if dh_table {
        format!(
            "{:>9} {:>9} {:>9} {:>7} {:>9}",
            "alpha°", "a mm", "d mm", "beta°", "offset°"
        )
    } else {
        format!("{:>44}", "placement in the previous joint frame")
    };
    let geometry = |joint: &deflex_model::Joint| {
        if dh_table {
            // A DH robot has a DH row on every joint.
            let dh = joint.dh.unwrap_or_default();
            format!(
                "{:>9} {:>9} {:>9} {:>7} {:>9}",
                fixed_decimals(dh.alpha.to_degrees(), 1),
                fixed_decimals(dh.a * 1e3, 1),
                fixed_decimals(dh.d * 1e3, 1),
                fixed_decimals(dh.beta.to_degrees(), 3),
                fixed_decimals(joint.theta_offset.to_degrees(), 1)
            )
        } else {
            format!("{:>44}", pose_text(&joint.placement))
        }
    };
    let _ = writeln!(
        out,
        "{:<width$} {geometry_header} {:>17} {:>9} {:>7}  stiffness x / y / z (10^6 N·m/rad)",
        "joint", "limits°", "shift mm", "mass kg"
    );
    for joint in &robot.joints {
        let s = joint.stiffness.0;
        let _ = writeln!(
            out,
            "{:<width$} {} {:>17} {:>9} {:>7}  {} / {} / {}",
            joint.name,
            geometry(joint),
            limits(joint),
            fixed_decimals(joint.center_shift * 1e3, 1),
            mass(joint),
            k(s[0]),
            k(s[1]),
            k(s[2])
        );
    }
    if robot.flange != deflex_model::Pose::identity() {
        let _ = writeln!(
            out,
            "flange (last joint frame → flange): {}",
            pose_text(&robot.flange)
        );
    }
    if !robot.has_tool() {
        let _ = writeln!(
            out,
            "tool (flange → TCP): none in the model, the flange (deflex compensate, sim and cell use the twin cell's tool)"
        );
    } else {
        let _ = writeln!(
            out,
            "tool (flange → TCP): {} (its cell keeps it: deflex compensate, sim and cell use it)",
            pose_text(&robot.tool)
        );
    }
    if robot.base != deflex_model::Pose::identity() {
        let _ = writeln!(out, "base (world → R0): {}", pose_text(&robot.base));
    }
    if let Some(payload) = &robot.payload {
        let c = payload.com * 1e3;
        let _ = writeln!(
            out,
            "payload: {:.2} kg at {:.1} {:.1} {:.1} mm (flange frame)",
            payload.mass_kg, c.x, c.y, c.z
        );
    }
    if robot.base_stiffness.count() > 0 {
        let s = robot.base_stiffness.0;
        let _ = writeln!(out, "base eDoFs: {} / {} / {}", k(s[0]), k(s[1]), k(s[2]));
    }
    let edofs: Vec<String> = robot.edofs().map(|e| e.label()).collect();
    let _ = writeln!(out, "eDoFs: {}", edofs.join(", "));
    for setup in &robot.setups {
        let _ = writeln!(
            out,
            "tracker set-up {}: {}",
            setup.name,
            pose_text(&setup.pose)
        );
    }
    for target in &robot.targets {
        let p = target.position * 1e3;
        let _ = writeln!(
            out,
            "target {}: {:.2} {:.2} {:.2} mm (flange frame)",
            target.name, p.x, p.y, p.z
        );
    }
    out
}

/// `value` with `decimals` decimals, for the tables.
fn fixed_decimals(value: f64, decimals: usize) -> String {
    format!("{value:.decimals$}")
}
