//! `deflex sim ...`: the digital twin of a robotised cell (SIMULATED), playing any 6-joint robot
//! (`--robot`, default the paper's TX200).
//!
//! * `deflex sim campaign --plan PLAN.csv --out MEAS.csv [--seed N]`: measure a calibration plan
//!   on the twin's true robot with the simulated laser tracker and load cell;
//! * `deflex sim campaign --grid [paper|cell] --out GRID.csv [--grid-center-m x,y …]`: a
//!   validation grid of dead-weight loads (the paper's for the TX200, Figs. 10–13);
//! * `deflex sim campaign --spiral --out SPIRAL.csv [--spiral-center-m x,y,z …]`: the spiral of
//!   Fig. 14;
//! * `deflex sim isf --path cone|cone-contour|pyramid|plunge|FILE.gcode --out DIR [--seed N]`:
//!   forming (or a plunge into a stiff fixture), open or closed loop, with its log, summary and
//!   plots (Figs. 17–19, A1);
//! * `deflex sim sensitivity --out DIR`: the closed loop across delay, model scale, sensor gain,
//!   bias drift and contact stiffness (table, heatmap).
//!
//! Every output names the robot the twin played. Every numeric option is checked (finite, within
//! its documented range); the error names the option.

use crate::args::{bounded, parse_list, print_report};
use crate::error::{CliError, CommandResult, UsageError};
use clap::{Args, Subcommand};
use deflex_app::twin::campaign::{CampaignKind, GridChoice, grid_params, measure};
use deflex_sim::CellConfig;
use deflex_sim::twin_campaign::{GridParams, SpiralParams};
use std::path::PathBuf;

mod cmd_sensitivity;
mod isf;
use cmd_sensitivity::{SensitivityArgs, sensitivity};
use isf::{IsfArgs, isf};

#[derive(Subcommand)]
pub enum SimCommand {
    /// Measure a calibration plan, a validation grid or a spiral on the twin.
    Campaign(CampaignArgs),
    /// Form a part (or plunge into a fixture) on the twin and write its log, summary and plots.
    Isf(IsfArgs),
    /// The closed loop across delay, model scale, sensor gain, bias drift and contact stiffness.
    Sensitivity(SensitivityArgs),
    /// Write the robot file of the simulated cell: the robot with the cell's tool and base pivot,
    /// the description a user would write for that cell (start of a calibration on the twin).
    Robot(RobotArgs),
}

#[derive(Args)]
pub struct RobotArgs {
    #[command(flatten)]
    pub twin: TwinArgs,
    /// The robot file to write (TOML).
    #[arg(long)]
    pub out: PathBuf,
}

/// The robot and the twin settings, shared by every `sim` command.
#[derive(Args, Clone)]
pub struct TwinArgs {
    /// The robot the twin plays: a built-in name (`tx200`, `ur10e`, …) or a robot file. Wins
    /// over the twin file's `[cell.part] robot`. Default: the twin file's, else `tx200`.
    #[arg(long)]
    pub robot: Option<String>,
    /// Twin settings (`[cell]` TOML) over the robot's cell; default: the robot's cell.
    #[arg(long)]
    pub config: Option<PathBuf>,
}

#[derive(Args)]
pub struct CampaignArgs {
    /// Plan file (the measurement format without displacement columns), e.g. from `deflex plan`.
    #[arg(long, conflicts_with_all = ["grid", "spiral"])]
    pub plan: Option<PathBuf>,
    /// A validation grid: `cell` (default: the robot cell's grid, the paper's for the TX200) or
    /// `paper` (200 poses, 600 N and 1100 N, at the TX200's work area). The `--grid-*` options
    /// change it.
    #[arg(
        long,
        value_enum,
        num_args = 0..=1,
        default_missing_value = "cell",
        conflicts_with = "spiral",
        hide_possible_values = true
    )]
    pub grid: Option<GridChoice>,
    /// Grid centre x,y (m, world).
    #[arg(long)]
    pub grid_center_m: Option<String>,
    /// Grid size along x,y (m, 0 < s ≤ 5), or one value for a square.
    #[arg(long)]
    pub grid_size_m: Option<String>,
    /// Grid height z (m, |z| ≤ 5).
    #[arg(long)]
    pub grid_height_m: Option<f64>,
    /// Grid step (m): round(size/step) + 1 positions per side, 2 to 200.
    #[arg(long)]
    pub grid_step_m: Option<f64>,
    /// Dead weights of the grid (N, comma-separated, 1 to 10 values within (0, 10⁵]).
    #[arg(long)]
    pub grid_loads_n: Option<String>,
    /// The spiral of Fig. 14 (the robot cell's; the paper's for the TX200). The `--spiral-*`
    /// options change it.
    #[arg(long)]
    pub spiral: bool,
    /// Spiral centre x,y,z (m, world).
    #[arg(long)]
    pub spiral_center_m: Option<String>,
    /// Spiral initial radius (m, within (0, 5]).
    #[arg(long)]
    pub spiral_radius_m: Option<f64>,
    /// Radius lost per turn (m, within (0, 1]).
    #[arg(long)]
    pub spiral_pitch_m: Option<f64>,
    /// Spiral length (m, within (0, 100]).
    #[arg(long)]
    pub spiral_length_m: Option<f64>,
    /// Spiral speed (m/s, 0.001–1).
    #[arg(long)]
    pub spiral_speed_m_s: Option<f64>,
    /// Spiral dead weight (N, within (0, 10⁵]).
    #[arg(long)]
    pub spiral_load_n: Option<f64>,
    /// Output measurement file (CSV), written whole or not at all.
    #[arg(long)]
    pub out: PathBuf,
    /// Random seed (tracker and load-cell noise).
    #[arg(long, default_value_t = 1)]
    pub seed: u64,
    #[command(flatten)]
    pub twin: TwinArgs,
}

pub fn sim(command: SimCommand, json: bool) -> CommandResult {
    match command {
        SimCommand::Campaign(args) => campaign(args, json),
        SimCommand::Isf(args) => isf(args, json),
        SimCommand::Sensitivity(args) => sensitivity(args, json),
        SimCommand::Robot(args) => cell_robot(args, json),
    }
}

/// `deflex sim robot`: the nominal robot of the simulated cell as a robot file.
fn cell_robot(args: RobotArgs, json: bool) -> CommandResult {
    let config = load_config(&args.twin)?;
    let written = deflex_app::twin::write_cell_robot(&config, &args.out)?;
    print_report(json, || written.text(), || written.to_json());
    Ok(())
}

/// The cell: the robot's (`--robot`, else the file's, else the TX200's), with the twin file's
/// settings over it.
pub(super) fn load_config(twin: &TwinArgs) -> Result<CellConfig, CliError> {
    Ok(deflex_app::twin::cell_config(
        twin.robot.as_deref(),
        twin.config.as_deref(),
    )?)
}

/// The grid `grid` (`--grid`) with the `--grid-*` options over it.
fn grid_params_of(
    args: &CampaignArgs,
    grid: GridChoice,
    config: &CellConfig,
) -> Result<GridParams, CliError> {
    let mut params = grid_params(grid, config)?;
    if let Some(text) = &args.grid_center_m {
        let v = crate::args::parse_fixed::<2>(text, "--grid-center-m")?;
        for x in v {
            bounded("--grid-center-m", x, -100.0, 100.0, "m")?;
        }
        params.center_xy_m = v;
    }
    if let Some(text) = &args.grid_size_m {
        let v = parse_list(text, "--grid-size-m")?;
        let size = match v.as_slice() {
            [s] => [*s, *s],
            [a, b] => [*a, *b],
            _ => {
                return Err(
                    UsageError::invalid("--grid-size-m", "one or two values (m)", v.len()).into(),
                );
            }
        };
        for s in size {
            if !(s > 0.0 && s <= 5.0) {
                return Err(UsageError::invalid("--grid-size-m", "within (0, 5] m", s).into());
            }
        }
        params.size_xy_m = size;
    }
    if let Some(z) = args.grid_height_m {
        params.height_m = bounded("--grid-height-m", z, -5.0, 5.0, "m")?;
    }
    if let Some(step) = args.grid_step_m {
        let step = bounded("--grid-step-m", step, 1e-4, 5.0, "m")?;
        for (i, size) in params.size_xy_m.into_iter().enumerate() {
            params.points_xy[i] = GridParams::points_for_step(size, step).map_err(|e| {
                CliError::in_context("--grid-step-m")(deflex_app::Error::from(e).into())
            })?;
        }
    }
    if let Some(text) = &args.grid_loads_n {
        params.loads_n = parse_list(text, "--grid-loads-n")?;
    }
    Ok(params)
}

/// The cell's spiral with the `--spiral-*` options over it.
fn spiral_params(args: &CampaignArgs, config: &CellConfig) -> Result<SpiralParams, CliError> {
    let mut p = deflex_app::twin::campaign::spiral_params(config)?;
    if let Some(text) = &args.spiral_center_m {
        p.center_m = crate::args::parse_fixed::<3>(text, "--spiral-center-m")?;
    }
    let set =
        |target: &mut f64, value: Option<f64>, name: &str, lo: f64, hi: f64, unit: &'static str| {
            if let Some(v) = value {
                *target = bounded(name, v, lo, hi, unit)?;
            }
            Ok::<(), UsageError>(())
        };
    set(
        &mut p.initial_radius_m,
        args.spiral_radius_m,
        "--spiral-radius-m",
        1e-4,
        5.0,
        "m",
    )?;
    set(
        &mut p.pitch_m,
        args.spiral_pitch_m,
        "--spiral-pitch-m",
        1e-5,
        1.0,
        "m",
    )?;
    set(
        &mut p.length_m,
        args.spiral_length_m,
        "--spiral-length-m",
        1e-4,
        100.0,
        "m",
    )?;
    set(
        &mut p.speed_m_s,
        args.spiral_speed_m_s,
        "--spiral-speed-m-s",
        0.001,
        1.0,
        "m/s",
    )?;
    set(
        &mut p.load_n,
        args.spiral_load_n,
        "--spiral-load-n",
        1e-3,
        1e5,
        "N",
    )?;
    Ok(p)
}

fn campaign(args: CampaignArgs, json: bool) -> CommandResult {
    let config = load_config(&args.twin)?;
    let grid_options = args.grid_center_m.is_some()
        || args.grid_size_m.is_some()
        || args.grid_height_m.is_some()
        || args.grid_step_m.is_some()
        || args.grid_loads_n.is_some();
    let spiral_options = args.spiral_center_m.is_some()
        || args.spiral_radius_m.is_some()
        || args.spiral_pitch_m.is_some()
        || args.spiral_length_m.is_some()
        || args.spiral_speed_m_s.is_some()
        || args.spiral_load_n.is_some();
    if grid_options && args.grid.is_none() {
        return Err(UsageError::DoesNotApply {
            flag: "the --grid-* options",
            applies: "need --grid",
        }
        .into());
    }
    if spiral_options && !args.spiral {
        return Err(UsageError::DoesNotApply {
            flag: "the --spiral-* options",
            applies: "need --spiral",
        }
        .into());
    }
    let what = match (&args.plan, &args.grid, args.spiral) {
        (Some(plan), None, false) => CampaignKind::Plan(plan.clone()),
        (None, Some(grid), false) => CampaignKind::Grid(grid_params_of(&args, *grid, &config)?),
        (None, None, true) => CampaignKind::Spiral(spiral_params(&args, &config)?),
        _ => {
            return Err(UsageError::Missing {
                what: "what to measure",
                give: "give one of --plan PLAN.csv, --grid [cell|paper] or --spiral",
            }
            .into());
        }
    };
    let written = measure(&config, &what, args.seed, &args.out)?;
    print_report(json, || written.text(), || written.to_json());
    Ok(())
}
