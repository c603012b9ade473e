//! `deflex cell --sim`: the digital twin served on loopback over the protocols of a real cell
//! (the work is `deflex_sim::twin::cell_server`, its endpoints from the runtime's link factory). It
//! reads the same `CELL.toml` as `deflex run`. The twin plays any robot (`--robot`: a built-in
//! name or a robot file; default the twin file's, else the paper's TX200) with that robot's cell
//! (`deflex_sim::CellConfig::for_robot`), and names it in every output.

use crate::args::{check_flag, print_json};
use crate::cmd_control::{load_cell_file, stats_json};
use crate::error::{CliError, CommandResult, UsageError};
use clap::Args;
use deflex_app::cell::config::CellFile;
use deflex_record::{McapRecorder, RecordReport};
use deflex_sim::twin::cell_server::{
    CellEnd, CellEvent, CellOutcome, ServeOptions, serve_cell_with,
};
use deflex_sim::twin::{TwinCellStream, twin_cell_session_info};
use deflex_sim::{CellConfig, ConeParams, ToolPath};
use deflex_telemetry::{CycleSample, Source, broadcast};
use deflex_view::ViewStats;
use serde_json::json;
use std::path::PathBuf;
use std::sync::Arc;
use std::sync::atomic::AtomicBool;

#[derive(Args, Clone, Debug)]
pub struct CellArgs {
    /// Serve the simulated cell (the digital twin); the only cell there is.
    #[arg(long)]
    pub sim: bool,
    /// The same CELL.toml as `deflex run`: robot.bind is where the robot's telegrams go (any
    /// robot.kind), sensor.address is where the simulated Net F/T answers. Both must be
    /// loopback addresses.
    #[arg(long)]
    pub config: PathBuf,
    /// Twin settings (`[cell]` TOML of `deflex sim`) over the robot's cell; default: the robot's
    /// cell.
    #[arg(long)]
    pub twin: Option<PathBuf>,
    /// The robot the twin plays: a built-in name (`tx200`, `ur10e`, …) or a robot file. Wins over
    /// the twin file's `[cell.part] robot`. Default: the twin file's, else `tx200`. The CELL.toml
    /// model must have the same number of joints.
    #[arg(long)]
    pub robot: Option<String>,
    /// Tool path: `cone` (the paper's cone, as `deflex sim isf`) or `helical`.
    #[arg(long, default_value = "cone")]
    pub path: String,
    /// Only the first part of the path (0 < mm ≤ 10⁶).
    #[arg(long)]
    pub length_mm: Option<f64>,
    /// Time scale: cycles run N times faster than the robot's cycle in wall time (0 < N ≤ 100).
    #[arg(long, default_value_t = 1.0)]
    pub speed: f64,
    /// Random seed of the twin.
    #[arg(long, default_value_t = 1)]
    pub seed: u64,
    /// How long to wait for the controller's first answer (0–3600 s).
    #[arg(long, default_value_t = 60.0)]
    pub wait_s: f64,
    /// Dwell at the start pose, out of contact, once the controller answers and the sensor
    /// streams, before the path starts (0–3600 s of robot time): the controller tares its
    /// sensor there, as a robot program that waits for the correction to be ready.
    #[arg(long, default_value_t = 0.5)]
    pub dwell_s: f64,
    /// No progress lines on stderr.
    #[arg(long)]
    pub quiet: bool,
    /// Serve the twin's own live page (SIMULATED ground truth: true contact force, the arm's
    /// true deflection, the correction the robot applies, the path error, the program,
    /// commanded and true TCP paths) on ADDR, 127.0.0.1:8766 when no address is given. The
    /// controller's own page is `deflex run --view`.
    #[arg(long, value_name = "ADDR", num_args = 0..=1, default_missing_value = crate::live::CELL_VIEW)]
    pub view: Option<String>,
    /// The twin's ground-truth log (CSV, the `deflex sim isf` log.csv columns), with its MCAP
    /// recording beside it (same name, `.mcap`). Default: beside the CELL.toml's `[log]
    /// path`, named after it with `.sim-cell` (`deflex-run.csv` → `deflex-run.sim-cell.csv`),
    /// or `deflex-run.sim-cell.csv` beside the CELL.toml without `[log]`.
    #[arg(long, value_name = "PATH")]
    pub log: Option<PathBuf>,
}

impl CellArgs {
    /// Every numeric flag within its documented bounds.
    pub fn check(&self) -> Result<(), CliError> {
        check_flag("--speed", self.speed, 1e-3, 100.0, "")?;
        if let Some(l) = self.length_mm {
            check_flag("--length-mm", l, 1e-3, 1e6, "mm")?;
        }
        check_flag("--wait-s", self.wait_s, 0.0, 3600.0, "s")?;
        check_flag("--dwell-s", self.dwell_s, 0.0, 3600.0, "s")?;
        if let Some(v) = &self.view {
            crate::live::view_address(v)?;
        }
        Ok(())
    }
}

/// The twin's log of a `cell --sim` session: `--log`, else beside the CELL.toml's run log,
/// named after it (`deflex-run.csv` → `deflex-run.sim-cell.csv`).
pub fn cell_log_path(args: &CellArgs, file: &CellFile) -> PathBuf {
    if let Some(p) = &args.log {
        return p.clone();
    }
    let run_log = file
        .log_path()
        .unwrap_or_else(|| file.base_dir.join("deflex-run.csv"));
    let stem = run_log
        .file_stem()
        .map_or_else(|| "deflex-run".into(), |s| s.to_string_lossy().into_owned());
    run_log.with_file_name(format!("{stem}.sim-cell.csv"))
}

/// What `cell --sim` served and wrote.
pub struct CellSession {
    /// The twin's run.
    pub outcome: CellOutcome,
    /// The ground-truth log written (rows).
    pub log: (PathBuf, usize),
    /// The MCAP recording: where, and what it held (or why it failed).
    pub recording: (PathBuf, Result<RecordReport, deflex_record::RecordError>),
    /// What the live view did.
    pub view: Option<ViewStats>,
}

pub(crate) fn twin_path(args: &CellArgs) -> Result<ToolPath, CliError> {
    let path = match args.path.as_str() {
        "cone" => ToolPath::paper_cone(),
        "helical" => ToolPath::cone(&ConeParams {
            helical: true,
            ..ConeParams::default()
        })?,
        other => {
            return Err(
                UsageError::invalid("--path", "cone or helical", format!("\"{other}\"")).into(),
            );
        }
    };
    Ok(match args.length_mm {
        Some(l) => path.truncated(l),
        None => path,
    })
}

/// The twin's cell: the robot's (`--robot`, else the twin file's, else the TX200's), with the
/// twin file's settings over it.
pub fn twin_config(args: &CellArgs) -> Result<CellConfig, CliError> {
    match (&args.twin, &args.robot) {
        (Some(p), robot) => Ok(deflex_app::cell::twin_cell_file::load_cell(
            p,
            robot.as_deref(),
        )?),
        (None, Some(robot)) => deflex_app::cell::twin_cell_file::cell_for_robot(robot)
            .map_err(|e| CliError::in_context(format!("--robot {robot}"))(e.into())),
        (None, None) => Ok(CellConfig::default()),
    }
}

/// The twin's progress on stderr (SIMULATED).
fn print_event(event: CellEvent) {
    match event {
        CellEvent::Playing {
            robot,
            robot_spec,
            robot_cycle_s,
            geometry_note,
        } => eprintln!(
            "cell (SIMULATED): the twin plays {robot} (`{robot_spec}`), robot cycle {:.1} ms{geometry_note}",
            robot_cycle_s * 1e3,
        ),
        CellEvent::Progress {
            forming,
            time_s,
            path_s,
            cycles,
            late,
            force_n,
            correction_m,
            max_error_m,
        } => eprintln!(
            "cell (SIMULATED): {} | t {time_s:6.1} of {path_s:.0} s | {cycles} robot cycles, {late} late | F {force_n:6.0} N | \
             correction {:.3} mm | max error so far {:.3} mm",
            if forming {
                "forming"
            } else {
                "waiting for the controller"
            },
            correction_m * 1e3,
            max_error_m * 1e3
        ),
    }
}

/// Serves the twin until the path is done (or `stop`). With `progress`, prints a status line
/// on stderr every two seconds. The twin's own stream (ground truth, [`Source::TwinCell`]) is
/// recorded in MCAP on its own thread and, with `--view`, served live; at the end the twin's
/// ground-truth log is written, the recording beside it (both only when the session served).
pub fn cell_session(
    args: &CellArgs,
    stop: &AtomicBool,
    progress: bool,
) -> Result<CellSession, CliError> {
    if !args.sim {
        return Err(UsageError::Missing {
            what: "cell",
            give: "only the simulated cell exists; pass --sim",
        }
        .into());
    }
    args.check()?;
    let file = load_cell_file(&args.config)?;
    if file.sensor.kind == deflex_app::cell::config::SensorKind::Ros2 {
        return Err(CliError::SimCellNeedsNetFt {
            origin: file.origin.to_string(),
        });
    }
    let options = ServeOptions {
        twin: twin_config(args)?,
        path: twin_path(args)?,
        seed: args.seed,
        speed: args.speed,
        wait_s: args.wait_s,
        dwell_s: args.dwell_s,
    };
    let log_path = cell_log_path(args, &file);
    let mcap_path = crate::live::mcap_beside(&log_path, "--log")?;
    let nominal = options.twin.nominal_robot()?;
    let info = Arc::new(twin_cell_session_info(&nominal, &options.twin));
    debug_assert_eq!(info.source, Source::TwinCell);
    let (publisher, ring) = broadcast::<CycleSample>(1 << 14);
    let recorder = McapRecorder::spawn(&mcap_path, &ring, info.clone())?;
    let view = match &args.view {
        Some(addr) => {
            let addr = crate::live::view_address(addr)?;
            match crate::live::start_view(addr, ring.clone(), info, None, false) {
                Ok(v) => Some(v),
                Err(e) => {
                    let _ = recorder.finish_with(false);
                    return Err(e.into());
                }
            }
        }
        None => None,
    };
    let mut stream = TwinCellStream::new(nominal).with_publisher(publisher);
    let mut events = |event| {
        if progress {
            print_event(event)
        }
    };
    let served = file
        .cell_sides(&options.twin)
        .map_err(CliError::from)
        .and_then(|sides| {
            serve_cell_with(&sides, &options, stop, &mut events, Some(&mut stream))
                .map_err(CliError::from)
        });
    drop(stream); // the stream ends
    let view = view.map(|v| {
        let stats = v.stats();
        v.shutdown();
        stats
    });
    let outcome = match served {
        Ok(o) => o,
        Err(e) => {
            let _ = recorder.finish_with(false);
            return Err(e);
        }
    };
    let rows = outcome.log.rows.len();
    let written = deflex_files::write_atomic(&log_path, outcome.log.to_csv())
        .map_err(CliError::write(&log_path));
    let recording = recorder.finish_with(written.is_ok());
    written?;
    Ok(CellSession {
        outcome,
        log: (log_path, rows),
        recording: (mcap_path, recording),
        view,
    })
}

/// Runs `deflex cell`.
pub fn cell(args: CellArgs, json_out: bool) -> CommandResult {
    let stop = deflex_runtime::rt::interrupt_flag();
    if !json_out && !args.quiet {
        eprintln!(
            "SIMULATED cell serving the robot link of the config and an ATI Net F/T on loopback; \
             waiting for `deflex run`…"
        );
    }
    let session = cell_session(&args, stop, !args.quiet)?;
    let o = &session.outcome;
    let s = &o.summary;
    let (log_path, log_rows) = &session.log;
    let (mcap_path, recording) = &session.recording;
    let phase = match o.end {
        CellEnd::ProgramFinished => "ended (robot program finished)",
        CellEnd::Stopped => "stopped (signal)",
    };
    if json_out {
        let value = json!({
            "simulated": true, "robot": o.robot, "robot_spec": o.robot_spec,
            "model_geometry_matches": o.model_geometry_matches, "phase": match o.end { CellEnd::ProgramFinished => "ended", CellEnd::Stopped => "stopped" },
            "phase_text": phase, "cycles": o.cycles, "late_replies": o.late, "duration_s": o.duration_s,
            "round_trip": stats_json(&o.round_trip),
            "max_error_norm_mm": s.max_error_norm_m * 1e3, "rms_error_norm_mm": s.rms_error_norm_m() * 1e3,
            "max_force_norm_n": s.max_force_norm_n, "max_fz_n": s.max_fz_n,
            "max_correction_mm": s.max_correction_m * 1e3,
            "log": log_path, "log_rows": log_rows,
        });
        let mut value = value;
        let ok = recording.as_ref().ok();
        value["mcap"] = json!({
            "path": mcap_path, "committed": ok.is_some(),
            "cycles": ok.map(|r| r.stats.recorded), "lost": ok.map(|r| r.lost),
            "error": recording.as_ref().err().map(ToString::to_string),
        });
        value["view"] = json!(session.view.as_ref().map(|v| json!({
            "samples": v.samples_received, "samples_lost": v.samples_lost,
            "messages_dropped": v.frames_dropped,
        })));
        print_json(&value);
    } else {
        println!(
            "deflex cell (SIMULATED {} cell, `{}`): {:.1} s simulated, {} robot cycles, phase: {phase}",
            o.robot, o.robot_spec, o.duration_s, o.cycles
        );
        println!(
            "  late answers: {} (the robot's count: no answer before its next cycle; `deflex run` \
             over KUKA RSI reports the same number from the telegrams' Delay)",
            o.late
        );
        println!("  robot-side round trip: {}", o.round_trip);
        println!(
            "  max TCP error norm {:.3} mm (rms {:.3} mm), max force {:.0} N, max correction {:.3} mm",
            s.max_error_norm_m * 1e3,
            s.rms_error_norm_m() * 1e3,
            s.max_force_norm_n,
            s.max_correction_m * 1e3
        );
        println!(
            "  log: {} ({log_rows} rows, SIMULATED ground truth)",
            log_path.display()
        );
        match recording {
            Ok(r) => println!(
                "  recording: {} (MCAP, the twin's stream: {} samples, {} lost, {:.1} MB)",
                mcap_path.display(),
                r.stats.recorded,
                r.lost,
                r.stats.bytes as f64 / 1e6
            ),
            Err(e) => println!("  recording: failed: {e}"),
        }
        if let Some(v) = &session.view {
            println!("  live view: {}", crate::live::view_line(v));
        }
    }
    Ok(())
}
