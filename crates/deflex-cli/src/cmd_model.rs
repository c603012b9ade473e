//! `deflex model show`, `pose`, `deflect`, `ik`, `map`.

use crate::args::{fixed, joint_values, parse_fixed, parse_length_mm_default, print_json, robot};
use crate::error::{CliError, CommandResult, UsageError};
use clap::{Args, Subcommand};
use deflex_model::spatial::{pose_from_xyz_rpy, rpy_from_rotation};
use deflex_model::{Data, IkOptions, Robot, TX200_FORMING_Q_DEG, Wrench};
use serde_json::json;
use std::fmt::Write as _;
use std::path::PathBuf;

#[derive(Subcommand)]
pub enum ModelCommand {
    /// The joint table, eDoFs and stiffnesses.
    Show {
        /// Robot: built-in name (tx200, tx200-1edof, ur10, ur10e, kr210-r2700, irb4600) or TOML file.
        #[arg(long)]
        robot: String,
    },
}

#[derive(Args)]
pub struct JointArgs {
    /// Joint values in degrees, comma-separated.
    #[arg(long, allow_hyphen_values = true)]
    pub q_deg: Option<String>,
    /// Joint values in radians, comma-separated.
    #[arg(long, allow_hyphen_values = true)]
    pub q_rad: Option<String>,
}

impl JointArgs {
    /// The joint values in radians, checked against `robot`'s joint count.
    pub fn values(&self, robot: &Robot) -> Result<Vec<f64>, UsageError> {
        joint_values(robot, self.q_deg.as_deref(), self.q_rad.as_deref())
    }
}

#[derive(Args)]
pub struct PoseArgs {
    /// Robot: built-in name (tx200, tx200-1edof, ur10, ur10e, kr210-r2700, irb4600) or TOML file.
    #[arg(long)]
    pub robot: String,
    #[command(flatten)]
    pub joints: JointArgs,
}

#[derive(Args)]
pub struct DeflectArgs {
    /// Robot: built-in name (tx200, tx200-1edof, ur10, ur10e, kr210-r2700, irb4600) or TOML file.
    #[arg(long)]
    pub robot: String,
    #[command(flatten)]
    pub joints: JointArgs,
    /// Wrench at the TCP, world axes: fx,fy,fz,mx,my,mz in N and N·m.
    #[arg(long, allow_hyphen_values = true)]
    pub wrench: String,
}

#[derive(Args)]
pub struct IkArgs {
    /// Robot: built-in name (tx200, tx200-1edof, ur10, ur10e, kr210-r2700, irb4600) or TOML file.
    #[arg(long)]
    pub robot: String,
    /// TCP position in world, mm.
    #[arg(long, allow_hyphen_values = true)]
    pub xyz_mm: String,
    /// TCP orientation roll,pitch,yaw in degrees (R = Rz(yaw) Ry(pitch) Rx(roll)).
    #[arg(long, allow_hyphen_values = true)]
    pub rpy_deg: String,
    /// Seed configuration in degrees (default: the paper's forming configuration for 6 joints, else zeros).
    #[arg(long, allow_hyphen_values = true)]
    pub seed_deg: Option<String>,
}

#[derive(Args)]
pub struct MapArgs {
    /// Robot: built-in name (tx200, tx200-1edof, ur10, ur10e, kr210-r2700, irb4600) or TOML file.
    #[arg(long)]
    pub robot: String,
    /// Grid plane, e.g. z=100mm (bare numbers are mm).
    #[arg(long, default_value = "z=100mm")]
    pub plane: String,
    /// Grid centre x,y (bare numbers are mm; suffix m for metres).
    #[arg(long, default_value = "1500,0", allow_hyphen_values = true)]
    pub center: String,
    /// Grid side length (square), e.g. 600mm.
    #[arg(long, default_value = "600mm")]
    pub size: String,
    /// Grid step, e.g. 40mm.
    #[arg(long, default_value = "40mm")]
    pub step: String,
    /// Wrench at the TCP, world axes: fx,fy,fz,mx,my,mz in N and N·m.
    #[arg(long, allow_hyphen_values = true, default_value = "0,0,-1100,0,0,0")]
    pub wrench: String,
    /// Output folder (CSV + PNG heatmaps).
    #[arg(long)]
    pub out: PathBuf,
}

pub fn model(command: ModelCommand, json_output: bool) -> CommandResult {
    match command {
        ModelCommand::Show { robot: spec } => {
            let robot = robot(&spec)?;
            // The twin cell `compensate`, `sim` and `demo` use for this robot; a robot no cell
            // can be built around (not 6 joints, no reachable part placement) says why.
            let cell =
                deflex_app::cell::twin_cell_file::cell_for_robot(&spec).and_then(|c| c.summary());
            if json_output {
                let mut value = describe_json(&robot);
                value["cell"] = match &cell {
                    Ok(summary) => summary.to_json(),
                    Err(e) => json!({"error": e.to_string()}),
                };
                print_json(&value);
            } else {
                print!("{}", describe(&robot));
                match &cell {
                    Ok(summary) => println!("{summary}"),
                    Err(e) => println!("twin cell: none ({e})"),
                }
            }
            Ok(())
        }
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
        "xyz {:.1} {:.1} {:.1} mm, rpy {:.2} {:.2} {:.2}°",
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
            let dh = joint.dh.unwrap_or_default();
            format!(
                "{:>9} {:>9} {:>9} {:>7} {:>9}",
                fixed(dh.alpha.to_degrees(), 1),
                fixed(dh.a * 1e3, 1),
                fixed(dh.d * 1e3, 1),
                fixed(dh.beta.to_degrees(), 3),
                fixed(joint.theta_offset.to_degrees(), 1)
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
            fixed(joint.center_shift * 1e3, 1),
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
    let _ = writeln!(out, "tool (flange → TCP): {}", pose_text(&robot.tool));
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

fn rotation_rows(rotation: &nalgebra::Rotation3<f64>) -> Vec<[f64; 3]> {
    let m = rotation.matrix();
    (0..3).map(|r| [m[(r, 0)], m[(r, 1)], m[(r, 2)]]).collect()
}

pub fn pose(args: PoseArgs, json_output: bool) -> CommandResult {
    let robot = robot(&args.robot)?;
    let q = args.joints.values(&robot)?;
    let mut data = Data::new();
    robot
        .forward_kinematics(&mut data, &q)
        .map_err(deflex_model::ModelError::from)?;
    let pose = data.tcp;
    let p = pose.translation.vector;
    let rpy = rpy_from_rotation(&pose.rotation);
    // The arm's own weight (and payload) sags the TCP when the model knows its masses.
    let has_masses = robot.joints.iter().any(|j| j.inertia.is_some()) || robot.payload.is_some();
    let sag = has_masses.then(|| robot.gravity_displacement(&data, &p, robot.joint_count()));
    if json_output {
        let value = json!({
            "tcp_m": [p.x, p.y, p.z],
            "rotation": rotation_rows(&pose.rotation),
            "rpy_rad": rpy,
            "gravity_sag_m": sag.map(|d| [d[0], d[1], d[2]]),
            "gravity_sag_rad": sag.map(|d| [d[3], d[4], d[5]]),
            "tcp_with_gravity_m": sag.map(|d| [p.x + d[0], p.y + d[1], p.z + d[2]]),
        });
        print_json(&value);
    } else {
        println!(
            "TCP position (mm): x {:.3}  y {:.3}  z {:.3}",
            p.x * 1e3,
            p.y * 1e3,
            p.z * 1e3
        );
        println!(
            "TCP orientation (deg, R = Rz·Ry·Rx): roll {:.3}  pitch {:.3}  yaw {:.3}",
            rpy[0].to_degrees(),
            rpy[1].to_degrees(),
            rpy[2].to_degrees()
        );
        let z = pose.rotation.matrix().column(2);
        println!("tool axis z_t: [{:.4}, {:.4}, {:.4}]", z[0], z[1], z[2]);
        if let Some(d) = sag {
            println!(
                "sag under the arm's own weight (mm): x {:+.4}  y {:+.4}  z {:+.4}  → TCP x {:.3}  y {:.3}  z {:.3}",
                d[0] * 1e3,
                d[1] * 1e3,
                d[2] * 1e3,
                (p.x + d[0]) * 1e3,
                (p.y + d[1]) * 1e3,
                (p.z + d[2]) * 1e3
            );
        }
    }
    Ok(())
}

pub fn deflect(args: DeflectArgs, json_output: bool) -> CommandResult {
    let robot = robot(&args.robot)?;
    let q = args.joints.values(&robot)?;
    let w = crate::args::parse_wrench(&args.wrench, "--wrench")?;
    let wrench = Wrench::from_row_slice(&w);
    let mut data = Data::new();
    robot
        .forward_kinematics(&mut data, &q)
        .map_err(deflex_model::ModelError::from)?;
    let compliance = robot.compliance_matrix(&data);
    let ds = robot.tcp_deflection(&data, &wrench);
    let p = data.tcp_position();
    if json_output {
        let rows: Vec<Vec<f64>> = (0..6)
            .map(|r| (0..6).map(|c| compliance[(r, c)]).collect())
            .collect();
        let value = json!({
            "tcp_m": [p.x, p.y, p.z],
            "wrench": w,
            "dp_m": [ds[0], ds[1], ds[2]],
            "dphi_rad": [ds[3], ds[4], ds[5]],
            "compliance": rows,
        });
        print_json(&value);
    } else {
        println!(
            "TCP (mm): x {:.3}  y {:.3}  z {:.3}",
            p.x * 1e3,
            p.y * 1e3,
            p.z * 1e3
        );
        println!("wrench (N, N·m, world axes at the TCP): {w:?}");
        println!(
            "deflection δp (mm):   x {:+.4}  y {:+.4}  z {:+.4}   |δp| {:.4}",
            ds[0] * 1e3,
            ds[1] * 1e3,
            ds[2] * 1e3,
            ds.fixed_rows::<3>(0).norm() * 1e3
        );
        println!(
            "deflection δφ (mrad): x {:+.4}  y {:+.4}  z {:+.4}",
            ds[3] * 1e3,
            ds[4] * 1e3,
            ds[5] * 1e3
        );
    }
    Ok(())
}

/// The paper's forming configuration, a good seed for work near the ISF cell.
pub fn default_seed(robot: &Robot) -> Vec<f64> {
    if robot.joint_count() == 6 {
        TX200_FORMING_Q_DEG.map(f64::to_radians).to_vec()
    } else {
        vec![0.0; robot.joint_count()]
    }
}

pub fn ik(args: IkArgs, json_output: bool) -> CommandResult {
    let robot = robot(&args.robot)?;
    let xyz = parse_fixed::<3>(&args.xyz_mm, "--xyz-mm")?;
    let rpy = parse_fixed::<3>(&args.rpy_deg, "--rpy-deg")?;
    let seed = match &args.seed_deg {
        Some(s) => joint_values(&robot, Some(s), None).map_err(|e| match e {
            crate::error::UsageError::Range {
                flag,
                lo,
                hi,
                unit,
                got,
            } => crate::error::UsageError::Range {
                flag: flag.replace("--q-deg", "--seed-deg"),
                lo,
                hi,
                unit,
                got,
            },
            other => other,
        })?,
        None => default_seed(&robot),
    };
    let target = pose_from_xyz_rpy(xyz.map(|v| v * 1e-3), rpy.map(f64::to_radians));
    let solution = robot
        .inverse_kinematics_search(&target, Some(&seed), &IkOptions::default())
        .map_err(|source| CliError::Unreachable {
            xyz_mm: xyz,
            rpy_deg: rpy,
            source,
        })?;
    if json_output {
        let value = json!({
            "q_rad": solution.q,
            "q_deg": solution.q.iter().map(|v| v.to_degrees()).collect::<Vec<_>>(),
            "iterations": solution.iterations,
            "position_error_m": solution.position_error_m,
            "orientation_error_rad": solution.orientation_error_rad,
        });
        print_json(&value);
    } else {
        let degrees: Vec<String> = solution
            .q
            .iter()
            .map(|v| format!("{:.4}", v.to_degrees()))
            .collect();
        println!("q (deg): {}", degrees.join(", "));
        println!(
            "converged in {} iterations; residual {:.2e} mm, {:.2e} mrad",
            solution.iterations,
            solution.position_error_m * 1e3,
            solution.orientation_error_rad * 1e3
        );
    }
    Ok(())
}

/// Largest `deflex map` grid side (m).
pub const MAX_MAP_SIZE_M: f64 = 20.0;
/// Most `deflex map` nodes per grid side (the grid holds the square of it).
pub const MAX_MAP_NODES_PER_SIDE: usize = 1001;

/// One grid node of `deflex map`.
pub struct MapNode {
    pub position_m: [f64; 3],
    pub q_rad: Vec<f64>,
    pub deflection: deflex_model::Displacement,
}

/// Deflection over a square grid of TCP positions with the tool pointing down (the orientation
/// of the paper's forming configuration), IK seeded along a serpentine so neighbours share a
/// branch. Nodes out of reach are skipped and counted.
pub fn deflection_grid(
    robot: &Robot,
    z_m: f64,
    center_m: [f64; 2],
    size_m: f64,
    step_m: f64,
    wrench: &Wrench,
) -> Result<(Vec<MapNode>, usize), CliError> {
    if !(step_m > 0.0 && size_m >= 0.0) {
        return Err(UsageError::invalid(
            "--step",
            "a positive step over a non-negative --size",
            format!("{} mm over {} mm", step_m * 1e3, size_m * 1e3),
        )
        .into());
    }
    if size_m > MAX_MAP_SIZE_M {
        return Err(UsageError::invalid(
            "--size",
            format!("at most {:.0} mm", MAX_MAP_SIZE_M * 1e3),
            format!("{:.1} mm", size_m * 1e3),
        )
        .into());
    }
    let per_side = size_m / step_m + 1e-9;
    if per_side >= MAX_MAP_NODES_PER_SIDE as f64 {
        return Err(UsageError::invalid(
            "--step",
            format!("at most {MAX_MAP_NODES_PER_SIDE} nodes per side (raise --step)"),
            format!(
                "{:.4} mm over --size {:.1} mm, {:.0} nodes per side",
                step_m * 1e3,
                size_m * 1e3,
                per_side.floor() + 1.0
            ),
        )
        .into());
    }
    let count = per_side.floor() as usize + 1;
    let seed = default_seed(robot);
    let reference = robot
        .tcp_pose(&seed)
        .map_err(deflex_model::ModelError::from)?;
    let mut data = Data::new();
    let mut nodes = Vec::with_capacity(count * count);
    let mut unreachable = 0;
    let mut previous = seed.clone();
    let offset = (count as f64 - 1.0) * step_m / 2.0;
    for row in 0..count {
        let y = center_m[1] - offset + row as f64 * step_m;
        let mut row_seed = previous.clone();
        for k in 0..count {
            let col = if row % 2 == 0 { k } else { count - 1 - k };
            let x = center_m[0] - offset + col as f64 * step_m;
            let mut target = reference;
            target.translation.vector = nalgebra::Vector3::new(x, y, z_m);
            match robot.inverse_kinematics(&target, &row_seed, &IkOptions::default()) {
                Ok(solution) => {
                    robot
                        .forward_kinematics(&mut data, &solution.q)
                        .map_err(deflex_model::ModelError::from)?;
                    let deflection = robot.tcp_deflection(&data, wrench);
                    row_seed = solution.q.clone();
                    nodes.push(MapNode {
                        position_m: [x, y, z_m],
                        q_rad: solution.q,
                        deflection,
                    });
                }
                Err(_) => unreachable += 1,
            }
        }
        previous = row_seed;
    }
    Ok((nodes, unreachable))
}

pub fn map(args: MapArgs, json_output: bool) -> CommandResult {
    let robot = robot(&args.robot)?;
    let plane = args.plane.trim();
    let z_text = plane.strip_prefix("z=").ok_or_else(|| {
        UsageError::invalid(
            "--plane",
            "a horizontal plane, written z=100mm",
            format!("\"{plane}\""),
        )
    })?;
    let z_m = parse_length_mm_default(z_text, "--plane")?;
    let center: Vec<&str> = args.center.split(',').collect();
    let [cx, cy] = center.as_slice() else {
        return Err(UsageError::invalid("--center", "x,y", format!("\"{}\"", args.center)).into());
    };
    let center_m = [
        parse_length_mm_default(cx, "--center")?,
        parse_length_mm_default(cy, "--center")?,
    ];
    let size_m = parse_length_mm_default(&args.size, "--size")?;
    let step_m = parse_length_mm_default(&args.step, "--step")?;
    let w = crate::args::parse_wrench(&args.wrench, "--wrench")?;
    let wrench = Wrench::from_row_slice(&w);
    let started = std::time::Instant::now();
    let (nodes, unreachable) = deflection_grid(&robot, z_m, center_m, size_m, step_m, &wrench)?;
    let elapsed = started.elapsed();
    if nodes.is_empty() {
        return Err(CliError::NoReachableNode);
    }
    // Built aside and swapped in whole: a failed run leaves the earlier map as it was, and a
    // second run on the same folder is refused while this one writes.
    let folder = deflex_files::AtomicDir::create(&args.out).map_err(CliError::write(&args.out))?;
    let n = robot.joint_count();
    let mut csv = String::from("x_m,y_m,z_m,");
    for i in 1..=n {
        let _ = write!(csv, "q{i}_rad,");
    }
    csv.push_str("dx_m,dy_m,dz_m,drx_rad,dry_rad,drz_rad\n");
    for node in &nodes {
        let _ = write!(
            csv,
            "{:?},{:?},{:?},",
            node.position_m[0], node.position_m[1], node.position_m[2]
        );
        for q in &node.q_rad {
            let _ = write!(csv, "{q:?},");
        }
        let d = &node.deflection;
        let _ = writeln!(
            csv,
            "{:e},{:e},{:e},{:e},{:e},{:e}",
            d[0], d[1], d[2], d[3], d[4], d[5]
        );
    }
    let csv_path = args.out.join("deflection_map.csv");
    deflex_files::write_atomic(folder.path().join("deflection_map.csv"), csv)
        .map_err(CliError::write(&csv_path))?;
    let norms: Vec<f64> = nodes
        .iter()
        .map(|n| n.deflection.fixed_rows::<3>(0).norm())
        .collect();
    let max = norms.iter().cloned().fold(0.0, f64::max);
    let mean = norms.iter().sum::<f64>() / norms.len() as f64;
    let pngs: Vec<PathBuf> = crate::cmd_model::map_plots(folder.path(), &nodes, &robot.name, &w)?
        .iter()
        .filter_map(|p| p.file_name().map(|name| args.out.join(name)))
        .collect();
    folder.commit().map_err(CliError::write(&args.out))?;
    if json_output {
        let value = json!({
            "nodes": nodes.len(),
            "unreachable": unreachable,
            "max_dp_norm_m": max,
            "mean_dp_norm_m": mean,
            "csv": csv_path,
            "png": pngs,
            "elapsed_s": elapsed.as_secs_f64(),
        });
        print_json(&value);
    } else {
        println!(
            "{} grid nodes ({} unreachable) in {:.1} ms; |δp| max {:.4} mm, mean {:.4} mm",
            nodes.len(),
            unreachable,
            elapsed.as_secs_f64() * 1e3,
            max * 1e3,
            mean * 1e3
        );
        println!("wrote {}", csv_path.display());
        for png in pngs {
            println!("wrote {}", png.display());
        }
    }
    Ok(())
}

/// Heatmaps of δz and |δp| over the grid (mm), one cell per node.
pub fn map_plots(
    out: &std::path::Path,
    nodes: &[MapNode],
    robot_name: &str,
    wrench: &[f64; 6],
) -> Result<Vec<PathBuf>, deflex_plot::PlotError> {
    let mut xs: Vec<f64> = nodes.iter().map(|n| n.position_m[0] * 1e3).collect();
    let mut ys: Vec<f64> = nodes.iter().map(|n| n.position_m[1] * 1e3).collect();
    for v in [&mut xs, &mut ys] {
        v.sort_by(f64::total_cmp);
        v.dedup_by(|a, b| (*a - *b).abs() < 1e-6);
    }
    let index = |values: &[f64], v: f64| values.iter().position(|x| (x - v).abs() < 1e-6);
    let mut dz = vec![f64::NAN; xs.len() * ys.len()];
    let mut norm = vec![f64::NAN; xs.len() * ys.len()];
    for node in nodes {
        if let (Some(ix), Some(iy)) = (
            index(&xs, node.position_m[0] * 1e3),
            index(&ys, node.position_m[1] * 1e3),
        ) {
            dz[iy * xs.len() + ix] = node.deflection[2] * 1e3;
            norm[iy * xs.len() + ix] = node.deflection.fixed_rows::<3>(0).norm() * 1e3;
        }
    }
    let load = format!(
        "F = ({:.0}, {:.0}, {:.0}) N",
        wrench[0], wrench[1], wrench[2]
    );
    let z_mm = nodes.first().map(|n| n.position_m[2] * 1e3).unwrap_or(0.0);
    let mut written = Vec::new();
    for (name, values, label) in [
        ("deflection_dz.png", &dz, "δz [mm]"),
        ("deflection_norm.png", &norm, "|δp| [mm]"),
    ] {
        let path = out.join(name);
        let spec = deflex_plot::PlotSpec::new(
            format!("{robot_name}: predicted {label} at z = {z_mm:.0} mm, {load}"),
            "x [mm]",
            "y [mm]",
        )
        .size(1000, 800);
        deflex_app::report::draw::heatmap(&path, &spec, &xs, &ys, values, label)?;
        written.push(path);
    }
    Ok(written)
}
