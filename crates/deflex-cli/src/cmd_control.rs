//! `deflex run` — the real-time correction controller (Johra et al. 2022, Section 4.2: eq. 5–7,
//! 15, 17) against a robot link and a force/torque sensor described by `CELL.toml`
//! (docs/cell.example.toml). The session is `deflex_app::cell::run_session`; this module holds
//! the flags, the signal handling (Ctrl-C or SIGTERM ramps the correction out), the outlets it
//! attaches (the live view, the ROS 2 sensor link and bridge), the live status, the printing
//! and the exit codes. Its counterpart without hardware, `deflex cell --sim`, is in
//! [`crate::cell_server`].

use crate::args::{check_flag, print_json};
use crate::error::{CliError, RunFailure};
use crate::ros2_parts::Ros2Parts;
use clap::Args;
use deflex_app::cell::run_session::{RunEvent, RunOptions, RunPlan, RunReport, RunSession};
use deflex_app::cell::run_summary::OutletLines;
use deflex_runtime::LiveStatus;
use deflex_view::ViewHandle;
use serde_json::json;
use std::path::PathBuf;
use std::sync::atomic::{AtomicBool, Ordering};

#[derive(Args, Clone, Debug)]
pub struct RunArgs {
    /// Cell configuration (robot link, sensor link, mounting, model, gains, limits, log).
    #[arg(long)]
    pub config: PathBuf,
    /// Stop (ramping the correction out) after this many seconds (0 < s ≤ 10⁷).
    #[arg(long)]
    pub duration_s: Option<f64>,
    /// Exit once the robot has been silent this long after the session started (0.01–3600 s).
    #[arg(long, default_value_t = 2.0)]
    pub idle_exit_s: f64,
    /// Give up when no robot telegram and sensor sample arrive within this time (0.1–3600 s).
    #[arg(long, default_value_t = 60.0)]
    pub startup_timeout_s: f64,
    /// No live status lines.
    #[arg(long)]
    pub quiet: bool,
    /// Serve the live view (a page in the browser: forces, δŝ, ξ against its limits, state,
    /// loop timing, 3-D path; a stop button that ramps the correction out as Ctrl-C does) on
    /// ADDR, 127.0.0.1:8765 when no address is given. Another address than loopback is
    /// reachable from the network: a warning is printed.
    #[arg(long, value_name = "ADDR", num_args = 0..=1, default_missing_value = crate::live::RUN_VIEW)]
    pub view: Option<String>,
}

impl RunArgs {
    /// Every numeric flag within its documented bounds.
    pub fn check(&self) -> Result<(), CliError> {
        if let Some(d) = self.duration_s {
            check_flag("--duration-s", d, 1e-3, 1e7, "s")?;
        }
        check_flag("--idle-exit-s", self.idle_exit_s, 0.01, 3600.0, "s")?;
        check_flag(
            "--startup-timeout-s",
            self.startup_timeout_s,
            0.1,
            3600.0,
            "s",
        )?;
        if let Some(v) = &self.view {
            crate::live::view_address(v)?;
        }
        Ok(())
    }

    /// The session's options.
    fn options(&self) -> RunOptions {
        RunOptions {
            startup_timeout_s: self.startup_timeout_s,
            idle_exit_s: self.idle_exit_s,
            duration_s: self.duration_s,
        }
    }
}

/// Everything `deflex run` did: the session's report and what the outlets did.
struct RunOutcome {
    report: RunReport,
    /// What the ROS 2 bridge published (with `[ros2]`) and the ROS 2 sensor link took and
    /// refused (`sensor.kind = "ros2"`).
    ros2: crate::ros2_parts::Ros2Outcome,
    /// What the live view did.
    view: Option<deflex_view::ViewStats>,
}

/// One live status line.
fn print_status(s: &LiveStatus, rate_hz: f64) {
    let faults = s.flags.describe();
    eprintln!(
        "t {:7.1} s | {:8} | {:5.1} Hz | F {:7.1} N | ξ [{:+.3} {:+.3} {:+.3}] mm | telegrams {}{} | samples {} | {}",
        s.time_s,
        s.phase.name(),
        rate_hz,
        s.force_n,
        s.xi_m[0] * 1e3,
        s.xi_m[1] * 1e3,
        s.xi_m[2] * 1e3,
        s.telegrams,
        s.robot_late
            .map(|l| format!(" (robot counts {l} late)"))
            .unwrap_or_default(),
        s.samples,
        if faults.is_empty() {
            "ok".to_string()
        } else {
            faults
        },
    );
}

/// The `deflex run` session: the plan, the ROS 2 parts, the session with its recording and live
/// view, the live status, the end. `stop` ends it early (the live view's stop button sets it
/// too).
fn run_session(
    args: &RunArgs,
    live: bool,
    stop: &'static AtomicBool,
) -> Result<RunOutcome, CliError> {
    args.check()?;
    let plan = RunPlan::load(&args.config)?;
    let cell = &plan.cell;
    let mut ros2 = Ros2Parts::open(cell)?;
    let sensor = ros2.take_sensor();
    let session = plan.start(&args.options(), sensor, &mut |telemetry| {
        ros2.subscribe_bridge(cell, telemetry)
    })?;
    if let Some(error) = ros2.start_error() {
        session.abort();
        return Err(error);
    }
    if live {
        ros2.announce(cell);
    }
    // The sinks join right after the threads started, from the oldest sample the ring holds
    // (nothing can be lost: no robot has answered yet). A sink that cannot start ends the
    // session before the robot is served.
    let session = session.record()?;
    let view = match start_view(&session, args, stop) {
        Ok(view) => view,
        Err(error) => {
            session.abort();
            return Err(error);
        }
    };
    if let Ok(policy) = cell.peer_policy()
        && let Some(warning) = policy.warning()
        && !args.quiet
    {
        eprintln!("deflex run: warning: {warning}");
    }
    if live && let Some(text) = session.feedforward() {
        eprintln!("deflex run: feed-forward: {text}");
    }
    if live {
        eprintln!(
            "deflex run: waiting for the robot ({}) on {} and the sensor at {} (Ctrl-C or \
             SIGTERM stops, ramping the correction out)",
            cell.robot.kind.name(),
            cell.robot_link_address(),
            cell.sensor.address
        );
    }
    session.wait(stop, &mut |event| match event {
        RunEvent::Status { status, rate_hz } if live => print_status(&status, rate_hz),
        RunEvent::Status { .. } => {}
        // A full disk is reported when it happens; the session stops, ramping the correction
        // out, rather than running on without its record.
        RunEvent::LogFailed { path, error } => eprintln!(
            "deflex run: the log {} cannot be written ({error}); stopping the session, the \
             correction ramps out",
            deflex_files::shown_path(path)
        ),
    });
    let view = view.map(|v| {
        let stats = v.stats();
        v.shutdown();
        stats
    });
    let report = session.finish()?;
    let ros2 = ros2.finish()?;
    Ok(RunOutcome { report, ros2, view })
}

/// The live view of a started run (with `--view`): its stop button sets the same flag as
/// Ctrl-C, so the same ramp-out.
fn start_view(
    session: &RunSession,
    args: &RunArgs,
    stop: &'static AtomicBool,
) -> Result<Option<ViewHandle>, CliError> {
    let Some(addr) = &args.view else {
        return Ok(None);
    };
    let runtime = session.runtime();
    let on_stop: deflex_view::StopCallback = Box::new(move || stop.store(true, Ordering::SeqCst));
    let view = crate::live::start_view(
        crate::live::view_address(addr)?,
        runtime.telemetry().clone(),
        runtime.session_info().clone(),
        Some(on_stop),
        false,
    )?;
    Ok(Some(view))
}

pub fn run(args: RunArgs, json_out: bool) -> Result<(), CliError> {
    let stop = deflex_runtime::rt::interrupt_flag();
    let o = run_session(&args, !args.quiet && !json_out, stop)?;
    if json_out {
        let mut value = o.report.summary_json();
        value["exit_code"] = json!(run_failure(&o.report).map_or(0, |f| f.exit_code()));
        o.ros2.add_json(&mut value);
        value["view"] = json!(o.view.as_ref().map(|v| json!({
            "samples": v.samples_received, "samples_lost": v.samples_lost,
            "messages_dropped": v.frames_dropped, "stop_requests": v.stop_requests,
        })));
        print_json(&value);
    } else {
        let outlets = OutletLines {
            links: o.ros2.lines(),
            view: o.view.as_ref().map(crate::live::view_line),
        };
        print!("{}", o.report.summary_text(&outlets));
    }
    match run_failure(&o.report) {
        Some(failure) => Err(CliError::Run(failure)),
        None => Ok(()),
    }
}

/// How the session failed, if it did: its error, a latched fault (the robot starved
/// included), then the log (see [`RunFailure::exit_code`]).
fn run_failure(report: &RunReport) -> Option<RunFailure> {
    let o = &report.session;
    let s = &o.summary;
    if let Some(e) = &s.error {
        return Some(RunFailure::Failed(e.to_string()));
    }
    if s.robot_starved {
        return Some(RunFailure::Starved);
    }
    if let Some(f) = &s.fault {
        return Some(RunFailure::Faulted(f.to_string()));
    }
    if let Some(message) = &o.log_error {
        return Some(RunFailure::Log {
            path: o.log_path.clone(),
            message: message.clone(),
        });
    }
    None
}
