//! `deflex compensate`: offline compensation of a tool path and robot programs, for cells
//! without a real-time option. Parsing, progress and printing only: the compensation is
//! `deflex_compensate`, the process model `deflex_sim::process_model`, the programs
//! `deflex_program`.
//!
//! Outputs in `--out DIR` (written whole, or not at all): `compensated_path.csv`,
//! `summary.json`, `summary.txt` and, when every point is compensated and the iteration
//! converged, `programs/` with one program per `--format`. When points cannot be compensated
//! (limits, reach) or the iteration did not converge, the table and the summaries are still
//! written (the `status` column names each failed point and why), no program is, and the
//! command fails listing the failed points.

use crate::args::{CliResult, parse_fixed, parse_list, print_json, robot};
use clap::Args;
use deflex_compensate::log::{ResampleOptions, read_log, resample_on_path};
use deflex_compensate::table::write_csv;
use deflex_compensate::{
    Compensation, CompensationOptions, Progress, Stage, TcpPath, WrenchSource, compensate,
};
use deflex_program::{Format, ProgramInput, ProgramSettings, export, write_files};
use deflex_sim::{CellConfig, FormingProcess, tcp_path, tool_path_by_name};
use serde_json::json;
use std::fmt::Write as _;
use std::path::{Path, PathBuf};

#[derive(Args)]
pub struct CompensateArgs {
    /// Robot model: a built-in name or a robot TOML (calibrated or nominal).
    #[arg(long)]
    pub robot: String,
    /// Tool path: `cone` (the paper's helical cone), `cone-contour`, `pyramid` or a G-code
    /// file (part frame, mm).
    #[arg(long, default_value = "cone")]
    pub path: String,
    /// Wrench source: `process` (the twin's forming model, SIMULATED) or `log:FILE` (a `deflex
    /// run` log or a `deflex sim isf` log.csv of a previous run of this path).
    #[arg(long, default_value = "process")]
    pub wrench: String,
    /// Part frame origin in the robot's world (mm); default: the twin's [1500, 0, −183].
    #[arg(long)]
    pub part_xyz_mm: Option<String>,
    /// IK seed near the start of the path (deg); the tool keeps the TCP orientation of this
    /// configuration. Default: the twin's forming configuration (6-joint robots).
    #[arg(long)]
    pub seed_deg: Option<String>,
    /// Twin settings (`[cell]` TOML): part placement, seed, sheet of the process model.
    #[arg(long)]
    pub twin: Option<PathBuf>,
    /// Only the first part of the path (mm of travel).
    #[arg(long)]
    pub length_mm: Option<f64>,
    /// Split moves longer than this (mm, 0.001–10000) before compensating: a compensation
    /// moves each waypoint, so a long move into the sheet (a plunge written as one line) is
    /// only compensated at its ends otherwise. Default: the program's moves as they are.
    #[arg(long)]
    pub max_segment_mm: Option<f64>,
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
    /// Programs to write: comma-separated `krl`, `rapid`, `val3`, `urscript`, `gcode`, or
    /// `none`.
    #[arg(long, default_value = "krl,rapid,val3,urscript,gcode")]
    pub format: String,
    /// Program template (TOML, see docs/program.example.toml): frame and tool names, speeds,
    /// zones, limits.
    #[arg(long)]
    pub program_config: Option<PathBuf>,
}

fn formats(text: &str) -> Result<Vec<Format>, String> {
    if text.trim() == "none" {
        return Ok(Vec::new());
    }
    let mut out = Vec::new();
    for name in text.split(',') {
        let format = Format::parse(name).ok_or_else(|| {
            format!(
                "--format: unknown format \"{}\"; expected krl, rapid, val3, urscript, gcode or none",
                name.trim()
            )
        })?;
        if !out.contains(&format) {
            out.push(format);
        }
    }
    Ok(out)
}

/// Everything the run needs, parsed and checked before any work.
struct Setup {
    robot: deflex_model::Robot,
    config: CellConfig,
    tool_path: deflex_sim::ToolPath,
    path: TcpPath,
    seed: Vec<f64>,
    formats: Vec<Format>,
    settings: ProgramSettings,
    options: CompensationOptions,
}

fn setup(args: &CompensateArgs) -> Result<Setup, String> {
    let robot = robot(&args.robot)?;
    let mut config = match &args.twin {
        Some(p) => deflex_load::load_cell(p, None).map_err(|e| e.to_string())?,
        None => CellConfig::default(),
    };
    if let Some(text) = &args.part_xyz_mm {
        let xyz = parse_fixed::<3>(text, "--part-xyz-mm")?;
        if xyz.iter().any(|v| v.abs() > 1e5) {
            return Err(format!("--part-xyz-mm: {xyz:?} is farther than 100 m"));
        }
        config.part.origin_mm = xyz;
    }
    let seed: Vec<f64> = match &args.seed_deg {
        Some(text) => parse_list(text, "--seed-deg")?
            .into_iter()
            .map(f64::to_radians)
            .collect(),
        None if robot.joint_count() == 6 => config.seed_q_rad().to_vec(),
        None => {
            return Err(format!(
                "robot \"{}\" has {} joints: give --seed-deg (a configuration near the start of the path)",
                robot.name,
                robot.joint_count()
            ));
        }
    };
    if seed.len() != robot.joint_count() {
        return Err(format!(
            "--seed-deg: robot \"{}\" has {} joints, {} values given",
            robot.name,
            robot.joint_count(),
            seed.len()
        ));
    }
    let mut tool_path = tool_path_by_name(&args.path).map_err(|e| e.to_string())?;
    match args.length_mm {
        Some(l) if l.is_finite() && l > 0.0 => tool_path = tool_path.truncated(l),
        Some(l) => return Err(format!("--length-mm must be positive, got {l}")),
        None => {}
    }
    if let Some(max) = args.max_segment_mm {
        tool_path = tool_path
            .subdivided(max)
            .map_err(|e| format!("--max-segment-mm: {e}"))?;
    }
    let rotation = robot
        .tcp_pose(&seed)
        .map_err(|e| format!("--seed-deg: {e}"))?
        .rotation;
    let path = tcp_path(
        &tool_path,
        &config.part_frame(),
        &rotation,
        config.controller.rapid_feed_mm_s,
    )
    .map_err(|e| e.to_string())?;
    if !(args.tolerance_um.is_finite() && (0.001..=1000.0).contains(&args.tolerance_um)) {
        return Err(format!(
            "--tolerance-um: expected 0.001 ..= 1000, got {}",
            args.tolerance_um
        ));
    }
    if !(1..=200).contains(&args.max_iterations) {
        return Err(format!(
            "--max-iterations: expected 1 ..= 200, got {}",
            args.max_iterations
        ));
    }
    let settings = match &args.program_config {
        Some(p) => ProgramSettings::load(p).map_err(|e| e.to_string())?,
        None => ProgramSettings::default(),
    };
    Ok(Setup {
        robot,
        config,
        tool_path,
        path,
        seed,
        formats: formats(&args.format)?,
        settings,
        options: CompensationOptions {
            orientation: !args.position_only,
            include_gravity: args.include_gravity,
            tolerance_m: args.tolerance_um * 1e-6,
            tolerance_rad: args.tolerance_um * 1e-6,
            max_iterations: args.max_iterations,
            ..CompensationOptions::default()
        },
    })
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

pub fn compensate_command(args: CompensateArgs, json: bool) -> CliResult {
    let s = setup(&args)?;
    let started = std::time::Instant::now();
    let bar = progress_bar(json, s.path.len());
    let mut on_progress = |p: &Progress| {
        let stage = match p.stage {
            Stage::Desired => "IK of the path".to_string(),
            Stage::Process => format!("iteration {}: process", p.iteration),
            Stage::Compensation => format!("iteration {}: compensation", p.iteration),
            Stage::Final => "final process pass".to_string(),
        };
        bar.set_message(stage);
        bar.set_position(p.done as u64);
    };
    let part = s.config.part_frame();
    let mut source_lines: Vec<String> = Vec::new();
    let result = if let Some(file) = args.wrench.strip_prefix("log:") {
        let log = read_log(Path::new(file), &s.robot, &part).map_err(|e| e.to_string())?;
        let resampled = resample_on_path(&log, &s.path, &ResampleOptions::default())
            .map_err(|e| e.to_string())?;
        source_lines.push(format!(
            "{}{} {file}: {} rows used, {} skipped (flags), {} off the path (max offset {:.2} mm)",
            if log.simulated { "SIMULATED " } else { "" },
            log.kind.name(),
            resampled.used_rows,
            log.skipped_rows,
            resampled.off_path_rows,
            resampled.max_offset_m * 1e3
        ));
        let label = format!(
            "{}{} {file}",
            if log.simulated { "SIMULATED " } else { "" },
            log.kind.name()
        );
        compensate(
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
        )
    } else if args.wrench == "process" {
        let mut process =
            FormingProcess::from_cell(&s.config, &s.tool_path).map_err(|e| e.to_string())?;
        compensate(
            &s.robot,
            &s.path,
            &s.seed,
            WrenchSource::Process(&mut process),
            &s.options,
            &mut on_progress,
        )
    } else {
        return Err(format!(
            "--wrench: expected `process` or `log:FILE`, got \"{}\"",
            args.wrench
        ));
    }
    .map_err(|e| e.to_string())?;
    bar.finish_and_clear();
    let elapsed_s = started.elapsed().as_secs_f64();
    let written = write_outputs(&args, &s, &result, &source_lines, elapsed_s)?;
    let summary = summary_json(&args, &s, &result, &written, elapsed_s);
    if json {
        print_json(&summary);
    } else {
        print!(
            "{}",
            summary_text(&s, &result, &source_lines, &written, elapsed_s)
        );
    }
    refusal(&result, &s)
}

/// The command fails (after writing the table and summaries) when points are not compensated
/// or the iteration did not converge.
fn refusal(result: &Compensation, s: &Setup) -> CliResult {
    let failures: Vec<String> = result
        .failures()
        .take(20)
        .map(|(i, f)| format!("  point {i}: {f}"))
        .collect();
    if !failures.is_empty() {
        let count = result.failure_count();
        return Err(format!(
            "{count} of {} points cannot be compensated (status column of compensated_path.csv); no robot program written:\n{}{}",
            s.path.len(),
            failures.join("\n"),
            if count > 20 {
                format!("\n  … and {} more", count - 20)
            } else {
                String::new()
            }
        ));
    }
    if !result.converged {
        let last = result.iterations.last();
        return Err(format!(
            "the compensation did not converge in {} iterations (last change {:.4} mm, {:.4} mrad, tolerance {:.4} mm); no robot program written",
            result.iterations.len(),
            last.map_or(f64::NAN, |r| r.max_change_m * 1e3),
            last.map_or(f64::NAN, |r| r.max_change_rad * 1e3),
            s.options.tolerance_m * 1e3
        ));
    }
    Ok(())
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

/// Write the output folder whole; returns the relative paths written.
fn write_outputs(
    args: &CompensateArgs,
    s: &Setup,
    result: &Compensation,
    source_lines: &[String],
    elapsed_s: f64,
) -> Result<Vec<String>, String> {
    let out_error = |e: std::io::Error| format!("{}: {e}", args.out.display());
    let dir = deflex_files::AtomicDir::create(&args.out).map_err(out_error)?;
    let mut written = Vec::new();
    let mut comments = description(s, result);
    comments.extend(source_lines.iter().cloned());
    comments.push("SI units; commanded = desired ⊕ compensation (dx_m … drz_rad); world frame of the robot model".into());
    let table = write_csv(&s.path, result, s.robot.joint_count(), &comments);
    deflex_files::write_atomic(dir.path().join("compensated_path.csv"), table)
        .map_err(out_error)?;
    written.push("compensated_path.csv".to_string());
    if result.failure_count() == 0 && result.converged && !s.formats.is_empty() {
        let input = ProgramInput::from_world_poses(
            s.path
                .points()
                .iter()
                .zip(&result.points)
                .map(|(p, c)| (c.commanded(&p.pose), p.feed_m_s)),
            &s.robot.base,
            &s.config.part_frame(),
            s.settings.program.coordinates,
            &s.robot.tool,
            description(s, result),
        );
        let programs = dir.path().join("programs");
        std::fs::create_dir_all(&programs).map_err(out_error)?;
        for format in &s.formats {
            let files = export(*format, &input, &s.settings).map_err(|e| e.to_string())?;
            write_files(&programs, &files).map_err(|e| e.to_string())?;
            written.extend(files.iter().map(|f| format!("programs/{}", f.path)));
        }
    }
    written.push("summary.json".into());
    written.push("summary.txt".into());
    let summary = summary_json(args, s, result, &written, elapsed_s);
    deflex_files::write_atomic(
        dir.path().join("summary.json"),
        serde_json::to_string_pretty(&summary).unwrap_or_default(),
    )
    .map_err(out_error)?;
    deflex_files::write_atomic(
        dir.path().join("summary.txt"),
        summary_text(s, result, source_lines, &written, elapsed_s),
    )
    .map_err(out_error)?;
    dir.commit().map_err(out_error)?;
    Ok(written)
}

fn summary_json(
    args: &CompensateArgs,
    s: &Setup,
    result: &Compensation,
    written: &[String],
    elapsed_s: f64,
) -> serde_json::Value {
    let iterations: Vec<serde_json::Value> = result
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
            })
        })
        .collect();
    let failures: Vec<serde_json::Value> = result
        .failures()
        .take(1000)
        .map(|(i, f)| json!({"index": i, "status": f.code(), "reason": f.to_string()}))
        .collect();
    json!({
        "simulated": result.simulated,
        "robot": s.robot.name,
        "robot_geometry": s.robot.geometry_fingerprint(),
        "path": s.path.name(),
        "points": s.path.len(),
        "path_length_m": s.path.length_m(),
        "wrench_source": result.source,
        "orientation_compensated": s.options.orientation,
        "tolerance_m": s.options.tolerance_m,
        "tolerance_rad": s.options.tolerance_rad,
        "converged": result.converged,
        "iterations": iterations,
        "final_max_predicted_error_m": result.final_max_error_m,
        "final_max_predicted_error_rad": result.final_max_error_rad,
        "final_max_force_N": result.final_max_force_n,
        "max_compensation_m": result.max_compensation_m,
        "max_compensation_rad": result.max_compensation_rad,
        "failed_points": result.failure_count(),
        "failures": failures,
        "out": args.out.display().to_string(),
        "files": written,
        "run_on_a_real_controller": false,
        "elapsed_s": elapsed_s,
    })
}

fn summary_text(
    s: &Setup,
    result: &Compensation,
    source_lines: &[String],
    written: &[String],
    elapsed_s: f64,
) -> String {
    let mut t = String::new();
    for line in description(s, result).iter().take(2) {
        let _ = writeln!(t, "{line}");
    }
    for line in source_lines {
        let _ = writeln!(t, "  {line}");
    }
    let _ = writeln!(
        t,
        "  iteration   predicted error (mm, mrad)   max force (N)   max change (mm, mrad)   failed"
    );
    for r in &result.iterations {
        let _ = writeln!(
            t,
            "  {:>9}   {:>10.4} {:>10.4}        {:>10.1}      {:>9.5} {:>9.5}   {:>6}",
            r.iteration,
            r.max_predicted_error_m * 1e3,
            r.max_predicted_error_rad * 1e3,
            r.max_force_n,
            r.max_change_m * 1e3,
            r.max_change_rad * 1e3,
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
    let _ = writeln!(
        t,
        "  wrote {}; none of the programs has been run on a real controller",
        written.join(", ")
    );
    t
}

#[cfg(test)]
mod tests {
    use super::*;
    use deflex_compensate::table::read_csv;

    fn scratch(name: &str) -> PathBuf {
        let dir =
            std::env::temp_dir().join(format!("deflex-compensate-{name}-{}", std::process::id()));
        let _ = std::fs::remove_dir_all(&dir);
        std::fs::create_dir_all(&dir).unwrap();
        dir
    }

    fn args(out: &Path) -> CompensateArgs {
        CompensateArgs {
            robot: "tx200".into(),
            path: "cone".into(),
            wrench: "process".into(),
            part_xyz_mm: None,
            seed_deg: None,
            twin: None,
            length_mm: Some(400.0),
            max_segment_mm: None,
            position_only: false,
            include_gravity: false,
            tolerance_um: 1.0,
            max_iterations: 30,
            out: out.to_path_buf(),
            format: "krl,rapid,val3,urscript,gcode".into(),
            program_config: None,
        }
    }

    #[test]
    fn the_command_writes_the_table_summaries_and_programs_that_read_back() {
        let dir = scratch("ok");
        let out = dir.join("out");
        compensate_command(args(&out), true).unwrap();
        let table = std::fs::read_to_string(out.join("compensated_path.csv")).unwrap();
        assert!(table.starts_with("# SIMULATED"));
        let rows = read_csv(&table, "compensated_path.csv").unwrap();
        assert!(rows.iter().all(|r| r.status == "ok"));
        let summary: serde_json::Value =
            serde_json::from_str(&std::fs::read_to_string(out.join("summary.json")).unwrap())
                .unwrap();
        assert_eq!(summary["simulated"], true);
        assert_eq!(summary["converged"], true);
        assert_eq!(summary["run_on_a_real_controller"], false);
        assert!(summary["final_max_predicted_error_m"].as_f64().unwrap() < 1e-6);
        assert!(
            summary["iterations"][0]["max_predicted_error_m"]
                .as_f64()
                .unwrap()
                > 1e-4
        );
        // Commanded positions in the part frame (mm), from the table.
        let part = CellConfig::default().part_frame();
        let commanded: Vec<Vector3> = rows
            .iter()
            .map(|r| {
                let c = deflex_compensate::commanded_pose(&r.desired, &r.compensation);
                (part.inverse() * nalgebra::Point3::from(c.translation.vector)).coords
            })
            .collect();
        // The twin's own G-code reader reads the program back (after its start at the origin).
        let gcode = deflex_sim::gcode::read_gcode(&out.join("programs/deflex_path.gcode")).unwrap();
        assert_eq!(gcode.waypoints.len(), rows.len() + 1);
        for (w, c) in gcode.waypoints[1..].iter().zip(&commanded) {
            let d = (Vector3::from(w.p_mm) * 1e-3 - c).norm();
            assert!(d < 1e-6, "{d}");
        }
        // Every vendor program reads back to the commanded poses within 1 µm and 1 µrad.
        for (format, file) in [
            (Format::Krl, "programs/deflex_path.src"),
            (Format::Rapid, "programs/deflex_path.mod"),
            (Format::Val3, "programs/deflex_path/deflex_path.dtx"),
            (Format::UrScript, "programs/deflex_path.script"),
        ] {
            let text = std::fs::read_to_string(out.join(file)).unwrap();
            let files = [deflex_program::ProgramFile {
                path: file.into(),
                contents: text,
            }];
            let read = deflex_program::readback::read_files(format, &files).unwrap();
            assert_eq!(read.len(), rows.len(), "{format:?}");
            for ((p, c), row) in read.iter().zip(&commanded).zip(&rows) {
                assert!((p.position_m - c).norm() < 1e-6, "{format:?}");
                let want = deflex_compensate::commanded_pose(&row.desired, &row.compensation);
                let got = p.rotation.unwrap();
                let angle = deflex_program::orientation::rotation_distance(&want.rotation, &got);
                assert!(angle < 2e-6, "{format:?}: {angle}");
            }
        }
        std::fs::remove_dir_all(dir).unwrap();
    }

    type Vector3 = nalgebra::Vector3<f64>;

    #[test]
    fn uncompensable_points_fail_the_command_with_their_indices_and_no_program() {
        let dir = scratch("limits");
        // The TX200 with joint 3 stopped just beyond the desired path's values: the compensated
        // poses need more.
        let mut robot = deflex_model::builtin("tx200").unwrap();
        let path = tool_path_by_name("cone").unwrap().truncated(60.0);
        let config = CellConfig::default();
        let seed = config.seed_q_rad();
        let rotation = robot.tcp_pose(&seed).unwrap().rotation;
        let tcp = tcp_path(&path, &config.part_frame(), &rotation, 50.0).unwrap();
        let mut q = seed.to_vec();
        let mut range = [f64::MAX, f64::MIN];
        for p in tcp.points() {
            q = robot
                .inverse_kinematics(&p.pose, &q, &Default::default())
                .unwrap()
                .q;
            range = [range[0].min(q[2]), range[1].max(q[2])];
        }
        robot.joints[2].limits = Some([range[0] - 1e-6, range[1] + 1e-6]);
        let robot_file = dir.join("tight.toml");
        std::fs::write(&robot_file, deflex_model::robot_to_toml(&robot)).unwrap();
        let out = dir.join("out");
        let mut a = args(&out);
        a.robot = robot_file.display().to_string();
        a.length_mm = Some(60.0);
        let e = compensate_command(a, true).unwrap_err();
        assert!(e.contains("cannot be compensated"), "{e}");
        assert!(e.contains("joint 3"), "{e}");
        let rows = read_csv(
            &std::fs::read_to_string(out.join("compensated_path.csv")).unwrap(),
            "t",
        )
        .unwrap();
        let failed: Vec<usize> = rows
            .iter()
            .enumerate()
            .filter(|(_, r)| r.status != "ok")
            .map(|(i, _)| i)
            .collect();
        assert!(!failed.is_empty());
        for i in &failed {
            assert_eq!(rows[*i].status, "compensated:joint_limit:J3");
            assert!(e.contains(&format!("point {i}:")), "{e}");
        }
        assert!(
            !out.join("programs").exists(),
            "no program with failed points"
        );
        std::fs::remove_dir_all(dir).unwrap();
    }

    #[test]
    fn a_deflex_run_log_serves_as_the_wrench_source() {
        use deflex_control::log::{LogRecord, csv_header, csv_row};
        use deflex_control::{CycleOutput, Flags};
        // The skipped flag bits are deflex-control's.
        assert_eq!(
            deflex_compensate::log::RUN_LOG_SKIP_FLAGS,
            Flags::FORCE_OVER_LIMIT
                | Flags::TORQUE_OVER_LIMIT
                | Flags::SENSOR_TIMEOUT
                | Flags::SENSOR_STATUS
                | Flags::ROBOT_LINK_LOST
                | Flags::NON_FINITE
                | Flags::SENSOR_OVER_RANGE
                | Flags::JOINT_OUT_OF_LIMITS
                | Flags::JOINT_JUMP
                | Flags::JOINT_COUNT_MISMATCH
                | Flags::CONTACT_RUNAWAY
                | Flags::LATCHED
                | Flags::TARING
                | Flags::STALE_WRENCH
        );
        let dir = scratch("runlog");
        let robot = deflex_model::builtin("tx200").unwrap();
        let config = CellConfig::default();
        let path = tool_path_by_name("cone").unwrap().truncated(40.0);
        let seed = config.seed_q_rad();
        let rotation = robot.tcp_pose(&seed).unwrap().rotation;
        let tcp = tcp_path(&path, &config.part_frame(), &rotation, 50.0).unwrap();
        // A log written by deflex-control's own writer functions: 0.1 mm steps, a constant
        // 900 N push up, taring rows with nonsense at the start.
        let mut text = csv_header(6);
        text.push('\n');
        let mut q = seed.to_vec();
        let steps = (tcp.length_m() / 1e-4) as usize;
        for k in 0..=steps + 5 {
            let s = (k as f64 * 1e-4).min(tcp.length_m());
            let (i, f) = tcp.locate(s);
            let a = tcp.points()[i].pose;
            let b = tcp.points()[i + 1].pose;
            let p = a.translation.vector + (b.translation.vector - a.translation.vector) * f;
            let target = deflex_model::Pose::from_parts(p.into(), a.rotation);
            q = robot
                .inverse_kinematics(&target, &q, &Default::default())
                .unwrap()
                .q;
            let taring = k < 5;
            let out = CycleOutput {
                time_s: k as f64 * 0.01,
                wrench_tcp: if taring {
                    [0.0, 0.0, 1e5, 0.0, 0.0, 0.0]
                } else {
                    [0.0, 0.0, 900.0, 0.0, 0.0, 0.0]
                },
                flags: Flags(if taring { Flags::TARING } else { Flags::ACTIVE }),
                ..CycleOutput::default()
            };
            text.push_str(&csv_row(&LogRecord::new(&q, &[0.0; 6], &out, 10.0)));
            text.push('\n');
        }
        let log_file = dir.join("run.csv");
        std::fs::write(&log_file, text).unwrap();
        let out = dir.join("out");
        let mut a = args(&out);
        a.length_mm = Some(40.0);
        a.wrench = format!("log:{}", log_file.display());
        a.format = "gcode".into();
        compensate_command(a, true).unwrap();
        let rows = read_csv(
            &std::fs::read_to_string(out.join("compensated_path.csv")).unwrap(),
            "t",
        )
        .unwrap();
        for r in &rows {
            assert!((r.wrench[2] - 900.0).abs() < 1e-6, "{}", r.wrench[2]);
        }
        let summary: serde_json::Value =
            serde_json::from_str(&std::fs::read_to_string(out.join("summary.json")).unwrap())
                .unwrap();
        assert_eq!(
            summary["simulated"], false,
            "a deflex run log is a measurement"
        );
        assert_eq!(summary["iterations"].as_array().unwrap().len(), 1);
        std::fs::remove_dir_all(dir).unwrap();
    }

    #[test]
    fn bad_options_are_refused_before_any_work() {
        let dir = scratch("bad");
        let out = dir.join("out");
        for (change, expected) in [
            (
                Box::new(|a: &mut CompensateArgs| a.format = "krl,fanuc".into())
                    as Box<dyn Fn(&mut CompensateArgs)>,
                "unknown format \"fanuc\"",
            ),
            (Box::new(|a| a.wrench = "sensor".into()), "--wrench"),
            (Box::new(|a| a.tolerance_um = 0.0), "--tolerance-um"),
            (Box::new(|a| a.max_iterations = 0), "--max-iterations"),
            (
                Box::new(|a| a.seed_deg = Some("0,1,2".into())),
                "3 values given",
            ),
            (
                Box::new(|a| a.part_xyz_mm = Some("1,2".into())),
                "--part-xyz-mm",
            ),
            (Box::new(|a| a.length_mm = Some(-1.0)), "--length-mm"),
            (
                Box::new(|a| a.path = "/nonexistent/part.gcode".into()),
                "/nonexistent/part.gcode",
            ),
        ] {
            let mut a = args(&out);
            change(&mut a);
            let e = compensate_command(a, true).unwrap_err();
            assert!(e.contains(expected), "{e}");
        }
        assert!(!out.exists());
        std::fs::remove_dir_all(dir).unwrap();
    }
}
