//! `deflex plan`: the measurement campaign for a real cell (floor, table, cable or dead-weight
//! loads, bracket, measured points), with expected standard errors and the technician's sheet.
//! The workflow is `deflex_app::calibrate::plan`'s; here the flags are checked, converted into
//! its options and the result printed.

use crate::args::{check_range, print_json, robot};
use crate::error::{CliError, CommandResult, UsageError};
use clap::Args;
use deflex_app::calibrate::plan::{
    self, BasePoint, Floor, LoadKind, MAX_PLAN_FORCE_N, MAX_USER_POINTS, PlanOptions, PointSet,
    TableOption, WorkTable, parse_directions, parse_point_flag,
};
use deflex_app::calibrate::{LoadChoice, PointsChoice};
use deflex_model::Robot;
use std::path::PathBuf;

#[derive(Args)]
pub struct PlanArgs {
    /// Nominal model: built-in name or TOML file (joint limits required).
    #[arg(long)]
    pub robot: String,
    /// Cable tension (N, up to 1e5). Default: from the robot (the force whose median TCP
    /// deflection is 2.5 mm with its stiffnesses, at most half the arm's weight when its masses
    /// are known): 1400 N for the TX200, 140 N for a UR10e.
    #[arg(long = "max-force-N")]
    pub max_force_n: Option<f64>,
    /// How loads are applied: cable (tension along --cable-directions) or dead-weight (masses
    /// along gravity, --masses-kg).
    #[arg(long, value_enum, default_value = "cable")]
    pub load: LoadChoice,
    /// Directions a cable may lead from the attachment (world axes): x,-x,y,-y,z,-z (default
    /// all; +z needs an overhead anchor).
    #[arg(long)]
    pub cable_directions: Option<String>,
    /// Dead weights (kg, comma-separated, at most 4). Default: one weight of the default force.
    #[arg(long)]
    pub masses_kg: Option<String>,
    /// Off-axis bracket: load point offset from the TCP in the TCP frame (m, `x,y,z`, e.g.
    /// 0.2,0,0). Loads then also act there, its moment turns the wrist, and the bracket point
    /// is measured (`BR`).
    #[arg(long)]
    pub bracket_m: Option<String>,
    /// Number of load cases (1 to 1000; axis-by-axis ones included).
    #[arg(long, default_value_t = 24)]
    pub load_cases: usize,
    /// Plan for every eDoF of the model family (what `calibrate --structure auto` needs), not
    /// only the model's.
    #[arg(long)]
    pub full_family: bool,
    /// Points measured on the arm besides the TCP: `standard` (two mid-arm points), `none`, or
    /// a CSV file with columns name,link,x_m,y_m,z_m (position in the link's frame).
    #[arg(long, default_value = "standard", value_parser = parse_points_choice)]
    pub points: PointsChoice,
    /// An extra measured point `NAME,LINK,X,Y,Z` (m, link frame; repeatable).
    #[arg(long)]
    pub point: Vec<String>,
    /// Base reflector M0 position in R0 (m, `x,y,z`). Default: (0.3, 0, −0.3), raised to
    /// 0.15 m above the floor when the floor is higher.
    #[arg(long)]
    pub base_point_m: Option<String>,
    /// Do not measure the base reflector M0 (which separates a baseplate tilt from joint 1).
    #[arg(long)]
    pub no_base_point: bool,
    /// Floor height (world z, m). Default: from the robot (its base pivot, the TX200's
    /// 0.642 m shoulder height, or R0 when R0 is below the shoulder).
    #[arg(long)]
    pub floor_z_m: Option<f64>,
    /// No floor check.
    #[arg(long)]
    pub no_floor: bool,
    /// Work table `x_min,x_max,y_min,y_max,top_z` (world, m). Default: in front of the robot,
    /// x 0.5–0.85 × reach, y ±0.3 × reach, top 0.2 × reach above the floor.
    #[arg(long)]
    pub table: Option<String>,
    /// No table check.
    #[arg(long)]
    pub no_table: bool,
    /// Clearance kept above the floor and the table (m, 0 to 1).
    #[arg(long, default_value_t = 0.05)]
    pub clearance_m: f64,
    /// Free height a dead weight or a cable leading down needs below its attachment (m, 0 to 5).
    #[arg(long, default_value_t = 0.3)]
    pub hanging_drop_m: f64,
    /// Tracker noise (µm, 0.001 to 10000) for the expected standard errors.
    #[arg(long, default_value_t = 15.0)]
    pub noise_um: f64,
    /// Random configurations tried (1 to 2000; each with every load direction or weight).
    #[arg(long, default_value_t = 600)]
    pub configurations: usize,
    /// Random seed.
    #[arg(long, default_value_t = 1)]
    pub seed: u64,
    /// Output plan CSV (with `# robot:` and `# geometry:` header lines).
    #[arg(long)]
    pub out: PathBuf,
}

/// `--points`: `standard`, `none`, or a file name.
fn parse_points_choice(text: &str) -> Result<PointsChoice, std::convert::Infallible> {
    text.parse()
}

/// Comma-separated numbers of a flag, exactly `N` of them.
fn fixed<const N: usize>(flag: &str, text: &str) -> Result<[f64; N], UsageError> {
    crate::args::parse_fixed::<N>(text, flag)
}

/// The plan options from the flags (every number checked, the flag named).
fn plan_options(args: &PlanArgs, nominal: &Robot) -> Result<PlanOptions, CliError> {
    let n = nominal.joint_count();
    let max_force_n = match args.max_force_n {
        Some(f) => {
            check_range("--max-force-N", f, 1e-3, MAX_PLAN_FORCE_N)?;
            f
        }
        None => plan::default_force_n(nominal)?,
    };
    check_range("--noise-um", args.noise_um, 1e-3, 1e4)?;
    check_range("--clearance-m", args.clearance_m, 0.0, 1.0)?;
    check_range("--hanging-drop-m", args.hanging_drop_m, 0.0, 5.0)?;
    if let Some(z) = args.floor_z_m {
        check_range("--floor-z-m", z, -100.0, 100.0)?;
    }
    let load = load_kind(args, nominal, max_force_n)?;
    let points = point_set(args, n)?;
    let base_point = match (&args.base_point_m, args.no_base_point) {
        (Some(_), true) => {
            return Err(UsageError::NotBoth {
                first: "--base-point-m",
                second: "--no-base-point",
            }
            .into());
        }
        (Some(text), false) => BasePoint::At(fixed::<3>("--base-point-m", text)?),
        (None, true) => BasePoint::Off,
        (None, false) => BasePoint::Default,
    };
    let floor = match (args.floor_z_m, args.no_floor) {
        (Some(_), true) => {
            return Err(UsageError::NotBoth {
                first: "--floor-z-m",
                second: "--no-floor",
            }
            .into());
        }
        (Some(z), false) => Floor::At(z),
        (None, true) => Floor::Off,
        (None, false) => Floor::Default,
    };
    let table = match (&args.table, args.no_table) {
        (Some(_), true) => {
            return Err(UsageError::NotBoth {
                first: "--table",
                second: "--no-table",
            }
            .into());
        }
        (Some(text), false) => {
            let [x0, x1, y0, y1, top] = fixed::<5>("--table", text)?;
            TableOption::At(WorkTable {
                x_m: [x0, x1],
                y_m: [y0, y1],
                top_z_m: top,
            })
        }
        (None, true) => TableOption::Off,
        (None, false) => TableOption::Default,
    };
    let bracket_m = args
        .bracket_m
        .as_deref()
        .map(|text| fixed::<3>("--bracket-m", text))
        .transpose()?;
    Ok(PlanOptions {
        max_force_n,
        load_cases: args.load_cases,
        configurations: args.configurations,
        noise_sigma_m: args.noise_um * 1e-6,
        seed: args.seed,
        full_family: args.full_family,
        base_point,
        points,
        floor,
        table,
        clearance_m: args.clearance_m,
        hanging_drop_m: args.hanging_drop_m,
        load,
        bracket_m,
    })
}

/// The loads from `--load`, `--cable-directions` and `--masses-kg`.
fn load_kind(args: &PlanArgs, nominal: &Robot, max_force_n: f64) -> Result<LoadKind, CliError> {
    Ok(match args.load {
        LoadChoice::DeadWeight => {
            if args.cable_directions.is_some() {
                return Err(UsageError::DoesNotApply {
                    flag: "--cable-directions",
                    applies: "only with --load cable",
                }
                .into());
            }
            let masses_kg = match &args.masses_kg {
                Some(text) => crate::args::parse_list(text, "--masses-kg")?,
                None => plan::default_masses_kg(nominal, max_force_n)?,
            };
            LoadKind::DeadWeight { masses_kg }
        }
        LoadChoice::Cable => {
            if args.masses_kg.is_some() {
                return Err(UsageError::DoesNotApply {
                    flag: "--masses-kg",
                    applies: "only with --load dead-weight",
                }
                .into());
            }
            match &args.cable_directions {
                Some(text) => LoadKind::Cable {
                    directions: parse_directions(text).map_err(|e| {
                        UsageError::invalid(
                            "--cable-directions",
                            "directions among x, -x, y, -y, z, -z",
                            format!("\"{}\"", e.text),
                        )
                    })?,
                },
                None => LoadKind::cable_all_axes(),
            }
        }
    })
}

/// The measured points from `--points` and `--point`, for a robot with `n` joints.
fn point_set(args: &PlanArgs, n: usize) -> Result<PointSet, CliError> {
    let mut points = plan::read_point_set(&args.points, n)
        .map_err(|e| CliError::in_context("--points")(e.into()))?;
    if !args.point.is_empty() {
        let mut list = match points {
            PointSet::Standard => Vec::new(),
            PointSet::Custom(list) => list,
        };
        if args.points == PointsChoice::Standard {
            return Err(UsageError::DoesNotApply {
                flag: "--point",
                applies: "give --points none (or a file) with it; the standard mid-arm points are not combined with others",
            }
            .into());
        }
        for text in args.point.iter().take(MAX_USER_POINTS + 1) {
            list.push(
                parse_point_flag(text, n)
                    .map_err(|e| CliError::in_context(format!("--point {text}"))(e.into()))?,
            );
        }
        if list.len() > MAX_USER_POINTS {
            return Err(UsageError::invalid(
                "--point",
                format!("at most {MAX_USER_POINTS} points"),
                list.len(),
            )
            .into());
        }
        points = PointSet::Custom(list);
    }
    Ok(points)
}

pub fn plan(args: PlanArgs, json_output: bool) -> CommandResult {
    let nominal = robot(&args.robot)?;
    let options = plan_options(&args, &nominal)?;
    let planned = plan::plan(&nominal, &options, &args.out)?;
    if json_output {
        print_json(&plan::plan_json(&planned));
    } else {
        print!("{}", plan::plan_text(&planned, args.noise_um));
    }
    Ok(())
}
