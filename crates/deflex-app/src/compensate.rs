//! Offline compensation of a tool path (`deflex compensate`) and the five robot program
//! formats, with the CLI's checks, refusals and messages.
//!
//! Thin layer over `deflex-compensate`, `deflex-program` and the twin's paths, cell and process
//! model in `deflex-sim` (re-pointed at merge time): [`tool_path`], [`compensate`],
//! [`table_csv`], [`programs`], [`write_programs`].

use crate::error::{Error, Result, bounded};
use crate::load::gcode_file::tool_path_by_name;
use crate::load::parse_wrench_log;
use crate::load::wrench_log::MAX_LOG_BYTES;
use deflex_cam::program::{Format, ProgramFile, ProgramInput, ProgramSettings, export};
use deflex_compensate::log::{ResampleOptions, resample_on_path};
use deflex_compensate::table::write_csv;
use deflex_compensate::{Compensation, CompensationOptions, TcpPath, WrenchSource};
use deflex_model::{Pose, Robot, ToolLoad, Wrench};
use deflex_sim::{CellConfig, FormingProcess, ToolPath, Waypoint, tcp_path};
use nalgebra::{Rotation3, Translation3, Vector3};
use std::path::{Path, PathBuf};

/// The frame an array path is written in.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Frame {
    /// The part frame (G-code's), placed in the world at the cell's part origin.
    Part,
    /// The robot model's world frame.
    World,
}

/// The path to compensate.
#[derive(Clone, Debug)]
pub enum PathSpec {
    /// `cone`, `cone-contour`, `pyramid` or a G-code file (part frame, mm).
    Named(String),
    /// TCP positions (`rows × 3`, m) or poses (`rows × 6`: position m and rotation vector rad),
    /// in `frame`; positions alone keep the tool orientation of the seed configuration.
    Array {
        /// Row-major values.
        values: Vec<f64>,
        /// 3 or 6.
        cols: usize,
        /// Frame of the values.
        frame: Frame,
        /// Feed of every move (m/s); `None` moves are rapids.
        feed_m_s: Option<f64>,
    },
}

/// Where the wrench at each point comes from.
#[derive(Clone, Debug)]
pub enum WrenchSpec {
    /// The twin's forming model (SIMULATED), evaluated at each iteration's commanded path.
    Process,
    /// A `deflex run` log or a `deflex sim isf` log of a previous run of this path.
    Log(PathBuf),
    /// One wrench for every point (`6` values) or one per point (`points × 6`), world axes at
    /// the TCP (N, N·m).
    Array(Vec<f64>),
}

/// Options (the CLI's flags, SI).
#[derive(Clone, Debug)]
pub struct Options {
    /// Twin settings (`[cell]` TOML) for the part placement, seed and sheet.
    pub twin_config: Option<PathBuf>,
    /// Part frame origin in the world (m); default the cell's.
    pub part_xyz_m: Option<[f64; 3]>,
    /// IK seed near the start (rad); default the cell's forming configuration (6 joints).
    pub seed_q: Option<Vec<f64>>,
    /// Only the first part of the path (m of travel).
    pub length_m: Option<f64>,
    /// Split longer moves (m).
    pub max_segment_m: Option<f64>,
    /// Compensate the position only.
    pub position_only: bool,
    /// Add the deflection under the robot's own weight.
    pub include_gravity: bool,
    /// Convergence tolerance (m; the same number in rad for the orientation).
    pub tolerance_m: f64,
    /// Most iterations (1 ..= 200).
    pub max_iterations: usize,
}

/// A finished compensation with what the table and the programs need.
pub struct CompensationRun {
    /// The robot model.
    pub robot: Robot,
    /// The cell (part frame, program settings' frames).
    pub part_frame: Pose,
    /// The desired path.
    pub path: TcpPath,
    /// The tool's load declared in the programs (RAPID's tooldata), centre of mass in the
    /// flange frame: the cell's nominal tool, as the CLI's.
    pub tool_load_in_flange: ToolLoad,
    /// The result.
    pub result: Compensation,
    /// Lines on the wrench source (log rows used, …).
    pub source_lines: Vec<String>,
    /// Tolerance used (m).
    pub tolerance_m: f64,
    /// Wall time (s).
    pub elapsed_s: f64,
}

/// The robot's cell, as the CLI's: the twin file over it, else the cell of the robot (its maker's
/// cell, from its name); a robot with no cell (not six joints) needs `part_xyz_m` and `seed_q`
/// and wrenches that are not the process model's.
fn cell(robot: &Robot, wrench: &WrenchSpec, options: &Options) -> Result<CellConfig> {
    let mut config = match &options.twin_config {
        Some(p) => crate::cell::twin_cell_file::load_cell(p, None)?,
        None => match CellConfig::for_robot_description(&robot.name, robot.clone()) {
            Ok(c) => c,
            Err(_)
                if options.part_xyz_m.is_some()
                    && options.seed_q.is_some()
                    && !matches!(wrench, WrenchSpec::Process) =>
            {
                CellConfig::default()
            }
            Err(e) => return Err(e.into()),
        },
    };
    if let Some(xyz) = options.part_xyz_m {
        if xyz.iter().any(|v| !v.is_finite() || v.abs() > 100.0) {
            return Err(Error::invalid(
                "part_xyz_m",
                format!("{xyz:?} is farther than 100 m"),
            ));
        }
        config.part.origin_mm = xyz.map(|v| v * 1e3);
    }
    Ok(config)
}

/// The tool path (part frame, mm) of a spec: a named path, a G-code file or the array's
/// positions mapped into the part frame.
pub fn tool_path(spec: &PathSpec, part_frame: &Pose) -> Result<ToolPath> {
    match spec {
        PathSpec::Named(name) => Ok(tool_path_by_name(name)?),
        PathSpec::Array {
            values,
            cols,
            frame,
            feed_m_s,
        } => {
            let to_part = match frame {
                Frame::Part => Pose::identity(),
                Frame::World => part_frame.inverse(),
            };
            let waypoints = values
                .chunks(*cols)
                .enumerate()
                .map(|(i, r)| {
                    let p = to_part * nalgebra::Point3::new(r[0], r[1], r[2]) * 1e3;
                    Waypoint {
                        p_mm: [p.x, p.y, p.z],
                        feed_mm_s: if i == 0 {
                            None
                        } else {
                            feed_m_s.map(|f| f * 1e3)
                        },
                    }
                })
                .collect();
            Ok(ToolPath {
                name: "array path".into(),
                waypoints,
                step_down_mm: None,
                wall_angle_deg: None,
            })
        }
    }
}

/// The TCP path: a `(rows × 6)` array keeps its orientations, anything else the seed's tool
/// orientation.
fn tcp(
    spec: &PathSpec,
    tool_path: &ToolPath,
    part_frame: &Pose,
    rotation: &Rotation3<f64>,
    rapid_feed_mm_s: f64,
) -> Result<TcpPath> {
    if let PathSpec::Array {
        values,
        cols: 6,
        frame,
        feed_m_s,
    } = spec
    {
        let to_world = match frame {
            Frame::Part => *part_frame,
            Frame::World => Pose::identity(),
        };
        let poses = values.chunks(6).enumerate().map(|(i, r)| {
            let local = Pose::from_parts(
                Translation3::new(r[0], r[1], r[2]),
                Rotation3::from_scaled_axis(Vector3::new(r[3], r[4], r[5])),
            );
            (to_world * local, if i == 0 { None } else { *feed_m_s })
        });
        return Ok(TcpPath::new("array path", poses, rapid_feed_mm_s * 1e-3)?);
    }
    Ok(tcp_path(tool_path, part_frame, rotation, rapid_feed_mm_s)?)
}

/// The IK seed: the option, else the cell's forming configuration for a 6-joint robot.
fn seed(robot: &Robot, options: &Options, config: &CellConfig) -> Result<Vec<f64>> {
    let n = robot.joint_count();
    let seed: Vec<f64> = match &options.seed_q {
        Some(s) => s.clone(),
        None if n == 6 => config.seed_q_rad().to_vec(),
        None => {
            return Err(Error::invalid(
                "seed_q",
                format!(
                    "robot \"{}\" has {n} joints: give seed_q (a configuration near the start of the path)",
                    robot.name
                ),
            ));
        }
    };
    if seed.len() != n {
        return Err(Error::invalid(
            "seed_q",
            format!(
                "robot \"{}\" has {n} joints, {} values given",
                robot.name,
                seed.len()
            ),
        ));
    }
    Ok(seed)
}

/// The desired TCP path: the spec's tool path, cut to `length_m`, its moves split to
/// `max_segment_m`, in the world with the seed's tool orientation (or the array's).
fn desired_path(
    robot: &Robot,
    spec: &PathSpec,
    options: &Options,
    config: &CellConfig,
    seed: &[f64],
) -> Result<(ToolPath, TcpPath)> {
    let part_frame = config.part_frame();
    let mut tool_path = tool_path(spec, &part_frame)?;
    let array_poses = matches!(spec, PathSpec::Array { cols: 6, .. });
    if array_poses && (options.length_m.is_some() || options.max_segment_m.is_some()) {
        return Err(Error::invalid(
            "length_m",
            "length_m and max_segment_m apply to paths of positions; an (N, 6) path of poses is compensated as given",
        ));
    }
    if let Some(l) = options.length_m {
        tool_path = tool_path.truncated(bounded("length_m", l, 1e-6, 1e3, "m")? * 1e3);
    }
    if let Some(max) = options.max_segment_m {
        let max = bounded("max_segment_m", max, 1e-6, 10.0, "m")?;
        tool_path = tool_path
            .subdivided(max * 1e3)
            .map_err(|e| Error::invalid("max_segment_m", e.to_string()))?;
    }
    let rotation = robot
        .tcp_pose(seed)
        .map_err(|e| Error::invalid("seed_q", e.to_string()))?
        .rotation;
    let path = tcp(
        spec,
        &tool_path,
        &part_frame,
        &rotation,
        config.controller.rapid_feed_mm_s,
    )?;
    Ok((tool_path, path))
}

/// The iteration's settings, checked as the CLI checks its flags.
fn compensation_options(options: &Options) -> Result<CompensationOptions> {
    bounded("tolerance_m", options.tolerance_m, 1e-9, 1e-3, "m")?;
    if !(1..=200).contains(&options.max_iterations) {
        return Err(Error::invalid(
            "max_iterations",
            format!("expected 1 ..= 200, got {}", options.max_iterations),
        ));
    }
    Ok(CompensationOptions {
        orientation: !options.position_only,
        include_gravity: options.include_gravity,
        tolerance_m: options.tolerance_m,
        tolerance_rad: options.tolerance_m,
        max_iterations: options.max_iterations,
        ..CompensationOptions::default()
    })
}

/// `deflex compensate`: the CLI's checks, then the compensation against the process model, a
/// log's forces or given wrenches.
pub fn compensate(
    robot: &Robot,
    path_spec: &PathSpec,
    wrench: &WrenchSpec,
    options: &Options,
) -> Result<CompensationRun> {
    let config = cell(robot, wrench, options)?;
    let seed = seed(robot, options, &config)?;
    let part_frame = config.part_frame();
    let (tool_path, path) = desired_path(robot, path_spec, options, &config, &seed)?;
    let compensation_options = compensation_options(options)?;
    let started = std::time::Instant::now();
    let mut source_lines = Vec::new();
    let run = |source: WrenchSource| {
        deflex_compensate::compensate(
            robot,
            &path,
            &seed,
            source,
            &compensation_options,
            &mut |_| {},
        )
    };
    let result = match wrench {
        WrenchSpec::Process => {
            let mut process = FormingProcess::from_cell(&config, &tool_path)?;
            run(WrenchSource::Process(&mut process))?
        }
        WrenchSpec::Log(file) => {
            // The file is read here (bounded), the application layer reads its rows.
            let text = crate::calibrate_geometry::read_text(file, MAX_LOG_BYTES)?;
            let log = parse_wrench_log(&text, &file.display().to_string(), robot, &part_frame)?;
            let resampled = resample_on_path(&log, &path, &ResampleOptions::default())?;
            let shown = file.display();
            let simulated = if log.simulated { "SIMULATED " } else { "" };
            source_lines.push(format!(
                "{simulated}{} {shown}: {} rows used, {} skipped (flags), {} off the path (max offset {:.2} mm)",
                log.kind.name(),
                resampled.used_rows,
                log.skipped_rows,
                resampled.off_path_rows,
                resampled.max_offset_m * 1e3
            ));
            run(WrenchSource::Fixed {
                label: format!("{simulated}{} {shown}", log.kind.name()),
                simulated: log.simulated,
                wrenches: &resampled.wrenches,
            })?
        }
        WrenchSpec::Array(values) => {
            let wrenches = given_wrenches(values, path.len())?;
            run(WrenchSource::Fixed {
                label: "wrenches given from Python".into(),
                simulated: false,
                wrenches: &wrenches,
            })?
        }
    };
    Ok(CompensationRun {
        robot: robot.clone(),
        part_frame,
        path,
        tool_load_in_flange: cell_tool_load(&config),
        result,
        source_lines,
        tolerance_m: options.tolerance_m,
        elapsed_s: started.elapsed().as_secs_f64(),
    })
}

/// One wrench for every point (6 values) or one per point.
fn given_wrenches(values: &[f64], points: usize) -> Result<Vec<Wrench>> {
    if values.len() == 6 {
        Ok(vec![Wrench::from_row_slice(values); points])
    } else if values.len() == 6 * points {
        Ok(values.chunks(6).map(Wrench::from_row_slice).collect())
    } else {
        Err(Error::invalid(
            "wrench",
            format!(
                "{} wrenches for the {points} points of the path: give one (shape (6,)) or one per point (shape ({points}, 6))",
                values.len() / 6,
            ),
        ))
    }
}

/// The CLI's header lines of the table and the programs.
pub fn description(run: &CompensationRun) -> Vec<String> {
    let r = &run.result;
    let simulated = if r.simulated { "SIMULATED " } else { "" };
    vec![
        format!(
            "{simulated}deflex offline compensation of \"{}\" ({} points, {:.1} mm)",
            run.path.name(),
            run.path.len(),
            run.path.length_m() * 1e3
        ),
        format!(
            "robot model \"{}\", geometry {}; wrenches: {}",
            run.robot.name,
            run.robot.geometry_fingerprint(),
            r.source
        ),
        format!(
            "predicted error {:.4} mm uncompensated, {:.4} mm compensated; largest compensation {:.4} mm, {:.4} mrad",
            r.iterations
                .first()
                .map_or(0.0, |i| i.max_predicted_error_m * 1e3),
            r.final_max_error_m * 1e3,
            r.max_compensation_m * 1e3,
            r.max_compensation_rad * 1e3
        ),
    ]
}

/// The compensation's summary as the CLI's `summary.json` (SI).
pub fn summary_json(run: &CompensationRun) -> serde_json::Value {
    use serde_json::json;
    let r = &run.result;
    json!({
        "simulated": r.simulated,
        "robot": run.robot.name,
        "robot_geometry": run.robot.geometry_fingerprint(),
        "path": run.path.name(),
        "points": run.path.len(),
        "path_length_m": run.path.length_m(),
        "wrench_source": r.source,
        "source_lines": run.source_lines,
        "tolerance_m": run.tolerance_m,
        "converged": r.converged,
        "iterations": r.iterations.iter().map(|i| json!({
            "iteration": i.iteration, "max_predicted_error_m": i.max_predicted_error_m,
            "max_predicted_error_rad": i.max_predicted_error_rad, "max_force_N": i.max_force_n,
            "max_deflection_m": i.max_deflection_m, "max_change_m": i.max_change_m,
            "max_change_rad": i.max_change_rad, "failed_points": i.failed_points})).collect::<Vec<_>>(),
        "final_max_predicted_error_m": r.final_max_error_m,
        "final_max_predicted_error_rad": r.final_max_error_rad,
        "final_max_force_N": r.final_max_force_n,
        "max_compensation_m": r.max_compensation_m,
        "max_compensation_rad": r.max_compensation_rad,
        "failed_points": r.failure_count(),
        "failures": r.failures().take(1000).map(|(i, f)| json!({"index": i, "status": f.code(), "reason": f.to_string()})).collect::<Vec<_>>(),
        "elapsed_s": run.elapsed_s,
        "run_on_a_real_controller": false,
    })
}

/// Per point `ok` or the code of the reason it was not compensated.
pub fn statuses(run: &CompensationRun) -> Vec<String> {
    run.result
        .points
        .iter()
        .map(|p| p.failure.map_or_else(|| "ok".to_string(), |f| f.code()))
        .collect()
}

/// `compensated_path.csv` as the CLI writes it.
pub fn table_csv(run: &CompensationRun) -> String {
    let mut comments = description(run);
    comments.extend(run.source_lines.iter().cloned());
    comments.push("SI units; commanded = desired ⊕ compensation (dx_m … drz_rad); world frame of the robot model".into());
    write_csv(&run.path, &run.result, run.robot.joint_count(), &comments)
}

/// The CLI's refusal: no program when points are not compensated or the iteration did not
/// converge.
pub fn refusal(run: &CompensationRun) -> Result<()> {
    let r = &run.result;
    let failures: Vec<String> = r
        .failures()
        .take(20)
        .map(|(i, f)| format!("  point {i}: {f}"))
        .collect();
    if !failures.is_empty() {
        let count = r.failure_count();
        return Err(Error::NotCompensated {
            message: format!(
                "{count} of {} points cannot be compensated (status column of the table); no robot program written:\n{}{}",
                run.path.len(),
                failures.join("\n"),
                if count > 20 {
                    format!("\n  … and {} more", count - 20)
                } else {
                    String::new()
                }
            ),
        });
    }
    if !r.converged {
        let last = r.iterations.last();
        return Err(Error::NotCompensated {
            message: format!(
                "the compensation did not converge in {} iterations (last change {:.4} mm, {:.4} mrad, tolerance {:.4} mm); no robot program written",
                r.iterations.len(),
                last.map_or(f64::NAN, |i| i.max_change_m * 1e3),
                last.map_or(f64::NAN, |i| i.max_change_rad * 1e3),
                run.tolerance_m * 1e3
            ),
        });
    }
    Ok(())
}

/// A program format by name (`krl`, `rapid`, `val3`, `urscript`, `gcode`).
pub fn format(name: &str) -> Result<Format> {
    Format::parse(name).ok_or_else(|| {
        Error::invalid(
            "formats",
            format!(
                "unknown format \"{}\"; expected krl, rapid, val3, urscript or gcode",
                name.trim()
            ),
        )
    })
}

/// Where the programs' tool load comes from, for their headers (as the CLI's).
const CELL_TOOL_LOAD_SOURCE: &str = "the robot's twin cell";

/// The cell's nominal tool load in the flange frame (the sensor's tool mass and centre of mass,
/// sensor frame → flange), as the CLI's `deflex compensate` declares it.
fn cell_tool_load(config: &CellConfig) -> ToolLoad {
    let com = config.sensor_in_flange()
        * nalgebra::Point3::from(nalgebra::Vector3::from(config.tool_com_in_sensor_m()));
    ToolLoad {
        mass_kg: config.tool_mass_kg(),
        centre_of_mass_m: com.coords,
    }
}

/// Program settings from a TOML file (`--program-config`), or the defaults.
pub fn settings(path: Option<&Path>) -> Result<ProgramSettings> {
    Ok(match path {
        Some(p) => ProgramSettings::load(p)?,
        None => ProgramSettings::default(),
    })
}

/// The programs of a compensation in `format` (after the CLI's refusal checks).
pub fn programs(
    run: &CompensationRun,
    format: Format,
    settings: &ProgramSettings,
) -> Result<Vec<ProgramFile>> {
    refusal(run)?;
    let mut input = ProgramInput::from_world_poses(
        run.path
            .points()
            .iter()
            .zip(&run.result.points)
            .map(|(p, c)| (c.commanded(&p.pose), p.feed_m_s)),
        &run.robot.base,
        &run.part_frame,
        settings.program.coordinates,
        &run.robot.tool,
        description(run),
    );
    input.tool_load_in_flange = Some(run.tool_load_in_flange);
    input.tool_load_source = CELL_TOOL_LOAD_SOURCE.into();
    Ok(export(format, &input, settings)?)
}

/// Write program files under `dir` (created), each whole.
pub fn write_programs(dir: &Path, files: &[ProgramFile]) -> Result<Vec<PathBuf>> {
    std::fs::create_dir_all(dir).map_err(|source| Error::Io {
        path: dir.display().to_string(),
        source,
    })?;
    deflex_cam::program::write_files(dir, files)?;
    Ok(files.iter().map(|f| dir.join(&f.path)).collect())
}
