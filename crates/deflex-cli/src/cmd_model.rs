//! `deflex model show`, `pose`, `deflect`, `ik`, `map`: the flags (mm, degrees), their
//! conversion to SI and the printing of what `deflex_app::robot` computes.

use crate::args::{joint_values, parse_fixed, parse_length_mm_default, print_report, robot};
use crate::error::{CliError, CommandResult, UsageError};
use clap::{Args, Subcommand};
use deflex_app::robot::describe::ModelShow;
use deflex_app::robot::fk::FkTable;
use deflex_app::robot::map::{MAX_MAP_NODES_PER_SIDE, MAX_MAP_SIZE_M, MapGrid, write_map};
use deflex_app::robot::single::{DeflectionReport, IkReport, PoseReport};
use deflex_model::Robot;
use deflex_model::spatial::pose_from_xyz_rpy;
use std::path::PathBuf;

#[derive(Subcommand)]
pub enum ModelCommand {
    /// The joint table, eDoFs and stiffnesses.
    Show {
        /// Robot: built-in name (tx200, tx200-1edof, ur10, ur10e, kr210-r2700, irb4600,
        /// r2000ic-165f, gp180) or TOML file.
        #[arg(long)]
        robot: String,
    },
    /// Forward kinematics of a table of joint values (a controller's joint log, a
    /// compensated_path.csv): the TCP of the model's own tool in the world frame, a row per
    /// row. The built-in files have no tool (the flange); for the cell's tool, which compensate
    /// uses, give the robot file `deflex sim robot --robot R --out FILE` writes.
    Fk {
        /// Robot: built-in name (tx200, tx200-1edof, ur10, ur10e, kr210-r2700, irb4600) or TOML file.
        #[arg(long)]
        robot: String,
        /// CSV with a header and the columns q1_rad … qN_rad or q1_deg … qN_deg (other columns
        /// are ignored).
        #[arg(long)]
        joints: PathBuf,
        /// Output CSV (index,x_m,y_m,z_m,rx_rad,ry_rad,rz_rad: position m, rotation vector rad,
        /// world); default: standard output.
        #[arg(long)]
        out: Option<PathBuf>,
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
    /// Robot: built-in name (tx200, tx200-1edof, ur10, ur10e, kr210-r2700, irb4600,
    /// r2000ic-165f, gp180) or TOML file.
    #[arg(long)]
    pub robot: String,
    #[command(flatten)]
    pub joints: JointArgs,
}

#[derive(Args)]
pub struct DeflectArgs {
    /// Robot: built-in name (tx200, tx200-1edof, ur10, ur10e, kr210-r2700, irb4600,
    /// r2000ic-165f, gp180) or TOML file.
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
    /// Robot: built-in name (tx200, tx200-1edof, ur10, ur10e, kr210-r2700, irb4600,
    /// r2000ic-165f, gp180) or TOML file.
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
    /// Robot: built-in name (tx200, tx200-1edof, ur10, ur10e, kr210-r2700, irb4600,
    /// r2000ic-165f, gp180) or TOML file.
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
            // The robot and the twin cell `compensate`, `sim` and `demo` use for it; a robot no
            // cell can be built around (not 6 joints, no reachable part placement) says why.
            let shown = ModelShow::load(&spec)?;
            print_report(json_output, || shown.text(), || shown.to_json());
            Ok(())
        }
        ModelCommand::Fk {
            robot: spec,
            joints,
            out,
        } => {
            let robot = robot(&spec)?;
            let table = FkTable::read(&robot, &joints)?;
            match out {
                Some(path) => {
                    deflex_app::table::write_text(&path, &table.csv())?;
                    let rows = table.poses.len();
                    print_report(
                        json_output,
                        || {
                            let t = robot.tool.translation.vector * 1e3;
                            format!(
                                "wrote {rows} pose(s) to {} (TCP of the model's tool, flange → TCP ({:.4}, {:.4}, {:.4}) mm)\n",
                                path.display(),
                                t.x,
                                t.y,
                                t.z
                            )
                        },
                        || serde_json::json!({ "rows": rows, "out": path }),
                    );
                }
                None if json_output => print_report(true, String::new, || table.to_json()),
                None => print!("{}", table.csv()),
            }
            Ok(())
        }
    }
}

pub fn pose(args: PoseArgs, json_output: bool) -> CommandResult {
    let robot = robot(&args.robot)?;
    let q = args.joints.values(&robot)?;
    let report = PoseReport::at(&robot, &q)?;
    print_report(json_output, || report.text(), || report.to_json());
    Ok(())
}

pub fn deflect(args: DeflectArgs, json_output: bool) -> CommandResult {
    let robot = robot(&args.robot)?;
    let q = args.joints.values(&robot)?;
    let w = crate::args::parse_wrench(&args.wrench, "--wrench")?;
    let report = DeflectionReport::at(&robot, &q, w)?;
    print_report(json_output, || report.text(), || report.to_json());
    Ok(())
}

pub fn ik(args: IkArgs, json_output: bool) -> CommandResult {
    let robot = robot(&args.robot)?;
    let xyz = parse_fixed::<3>(&args.xyz_mm, "--xyz-mm")?;
    let rpy = parse_fixed::<3>(&args.rpy_deg, "--rpy-deg")?;
    let seed = match &args.seed_deg {
        Some(s) => joint_values(&robot, Some(s), None).map_err(|e| match e {
            UsageError::Range {
                flag,
                lo,
                hi,
                unit,
                got,
            } => UsageError::Range {
                flag: flag.replace("--q-deg", "--seed-deg"),
                lo,
                hi,
                unit,
                got,
            },
            other => other,
        })?,
        None => deflex_app::robot::default_seed(&robot),
    };
    let target = pose_from_xyz_rpy(xyz.map(|v| v * 1e-3), rpy.map(f64::to_radians));
    // A target not reached is named as given, in mm and degrees.
    let report = IkReport::solve(&robot, &target, &seed).map_err(|e| match e {
        deflex_app::Error::Model(source) => CliError::Unreachable {
            xyz_mm: xyz,
            rpy_deg: rpy,
            source,
        },
        other => other.into(),
    })?;
    print_report(json_output, || report.text(), || report.to_json());
    Ok(())
}

/// The grid of `--plane`, `--center`, `--size`, `--step` and `--wrench`, in SI, its size and
/// step checked against what a map holds (in mm, naming the flags).
fn map_grid(args: &MapArgs) -> Result<MapGrid, UsageError> {
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
        return Err(UsageError::invalid(
            "--center",
            "x,y",
            format!("\"{}\"", args.center),
        ));
    };
    let center_m = [
        parse_length_mm_default(cx, "--center")?,
        parse_length_mm_default(cy, "--center")?,
    ];
    let size_m = parse_length_mm_default(&args.size, "--size")?;
    let step_m = parse_length_mm_default(&args.step, "--step")?;
    let wrench = crate::args::parse_wrench(&args.wrench, "--wrench")?;
    if !(step_m > 0.0 && size_m >= 0.0) {
        return Err(UsageError::invalid(
            "--step",
            "a positive step over a non-negative --size",
            format!("{} mm over {} mm", step_m * 1e3, size_m * 1e3),
        ));
    }
    if size_m > MAX_MAP_SIZE_M {
        return Err(UsageError::invalid(
            "--size",
            format!("at most {:.0} mm", MAX_MAP_SIZE_M * 1e3),
            format!("{:.1} mm", size_m * 1e3),
        ));
    }
    let per_side = MapGrid::steps_per_side(size_m, step_m);
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
        ));
    }
    Ok(MapGrid {
        z_m,
        center_m,
        size_m,
        step_m,
        wrench,
    })
}

pub fn map(args: MapArgs, json_output: bool) -> CommandResult {
    let robot = robot(&args.robot)?;
    let grid = map_grid(&args)?;
    let map = write_map(&robot, &grid, &args.out)?;
    print_report(json_output, || map.text(), || map.to_json());
    Ok(())
}
