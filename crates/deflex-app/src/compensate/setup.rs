//! Everything a compensation needs, read and checked before any work: the robot and its cell,
//! the placement of the part and the seed, the path placed in the world ([`super::path`]), the
//! wrench source, the formats and the template, and every limit (reach, points per program).

use super::path::{PlacedPath, check_reach, placed_path};
use super::{Options, PathSpec, WrenchSpec};
use crate::error::{Error, Result};
use crate::option_names::OptionNames;
use deflex_cam::program::{Format, ProgramSettings};
use deflex_compensate::{CompensationOptions, TcpPath};
use deflex_model::{Pose, Robot, ToolLoad};
use deflex_sim::{CellConfig, ToolPath};
use nalgebra::Vector3;

/// The robot to compensate with, and how the user named it.
#[derive(Clone, Debug)]
pub struct RobotChoice {
    /// The robot model.
    pub model: Robot,
    /// A built-in name or a robot file, as given (`--robot`): its cell is that robot's cell, and
    /// it wins over a twin file's `part.robot`. `None` for a model given in memory (Python's
    /// `Robot`): its cell follows its name, a twin file keeps its own robot.
    pub spec: Option<String>,
}

impl RobotChoice {
    /// A robot by name or file (`--robot`), read here; a failure names `flag`.
    pub fn load(flag: &'static str, spec: &str) -> Result<RobotChoice> {
        Ok(RobotChoice {
            model: robot_from_spec(flag, spec)?,
            spec: Some(spec.to_string()),
        })
    }

    /// The robot as the user named it (its spec, else the model's name).
    fn shown(&self) -> &str {
        self.spec.as_deref().unwrap_or(&self.model.name)
    }
}

/// A robot by built-in name or robot file (`flag` names the option in the error).
pub fn robot_from_spec(flag: &'static str, spec: &str) -> Result<Robot> {
    crate::load::load_robot(spec).map_err(|source| Error::RobotSpec {
        flag,
        spec: spec.to_string(),
        source,
    })
}

/// Everything the compensation and its outputs need.
pub struct Setup {
    /// The robot model.
    pub robot: Robot,
    /// The robot's twin cell; `None` when the robot has none and the placement is given (then
    /// no process model and no tool load in the programs).
    pub config: Option<CellConfig>,
    /// The tool path without its waypoints (the process model reads its step-down and wall
    /// angle); the points are in `path`.
    pub tool_path: ToolPath,
    /// The desired TCP path in the world.
    pub path: TcpPath,
    /// The IK seed near the start of the path (rad).
    pub seed: Vec<f64>,
    /// The programs to write.
    pub formats: Vec<Format>,
    /// The program template.
    pub settings: ProgramSettings,
    /// The iteration's settings.
    pub options: CompensationOptions,
    /// The wrench source.
    pub wrench: WrenchSpec,
    /// What a log gives the compensation.
    pub log_forces: super::LogForces,
    /// With a log's law: use its measured TCP.
    pub use_measured_tcp: bool,
    /// The part frame in the world.
    pub part_frame: Pose,
    /// Its origin (mm).
    pub part_origin_mm: [f64; 3],
    /// The work offset the G-code names (`G54` …), if any.
    pub frame_name: Option<String>,
    /// Where the part frame and seed come from (`the ur10e cell`, `--part-xyz-mm` …).
    pub placement_source: String,
    /// Where the tool ([`Robot::tool`] of [`Setup::robot`]) comes from, for the user.
    pub tool_source: String,
    /// Lines for the user: the placement, the G-code reader's notes.
    pub notes: Vec<String>,
    /// The tool load of the cell (centre of mass in the flange frame), for the programs.
    pub tool_load_in_flange: Option<ToolLoad>,
    /// Where [`Setup::tool_load_in_flange`] comes from, for the programs' headers.
    pub tool_load_source: &'static str,
    /// The front end the run was set up from (its option names in the later refusals).
    pub front: OptionNames,
}

impl Setup {
    /// The placement in one line (headers and summaries), at the programs' precision.
    pub fn placement_line(&self) -> String {
        placement_text(
            self.frame_name.as_deref(),
            self.part_origin_mm,
            &self.seed,
            &self.placement_source,
        )
    }

    /// The tool in one line (headers and summaries), at the programs' precision.
    pub fn tool_line(&self) -> String {
        let t = &self.robot.tool;
        let xyz = t.translation.vector * 1e3;
        let rpy = deflex_model::spatial::rpy_from_rotation(&t.rotation);
        format!(
            "tool (flange to TCP) at ({}) mm, roll-pitch-yaw ({}) deg: {}",
            exact_mm([xyz.x, xyz.y, xyz.z]),
            degrees(&rpy),
            self.tool_source
        )
    }
}

/// Lengths in mm to 0.1 µm (4 decimals), comma-separated: the precision of the programs (every
/// number an operator types in from a header is printed as the program itself uses it).
pub(super) fn exact_mm(v: [f64; 3]) -> String {
    v.iter()
        .map(|v| format!("{:.4}", v + 0.0))
        .collect::<Vec<_>>()
        .join(", ")
}

/// Joint values or angles in degrees to 6 decimals (0.02 µrad), comma-separated.
pub(super) fn degrees(q: &[f64]) -> String {
    q.iter()
        .map(|q| format!("{:.6}", q.to_degrees() + 0.0))
        .collect::<Vec<_>>()
        .join(", ")
}

/// `part frame [NAME] at (x, y, z) mm and seed (…) deg: SOURCE`, at the programs' precision.
fn placement_text(
    frame_name: Option<&str>,
    origin_mm: [f64; 3],
    seed: &[f64],
    source: &str,
) -> String {
    format!(
        "part frame{} at ({}) mm and seed ({}) deg: {source}",
        frame_name.map_or(String::new(), |n| format!(" {n}")),
        exact_mm(origin_mm),
        degrees(seed),
    )
}

/// The robot's cell: the twin file over it, else the cell of the robot (built-in or file; a
/// model in memory by its name).
fn cell(robot: &RobotChoice, options: &Options) -> Result<CellConfig> {
    let shown = robot.shown().to_string();
    let error = |source| Error::TwinCellOf {
        robot: shown.clone(),
        source: Box::new(source),
    };
    match (&options.twin_config, &robot.spec) {
        (Some(p), spec) => {
            crate::cell::twin_cell_file::load_cell(p, spec.as_deref()).map_err(error)
        }
        (None, Some(spec)) if spec.trim().is_empty() || deflex_model::builtin(spec).is_some() => {
            CellConfig::for_robot(spec)
                .map_err(|e| error(crate::cell::twin_cell_file::TwinCellFileError::from(e)))
        }
        (None, spec) => CellConfig::for_robot_description(
            spec.as_deref().unwrap_or(&robot.model.name),
            robot.model.clone(),
        )
        .map_err(|e| error(crate::cell::twin_cell_file::TwinCellFileError::from(e))),
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

/// Read and check everything a compensation of `path` by `robot` under `wrench` needs (see the
/// module documentation of [`crate::compensate`]); the messages name the options as `front`
/// spells them.
pub fn setup(
    robot: RobotChoice,
    path_spec: &PathSpec,
    wrench: WrenchSpec,
    options: &Options,
    front: OptionNames,
) -> Result<Setup> {
    let names = front;
    // The cell is only needed for 6-joint arms' defaults and the process model.
    let mut config = match cell(&robot, options) {
        Ok(c) => Some(c),
        Err(e) if options.part_xyz_mm.is_some() && options.seed_q.is_some() => {
            if matches!(wrench, WrenchSpec::Process) {
                return Err(e);
            }
            None
        }
        Err(e) => return Err(e),
    };
    let placement = placement(&robot, options, config.as_mut(), names)?;
    let RobotChoice {
        model: mut robot,
        spec,
    } = robot;
    let robot_shown = spec.unwrap_or_else(|| robot.name.clone());
    let tool_source = one_tool(&mut robot, config.as_ref(), &robot_shown);
    let part_origin_mm = placement.part_origin_mm;
    let seed = placement.seed;
    let part_frame = Pose::translation(
        part_origin_mm[0] * 1e-3,
        part_origin_mm[1] * 1e-3,
        part_origin_mm[2] * 1e-3,
    );
    let rapid_feed = config
        .as_ref()
        .map_or(50.0, |c| c.controller.rapid_feed_mm_s);
    let PlacedPath {
        tool_path,
        path,
        frame_name,
        mut notes,
    } = placed_path(
        &robot,
        &robot_shown,
        path_spec,
        options,
        &seed,
        &part_frame,
        rapid_feed,
        names,
    )?;
    check_reach(&robot, &path, &part_origin_mm, names)?;
    let settings = super::settings(options.program_config.as_deref())?;
    if !options.formats.is_empty() {
        check_program_points(path.len(), &settings, names)?;
    }
    if matches!(wrench, WrenchSpec::Process) && config.is_none() {
        return Err(Error::invalid(
            names.name("wrench"),
            "the process model needs the robot's twin cell",
        ));
    }
    notes.insert(
        0,
        format!(
            "{}: {}",
            robot.name,
            placement_text(
                frame_name.as_deref(),
                part_origin_mm,
                &seed,
                &placement.source
            )
        ),
    );
    // A robot without a cell has no tool load of its cell to state in the programs.
    let tool_load_in_flange = config.as_ref().map(cell_tool_load);
    Ok(Setup {
        robot,
        tool_load_in_flange,
        tool_load_source: "the robot's twin cell",
        config,
        tool_path,
        path,
        seed,
        formats: options.formats.clone(),
        settings,
        options: CompensationOptions {
            orientation: !options.position_only,
            include_gravity: options.include_gravity,
            tolerance_m: options.tolerance_m,
            tolerance_rad: options.tolerance_m,
            max_iterations: options.max_iterations,
            ..CompensationOptions::default()
        },
        wrench,
        log_forces: options.log_forces,
        use_measured_tcp: options.use_measured_tcp,
        part_frame,
        part_origin_mm,
        frame_name,
        placement_source: placement.source,
        tool_source,
        notes,
        front,
    })
}

/// One tool per cell: a compensation with a cell uses the cell's tool (what `deflex sim`,
/// `deflex cell --sim` and `deflex model show` name), which is the robot model's own tool when
/// it has one ([`deflex_sim::profile::forming_tool`]); without a cell, the model's. Returns
/// where the tool comes from, for the headers.
fn one_tool(robot: &mut Robot, config: Option<&CellConfig>, shown: &str) -> String {
    let Some(config) = config else {
        return "the robot model's tool (no cell)".into();
    };
    let model_has_none = !robot.has_tool();
    let same = (robot.tool.translation.vector - config.tool().translation.vector).norm() < 1e-12
        && robot.tool.rotation.angle_to(&config.tool().rotation) < 1e-12;
    robot.tool = config.tool();
    if same {
        "the robot model's tool, as its cell's".into()
    } else if model_has_none {
        format!(
            "the forming tool of the cell of {shown} (the robot model has none; a tool in a robot file or part.tool_xyz_m in a twin file changes it)"
        )
    } else {
        "the twin file's tool (part.tool_xyz_m), not the robot model's".into()
    }
}

/// The programs hold at most `program.max_points` points.
pub(super) fn check_program_points(
    points: usize,
    settings: &ProgramSettings,
    names: OptionNames,
) -> Result<()> {
    if points > settings.program.max_points {
        return Err(Error::invalid(
            names.name("path"),
            format!(
                "{} points; the programs hold at most {} (program.max_points): shorten the path or raise the limit",
                points, settings.program.max_points
            ),
        ));
    }
    Ok(())
}

/// Where the part sits and the configuration the path starts from.
struct Placement {
    /// The part frame's origin in the robot base frame (mm).
    part_origin_mm: [f64; 3],
    /// The IK seed (rad).
    seed: Vec<f64>,
    /// Where each came from (the cell, or the options), for the user.
    source: String,
}

/// The part frame and the seed: from the options, the rest from the robot's twin cell
/// (`config`, whose part origin follows the option).
fn placement(
    robot: &RobotChoice,
    options: &Options,
    mut config: Option<&mut CellConfig>,
    names: OptionNames,
) -> Result<Placement> {
    let n = robot.model.joint_count();
    let shown = robot.shown();
    let mut placement: Vec<String> = Vec::new();
    let cell_name = if deflex_model::builtin(shown).is_some() {
        format!("the {shown} cell")
    } else {
        format!("the cell of {shown}")
    };
    let mut part_origin_mm = config.as_deref().map_or([0.0; 3], |c| c.part.origin_mm);
    if let Some(xyz) = options.part_xyz_mm {
        part_origin_mm = xyz;
        placement.push(format!("part frame from {}", names.name("part_xyz_m")));
        if let Some(c) = config.as_mut() {
            c.part.origin_mm = xyz;
        }
    }
    let seed: Vec<f64> = match (&options.seed_q, config.as_deref()) {
        (Some(seed), _) => {
            placement.push(format!("seed from {}", names.name("seed_q")));
            seed.clone()
        }
        (None, Some(c)) if n == 6 => c.seed_q_rad().to_vec(),
        (None, _) => {
            return Err(Error::invalid(
                names.name("seed_q"),
                format!(
                    "robot \"{}\" has {n} joints and no twin cell: give a configuration near the start of the path",
                    robot.model.name
                ),
            ));
        }
    };
    if seed.len() != n {
        return Err(Error::invalid(
            names.name("seed_q"),
            format!(
                "robot \"{}\" has {n} joints, {} values given",
                robot.model.name,
                seed.len()
            ),
        ));
    }
    let source = if placement.is_empty() {
        format!(
            "{cell_name} (change with {}, {})",
            names.name("part_xyz_m"),
            names.name("seed_q")
        )
    } else if placement.len() == 1 && config.is_some() {
        format!("{}, the rest from {cell_name}", placement[0])
    } else {
        placement.join(", ")
    };
    Ok(Placement {
        part_origin_mm,
        seed,
        source,
    })
}
