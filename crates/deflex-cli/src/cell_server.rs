//! `deflex cell --sim`: the digital twin served on loopback over the protocols of a real cell.
//! It plays the robot of `robot.kind` (a KUKA sending RSI telegrams, an ABB streaming EGM, the
//! Stäubli VAL3 program, a UR script on the simple UDP/TCP line links) at the twin's robot cycle
//! and the ATI Net F/T streaming its readings while the twin forms the cone, so `deflex run` can
//! be tried end to end with no hardware. It reads the same `CELL.toml` as `deflex run`. The twin
//! plays any robot (`--robot`: a built-in name or a robot file; default the twin file's, else the
//! paper's TX200) with that robot's cell (`deflex_sim::CellConfig::for_robot`: part position,
//! force level, controller rate, sensor), and names it in every output.

use crate::args::{CliResult, check_flag, print_json};
use crate::cmd_control::{load_cell_file, stats_json};
use clap::Args;
use deflex_control::config::{CellFile, RobotKind};
use deflex_control::stats::{CycleStats, StatsSummary};
use deflex_io::egm::{EgmConfig, EgmRobotEndpoint};
use deflex_io::netft::NetFtSensorServer;
use deflex_io::rsi::RsiRobotEndpoint;
use deflex_io::simple_tcp::SimpleTcpRobotEndpoint;
use deflex_io::simple_udp::SimpleUdpRobotEndpoint;
use deflex_io::staubli::StaubliRobotEndpoint;
use deflex_io::{LinkError, ReceivedCorrection, RobotSideLink, RobotState};
use deflex_model::{Data, Robot};
use deflex_sim::{Cell, CellConfig, ConeParams, ToolPath};
use nalgebra::Vector3;
use serde_json::json;
use std::path::PathBuf;
use std::sync::atomic::{AtomicBool, Ordering};
use std::time::{Duration, Instant};

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
}

impl CellArgs {
    /// Every numeric flag within its documented bounds.
    pub fn check(&self) -> Result<(), String> {
        check_flag("--speed", self.speed, 1e-3, 100.0, "")?;
        if let Some(l) = self.length_mm {
            check_flag("--length-mm", l, 1e-3, 1e6, "mm")?;
        }
        check_flag("--wait-s", self.wait_s, 0.0, 3600.0, "s")?;
        check_flag("--dwell-s", self.dwell_s, 0.0, 3600.0, "s")?;
        Ok(())
    }
}

/// How the served session ended.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum CellEnd {
    /// The simulated robot program reached the end of its path.
    ProgramFinished,
    /// Stopped by a signal before the end.
    Stopped,
}

/// What the served twin did.
pub struct CellOutcome {
    /// The robot the twin played (its description's name) and how it was given (`--robot`, the
    /// twin file's, or `tx200`).
    pub robot: String,
    pub robot_spec: String,
    /// The CELL.toml model has the geometry (fingerprint) of the robot the twin played.
    pub model_geometry_matches: bool,
    pub summary: deflex_sim::forming::RunningStats,
    pub round_trip: StatsSummary,
    pub cycles: u64,
    /// Robot cycles whose answer did not arrive within the cycle, judged when the next cycle
    /// starts — KUKA's own definition of a late answer (`Delay`), which the simulated KUKA
    /// sends in its telegrams, so `deflex run` reports the same number.
    pub late: u64,
    pub duration_s: f64,
    pub end: CellEnd,
}

pub(crate) fn twin_path(args: &CellArgs) -> Result<ToolPath, String> {
    let path = match args.path.as_str() {
        "cone" => ToolPath::paper_cone(),
        "helical" => ToolPath::cone(&ConeParams {
            helical: true,
            ..ConeParams::default()
        })
        .map_err(|e| e.to_string())?,
        other => return Err(format!("--path: expected cone or helical, got \"{other}\"")),
    };
    Ok(match args.length_mm {
        Some(l) => path.truncated(l),
        None => path,
    })
}

/// The twin's cell: the robot's (`--robot`, else the twin file's, else the TX200's), with the
/// twin file's settings over it.
pub fn twin_config(args: &CellArgs) -> Result<CellConfig, String> {
    match (&args.twin, &args.robot) {
        (Some(p), robot) => deflex_load::load_cell(p, robot.as_deref()).map_err(|e| e.to_string()),
        (None, Some(robot)) => {
            deflex_load::cell_for_robot(robot).map_err(|e| format!("--robot {robot}: {e}"))
        }
        (None, None) => Ok(CellConfig::default()),
    }
}

/// Empty when the CELL.toml model has the geometry of the robot the twin plays (with the cell's
/// tool); else a warning saying whether only the tool differs.
fn geometry_note(model: &Robot, nominal: &Robot) -> String {
    if model.geometry_fingerprint() == nominal.geometry_fingerprint() {
        return String::new();
    }
    let mut with_cell_tool = model.clone();
    with_cell_tool.tool = nominal.tool;
    if with_cell_tool.geometry_fingerprint() == nominal.geometry_fingerprint() {
        let t = nominal.tool.translation.vector;
        format!(
            "; warning: the CELL.toml model ({}) has another tool than the cell's (flange → TCP \
             [{:.3}, {:.3}, {:.3}] m): the controller estimates the deflection at another point",
            model.name, t.x, t.y, t.z
        )
    } else {
        format!(
            "; warning: the CELL.toml model ({}, geometry {}) is not the geometry of the robot the \
             twin plays ({})",
            model.name,
            model.geometry_fingerprint(),
            nominal.geometry_fingerprint()
        )
    }
}

/// The robot controller's own kinematics, for what a real controller does itself: turn joint
/// corrections (RSI `AK`) into a Cartesian one and know its tool orientation (EGM's sensor
/// frame). The simulated controller uses the nominal geometry of the robot the twin plays, with
/// the cell's tool.
struct ControllerKinematics {
    robot: Robot,
    data: Data,
}

impl ControllerKinematics {
    fn at(&mut self, q: &[f64]) -> bool {
        self.robot.forward_kinematics(&mut self.data, q).is_ok()
    }

    /// TCP orientation in base axes.
    fn tcp_rotation(&self) -> [[f64; 3]; 3] {
        let r = self.robot.base.rotation.inverse() * self.data.tcp.rotation;
        let m = r.matrix();
        std::array::from_fn(|i| std::array::from_fn(|j| m[(i, j)]))
    }

    /// J(q) Δq in base axes: the TCP motion of a joint correction.
    fn joint_to_cartesian(&self, dq: &[f64]) -> [f64; 6] {
        let tcp = self.data.tcp_position();
        let columns = self.robot.geometric_jacobian_columns(&self.data, &tcp);
        let mut v = nalgebra::Vector6::zeros();
        for (c, d) in columns.iter().zip(dq).take(self.robot.joint_count()) {
            v += c * *d;
        }
        let r_t = self.robot.base.rotation.inverse();
        let lin = r_t * Vector3::new(v[0], v[1], v[2]);
        let ang = r_t * Vector3::new(v[3], v[4], v[5]);
        [lin.x, lin.y, lin.z, ang.x, ang.y, ang.z]
    }
}

/// The robot side of `robot.kind`, played by the twin.
enum RobotSide {
    Rsi(RsiRobotEndpoint),
    Egm(Box<EgmRobotEndpoint>, EgmConfig),
    Other(Box<dyn RobotSideLink>),
}

impl RobotSide {
    fn link(&mut self) -> &mut dyn RobotSideLink {
        match self {
            RobotSide::Rsi(l) => l,
            RobotSide::Egm(l, _) => l.as_mut(),
            RobotSide::Other(l) => l.as_mut(),
        }
    }

    /// Whether replies echo the state's cycle id (RSI's IPOC, the Stäubli acknowledgement), so a
    /// late reply is never taken for the current one. The other protocols carry no echo: the
    /// first reply after a state is its answer.
    fn echoes_cycle(&self, kind: RobotKind) -> bool {
        matches!(kind, RobotKind::KukaRsi | RobotKind::Staubli)
    }

    fn receive(&mut self, wait: Duration) -> Result<Option<ReceivedCorrection>, LinkError> {
        self.link().receive_correction(wait)
    }
}

fn robot_side(
    file: &CellFile,
    joints: usize,
    wait: Duration,
    stop: &AtomicBool,
) -> Result<RobotSide, String> {
    let pc = file.robot.bind;
    let local = "127.0.0.1:0";
    let err = |e: LinkError| {
        format!(
            "simulated {} robot towards {pc}: {e}",
            file.robot.kind.name()
        )
    };
    Ok(match file.robot.kind {
        RobotKind::KukaRsi => {
            RobotSide::Rsi(RsiRobotEndpoint::new(local, pc, file.rsi_mode()).map_err(err)?)
        }
        RobotKind::AbbEgm => {
            let cfg = file.egm_config(joints);
            let mut ep = EgmRobotEndpoint::new(local, pc).map_err(err)?;
            ep.set_seven_axis(cfg.seven_axis);
            RobotSide::Egm(Box::new(ep), cfg)
        }
        RobotKind::Staubli => RobotSide::Other(Box::new(
            // The VAL3 program's watchdog: the robot's own timeout.
            StaubliRobotEndpoint::new(
                local,
                pc,
                Duration::from_secs_f64(file.robot.timeout_s.clamp(1e-3, 10.0)),
            )
            .map_err(err)?,
        )),
        RobotKind::SimpleUdp => RobotSide::Other(Box::new(
            SimpleUdpRobotEndpoint::new(local, pc).map_err(err)?,
        )),
        RobotKind::SimpleTcp => {
            // The robot's script connects to the PC: retry until `deflex run` listens.
            let start = Instant::now();
            loop {
                match SimpleTcpRobotEndpoint::connect(pc, Duration::from_millis(200)) {
                    Ok(ep) => break RobotSide::Other(Box::new(ep)),
                    Err(e) if start.elapsed() > wait || stop.load(Ordering::SeqCst) => {
                        return Err(err(e));
                    }
                    Err(_) => std::thread::sleep(Duration::from_millis(50)),
                }
            }
        }
    })
}

/// Serves the twin until the path is done (or `stop`). With `progress`, prints a status line
/// on stderr every two seconds.
pub fn cell_session(
    args: &CellArgs,
    stop: &AtomicBool,
    progress: bool,
) -> Result<CellOutcome, String> {
    if !args.sim {
        return Err("cell: only the simulated cell exists; pass --sim".into());
    }
    args.check()?;
    let file = load_cell_file(&args.config)?;
    for (field, addr) in [
        ("robot.bind", file.robot.bind),
        ("sensor.address", file.sensor.address),
    ] {
        if !addr.ip().is_loopback() {
            return Err(format!(
                "{}: {field} = {addr}: the simulated cell only uses loopback addresses",
                file.origin
            ));
        }
    }
    let model = deflex_load::load_robot(&file.model_spec())
        .map_err(|e| format!("{}: model.file: {e}", file.origin))?;
    let twin = twin_config(args)?;
    let nominal = twin.nominal_robot().map_err(|e| e.to_string())?;
    if model.joint_count() != nominal.joint_count() {
        return Err(format!(
            "{}: model.file: {} has {} joints, the robot the twin plays ({}) has {}",
            file.origin,
            model.name,
            model.joint_count(),
            nominal.name,
            nominal.joint_count()
        ));
    }
    let model_geometry_matches = model.geometry_fingerprint() == nominal.geometry_fingerprint();
    if progress {
        eprintln!(
            "cell (SIMULATED): the twin plays {} (`{}`), robot cycle {:.1} ms{}",
            nominal.name,
            twin.part.robot,
            twin.robot_period_s() * 1e3,
            geometry_note(&model, &nominal)
        );
    }
    let mut cell = Cell::new(&twin, twin_path(args)?, args.seed).map_err(|e| e.to_string())?;
    let mut server = NetFtSensorServer::bind(file.sensor.address, file.calibration())
        .map_err(|e| format!("sensor.address {}: {e}", file.sensor.address))?;
    let wait = Duration::from_secs_f64(args.wait_s);
    let mut kinematics = ControllerKinematics {
        data: Data::new(),
        robot: nominal.clone(),
    };
    let mut robot = robot_side(&file, kinematics.robot.joint_count(), wait, stop)?;
    let echoes_cycle = robot.echoes_cycle(file.robot.kind);
    let period = Duration::from_secs_f64(cell.robot_period_s() / args.speed);
    let mut round_trip = CycleStats::new(period);
    let mut step = cell.step();
    let (mut ipoc, mut cycles, mut late) = (0u64, 0u64, 0u64);
    let mut serving = false;
    let mut end = CellEnd::ProgramFinished;
    // Robot cycles still to hold the start pose once the controller answers and the sensor
    // streams.
    let mut dwell_cycles = (args.dwell_s / cell.robot_period_s()).ceil() as u64;
    let path_s = cell.path_duration_s();
    let start = Instant::now();
    let mut last_progress = Instant::now();
    let mut next = Instant::now();
    loop {
        if stop.load(Ordering::SeqCst) {
            end = CellEnd::Stopped;
            break;
        }
        while let Ok(Some(_)) = server.poll_request(Duration::ZERO) {}
        if serving {
            cell.step_into(&mut step);
            for s in &step.sensor_samples {
                let _ = server.send_sample(&s.wrench_sensor, 0);
            }
        } else if let Some(s) = step.sensor_samples.last() {
            // Waiting for the controller, then dwelling: hold the start pose, keep streaming.
            let _ = server.send_sample(&s.wrench_sensor, 0);
        }
        ipoc += 4;
        let kinematics_ok = kinematics.at(&step.q_measured_rad);
        if let RobotSide::Egm(ep, cfg) = &mut robot
            && kinematics_ok
        {
            ep.set_correction_frame(&cfg.correction_frame(&kinematics.tcp_rotation()));
        }
        let state = RobotState {
            cycle_id: ipoc,
            // A KUKA reports its count of late answers in every telegram.
            late_answers: Some(late.min(u64::from(u32::MAX)) as u32),
            ..RobotState::with_joints(&step.q_measured_rad)
        };
        let sent = Instant::now();
        let _ = robot.link().send_state(&state);
        next += period;
        let mut answered = false;
        loop {
            let wait = next.saturating_duration_since(Instant::now());
            if wait.is_zero() {
                break;
            }
            match robot.receive(wait) {
                Ok(Some(r)) if r.cycle_id == ipoc || !echoes_cycle => {
                    let correction = match r.joint_correction_rad {
                        Some(dq) if kinematics_ok => kinematics.joint_to_cartesian(&dq),
                        Some(_) => [0.0; 6],
                        None => r.correction.to_array(),
                    };
                    if serving {
                        round_trip.record(sent.elapsed());
                    }
                    if !serving && server.streaming() {
                        if dwell_cycles == 0 {
                            serving = true;
                        } else {
                            dwell_cycles -= 1;
                        }
                    }
                    cell.set_correction(correction);
                    answered = true;
                    break;
                }
                Ok(Some(_)) | Err(_) => continue,
                Ok(None) => {}
            }
        }
        if serving && !answered {
            round_trip.record_miss();
            // The next cycle starts without this cycle's answer: late, as the robot counts it
            // (and reports it in its next telegram; the program's last telegram has no next).
            if !step.finished {
                late += 1;
            }
        }
        if serving {
            cycles += 1;
            if step.finished {
                break;
            }
        } else if start.elapsed().as_secs_f64() > args.wait_s {
            return Err(format!(
                "no answer from a controller on {} within {} s",
                file.robot.bind, args.wait_s
            ));
        }
        if progress && last_progress.elapsed() >= Duration::from_secs(2) {
            last_progress = Instant::now();
            let (force, corr) = cell.truth().map_or((0.0, 0.0), |t| {
                let f = &t.wrench;
                let c = &t.correction;
                (
                    (f[0] * f[0] + f[1] * f[1] + f[2] * f[2]).sqrt(),
                    (c[0] * c[0] + c[1] * c[1] + c[2] * c[2]).sqrt(),
                )
            });
            eprintln!(
                "cell (SIMULATED): {} | t {:6.1} of {:.0} s | {} robot cycles, {} late | F {:6.0} N | \
                 correction {:.3} mm | max error so far {:.3} mm",
                if serving {
                    "forming"
                } else {
                    "waiting for the controller"
                },
                step.time_s,
                path_s,
                cycles,
                late,
                force,
                corr * 1e3,
                cell.stats().max_error_norm_m * 1e3
            );
        }
        std::thread::sleep(next.saturating_duration_since(Instant::now()));
    }
    Ok(CellOutcome {
        robot: nominal.name,
        robot_spec: twin.part.robot.clone(),
        model_geometry_matches,
        summary: cell.stats().clone(),
        round_trip: round_trip.summary(),
        cycles,
        late,
        duration_s: step.time_s,
        end,
    })
}

pub fn cell(args: CellArgs, json_out: bool) -> CliResult {
    let stop = deflex_control::rt::interrupt_flag();
    if !json_out && !args.quiet {
        eprintln!(
            "SIMULATED cell serving the robot link of the config and an ATI Net F/T on loopback; \
             waiting for `deflex run`…"
        );
    }
    let o = cell_session(&args, stop, !args.quiet)?;
    let s = &o.summary;
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
        });
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
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The twin plays the robot of `--robot`, over a twin file's settings too; an unknown robot
    /// is refused naming it; the CELL.toml model's geometry is checked against the robot's.
    #[test]
    fn the_twin_plays_the_robot_of_the_flag() {
        let args = |robot: Option<&str>, twin: Option<PathBuf>| CellArgs {
            sim: true,
            config: PathBuf::from("cell.toml"),
            twin,
            robot: robot.map(str::to_string),
            path: "cone".into(),
            length_mm: None,
            speed: 1.0,
            seed: 1,
            wait_s: 1.0,
            dwell_s: 0.5,
            quiet: true,
        };
        assert_eq!(twin_config(&args(None, None)).unwrap().part.robot, "tx200");
        let ur = twin_config(&args(Some("ur10e"), None)).unwrap();
        assert_eq!(ur.part.robot, "ur10e");
        assert_eq!(ur.robot_period_s(), 0.002);
        let dir = std::env::temp_dir().join(format!("deflex-cell-robot-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        let file = dir.join("twin.toml");
        std::fs::write(
            &file,
            "[cell.part]\nrobot = \"ur10e\"\n[cell.log]\nrate_hz = 25.0\n",
        )
        .unwrap();
        let from_file = twin_config(&args(None, Some(file.clone()))).unwrap();
        assert_eq!(from_file.part.robot, "ur10e");
        let flag_wins = twin_config(&args(Some("tx200"), Some(file))).unwrap();
        assert_eq!(flag_wins.part.robot, "tx200");
        let e = twin_config(&args(Some("nosuch-robot"), None)).unwrap_err();
        assert!(e.contains("nosuch-robot"), "{e}");
        let _ = std::fs::remove_dir_all(&dir);
        // Geometry: the cell's nominal robot matches itself; the built-in lacks the cell's tool;
        // a TX200 model is not a UR10e.
        let nominal = ur.nominal_robot().unwrap();
        assert_eq!(geometry_note(&nominal, &nominal), "");
        let builtin = deflex_load::load_robot("ur10e").unwrap();
        assert!(geometry_note(&builtin, &nominal).contains("another tool"));
        let tx = deflex_load::load_robot("tx200").unwrap();
        assert!(geometry_note(&tx, &nominal).contains("is not the geometry"));
    }

    /// `deflex cell --sim` refuses anything but loopback.
    #[test]
    fn cell_refuses_non_loopback_addresses() {
        let dir = std::env::temp_dir().join(format!("deflex-nonloop-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        let config = dir.join("cell.toml");
        std::fs::write(
            &config,
            "[robot]\nkind = \"kuka-rsi\"\nbind = \"10.0.0.2:59152\"\n\
             [sensor]\nkind = \"netft\"\naddress = \"127.0.0.1:49152\"\n[model]\nfile = \"tx200\"\n",
        )
        .unwrap();
        let args = CellArgs {
            sim: true,
            config,
            twin: None,
            robot: None,
            path: "cone".into(),
            length_mm: None,
            speed: 1.0,
            seed: 1,
            wait_s: 1.0,
            dwell_s: 0.5,
            quiet: true,
        };
        let e = cell_session(&args, &AtomicBool::new(false), false)
            .err()
            .unwrap_or_default();
        assert!(e.contains("loopback") && e.contains("robot.bind"), "{e}");
        let _ = std::fs::remove_dir_all(&dir);
    }
}
