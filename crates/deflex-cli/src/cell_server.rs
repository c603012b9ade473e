//! `deflex cell --sim`: the digital twin served on loopback over the protocols of a real cell,
//! from the same `CELL.toml` as `deflex run` (the session is `deflex_app::cell::sim_cell`). The
//! twin plays any robot (`--robot`: a built-in name or a robot file; default the twin file's,
//! else the paper's TX200) with that robot's cell (`deflex_sim::CellConfig::for_robot`), and
//! names it in every output. This module holds the flags, the twin they pick, the signal
//! handling, the twin's live view, the progress lines and the printing.

use crate::args::{check_flag, print_json};
use crate::error::{CliError, CommandResult, UsageError};
use clap::Args;
use deflex_app::cell::sim_cell::{SimCellPath, SimCellPlan, SimCellReport};
use deflex_sim::CellConfig;
use deflex_sim::twin::cell_server::{CellEvent, PoseJump, ServeOptions};
use deflex_view::ViewStats;
use serde_json::json;
use std::path::PathBuf;
use std::sync::atomic::AtomicBool;

#[derive(Args, Clone, Debug)]
pub struct CellArgs {
    /// Serve the simulated cell (the digital twin); the only cell there is.
    #[arg(long)]
    pub sim: bool,
    /// The same CELL.toml as `deflex run`: robot.bind is where the robot's telegrams go (any
    /// robot.kind; for ur-rtde, robot.peer is where the simulated UR controller serves RTDE;
    /// with fanuc-stream the simulated controller listens at robot.peer and follows the joints
    /// deflex streams), sensor.address is where the simulated Net F/T answers (for sensor.kind =
    /// "ur-rtde", the UR controller streams the flange sensor). All must be loopback addresses.
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
    /// A fault to try the model check with (SIMULATED): from `--pose-jump-at-s` on, the TCP pose
    /// the robot reports (KUKA RSI `RIst`, ABB EGM feedback, UR RTDE `actual_TCP_pose`) is MM (0–1000) higher along the
    /// robot base's z than its kinematics give, as when a controller's tool or base is changed
    /// mid-session; `deflex run` then latches `model_mismatch` once MM exceeds its tolerance.
    #[arg(long, value_name = "MM")]
    pub pose_jump_mm: Option<f64>,
    /// Time of the path (s, 0–3600) from which `--pose-jump-mm` applies.
    #[arg(long, default_value_t = 1.0)]
    pub pose_jump_at_s: f64,
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
        if let Some(mm) = self.pose_jump_mm {
            check_flag("--pose-jump-mm", mm, 0.0, 1000.0, "mm")?;
        }
        check_flag("--pose-jump-at-s", self.pose_jump_at_s, 0.0, 3600.0, "s")?;
        if let Some(v) = &self.view {
            crate::live::view_address(v)?;
        }
        Ok(())
    }
}

/// What `cell --sim` served and wrote, and what its live view did.
pub struct CellSession {
    /// The twin's run, its log and recording.
    pub report: SimCellReport,
    /// What the live view did.
    pub view: Option<ViewStats>,
}

/// The twin's tool path of `--path` and `--length-mm`.
fn twin_path(args: &CellArgs) -> Result<deflex_sim::ToolPath, CliError> {
    let path = SimCellPath::from_name(&args.path).ok_or_else(|| {
        UsageError::invalid("--path", "cone or helical", format!("\"{}\"", args.path))
    })?;
    Ok(path.tool_path(args.length_mm)?)
}

/// The twin's cell (`deflex_app::twin::cell_config`): the robot's (`--robot`, else the twin
/// file's, else the TX200's), with the twin file's settings over it; a robot without a twin
/// file is named with its flag.
pub fn twin_config(args: &CellArgs) -> Result<CellConfig, CliError> {
    let cell = deflex_app::twin::cell_config(args.robot.as_deref(), args.twin.as_deref());
    match (&args.twin, &args.robot) {
        (None, Some(robot)) => {
            cell.map_err(|e| CliError::in_context(format!("--robot {robot}"))(e.into()))
        }
        _ => Ok(cell?),
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
/// on stderr every two seconds. The twin's own stream (ground truth) is recorded in MCAP and,
/// with `--view`, served live; at the end the twin's ground-truth log is written, the recording
/// beside it (both only when the session served).
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
    let plan = SimCellPlan::load(&args.config)?;
    let options = ServeOptions {
        twin: twin_config(args)?,
        path: twin_path(args)?,
        seed: args.seed,
        speed: args.speed,
        wait_s: args.wait_s,
        dwell_s: args.dwell_s,
        pose_jump: args.pose_jump_mm.map(|mm| PoseJump {
            after_s: args.pose_jump_at_s,
            offset_m: [0.0, 0.0, mm * 1e-3],
        }),
    };
    let session = plan.start(options, args.log.as_deref())?;
    let view = match &args.view {
        Some(addr) => {
            let started = crate::live::view_address(addr)
                .map_err(CliError::from)
                .and_then(|addr| {
                    crate::live::start_view(
                        addr,
                        session.ring().clone(),
                        session.info().clone(),
                        None,
                        false,
                    )
                    .map_err(CliError::from)
                });
            match started {
                Ok(v) => Some(v),
                Err(e) => {
                    session.abort();
                    return Err(e);
                }
            }
        }
        None => None,
    };
    let served = session.serve(stop, &mut |event| {
        if progress {
            print_event(event)
        }
    });
    let view = view.map(|v| {
        let stats = v.stats();
        v.shutdown();
        stats
    });
    Ok(CellSession {
        report: served?,
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
    if json_out {
        let mut value = session.report.summary_json();
        value["view"] = json!(session.view.as_ref().map(|v| json!({
            "samples": v.samples_received, "samples_lost": v.samples_lost,
            "messages_dropped": v.frames_dropped,
        })));
        print_json(&value);
    } else {
        print!("{}", session.report.summary_text());
        if let Some(v) = &session.view {
            println!("  live view: {}", crate::live::view_line(v));
        }
    }
    Ok(())
}
