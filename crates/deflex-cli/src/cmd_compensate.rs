//! `deflex compensate`: offline compensation of a tool path and robot programs, for cells
//! without a real-time option. Parsing, checks, progress and printing only: the compensation is
//! `deflex_compensate`, the process model `deflex_sim::process_model`, the G-code reader
//! `deflex_cam::gcode`, the programs `deflex_cam::program`.
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

mod programs;
mod setup;

use crate::args::print_json;
use crate::error::CommandResult;
use clap::{Args, ValueEnum};
use deflex_app::load::read_wrench_log;
use deflex_compensate::log::{ResampleOptions, resample_on_path};
use deflex_compensate::table::write_csv_to;
use deflex_compensate::{
    Compensation, Identification, LoggedProcess, LoggedProcessOptions, WrenchSource, compensate,
};
use deflex_sim::FormingProcess;
use deflex_telemetry::Progress;
use serde_json::json;
use setup::Setup;
use std::fmt::Write as _;
use std::io::Write as _;
use std::path::{Path, PathBuf};

/// What a log gives the compensation (`--log-forces`).
#[derive(Clone, Copy, Debug, PartialEq, Eq, ValueEnum)]
pub enum LogForces {
    /// The force–depth law identified from the log: the compensated tool, reaching deeper,
    /// meets the force the log shows at that depth (`deflex_compensate::logged`).
    Law,
    /// The logged wrenches as they are (one pass).
    Fixed,
}

/// A program format on the command line.
#[derive(Clone, Copy, Debug, PartialEq, Eq, ValueEnum)]
pub enum FormatArg {
    /// KUKA KRL (`.src` + `.dat`).
    Krl,
    /// ABB RAPID (`.mod`).
    Rapid,
    /// Stäubli VAL3 (an SRS application folder).
    Val3,
    /// Universal Robots URScript (`.script`).
    Urscript,
    /// G-code in the part frame.
    Gcode,
    /// No program.
    None,
}

impl FormatArg {
    fn format(self) -> Option<deflex_cam::program::Format> {
        use deflex_cam::program::Format;
        match self {
            FormatArg::Krl => Some(Format::Krl),
            FormatArg::Rapid => Some(Format::Rapid),
            FormatArg::Val3 => Some(Format::Val3),
            FormatArg::Urscript => Some(Format::UrScript),
            FormatArg::Gcode => Some(Format::Gcode),
            FormatArg::None => None,
        }
    }
}

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
    /// With `--wrench log:FILE`: `law` (the force follows the depth the compensated tool reaches,
    /// as the log shows it does) or `fixed` (the logged wrenches, one pass).
    #[arg(long, value_enum, default_value = "law")]
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
    /// Programs to write (comma-separated).
    #[arg(
        long,
        value_enum,
        value_delimiter = ',',
        default_value = "krl,rapid,val3,urscript,gcode"
    )]
    pub format: Vec<FormatArg>,
    /// Program template (TOML, see docs/program.example.toml): frame and tool names, speeds,
    /// zones, clearance, tool load, limits.
    #[arg(long)]
    pub program_config: Option<PathBuf>,
}

/// Why `deflex compensate` stops.
#[derive(Debug, thiserror::Error)]
pub enum CompensateCommandError {
    /// A robot file, cell, path, template or option that cannot be used.
    #[error("{0}")]
    Setup(#[from] Box<setup::SetupError>),
    /// The log cannot be read as a wrench source.
    #[error(transparent)]
    LogRead(#[from] deflex_app::load::WrenchLogError),
    /// The log cannot serve as the wrench source of this path.
    #[error(transparent)]
    Log(#[from] deflex_compensate::LogError),
    /// The twin's process model cannot be built.
    #[error("the twin's process model: {0}")]
    Process(deflex_sim::SimError),
    /// The compensation stopped.
    #[error(transparent)]
    Compensate(#[from] deflex_compensate::CompensateError),
    /// Writing the output folder failed.
    #[error("{path}: {source}")]
    Output {
        /// The file or folder.
        path: String,
        /// The operating system's error.
        source: std::io::Error,
    },
    /// A program could not be written or did not read back.
    #[error(transparent)]
    Program(#[from] programs::ProgramCheckError),
    /// Points could not be compensated (the table and summaries are written).
    #[error(
        "{count} of {points} points cannot be compensated (status column of compensated_path.csv); no robot program written:\n{list}\n{hint}"
    )]
    Points {
        /// How many.
        count: usize,
        /// Path points.
        points: usize,
        /// The first ones, one per line.
        list: String,
        /// What to try.
        hint: String,
    },
    /// The iteration did not converge (the table and summaries are written).
    #[error(
        "the compensation did not converge in {iterations} iterations (last change {change_mm:.4} mm, {change_mrad:.4} mrad, tolerance {tolerance_mm:.4} mm); no robot program written"
    )]
    NotConverged {
        /// Iterations run.
        iterations: usize,
        /// Last change (mm).
        change_mm: f64,
        /// Last change (mrad).
        change_mrad: f64,
        /// The tolerance (mm).
        tolerance_mm: f64,
    },
}

fn output_error(path: &Path) -> impl Fn(std::io::Error) -> CompensateCommandError + '_ {
    move |source| CompensateCommandError::Output {
        path: path.display().to_string(),
        source,
    }
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
    Ok(run(args, json)?)
}

/// The command with its typed error.
pub fn run(args: CompensateArgs, json: bool) -> Result<(), CompensateCommandError> {
    let s = setup::setup(&args).map_err(Box::new)?;
    if !json {
        for line in &s.notes {
            eprintln!("{line}");
        }
    }
    let started = std::time::Instant::now();
    let bar = progress_bar(json, s.path.len());
    let mut on_progress = |p: Progress<'_>| match p {
        Progress::Stage { name, .. } => bar.set_message(name.to_string()),
        Progress::Work { done, .. } => bar.set_position(done as u64),
        Progress::Done { .. } => {}
    };
    let part = s.part_frame;
    let mut source_lines: Vec<String> = Vec::new();
    let mut law_json: Option<serde_json::Value> = None;
    let result = match &s.wrench {
        setup::WrenchArg::Log(file) => {
            let log = read_wrench_log(file, &s.robot, &part)?;
            let resampled = resample_on_path(&log, &s.path, &ResampleOptions::default())?;
            source_lines.push(format!(
                "{}{} {}: {} rows used, {} at a standstill (not used), {} skipped (flags), {} off the path (max offset {:.2} mm)",
                if log.simulated { "SIMULATED " } else { "" },
                log.kind.name(),
                file.display(),
                resampled.used_rows,
                resampled.standstill_rows,
                log.skipped_rows,
                resampled.off_path_rows,
                resampled.max_offset_m * 1e3
            ));
            let label = format!(
                "{}{} {}",
                if log.simulated { "SIMULATED " } else { "" },
                log.kind.name(),
                file.display()
            );
            match args.log_forces {
                LogForces::Fixed => compensate(
                    &s.robot,
                    &s.path,
                    &s.seed,
                    WrenchSource::Fixed {
                        label,
                        simulated: log.simulated,
                        wrenches: &resampled.wrenches,
                    },
                    &s.options,
                    &mut on_progress,
                )?,
                LogForces::Law => {
                    let label = format!("{} {}", log.kind.name(), file.display());
                    let mut process = LoggedProcess::new(
                        &label,
                        log.simulated,
                        resampled,
                        LoggedProcessOptions {
                            use_measured: !args.ignore_measured_tcp,
                            ..LoggedProcessOptions::default()
                        },
                    )
                    .map_err(deflex_compensate::CompensateError::from)?;
                    let result = compensate(
                        &s.robot,
                        &s.path,
                        &s.seed,
                        WrenchSource::Process(&mut process),
                        &s.options,
                        &mut on_progress,
                    )?;
                    if let Some(id) = process.identification() {
                        source_lines.push(identification_line(id, process.bounded_points()));
                        law_json = Some(identification_json(id, process.bounded_points()));
                    }
                    result
                }
            }
        }
        setup::WrenchArg::Process => {
            let mut process = FormingProcess::from_cell(&s.config, &s.tool_path)
                .map_err(CompensateCommandError::Process)?;
            compensate(
                &s.robot,
                &s.path,
                &s.seed,
                WrenchSource::Process(&mut process),
                &s.options,
                &mut on_progress,
            )?
        }
    };
    bar.finish_and_clear();
    let elapsed_s = started.elapsed().as_secs_f64();
    let summary = write_outputs(&args, &s, result, &source_lines, law_json, elapsed_s, json)?;
    if json {
        print_json(&summary.json);
    } else {
        print!("{}", summary.text);
    }
    match summary.refusal {
        Some(e) => Err(e),
        None => Ok(()),
    }
}

/// What the run reports.
struct Summary {
    json: serde_json::Value,
    text: String,
    refusal: Option<CompensateCommandError>,
}

/// The command fails when points are not compensated or the iteration did not converge: it
/// prints its summary and writes its table and summaries (no program) only where no earlier
/// output folder exists; an earlier one stays whole.
fn refusal(result: &Compensation, s: &Setup) -> Option<CompensateCommandError> {
    let count = result.failure_count();
    if count > 0 {
        let mut list: Vec<String> = result
            .failures()
            .take(20)
            .map(|(i, f)| format!("  point {i}: {f}"))
            .collect();
        if count > 20 {
            list.push(format!("  … and {} more", count - 20));
        }
        return Some(CompensateCommandError::Points {
            count,
            points: s.path.len(),
            list: list.join("\n"),
            hint: format!(
                "The path was placed with the part frame at ({:.1}, {:.1}, {:.1}) mm and the seed ({}) deg ({}): move the part with --part-xyz-mm x,y,z or choose the arm's branch with --seed-deg (deflex sim robot --robot R prints the robot's cell).",
                s.part_origin_mm[0],
                s.part_origin_mm[1],
                s.part_origin_mm[2],
                s.seed
                    .iter()
                    .map(|q| format!("{:.2}", q.to_degrees()))
                    .collect::<Vec<_>>()
                    .join(", "),
                s.placement_source
            ),
        });
    }
    if !result.converged {
        let last = result.iterations.last();
        return Some(CompensateCommandError::NotConverged {
            iterations: result.iterations.len(),
            change_mm: last.map_or(f64::NAN, |r| r.max_change_m * 1e3),
            change_mrad: last.map_or(f64::NAN, |r| r.max_change_rad * 1e3),
            tolerance_mm: s.options.tolerance_m * 1e3,
        });
    }
    None
}

/// Header lines of the table and of the programs.
fn description(s: &Setup, result: &Compensation) -> Vec<String> {
    let simulated = if result.simulated { "SIMULATED " } else { "" };
    vec![
        format!(
            "{simulated}deflex offline compensation of \"{}\" ({} points, {:.1} mm)",
            s.path.name(),
            s.path.len(),
            s.path.length_m() * 1e3
        ),
        format!(
            "robot model \"{}\", geometry {}; wrenches: {}",
            s.robot.name,
            s.robot.geometry_fingerprint(),
            result.source
        ),
        s.placement_line(),
        format!(
            "predicted error {:.4} mm uncompensated, {:.4} mm compensated; largest compensation {:.4} mm, {:.4} mrad",
            result
                .iterations
                .first()
                .map_or(0.0, |r| r.max_predicted_error_m * 1e3),
            result.final_max_error_m * 1e3,
            result.max_compensation_m * 1e3,
            result.max_compensation_rad * 1e3
        ),
    ]
}

/// Write the output folder whole; returns the summaries (and the refusal, if any).
fn write_outputs(
    args: &CompensateArgs,
    s: &Setup,
    result: Compensation,
    source_lines: &[String],
    law: Option<serde_json::Value>,
    elapsed_s: f64,
    json: bool,
) -> Result<Summary, CompensateCommandError> {
    let dir = deflex_files::AtomicDir::create(&args.out).map_err(output_error(&args.out))?;
    let mut written = Vec::new();
    let mut comments = description(s, &result);
    comments.extend(source_lines.iter().cloned());
    comments.push("SI units; commanded = desired ⊕ compensation (dx_m … drz_rad); world frame of the robot model; rx_rad … rz_rad: the TCP orientation (rotation vector, world)".into());
    let table_path = dir.path().join("compensated_path.csv");
    let mut table =
        deflex_files::AtomicFile::create(&table_path).map_err(output_error(&table_path))?;
    write_csv_to(
        &mut table,
        &s.path,
        &result,
        s.robot.joint_count(),
        &comments,
    )
    .and_then(|()| table.flush())
    .map_err(output_error(&table_path))?;
    table.commit().map_err(output_error(&table_path))?;
    written.push("compensated_path.csv".to_string());
    let refusal = refusal(&result, s);
    let mut program_report = Vec::new();
    let mut program_json = Vec::new();
    let iterations = iteration_json(&result);
    let text_head = summary_text(s, &result, source_lines, elapsed_s);
    let failures: Vec<serde_json::Value> = result
        .failures()
        .take(1000)
        .map(|(i, f)| json!({"index": i, "status": f.code(), "reason": f.to_string()}))
        .collect();
    let numbers = json!({
        "simulated": result.simulated,
        "wrench_source": result.source,
        "converged": result.converged,
        "iterations": iterations,
        "final_max_predicted_error_m": result.final_max_error_m,
        "final_max_predicted_error_rad": result.final_max_error_rad,
        "final_max_force_N": result.final_max_force_n,
        "max_compensation_m": result.max_compensation_m,
        "max_compensation_rad": result.max_compensation_rad,
        "failed_points": result.failure_count(),
        "failures": failures,
        "log_law": law,
    });
    if refusal.is_none() && !s.formats.is_empty() {
        let programs_dir = dir.path().join("programs");
        std::fs::create_dir_all(&programs_dir).map_err(output_error(&programs_dir))?;
        let description = description(s, &result);
        // The programs need the commanded poses and the joints; the rest of the result is in
        // the table and the summaries: hand it over and free it.
        let checks = programs::write_programs(s, result, description, &programs_dir, json)?;
        for c in &checks {
            written.extend(c.files.iter().map(|f| format!("programs/{f}")));
            program_report.push(c.line());
            program_json.push(c.json());
        }
    } else {
        drop(result);
    }
    written.push("summary.json".into());
    written.push("summary.txt".into());
    let summary_json = json!({
        "robot": s.robot.name,
        "robot_geometry": s.robot.geometry_fingerprint(),
        "path": s.path.name(),
        "points": s.path.len(),
        "path_length_m": s.path.length_m(),
        "part_frame": s.frame_name,
        "part_origin_m": s.part_origin_mm.map(|v| v * 1e-3),
        "seed_q_rad": s.seed,
        "placement": s.placement_source,
        "gcode_notes": s.notes,
        "orientation_compensated": s.options.orientation,
        "tolerance_m": s.options.tolerance_m,
        "tolerance_rad": s.options.tolerance_rad,
        "compensation": numbers,
        "programs": program_json,
        "out": args.out.display().to_string(),
        "files": written,
        "run_on_a_real_controller": false,
        "elapsed_s": elapsed_s,
    });
    let mut text = text_head;
    for line in &program_report {
        let _ = writeln!(text, "  {line}");
    }
    let programs = written
        .iter()
        .filter(|f| f.starts_with("programs/"))
        .count();
    let others: Vec<&str> = written
        .iter()
        .filter(|f| !f.starts_with("programs/"))
        .map(String::as_str)
        .collect();
    // A failed run keeps an earlier result whole (nothing swapped in); where there is none, its
    // table and summaries are written for diagnosis.
    let keep_earlier = refusal.is_some() && std::fs::symlink_metadata(&args.out).is_ok();
    if keep_earlier {
        let _ = writeln!(
            text,
            "  nothing written: {} is kept as it was (a failed run replaces no earlier result)",
            deflex_files::shown_path(&args.out)
        );
    } else {
        let _ = writeln!(
            text,
            "  wrote {}{}; none of the programs has been run on a real controller",
            others.join(", "),
            if programs > 0 {
                format!(" and {programs} program file(s) in programs/")
            } else {
                String::new()
            }
        );
    }
    deflex_files::write_atomic(
        dir.path().join("summary.json"),
        serde_json::to_string_pretty(&summary_json).unwrap_or_default(),
    )
    .map_err(output_error(&args.out))?;
    deflex_files::write_atomic(dir.path().join("summary.txt"), &text)
        .map_err(output_error(&args.out))?;
    if !keep_earlier {
        dir.commit().map_err(output_error(&args.out))?;
    }
    Ok(Summary {
        json: summary_json,
        text,
        refusal,
    })
}

/// The law identified from a log, for the summary text.
fn identification_line(id: &Identification, bounded: usize) -> String {
    if id.sloped_bins == 0 {
        return format!(
            "the logged forces do not follow the depth ({} of {} points in contact): used as they are",
            id.contact_points, id.points
        );
    }
    format!(
        "force-depth law from the log: {} of {} points in contact over {:.2} mm of actual depth, {:.0} … {:.0} N; {}; {} point(s) at the force-ratio bound",
        id.contact_points,
        id.points,
        (id.depth_range_m[1] - id.depth_range_m[0]) * 1e3,
        id.force_range_n[0],
        id.force_range_n[1],
        if id.measured {
            format!(
                "measured TCP used (the model missed up to {:.3} mm)",
                id.max_unmodelled_m * 1e3
            )
        } else {
            "no measured TCP (depths from the model's deflection)".to_string()
        },
        bounded
    )
}

fn identification_json(id: &Identification, bounded: usize) -> serde_json::Value {
    json!({
        "points": id.points,
        "contact_points": id.contact_points,
        "law_bins": id.law_bins,
        "sloped_bins": id.sloped_bins,
        "depth_range_m": id.depth_range_m,
        "force_range_N": id.force_range_n,
        "relative_slope_range_per_m": id.relative_slope_range_per_m,
        "max_axial_force_N": id.max_axial_force_n,
        "measured_tcp": id.measured,
        "max_unmodelled_deflection_m": id.max_unmodelled_m,
        "points_at_force_ratio_bound": bounded,
    })
}

fn iteration_json(result: &Compensation) -> Vec<serde_json::Value> {
    result
        .iterations
        .iter()
        .map(|r| {
            json!({
                "iteration": r.iteration,
                "max_predicted_error_m": r.max_predicted_error_m,
                "max_predicted_error_rad": r.max_predicted_error_rad,
                "max_force_N": r.max_force_n,
                "max_deflection_m": r.max_deflection_m,
                "max_change_m": r.max_change_m,
                "max_change_rad": r.max_change_rad,
                "failed_points": r.failed_points,
                "solved_points": r.solved_points,
            })
        })
        .collect()
}

fn summary_text(
    s: &Setup,
    result: &Compensation,
    source_lines: &[String],
    elapsed_s: f64,
) -> String {
    let mut t = String::new();
    for line in description(s, result).iter().take(3) {
        let _ = writeln!(t, "{line}");
    }
    for line in source_lines {
        let _ = writeln!(t, "  {line}");
    }
    let _ = writeln!(
        t,
        "  iteration   predicted error (mm, mrad)   max force (N)   max change (mm, mrad)   solved   failed"
    );
    for r in &result.iterations {
        let _ = writeln!(
            t,
            "  {:>9}   {:>10.4} {:>10.4}        {:>10.1}      {:>9.5} {:>9.5}   {:>6}   {:>6}",
            r.iteration,
            r.max_predicted_error_m * 1e3,
            r.max_predicted_error_rad * 1e3,
            r.max_force_n,
            r.max_change_m * 1e3,
            r.max_change_rad * 1e3,
            r.solved_points,
            r.failed_points
        );
    }
    let _ = writeln!(
        t,
        "  {} in {} iteration(s) (tolerance {:.4} mm); after compensation the model predicts {:.5} mm, {:.5} mrad of error at {:.0} N",
        if result.converged {
            "converged"
        } else {
            "NOT converged"
        },
        result.iterations.len(),
        s.options.tolerance_m * 1e3,
        result.final_max_error_m * 1e3,
        result.final_max_error_rad * 1e3,
        result.final_max_force_n
    );
    let _ = writeln!(
        t,
        "  largest compensation {:.4} mm, {:.4} mrad; {} point(s) not compensated; {:.2} s",
        result.max_compensation_m * 1e3,
        result.max_compensation_rad * 1e3,
        result.failure_count(),
        elapsed_s
    );
    t
}
