//! `deflex run` — the real-time correction controller (Johra et al. 2022, Section 4.2: eq. 5–7,
//! 15, 17) against a robot link and a force/torque sensor described by `CELL.toml`
//! (docs/cell.example.toml). The session is `deflex_app::cell::cell_run::CellRun`; this module prints its
//! live status and summary. Its counterpart without hardware, `deflex cell --sim`, is in
//! [`crate::cell_server`]; the two together over loopback are tested in deflex-twin.

use crate::args::{check_flag, print_json};
use crate::error::{CliError, RunFailure};
use crate::ros2_parts::{Ros2Outcome, Ros2Parts};
use clap::Args;
use deflex_app::cell::cell_run::FeedForwardInUse;
use deflex_app::cell::cell_run::{CellRun, CellRunOutcome};
use deflex_app::cell::config::CellFile;
use deflex_control::Fault;
use deflex_record::{McapRecorder, RecordOptions, RecordReport};
use deflex_runtime::LiveStatus;
use deflex_runtime::stats::StatsSummary;
use deflex_view::{ViewHandle, ViewStats};
use serde_json::json;
use std::path::PathBuf;
use std::sync::atomic::{AtomicBool, Ordering};
use std::time::{Duration, Instant};

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
}

pub(crate) fn load_cell_file(path: &std::path::Path) -> Result<CellFile, CliError> {
    Ok(CellFile::load(path)?)
}

/// Everything `deflex run` did.
pub struct RunOutcome {
    /// The session (summary, log, link, feed-forward).
    pub session: CellRunOutcome,
    pub wall_s: f64,
    /// The feed-forward in use, described.
    pub feedforward: Option<String>,
    /// What the ROS 2 bridge published (with `[ros2]`) and the ROS 2 sensor link took and
    /// refused (`sensor.kind = "ros2"`).
    pub ros2: Ros2Outcome,
    /// The MCAP recording beside the log: where, and what it held (or why it failed).
    pub recording: Option<(PathBuf, Result<RecordReport, deflex_record::RecordError>)>,
    /// What the live view did.
    pub view: Option<ViewStats>,
}

/// The feed-forward in use, for people.
fn describe_feedforward(ff: &FeedForwardInUse) -> String {
    format!(
        "{} from {} ({} points, {:.1} mm), indexed by {}{}",
        ff.mode.name(),
        ff.table.display(),
        ff.points,
        ff.length_m * 1e3,
        ff.index.name(),
        if ff.lead_s > 0.0 {
            format!(", lead {:.3} s", ff.lead_s)
        } else {
            String::new()
        }
    )
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

/// The `deflex run` session: links, threads, live status, summary. `stop` ends it early (the
/// live view's stop button sets it too). With `[log]`, the session is also recorded in MCAP
/// beside the CSV log ([`crate::live::mcap_beside`]), on its own thread.
pub fn run_session(
    args: &RunArgs,
    live: bool,
    stop: &'static AtomicBool,
) -> Result<RunOutcome, CliError> {
    args.check()?;
    let cell = load_cell_file(&args.config)?;
    if let Some(log) = cell.log_path() {
        // Before any link opens: a folder, a device or the configuration itself (read just
        // above, so known as an input) is refused here, not after the session.
        deflex_files::check_output_flag("[log] path", &log, deflex_files::OutputKind::File)
            .map_err(|e| CliError::in_context(deflex_files::shown_path(&args.config))(e.into()))?;
    }
    let mcap_path = match cell.log_path() {
        Some(log) => Some(crate::live::mcap_beside(&log, "log.path")?),
        None => None,
    };
    let started = Instant::now();
    let mut ros2 = Ros2Parts::open(&cell)?;
    let sensor = ros2.take_sensor();
    let run = CellRun::start_with(
        &cell,
        args.startup_timeout_s,
        Some(args.idle_exit_s),
        sensor,
        &mut |telemetry| ros2.subscribe_bridge(&cell, telemetry),
    )?;
    if let Some(error) = ros2.start_error() {
        run.runtime.request_stop();
        let _ = run.finish();
        return Err(error);
    }
    if live {
        ros2.announce(&cell);
    }
    // The sinks join right after the threads started, from the oldest sample the ring holds
    // (nothing can be lost: no robot has answered yet). A sink that cannot start ends the
    // session before the robot is served.
    let (recorder, view) = match start_sinks(&run, mcap_path, args, stop) {
        Ok(sinks) => sinks,
        Err(error) => {
            run.runtime.request_stop();
            let _ = run.finish();
            return Err(error);
        }
    };
    let feedforward = run.feedforward.as_ref().map(describe_feedforward);
    if let Ok(policy) = cell.peer_policy()
        && let Some(warning) = policy.warning()
        && !args.quiet
    {
        eprintln!("deflex run: warning: {warning}");
    }
    if live && let Some(text) = &feedforward {
        eprintln!("deflex run: feed-forward: {text}");
    }
    if live {
        eprintln!(
            "deflex run: waiting for the robot ({}) on {} and the sensor at {} (Ctrl-C or \
             SIGTERM stops, ramping the correction out)",
            cell.robot.kind.name(),
            cell.robot.bind,
            cell.sensor.address
        );
    }
    let mut last_cycles = 0u64;
    let mut last_print = Instant::now();
    let mut log_failure_shown = false;
    while !run.runtime.is_finished() {
        std::thread::sleep(Duration::from_millis(20));
        let elapsed = started.elapsed().as_secs_f64();
        if stop.load(Ordering::SeqCst) || args.duration_s.is_some_and(|d| elapsed >= d) {
            run.runtime.request_stop();
        }
        if !log_failure_shown && let Some(error) = run.log_failure() {
            // A full disk is reported when it happens; the session stops, ramping the
            // correction out, rather than running on without its record.
            log_failure_shown = true;
            eprintln!(
                "deflex run: the log {} cannot be written ({error}); stopping the session, the \
                 correction ramps out",
                run.log_path
                    .as_deref()
                    .map(deflex_files::shown_path)
                    .unwrap_or_default()
            );
            run.runtime.request_stop();
        }
        if live && last_print.elapsed() >= Duration::from_secs(1) {
            let s = run.runtime.status();
            let rate = (s.cycles - last_cycles) as f64 / last_print.elapsed().as_secs_f64();
            last_cycles = s.cycles;
            last_print = Instant::now();
            print_status(&s, rate);
        }
    }
    let finished = run.finish();
    let view = view.map(|v| {
        let stats = v.stats();
        v.shutdown();
        stats
    });
    // Kept exactly when the CSV log is: a failed run leaves both earlier files whole.
    let commit = finished.as_ref().is_ok_and(|s| s.summary.error.is_none());
    let recording = recorder.map(|r| {
        let path = r.path().to_path_buf();
        (path, r.finish_with(commit))
    });
    let session = finished.map_err(CliError::LogWriter)?;
    let ros2 = ros2.finish()?;
    Ok(RunOutcome {
        session,
        wall_s: started.elapsed().as_secs_f64(),
        feedforward,
        ros2,
        recording,
        view,
    })
}

/// The MCAP recorder (with `[log]`) and the live view (with `--view`) of a started run.
fn start_sinks(
    run: &CellRun,
    mcap_path: Option<PathBuf>,
    args: &RunArgs,
    stop: &'static AtomicBool,
) -> Result<(Option<McapRecorder>, Option<ViewHandle>), CliError> {
    let ring = run.runtime.telemetry();
    let info = run.runtime.session_info();
    let recorder = match mcap_path {
        Some(path) => Some(McapRecorder::spawn_with(
            path,
            ring.subscribe_from_oldest(),
            info.clone(),
            RecordOptions::default(),
        )?),
        None => None,
    };
    let view = match &args.view {
        Some(addr) => {
            // The page's stop button: the same flag as Ctrl-C, so the same ramp-out.
            let on_stop: deflex_view::StopCallback =
                Box::new(move || stop.store(true, Ordering::SeqCst));
            let view = crate::live::start_view(
                crate::live::view_address(addr)?,
                ring.clone(),
                info.clone(),
                Some(on_stop),
                false,
            );
            match view {
                Ok(v) => Some(v),
                Err(e) => {
                    if let Some(r) = recorder {
                        let _ = r.finish_with(false);
                    }
                    return Err(e.into());
                }
            }
        }
        None => None,
    };
    Ok((recorder, view))
}

pub(crate) fn stats_json(s: &StatsSummary) -> serde_json::Value {
    json!({"count": s.count, "p50_us": s.p50_us, "p99_us": s.p99_us, "max_us": s.max_us,
           "mean_us": s.mean_us, "deadline_misses": s.deadline_misses})
}

pub(crate) fn fault_json(f: &Fault) -> serde_json::Value {
    json!({"kind": f.kind.name(), "channel": f.channel.to_string(), "time_s": f.time_s,
           "value": f.value, "limit": f.limit, "unit": f.kind.unit(), "text": f.to_string()})
}

pub fn run(args: RunArgs, json_out: bool) -> Result<(), CliError> {
    let stop = deflex_runtime::rt::interrupt_flag();
    let o = run_session(&args, !args.quiet && !json_out, stop)?;
    let s = &o.session.summary;
    let (kind, step_limit_m) = (o.session.robot_kind, o.session.step_limit_m);
    if json_out {
        let value = json!({
            "wall_s": o.wall_s, "cycles": s.cycles, "phase": s.end.name(),
            "phase_text": s.phase_text(), "controller_phase": s.phase.name(),
            "robot_protocol": kind.name(), "robot_joints": s.robot_joints,
            "control_cycle": stats_json(&s.control), "reply_latency": stats_json(&s.reply_latency),
            "telegrams": s.telegrams,
            "late_replies": s.reply_latency.deadline_misses,
            "robot_reported_late": s.robot_late,
            "robot_timeouts": s.robot_timeouts,
            "robot_bad_packets": s.robot_bad_packets, "robot_errors": s.robot_errors,
            "robot_foreign": s.robot_foreign,
            "last_foreign": s.last_foreign.map(|a| a.to_string()),
            "max_step_sent_m": s.max_step_sent[..3].iter().fold(0.0f64, |m, v| m.max(*v)),
            "max_step_sent_rad": s.max_step_sent[3..].iter().fold(0.0f64, |m, v| m.max(*v)),
            "step_limit_m": step_limit_m,
            "feedforward": o.feedforward,
            "samples": s.samples, "sample_gaps": s.sample_gaps, "sensor_faults": s.sensor_faults,
            "sensor_errors": s.sensor_errors, "sensor_foreign": s.sensor_foreign,
            "fault": s.fault.as_ref().map(fault_json),
            "final_silence": s.final_silence.as_ref().map(fault_json),
            "log_error": o.session.log_error,
            "exit_code": run_failure(&o).map_or(0, |f| f.exit_code()),
            "runaway_events": s.runaway_events,
            "first_runaway": s.first_runaway.as_ref().map(fault_json),
            "max_force_n": s.max_force_n, "max_correction_mm": s.max_xi_m * 1e3,
            "log_rows": o.session.log_rows, "log_committed": o.session.log_committed,
            "log_dropped": s.log_dropped, "warnings": s.warnings,

            "error": s.error.as_ref().map(ToString::to_string),
        });
        let mut value = value;
        o.ros2.add_json(&mut value);
        let link = &s.robot_link;
        for (key, v) in [
            ("mcap", recording_json(&o)),
            (
                "view",
                json!(o.view.as_ref().map(|v| json!({
                    "samples": v.samples_received, "samples_lost": v.samples_lost,
                    "messages_dropped": v.frames_dropped, "stop_requests": v.stop_requests,
                }))),
            ),
            ("robot_dropped", json!(s.robot_dropped)),
            ("robot_starved", json!(s.robot_starved)),
            (
                "robot_dropped_sequence",
                json!(link.dropped_sequence + link.dropped_sequence_mismatch),
            ),
            ("robot_dropped_time", json!(link.dropped_time)),
            ("robot_dropped_joint_count", json!(link.dropped_joint_count)),
            (
                "robot_refused_connections",
                json!(link.refused_busy + link.refused_starving),
            ),
        ] {
            value[key] = v;
        }
        print_json(&value);
    } else {
        print_summary(&o);
    }
    match run_failure(&o) {
        Some(failure) => Err(CliError::Run(failure)),
        None => Ok(()),
    }
}

/// The recording, for `--json`.
fn recording_json(o: &RunOutcome) -> serde_json::Value {
    let Some((path, report)) = &o.recording else {
        return serde_json::Value::Null;
    };
    let ok = report.as_ref().ok();
    json!({
        "path": path,
        "committed": o.session.log_committed && ok.is_some(),
        "cycles": ok.map(|r| r.stats.recorded),
        "lost": ok.map(|r| r.lost),
        "bytes": ok.map(|r| r.stats.bytes),
        "error": report.as_ref().err().map(ToString::to_string),
    })
}

/// How the session failed, if it did: its error, a latched fault (the robot starved
/// included), then the log (see [`RunFailure::exit_code`]).
fn run_failure(o: &RunOutcome) -> Option<RunFailure> {
    let s = &o.session.summary;
    if let Some(e) = &s.error {
        return Some(RunFailure::Failed(e.to_string()));
    }
    if s.robot_starved {
        return Some(RunFailure::Starved);
    }
    if let Some(f) = &s.fault {
        return Some(RunFailure::Faulted(f.to_string()));
    }
    if let Some(message) = &o.session.log_error {
        return Some(RunFailure::Log {
            path: o.session.log_path.clone().unwrap_or_default(),
            message: message.clone(),
        });
    }
    None
}

fn print_summary(o: &RunOutcome) {
    let s = &o.session.summary;
    println!(
        "deflex run: {:.1} s, {} control cycles ({:.1} Hz), phase: {}",
        o.wall_s,
        s.cycles,
        s.cycles as f64 / o.wall_s.max(1e-9),
        s.phase_text()
    );
    println!("  control cycle:     {}", s.control);
    if let Some(text) = &o.feedforward {
        println!("  feed-forward:      {text}");
    }
    println!(
        "  {} ({} joints) reply latency: p50 {:.0} µs, p99 {:.0} µs, max {:.0} µs; {} telegrams answered, {} answered later than one robot cycle{}",
        o.session.robot_kind.name(),
        s.robot_joints,
        s.reply_latency.p50_us,
        s.reply_latency.p99_us,
        s.reply_latency.max_us,
        s.telegrams,
        s.reply_latency.deadline_misses,
        match s.robot_late {
            Some(l) => format!("; the robot counted {l} late answers (RSI Delay)"),
            None => String::new(),
        }
    );
    println!(
        "  robot link: {} receive timeouts, {} malformed packets, {} errors, {} from other hosts or second connections refused{}; {} robot messages dropped as no new state ({} sequence not advancing, {} clock going back, {} joint count)",
        s.robot_timeouts,
        s.robot_bad_packets,
        s.robot_errors,
        s.robot_foreign,
        s.last_foreign
            .map(|a| format!(" (last {a})"))
            .unwrap_or_default(),
        s.robot_dropped,
        s.robot_link.dropped_sequence + s.robot_link.dropped_sequence_mismatch,
        s.robot_link.dropped_time,
        s.robot_link.dropped_joint_count,
    );
    println!(
        "  largest correction step sent: {:.4} mm (limit {:.4} mm per robot cycle)",
        s.max_step_sent[..3].iter().fold(0.0f64, |m, v| m.max(*v)) * 1e3,
        o.session.step_limit_m * 1e3
    );
    println!(
        "  sensor: {} samples, {} lost, {} flagged by the status word, {} malformed or failed, {} from other hosts refused",
        s.samples, s.sample_gaps, s.sensor_faults, s.sensor_errors, s.sensor_foreign
    );
    o.ros2.print();
    println!(
        "  max force {:.1} N, max |ξp| {:.3} mm",
        s.max_force_n,
        s.max_xi_m * 1e3
    );
    if let Some(f) = &s.first_runaway {
        println!(
            "  warning: the runaway guard acted {} time(s); first: {f}",
            s.runaway_events
        );
    }
    match (&s.fault, &s.final_silence) {
        (Some(f), _) => println!("  fault: {f} — the correction was ramped to its safe value"),
        (None, Some(f)) => println!(
            "  fault: none — the {} latched at t {:.2} s (shown by the live line) was the robot's \
             final silence: no telegram came after it, the end of its program",
            f.kind.name(),
            f.time_s
        ),
        (None, None) => println!("  fault: none"),
    }
    if let Some(p) = &o.session.log_path {
        if let Some(e) = &o.session.log_error {
            println!(
                "  log: NOT written: {e} ({} keeps what it held)",
                deflex_files::shown_path(p)
            );
        } else if o.session.log_committed {
            println!(
                "  log: {} ({} rows, {} dropped)",
                p.display(),
                o.session.log_rows,
                s.log_dropped
            );
        } else {
            println!(
                "  log: not written, the run failed ({} keeps what it held)",
                p.display()
            );
        }
    }
    if let Some((path, report)) = &o.recording {
        match report {
            Ok(r) if o.session.log_committed => println!(
                "  recording: {} (MCAP, {} cycles, {} lost, {:.1} MB)",
                path.display(),
                r.stats.recorded,
                r.lost,
                r.stats.bytes as f64 / 1e6
            ),
            Ok(_) => println!(
                "  recording: not written, the run failed ({} keeps what it held)",
                path.display()
            ),
            Err(e) => println!("  recording: failed: {e}"),
        }
    }
    if let Some(v) = &o.view {
        println!("  live view: {}", crate::live::view_line(v));
    }
    for w in &s.warnings {
        println!("  warning: {w}");
    }
}
