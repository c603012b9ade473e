//! `deflex compensate`: offline compensation of a tool path and robot programs, for cells
//! without a real-time option. Flags, their checks in the command line's units, the progress
//! bar and printing only: the workflow — the set-up, the compensation, the output folder with
//! its programs read back, the summaries and the refusals — is `deflex_app::compensate`.
//!
//! The robot's twin cell ([`deflex_sim::CellConfig::for_robot`]: part frame, seed
//! configuration, sheet, tool) places the path unless `--part-xyz-mm` / `--seed-deg` say
//! otherwise; the command prints which it used. The path's tool axis is −Z of its part frame (a
//! 3-axis CAM program); a seed that holds the tool more than 1° off it is refused.
//!
//! Outputs in `--out DIR` (written whole, or not at all): `compensated_path.csv`,
//! `summary.json`, `summary.txt` and, when every point is compensated and the iteration
//! converged, `programs/` with one program per `--format`, each read back and compared. When
//! points cannot be compensated (limits, reach) or the iteration did not converge, the table
//! and the summaries are still written (the `status` column names each failed point and why),
//! no program is, and the command fails listing the failed points.

use crate::args::{check_joint_values, parse_list, print_json};
use crate::error::{CliError, CommandResult, UsageError};
use clap::Args;
use deflex_app::compensate::{
    BUILTIN_PATHS, LogForces, Options, PathSpec, ProgramFormat, RobotChoice, WrenchSpec,
    compensate, setup, write_output_folder,
};
use deflex_app::option_names::OptionNames;
use deflex_telemetry::Progress;
use std::path::PathBuf;

#[derive(Args)]
pub struct CompensateArgs {
    /// Robot model: a built-in name or a robot TOML (calibrated or nominal). Its twin cell gives
    /// the part frame, the seed configuration and the sheet unless the options below say
    /// otherwise.
    #[arg(long)]
    pub robot: String,
    /// Tool path: `cone` (the paper's helical cone), `cone-contour`, `pyramid` or a CAM G-code
    /// file (ISO/Fanuc subset: lines, arcs, helices, G17-G19, G20/G21, G90/G91, G54-G59; the
    /// TCP in the work offset's frame, mm).
    #[arg(long, default_value = "cone")]
    pub path: String,
    /// Wrench source: `process` (the twin's forming model, SIMULATED) or `log:FILE` (a `deflex
    /// run` log or a `deflex sim isf` log.csv of a previous run of this path).
    #[arg(long, default_value = "process")]
    pub wrench: String,
    /// Part frame origin in the robot's world (mm, `x,y,z`); default: the robot cell's (printed
    /// by `deflex sim robot`). Negative values may follow directly (`--part-xyz-mm -20,0,5`).
    #[arg(long, allow_hyphen_values = true)]
    pub part_xyz_mm: Option<String>,
    /// IK seed near the start of the path (deg, one per joint); the tool keeps the orientation
    /// of this configuration about its axis. Default: the robot cell's seed.
    #[arg(long, allow_hyphen_values = true)]
    pub seed_deg: Option<String>,
    /// With `--wrench log:FILE`: `auto` (the force–depth law when the log supports it as a
    /// cause — the commanded depth explains the held-out force at least as well as the path
    /// position, the loop gain is below 0.8, the force does not fall with depth — else the
    /// logged wrenches; the output says which and why), `law` (the force follows the depth the
    /// compensated tool reaches, whatever the evidence) or `fixed` (the logged wrenches, one
    /// pass). A law whose iteration does not converge falls back to the logged wrenches.
    #[arg(long, value_enum, default_value = "auto")]
    pub log_forces: LogForces,
    /// With `--wrench log:FILE`: do not use the log's measured TCP (a sim log's laser-tracker
    /// columns) to correct what the robot model misses.
    #[arg(long)]
    pub ignore_measured_tcp: bool,
    /// Twin settings (`[cell]` TOML) over the robot's cell: part placement, seed, sheet.
    #[arg(long)]
    pub twin: Option<PathBuf>,
    /// Only the first part of the path (mm of travel).
    #[arg(long)]
    pub length_mm: Option<f64>,
    /// Split feed moves longer than this (mm, 0.001–10000) before compensating: a
    /// compensation moves each waypoint, so a long move into the sheet (a plunge written as one
    /// line) is only compensated at its ends otherwise. Rapids stay one move.
    #[arg(long)]
    pub max_segment_mm: Option<f64>,
    /// Chord tolerance of G-code arcs (mm, 0.0001–1).
    #[arg(long, default_value_t = 0.005)]
    pub chord_tolerance_mm: f64,
    /// Compensate the position only (keep the desired orientation).
    #[arg(long)]
    pub position_only: bool,
    /// Add the deflection under the robot's own weight (robot models with masses).
    #[arg(long)]
    pub include_gravity: bool,
    /// Convergence tolerance on the change of the compensation (µm; µrad for orientation).
    #[arg(long, default_value_t = 1.0)]
    pub tolerance_um: f64,
    /// Most process/compensation iterations (1 ..= 200).
    #[arg(long, default_value_t = 30)]
    pub max_iterations: usize,
    /// Output folder.
    #[arg(long)]
    pub out: PathBuf,
    /// Programs to write (comma-separated; `fanuc`, FANUC TP `.ls`, and `inform`, Yaskawa
    /// INFORM `.JBI`, on request).
    #[arg(
        long,
        value_enum,
        value_delimiter = ',',
        default_value = "krl,rapid,val3,urscript,gcode"
    )]
    pub format: Vec<ProgramFormat>,
    /// Program template (TOML, see docs/program.example.toml): frame and tool names, speeds,
    /// zones, clearance, tool load, limits.
    #[arg(long)]
    pub program_config: Option<PathBuf>,
}

/// Comma-separated numbers of `flag` (a message naming the flag, after it).
fn numbers(flag: &str, text: &str) -> Result<Vec<f64>, CliError> {
    parse_list(text, flag).map_err(|usage| CliError::in_context(flag)(usage.into()))
}

/// `--part-xyz-mm`: three values within 100 m (mm).
fn part_xyz_mm(text: &str) -> Result<[f64; 3], CliError> {
    let flag = "--part-xyz-mm";
    let v = numbers(flag, text)?;
    let xyz: [f64; 3] = v
        .as_slice()
        .try_into()
        .map_err(|_| UsageError::invalid(flag, "3 values x,y,z", v.len()))?;
    if xyz.iter().any(|v| v.abs() > 1e5) {
        return Err(UsageError::TooFar { flag, xyz }.into());
    }
    Ok(xyz)
}

/// `--seed-deg` in radians, each joint value within the range a joint may take.
fn seed_rad(text: &str) -> Result<Vec<f64>, CliError> {
    let flag = "--seed-deg";
    let seed: Vec<f64> = numbers(flag, text)?
        .into_iter()
        .map(f64::to_radians)
        .collect();
    check_joint_values(flag, &seed, true)
        .map_err(|usage| CliError::in_context(flag)(usage.into()))?;
    Ok(seed)
}

/// The workflow's options from the flags, checked in the command line's units.
fn options(args: &CompensateArgs) -> Result<(PathSpec, WrenchSpec, Options), CliError> {
    let part_xyz_mm = args.part_xyz_mm.as_deref().map(part_xyz_mm).transpose()?;
    let seed_q = args.seed_deg.as_deref().map(seed_rad).transpose()?;
    let path = PathSpec::named(&args.path);
    // A G-code file's arcs are interpolated to the chord tolerance: it must be sound.
    let chord_ok = (1e-4..=1.0).contains(&args.chord_tolerance_mm);
    if !BUILTIN_PATHS.contains(&args.path.as_str()) && !chord_ok {
        return Err(UsageError::invalid(
            "--chord-tolerance-mm",
            "0.0001 ..= 1",
            args.chord_tolerance_mm,
        )
        .into());
    }
    // From a micrometre to a kilometre (1e-300 mm once made an empty path).
    if let Some(l) = args.length_mm
        && !(1e-3..=1e6).contains(&l)
    {
        return Err(UsageError::invalid(
            "--length-mm",
            "a length from 0.001 to 1000000 mm",
            format!("{l:e}"),
        )
        .into());
    }
    if !(args.tolerance_um.is_finite() && (0.001..=1000.0).contains(&args.tolerance_um)) {
        return Err(
            UsageError::invalid("--tolerance-um", "0.001 ..= 1000", args.tolerance_um).into(),
        );
    }
    if !(1..=200).contains(&args.max_iterations) {
        return Err(
            UsageError::invalid("--max-iterations", "1 ..= 200", args.max_iterations).into(),
        );
    }
    let wrench = WrenchSpec::parse(&args.wrench).ok_or_else(|| {
        UsageError::invalid(
            "--wrench",
            "`process` or `log:FILE`",
            format!("\"{}\"", args.wrench),
        )
    })?;
    let options = Options {
        twin_config: args.twin.clone(),
        part_xyz_mm,
        seed_q,
        length_mm: args.length_mm,
        max_segment_mm: args.max_segment_mm,
        chord_tolerance_mm: args.chord_tolerance_mm,
        position_only: args.position_only,
        include_gravity: args.include_gravity,
        tolerance_m: args.tolerance_um * 1e-6,
        max_iterations: args.max_iterations,
        log_forces: args.log_forces,
        use_measured_tcp: !args.ignore_measured_tcp,
        formats: ProgramFormat::formats(&args.format),
        program_config: args.program_config.clone(),
    };
    Ok((path, wrench, options))
}

fn progress_bar(json: bool, points: usize) -> indicatif::ProgressBar {
    let bar = if json {
        indicatif::ProgressBar::hidden()
    } else {
        indicatif::ProgressBar::new(points as u64)
    };
    bar.set_style(
        indicatif::ProgressStyle::with_template("{msg:28} {bar:40} {pos}/{len} {elapsed}")
            .unwrap_or_else(|_| indicatif::ProgressStyle::default_bar()),
    );
    bar
}

/// Runs `deflex compensate`.
pub fn compensate_command(args: CompensateArgs, json: bool) -> CommandResult {
    let robot = RobotChoice::load("--robot", &args.robot)?;
    let (path, wrench, options) = options(&args)?;
    let s = setup(robot, &path, wrench, &options, OptionNames::Cli)?;
    if !json {
        for line in &s.notes {
            eprintln!("{line}");
        }
    }
    let bar = progress_bar(json, s.path.len());
    let mut on_progress = |p: Progress<'_>| match p {
        Progress::Stage { name, .. } => bar.set_message(name.to_string()),
        Progress::Work { done, .. } => bar.set_position(done as u64),
        Progress::Done { .. } => {}
    };
    let result = compensate(s, &mut on_progress);
    bar.finish_and_clear();
    let summary = write_output_folder(result?, &args.out)?;
    if json {
        print_json(&summary.json);
    } else {
        print!("{}", summary.text);
    }
    match summary.refusal {
        Some(e) => Err(e.into()),
        None => Ok(()),
    }
}
