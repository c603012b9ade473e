//! `deflex run` — the real-time correction controller (Johra et al. 2022, Section 4.2: eq. 5–7,
//! 15, 17) against a robot link and a force/torque sensor described by `CELL.toml`
//! (docs/cell.example.toml). Its counterpart without hardware, `deflex cell --sim`, is in
//! [`crate::cell_server`].

use crate::args::{CliResult, print_json};
use clap::Args;
use deflex_control::config::{CellFile, RobotKind, SensorKind};
use deflex_control::log::spawn_writer;
use deflex_control::runtime::{RunSummary, RuntimeOptions, spawn};
use deflex_control::stats::StatsSummary;
use deflex_control::{Controller, WallClock};
use deflex_io::netft::{Calibration, NetFtClient};
use deflex_io::rsi::{CorrectionMode, RsiConfig, RsiLink};
use deflex_io::{ForceSensorLink, RobotLink};
use serde_json::json;
use std::path::PathBuf;
use std::sync::atomic::{AtomicBool, Ordering};
use std::time::{Duration, Instant};

#[derive(Args, Clone, Debug)]
pub struct RunArgs {
    /// Cell configuration (robot link, sensor link, mounting, model, gains, limits, log).
    #[arg(long)]
    pub config: PathBuf,
    /// Stop (ramping the correction out) after this many seconds.
    #[arg(long)]
    pub duration_s: Option<f64>,
    /// Exit once the robot has been silent this long after the session started (s).
    #[arg(long, default_value_t = 2.0)]
    pub idle_exit_s: f64,
    /// Give up when no robot telegram and sensor sample arrive within this time (s).
    #[arg(long, default_value_t = 60.0)]
    pub startup_timeout_s: f64,
    /// No live status lines.
    #[arg(long)]
    pub quiet: bool,
}

pub(crate) fn load_cell_file(path: &std::path::Path) -> Result<CellFile, String> {
    CellFile::load(path).map_err(|e| e.to_string())
}

fn robot_link(cell: &CellFile) -> Result<Box<dyn RobotLink + Send>, String> {
    let r = &cell.robot;
    let err = |e: deflex_io::LinkError| format!("robot link on {}: {e}", r.bind);
    Ok(match r.kind {
        RobotKind::KukaRsi => Box::new(
            RsiLink::bind(
                r.bind,
                RsiConfig {
                    sen_type: r.sen_type.clone(),
                    estr: None,
                    mode: rsi_mode(cell),
                    ..RsiConfig::default()
                },
            )
            .map_err(err)?,
        ),
        RobotKind::AbbEgm => {
            // EGM's measurement age: one control period.
            let age_ms = (1000.0 / cell.control.rate_hz).round() as u32;
            let cfg = deflex_io::egm::EgmConfig {
                frame: deflex_io::egm::EgmFrame::Base,
                age_ms,
                ..Default::default()
            };
            Box::new(deflex_io::egm::EgmLink::bind(r.bind, cfg).map_err(err)?)
        }
        RobotKind::Staubli => Box::new(deflex_io::staubli::StaubliLink::bind(r.bind).map_err(err)?),
        RobotKind::SimpleUdp => Box::new(
            deflex_io::simple_udp::SimpleUdpLink::bind(r.bind, Default::default()).map_err(err)?,
        ),
        RobotKind::SimpleTcp => {
            Box::new(deflex_io::simple_tcp::SimpleTcpLink::bind(r.bind).map_err(err)?)
        }
    })
}

pub(crate) fn rsi_mode(cell: &CellFile) -> CorrectionMode {
    if cell.robot.correction_mode == "relative" {
        CorrectionMode::Relative
    } else {
        CorrectionMode::Absolute
    }
}

pub(crate) fn calibration(cell: &CellFile) -> Calibration {
    Calibration {
        counts_per_force: cell.sensor.counts_per_force,
        counts_per_torque: cell.sensor.counts_per_torque,
    }
}

/// Everything `deflex run` did.
pub struct RunOutcome {
    pub summary: RunSummary,
    pub wall_s: f64,
    pub log_path: Option<PathBuf>,
    pub log_rows: u64,
    /// The robot link's protocol, for the summary.
    pub robot_kind: RobotKind,
}

/// The `deflex run` session: links, threads, live status, summary. `stop` ends it early.
pub fn run_session(args: &RunArgs, live: bool, stop: &AtomicBool) -> Result<RunOutcome, String> {
    let cell = load_cell_file(&args.config)?;
    let model = deflex_model::load_robot(&cell.model_spec())
        .map_err(|e| format!("{}: model.file: {e}", cell.origin))?;
    let controller = Controller::new(model, cell.controller_config()).map_err(|e| e.to_string())?;
    let joints = controller.robot().joint_count();
    let robot = robot_link(&cell)?;
    let sensor: Box<dyn ForceSensorLink + Send> = match cell.sensor.kind {
        SensorKind::Netft => Box::new(
            NetFtClient::new(cell.sensor.bind, cell.sensor.address, calibration(&cell))
                .map_err(|e| format!("sensor link to {}: {e}", cell.sensor.address))?,
        ),
    };
    let log_path = cell.log_path();
    let (sink, writer) = match (&log_path, &cell.log) {
        (Some(path), Some(section)) => {
            let file = std::fs::File::create(path)
                .map_err(|e| format!("log.path {}: {e}", path.display()))?;
            let (s, w) = spawn_writer(section.ring_capacity, joints, Box::new(file));
            (Some(s), Some(w))
        }
        _ => (None, None),
    };
    let options = RuntimeOptions {
        robot_cycle_s: cell.robot.cycle_s,
        realtime: cell.control.realtime,
        lock_memory: cell.control.lock_memory,
        startup_timeout_s: args.startup_timeout_s,
        idle_exit_s: Some(args.idle_exit_s),
    };
    let started = Instant::now();
    let runtime = spawn(controller, robot, sensor, WallClock::new(), sink, options);
    let mut last_cycles = 0u64;
    let mut last_print = Instant::now();
    while !runtime.is_finished() {
        std::thread::sleep(Duration::from_millis(50));
        let elapsed = started.elapsed().as_secs_f64();
        if stop.load(Ordering::SeqCst) || args.duration_s.is_some_and(|d| elapsed >= d) {
            runtime.request_stop();
        }
        if live && last_print.elapsed() >= Duration::from_secs(1) {
            let s = runtime.status();
            let rate = (s.cycles - last_cycles) as f64 / last_print.elapsed().as_secs_f64();
            last_cycles = s.cycles;
            last_print = Instant::now();
            let faults = s.flags.describe();
            eprintln!(
                "t {:7.1} s | {:8} | {:5.1} Hz | F {:7.1} N | ξ [{:+.3} {:+.3} {:+.3}] mm | telegrams {} | samples {} | {}",
                s.time_s,
                s.phase.name(),
                rate,
                s.force_n,
                s.xi_m[0] * 1e3,
                s.xi_m[1] * 1e3,
                s.xi_m[2] * 1e3,
                s.telegrams,
                s.samples,
                if faults.is_empty() {
                    "ok".to_string()
                } else {
                    faults
                },
            );
        }
    }
    let summary = runtime.join();
    let log_rows = match writer {
        Some(w) => w.finish().map_err(|e| format!("log writer: {e}"))?.written,
        None => 0,
    };
    Ok(RunOutcome {
        summary,
        wall_s: started.elapsed().as_secs_f64(),
        log_path,
        log_rows,
        robot_kind: cell.robot.kind,
    })
}

pub(crate) fn stats_json(s: &StatsSummary) -> serde_json::Value {
    json!({"count": s.count, "p50_us": s.p50_us, "p99_us": s.p99_us, "max_us": s.max_us,
           "mean_us": s.mean_us, "deadline_misses": s.deadline_misses})
}

pub fn run(args: RunArgs, json_out: bool) -> CliResult {
    let stop = deflex_control::rt::interrupt_flag();
    let o = run_session(&args, !args.quiet && !json_out, stop)?;
    let s = &o.summary;
    if json_out {
        let value = json!({
            "wall_s": o.wall_s, "cycles": s.cycles, "phase": s.phase.name(),
            "control_cycle": stats_json(&s.control), "reply_latency": stats_json(&s.reply_latency),
            "telegrams": s.telegrams, "robot_timeouts": s.robot_timeouts,
            "robot_bad_packets": s.robot_bad_packets, "robot_errors": s.robot_errors,
            "samples": s.samples, "sample_gaps": s.sample_gaps, "sensor_faults": s.sensor_faults,
            "fault": s.fault.map(|f| json!({"kind": f.kind.name(), "time_s": f.time_s, "value": f.value, "limit": f.limit})),
            "max_force_n": s.max_force_n, "max_correction_mm": s.max_xi_m * 1e3,
            "log_rows": o.log_rows, "log_dropped": s.log_dropped, "warnings": s.warnings,
            "error": s.error,
        });
        print_json(&value);
    } else {
        println!(
            "deflex run: {:.1} s, {} control cycles ({:.1} Hz), final phase {}",
            o.wall_s,
            s.cycles,
            s.cycles as f64 / o.wall_s.max(1e-9),
            s.phase.name()
        );
        println!("  control cycle:     {}", s.control);
        println!(
            "  {} reply latency: p50 {:.0} µs, p99 {:.0} µs, max {:.0} µs (late: {}); {} telegrams answered, {} receive timeouts, {} bad packets, {} errors",
            o.robot_kind.name(),
            s.reply_latency.p50_us,
            s.reply_latency.p99_us,
            s.reply_latency.max_us,
            s.reply_latency.deadline_misses,
            s.telegrams,
            s.robot_timeouts,
            s.robot_bad_packets,
            s.robot_errors
        );
        println!(
            "  sensor: {} samples, {} lost, {} flagged",
            s.samples, s.sample_gaps, s.sensor_faults
        );
        println!(
            "  max force {:.1} N, max |ξp| {:.3} mm",
            s.max_force_n,
            s.max_xi_m * 1e3
        );
        match &s.fault {
            Some(f) if f.kind == deflex_control::FaultKind::RobotLinkLost && s.telegrams > 0 => {
                println!(
                    "  fault: {f} — the robot stopped sending (the end of its program, or a lost \
                     link); the correction was ramped to its safe value"
                )
            }
            Some(f) => println!("  fault: {f} — the correction was ramped to its safe value"),
            None => println!("  fault: none"),
        }
        if let Some(p) = &o.log_path {
            println!(
                "  log: {} ({} rows, {} dropped)",
                p.display(),
                o.log_rows,
                s.log_dropped
            );
        }
        for w in &s.warnings {
            println!("  warning: {w}");
        }
    }
    match &s.error {
        Some(e) => Err(e.clone()),
        None => Ok(()),
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::cell_server::{CellArgs, cell_session, twin_path};
    use deflex_demo::twin_controller::{controller_config_for, run_closed_loop};
    use deflex_sim::CellConfig;

    fn free_port() -> u16 {
        std::net::UdpSocket::bind("127.0.0.1:0")
            .and_then(|s| s.local_addr())
            .map(|a| a.port())
            .unwrap()
    }

    #[test]
    fn every_robot_kind_binds_on_loopback() {
        for kind in ["kuka-rsi", "abb-egm", "staubli", "simple-udp", "simple-tcp"] {
            let text = format!(
                "[robot]\nkind = \"{kind}\"\nbind = \"127.0.0.1:0\"\n\
                 [sensor]\nkind = \"netft\"\naddress = \"127.0.0.1:49152\"\n[model]\nfile = \"tx200\"\n"
            );
            let cell = CellFile::parse(&text, "cell.toml", PathBuf::new()).unwrap();
            assert!(robot_link(&cell).is_ok(), "{kind}");
        }
    }

    /// What one `deflex cell --sim` + `deflex run` session over loopback did, beside the same
    /// controller run in-process in simulated time.
    struct Loopback {
        run: RunOutcome,
        cell: crate::cell_server::CellOutcome,
        log_header: String,
        in_process_mm: f64,
        /// The tool path the twin formed.
        path: deflex_sim::ToolPath,
    }

    /// `deflex cell --sim` and `deflex run` over loopback with robot link `kind`, for the first
    /// `length_mm` of the helical cone; then the same controller and path in-process.
    fn loopback(kind: &str, length_mm: f64, seed: u64) -> Loopback {
        let dir =
            std::env::temp_dir().join(format!("deflex-loopback-{kind}-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        let twin = CellConfig::default();
        let s = &twin.sensor;
        let robot_port = if kind == "simple-tcp" {
            std::net::TcpListener::bind("127.0.0.1:0")
                .and_then(|l| l.local_addr())
                .map(|a| a.port())
                .unwrap()
        } else {
            free_port()
        };
        let text = format!(
            "[robot]\nkind = \"{kind}\"\nbind = \"127.0.0.1:{robot_port}\"\ntimeout_s = 0.1\n\
             [sensor]\nkind = \"netft\"\naddress = \"127.0.0.1:{}\"\nbind = \"127.0.0.1:0\"\n\
             timeout_s = 0.1\nrange = {:?}\n\
             [mounting]\nsensor_xyz_m = {:?}\nsensor_rpy_rad = {:?}\ntool_mass_kg = {}\ntool_com_m = {:?}\n\
             gravity_m_s2 = [0.0, 0.0, {}]\n\
             [model]\nfile = \"model.toml\"\n[control]\nrealtime = false\nlock_memory = false\n\
             [log]\npath = \"run.csv\"\n",
            free_port(),
            s.range,
            s.sensor_in_flange_xyz_m,
            s.sensor_in_flange_rpy,
            s.tool_mass_kg,
            s.tool_com_in_sensor_m,
            -s.gravity_m_s2,
        );
        let model = deflex_demo::twin_controller::identify_from_twin_campaign(&twin, 11).unwrap();
        std::fs::write(dir.join("model.toml"), deflex_model::robot_to_toml(&model)).unwrap();
        let config = dir.join("cell.toml");
        std::fs::write(&config, text).unwrap();
        let cell_args = CellArgs {
            sim: true,
            config: config.clone(),
            twin: None,
            path: "helical".into(),
            length_mm: Some(length_mm),
            speed: 1.0,
            seed,
            wait_s: 20.0,
            dwell_s: 0.5,
        };
        let run_args = RunArgs {
            config: config.clone(),
            duration_s: None,
            idle_exit_s: 0.5,
            startup_timeout_s: 20.0,
            quiet: true,
        };
        let stop = std::sync::Arc::new(AtomicBool::new(false));
        let cell_thread = {
            let (a, stop) = (cell_args.clone(), stop.clone());
            std::thread::spawn(move || cell_session(&a, &stop))
        };
        let run = run_session(&run_args, false, &stop).unwrap();
        let cell = cell_thread.join().unwrap().unwrap();
        let log = std::fs::read_to_string(dir.join("run.csv")).unwrap();
        let log_header = log.lines().next().unwrap_or_default().to_string();

        let path = twin_path(&cell_args).unwrap();
        let closed = run_closed_loop(
            &twin,
            path.clone(),
            seed,
            model,
            controller_config_for(&twin),
            false,
            &mut |_| {},
        )
        .unwrap();
        let s = &run.summary;
        eprintln!(
            "loopback {kind}: {} cycles, reply latency p50 {:.0} µs p99 {:.0} µs max {:.0} µs; \
             robot-side round trip {}; late {} of {}; twin max error {:.4} mm (in-process {:.4} mm), \
             max F {:.0} N, max corr {:.4} mm (controller max xi {:.4} mm); fault {:?}",
            s.cycles,
            s.reply_latency.p50_us,
            s.reply_latency.p99_us,
            s.reply_latency.max_us,
            cell.round_trip,
            cell.late,
            cell.cycles,
            cell.summary.max_error_norm_m * 1e3,
            closed.forming.summary.max_error_norm_mm,
            cell.summary.max_force_norm_n,
            cell.summary.max_correction_m * 1e3,
            s.max_xi_m * 1e3,
            s.fault
        );
        let _ = std::fs::remove_dir_all(&dir);
        Loopback {
            run,
            cell,
            log_header,
            in_process_mm: closed.forming.summary.max_error_norm_mm,
            path,
        }
    }

    /// Common checks: the run started, nearly every telegram was answered within the robot
    /// cycle (≥ 90 % on a loaded 2-core machine without real-time scheduling; typically all),
    /// and the twin's error agrees with the in-process run.
    fn check_loopback(kind: &str, l: &Loopback, min_telegrams: u64) {
        let s = &l.run.summary;
        assert!(s.error.is_none(), "{kind}: {:?}", s.error);
        assert!(
            s.telegrams > min_telegrams && s.reply_latency.count > min_telegrams,
            "{kind}: {} telegrams",
            s.telegrams
        );
        assert!(
            l.cell.late * 10 <= l.cell.cycles,
            "{kind}: {} of {} late",
            l.cell.late,
            l.cell.cycles
        );
        assert!(l.run.log_rows > 50, "{kind}: {} log rows", l.run.log_rows);
        // The controller's largest tared force matches the twin's true contact force.
        let (seen, truth) = (s.max_force_n, l.cell.summary.max_force_norm_n);
        assert!(
            (seen - truth).abs() <= 0.15 * truth + 3.0,
            "{kind}: controller max force {seen:.1} N vs twin {truth:.1} N"
        );
        assert!(l.log_header.starts_with("time_s,q1_rad"), "{kind}");
        let loop_mm = l.cell.summary.max_error_norm_m * 1e3;
        assert!(
            (loop_mm - l.in_process_mm).abs() <= 0.1 * l.in_process_mm + 0.003,
            "{kind}: loopback {loop_mm:.4} mm vs in-process {:.4} mm",
            l.in_process_mm
        );
    }

    /// `deflex cell --sim` and `deflex run` over KUKA RSI on loopback for a few seconds of the
    /// helical cone; the result agrees with the same controller run in-process in simulated time.
    #[test]
    fn loopback_cell_and_run_agree_with_in_process() {
        let _serial = crate::realtime_test_lock();
        let l = loopback("kuka-rsi", 60.0, 3);
        check_loopback("kuka-rsi", &l, 500);
        // The correction really acted: the same path without it ends further off.
        let open =
            deflex_sim::run_forming(&CellConfig::default(), l.path.clone(), 3, None).unwrap();
        eprintln!("open loop: {:.4} mm", open.summary.max_error_norm_mm);
        assert!(l.cell.summary.max_error_norm_m * 1e3 < open.summary.max_error_norm_mm);
    }

    /// The simulated cell plays every other robot protocol too (ABB EGM, the Stäubli VAL3
    /// program's protocol, the simple UDP and TCP line links of a UR script), end to end.
    #[test]
    fn loopback_every_other_robot_protocol() {
        let _serial = crate::realtime_test_lock();
        for kind in ["abb-egm", "staubli", "simple-udp", "simple-tcp"] {
            let l = loopback(kind, 30.0, 4);
            check_loopback(kind, &l, 300);
        }
    }
}
