//! Everything a `deflex compensate` run needs, parsed and checked before any work: the robot and
//! its cell, the path placed in the world with the path's tool axis, the wrench source, the
//! formats and the template, and every limit (reach, points per program).

use super::{CompensateArgs, FormatArg};
use crate::args::parse_list;
use deflex_cam::program::{Format, ProgramSettings};
use deflex_compensate::{CompensationOptions, TcpPath};
use deflex_model::{Pose, Robot, ToolLoad};
use deflex_sim::{CellConfig, ToolPath};
use nalgebra::{Rotation3, Unit, Vector3};
use std::path::PathBuf;

/// Largest angle between the seed's tool axis and the path's (deg).
pub const MAX_TOOL_AXIS_DEG: f64 = 1.0;

/// A setup that cannot be used; each names the option or file and what was expected.
#[derive(Debug, thiserror::Error)]
pub enum SetupError {
    /// The robot file.
    #[error("--robot {spec}: {source}")]
    Robot {
        /// As given.
        spec: String,
        /// Why.
        source: deflex_model::ModelError,
    },
    /// The robot's cell (or the twin file).
    #[error("the twin cell of {robot}: {source}")]
    Cell {
        /// The robot.
        robot: String,
        /// Why.
        source: deflex_app::cell::twin_cell_file::TwinCellFileError,
    },
    /// The path.
    #[error("--path {spec}: {source}")]
    Path {
        /// As given.
        spec: String,
        /// Why.
        source: deflex_sim::SimError,
    },
    /// An option's value.
    #[error("{flag}: {message}")]
    Option {
        /// The flag.
        flag: &'static str,
        /// What was expected.
        message: String,
    },
    /// The program template.
    #[error(transparent)]
    Template(#[from] deflex_cam::program::ProgramError),
    /// The seed holds the tool off the path's tool axis.
    #[error(
        "the seed configuration ({seed}) deg holds the tool {angle_deg:.1}° off the path's tool axis (−Z of the part frame{frame}): the programs would tilt the tool. Give --seed-deg with the tool pointing along it (within {MAX_TOOL_AXIS_DEG}°); the cell's seed is printed by `deflex sim robot --robot {robot}`"
    )]
    ToolAxis {
        /// The seed (deg, comma-separated).
        seed: String,
        /// The angle (deg).
        angle_deg: f64,
        /// ` G54` when named.
        frame: String,
        /// The robot spec.
        robot: String,
    },
    /// Path points beyond the arm's reach.
    #[error(
        "{count} of {points} path points lie beyond the arm's reach ({reach_mm:.0} mm from joint 1), the first point {first} at {distance_mm:.1} mm, with the part frame at ({x:.1}, {y:.1}, {z:.1}) mm: move the part with --part-xyz-mm x,y,z (deflex sim robot --robot R prints the robot's cell)"
    )]
    Reach {
        /// Points out of reach.
        count: usize,
        /// Path points.
        points: usize,
        /// The first.
        first: usize,
        /// Its distance (mm).
        distance_mm: f64,
        /// The reach (mm).
        reach_mm: f64,
        /// Part origin (mm).
        x: f64,
        /// Part origin (mm).
        y: f64,
        /// Part origin (mm).
        z: f64,
    },
}

/// The wrench source.
pub enum WrenchArg {
    /// The twin's process model.
    Process,
    /// A previous run's log.
    Log(PathBuf),
}

/// Everything the run needs.
pub struct Setup {
    pub robot: Robot,
    pub config: CellConfig,
    /// The tool path without its waypoints (the process model reads its step-down and wall
    /// angle); the points are in `path`.
    pub tool_path: ToolPath,
    pub path: TcpPath,
    pub seed: Vec<f64>,
    pub formats: Vec<Format>,
    pub settings: ProgramSettings,
    pub options: CompensationOptions,
    pub wrench: WrenchArg,
    pub part_frame: Pose,
    pub part_origin_mm: [f64; 3],
    /// The work offset the G-code names (`G54` …), if any.
    pub frame_name: Option<String>,
    /// Where the part frame and seed come from (`the ur10e cell`, `--part-xyz-mm` …).
    pub placement_source: String,
    /// Lines for the user: the placement, the G-code reader's notes.
    pub notes: Vec<String>,
    /// The tool load of the cell (centre of mass in the flange frame), for the programs.
    pub tool_load_in_flange: Option<ToolLoad>,
    /// Where [`Setup::tool_load_in_flange`] comes from, for the programs' headers.
    pub tool_load_source: &'static str,
}

impl Setup {
    /// The placement in one line (headers and summaries).
    pub fn placement_line(&self) -> String {
        let o = self.part_origin_mm;
        format!(
            "part frame{} at ({:.1}, {:.1}, {:.1}) mm and seed ({}) deg: {}",
            self.frame_name
                .as_ref()
                .map_or(String::new(), |n| format!(" {n}")),
            o[0],
            o[1],
            o[2],
            self.seed
                .iter()
                .map(|q| format!("{:.2}", q.to_degrees()))
                .collect::<Vec<_>>()
                .join(", "),
            self.placement_source
        )
    }
}

fn option(flag: &'static str, message: impl Into<String>) -> SetupError {
    SetupError::Option {
        flag,
        message: message.into(),
    }
}

fn parsed(flag: &'static str, text: &str) -> Result<Vec<f64>, SetupError> {
    parse_list(text, flag).map_err(|message| SetupError::Option {
        flag,
        message: message.to_string(),
    })
}

/// The robot's cell: the twin file over it, else the cell of the robot (built-in or file).
fn cell(args: &CompensateArgs) -> Result<CellConfig, SetupError> {
    let error = |source| SetupError::Cell {
        robot: args.robot.clone(),
        source,
    };
    match &args.twin {
        Some(p) => deflex_app::cell::twin_cell_file::load_cell(p, Some(&args.robot)).map_err(error),
        None => deflex_app::cell::twin_cell_file::cell_for_robot(&args.robot)
            .map_err(|e| error(deflex_app::cell::twin_cell_file::TwinCellFileError::from(e))),
    }
}

/// The tool load of the cell in the flange frame: the sensor's nominal tool mass and centre of
/// mass (sensor frame → flange).
fn cell_tool_load(config: &CellConfig) -> ToolLoad {
    let com = config.sensor_in_flange()
        * nalgebra::Point3::from(Vector3::from(config.tool_com_in_sensor_m()));
    ToolLoad {
        mass_kg: config.tool_mass_kg(),
        centre_of_mass_m: com.coords,
    }
}

pub fn setup(args: &CompensateArgs) -> Result<Setup, SetupError> {
    let robot = deflex_app::load::load_robot(&args.robot).map_err(|source| SetupError::Robot {
        spec: args.robot.clone(),
        source,
    })?;
    // The cell is only needed for 6-joint arms' defaults and the process model.
    let mut config = match cell(args) {
        Ok(c) => Some(c),
        Err(e) if args.part_xyz_mm.is_some() && args.seed_deg.is_some() => {
            if matches!(args.wrench.as_str(), "process") {
                return Err(e);
            }
            None
        }
        Err(e) => return Err(e),
    };
    let Placement {
        part_origin_mm,
        seed,
        source: placement_source,
    } = placement(args, &robot, config.as_mut())?;
    let (mut tool_path, program) = tool_path(args)?;
    match args.length_mm {
        // From a micrometre to a kilometre (1e-300 mm once made an empty path).
        Some(l) if (1e-3..=1e6).contains(&l) => tool_path = tool_path.truncated(l),
        Some(l) => {
            return Err(option(
                "--length-mm",
                format!("expected a length from 0.001 to 1000000 mm, got {l:e}"),
            ));
        }
        None => {}
    }
    if let Some(max) = args.max_segment_mm {
        tool_path = tool_path
            .subdivided(max)
            .map_err(|e| option("--max-segment-mm", e.to_string()))?;
    }
    let mut notes = Vec::new();
    let frame_name = program
        .as_ref()
        .and_then(|p| p.work_offset)
        .map(|w| w.name().to_string());
    if let Some(p) = &program {
        notes.extend(p.notes.iter().map(|n| format!("{}: {n}", args.path)));
    }
    let part_frame = Pose::translation(
        part_origin_mm[0] * 1e-3,
        part_origin_mm[1] * 1e-3,
        part_origin_mm[2] * 1e-3,
    );
    let rotation = tool_rotation(&robot, &seed, &part_frame, frame_name.as_deref(), args)?;
    let rapid_feed = config
        .as_ref()
        .map_or(50.0, |c| c.controller.rapid_feed_mm_s);
    let path =
        deflex_sim::tcp_path(&tool_path, &part_frame, &rotation, rapid_feed).map_err(|source| {
            SetupError::Path {
                spec: args.path.clone(),
                source,
            }
        })?;
    // The process model reads only the step-down and the wall angle: free the waypoints.
    tool_path.waypoints = Vec::new();
    check_reach(&robot, &path, &part_origin_mm)?;
    if !(args.tolerance_um.is_finite() && (0.001..=1000.0).contains(&args.tolerance_um)) {
        return Err(option(
            "--tolerance-um",
            format!("expected 0.001 ..= 1000, got {}", args.tolerance_um),
        ));
    }
    if !(1..=200).contains(&args.max_iterations) {
        return Err(option(
            "--max-iterations",
            format!("expected 1 ..= 200, got {}", args.max_iterations),
        ));
    }
    let (settings, formats, wrench) = outputs(args, config.is_some(), path.len())?;
    notes.insert(
        0,
        format!(
            "{}: part frame{} at ({:.1}, {:.1}, {:.1}) mm, seed ({}) deg — {placement_source}",
            robot.name,
            frame_name
                .as_ref()
                .map_or(String::new(), |n| format!(" {n}")),
            part_origin_mm[0],
            part_origin_mm[1],
            part_origin_mm[2],
            seed.iter()
                .map(|q| format!("{:.2}", q.to_degrees()))
                .collect::<Vec<_>>()
                .join(", ")
        ),
    );
    let config = config.unwrap_or_default();
    let tool_load_in_flange = Some(cell_tool_load(&config));
    Ok(Setup {
        robot,
        tool_load_in_flange,
        tool_load_source: "the robot's twin cell",
        config,
        tool_path,
        path,
        seed,
        formats,
        settings,
        options: CompensationOptions {
            orientation: !args.position_only,
            include_gravity: args.include_gravity,
            tolerance_m: args.tolerance_um * 1e-6,
            tolerance_rad: args.tolerance_um * 1e-6,
            max_iterations: args.max_iterations,
            ..CompensationOptions::default()
        },
        wrench,
        part_frame,
        part_origin_mm,
        frame_name,
        placement_source,
        notes,
    })
}

/// Where the part sits and the configuration the path starts from.
struct Placement {
    /// The part frame's origin in the robot base frame (mm).
    part_origin_mm: [f64; 3],
    /// The IK seed (rad).
    seed: Vec<f64>,
    /// Where each came from (the cell, or the flags), for the user.
    source: String,
}

/// The part frame and the seed: from `--part-xyz-mm` and `--seed-deg`, the rest from the
/// robot's twin cell (`config`, whose part origin follows `--part-xyz-mm`).
fn placement(
    args: &CompensateArgs,
    robot: &Robot,
    mut config: Option<&mut CellConfig>,
) -> Result<Placement, SetupError> {
    let n = robot.joint_count();
    let mut placement: Vec<&str> = Vec::new();
    let cell_name = if deflex_model::builtin(&args.robot).is_some() {
        format!("the {} cell", args.robot)
    } else {
        format!("the cell of {}", args.robot)
    };
    let mut part_origin_mm = config.as_deref().map_or([0.0; 3], |c| c.part.origin_mm);
    if let Some(text) = &args.part_xyz_mm {
        let v = parsed("--part-xyz-mm", text)?;
        let xyz: [f64; 3] = v.as_slice().try_into().map_err(|_| {
            option(
                "--part-xyz-mm",
                format!("expected 3 values x,y,z, got {}", v.len()),
            )
        })?;
        if xyz.iter().any(|v| v.abs() > 1e5) {
            return Err(option(
                "--part-xyz-mm",
                format!("{xyz:?} is farther than 100 m"),
            ));
        }
        part_origin_mm = xyz;
        placement.push("part frame from --part-xyz-mm");
        if let Some(c) = config.as_mut() {
            c.part.origin_mm = xyz;
        }
    }
    let seed: Vec<f64> = match (&args.seed_deg, config.as_deref()) {
        (Some(text), _) => {
            placement.push("seed from --seed-deg");
            let seed: Vec<f64> = parsed("--seed-deg", text)?
                .into_iter()
                .map(f64::to_radians)
                .collect();
            crate::args::check_joint_values("--seed-deg", &seed, true).map_err(|e| {
                SetupError::Option {
                    flag: "--seed-deg",
                    message: e.to_string(),
                }
            })?;
            seed
        }
        (None, Some(c)) if n == 6 => c.seed_q_rad().to_vec(),
        (None, _) => {
            return Err(option(
                "--seed-deg",
                format!(
                    "robot \"{}\" has {n} joints and no twin cell: give a configuration near the start of the path",
                    robot.name
                ),
            ));
        }
    };
    if seed.len() != n {
        return Err(option(
            "--seed-deg",
            format!(
                "robot \"{}\" has {n} joints, {} values given",
                robot.name,
                seed.len()
            ),
        ));
    }
    let placement_source = if placement.is_empty() {
        format!("{cell_name} (change with --part-xyz-mm, --seed-deg)")
    } else if placement.len() == 1 && config.is_some() {
        format!("{}, the rest from {cell_name}", placement[0])
    } else {
        placement.join(", ")
    };
    Ok(Placement {
        part_origin_mm,
        seed,
        source: placement_source,
    })
}

/// The program settings, the formats to write (checked against their point limit) and the
/// wrench source (`process` needs the robot's twin cell).
fn outputs(
    args: &CompensateArgs,
    has_cell: bool,
    points: usize,
) -> Result<(ProgramSettings, Vec<Format>, WrenchArg), SetupError> {
    let settings = match &args.program_config {
        Some(p) => ProgramSettings::load(p)?,
        None => ProgramSettings::default(),
    };
    let formats: Vec<Format> = if args.format.contains(&FormatArg::None) {
        Vec::new()
    } else {
        let mut out: Vec<Format> = Vec::new();
        for f in args.format.iter().filter_map(|f| f.format()) {
            if !out.contains(&f) {
                out.push(f);
            }
        }
        out
    };
    if !formats.is_empty() && points > settings.program.max_points {
        return Err(option(
            "--path",
            format!(
                "{} points; the programs hold at most {} (program.max_points): shorten the path or raise the limit",
                points, settings.program.max_points
            ),
        ));
    }
    let wrench = match args.wrench.strip_prefix("log:") {
        Some(file) => WrenchArg::Log(PathBuf::from(file)),
        None if args.wrench == "process" => {
            if !has_cell {
                return Err(option(
                    "--wrench",
                    "the process model needs the robot's twin cell",
                ));
            }
            WrenchArg::Process
        }
        None => {
            return Err(option(
                "--wrench",
                format!("expected `process` or `log:FILE`, got \"{}\"", args.wrench),
            ));
        }
    };
    Ok((settings, formats, wrench))
}

/// The tool path: a built-in one, or a G-code file read with its notes.
fn tool_path(
    args: &CompensateArgs,
) -> Result<(ToolPath, Option<deflex_sim::gcode::Program>), SetupError> {
    let path_error = |source| SetupError::Path {
        spec: args.path.clone(),
        source,
    };
    match args.path.as_str() {
        "cone" | "cone-contour" | "pyramid" => Ok((
            deflex_app::load::gcode_file::tool_path_by_name(&args.path).map_err(path_error)?,
            None,
        )),
        file => {
            if !(args.chord_tolerance_mm.is_finite()
                && (1e-4..=1.0).contains(&args.chord_tolerance_mm))
            {
                return Err(option(
                    "--chord-tolerance-mm",
                    format!("expected 0.0001 ..= 1, got {}", args.chord_tolerance_mm),
                ));
            }
            let options = deflex_sim::gcode::ReadOptions {
                chord_tolerance_mm: args.chord_tolerance_mm,
                ..deflex_sim::gcode::default_options()
            };
            let (path, program) =
                deflex_app::load::gcode_file::read_gcode_with(std::path::Path::new(file), &options)
                    .map_err(path_error)?;
            Ok((path, Some(program)))
        }
    }
}

/// The path's tool orientation: the tool axis (TCP z) exactly along −Z of the part frame (the
/// tool axis of a 3-axis program), turned about it as the seed holds the tool. A seed more than
/// [`MAX_TOOL_AXIS_DEG`] off is refused.
fn tool_rotation(
    robot: &Robot,
    seed: &[f64],
    part: &Pose,
    frame_name: Option<&str>,
    args: &CompensateArgs,
) -> Result<Rotation3<f64>, SetupError> {
    let held = robot
        .tcp_pose(seed)
        .map_err(|e| option("--seed-deg", e.to_string()))?
        .rotation;
    let axis = held * Vector3::z();
    let want = part.rotation * -Vector3::z();
    let angle = axis.angle(&want);
    if angle.to_degrees() > MAX_TOOL_AXIS_DEG {
        return Err(SetupError::ToolAxis {
            seed: seed
                .iter()
                .map(|q| format!("{:.2}", q.to_degrees()))
                .collect::<Vec<_>>()
                .join(", "),
            angle_deg: angle.to_degrees(),
            frame: frame_name.map_or(String::new(), |n| format!(" {n}")),
            robot: args.robot.clone(),
        });
    }
    // The smallest rotation taking the held axis onto the path's.
    let align = Rotation3::rotation_between(&axis, &want).unwrap_or_else(|| {
        Rotation3::from_axis_angle(
            &Unit::new_normalize(axis.cross(&Vector3::x())),
            std::f64::consts::PI,
        )
    });
    Ok(align * held)
}

/// Every path point within the arm's reach (the sum of its link lengths from joint 1).
fn check_reach(robot: &Robot, path: &TcpPath, part_origin_mm: &[f64; 3]) -> Result<(), SetupError> {
    let shoulder = (robot.base * robot.joints[0].placement).translation.vector;
    let reach = robot.reach_bound();
    let mut count = 0;
    let mut first = None;
    for (i, p) in path.points().iter().enumerate() {
        let d = (p.pose.translation.vector - shoulder).norm();
        if d > reach {
            count += 1;
            first.get_or_insert((i, d));
        }
    }
    match first {
        None => Ok(()),
        Some((i, d)) => Err(SetupError::Reach {
            count,
            points: path.len(),
            first: i,
            distance_mm: d * 1e3,
            reach_mm: reach * 1e3,
            x: part_origin_mm[0],
            y: part_origin_mm[1],
            z: part_origin_mm[2],
        }),
    }
}
