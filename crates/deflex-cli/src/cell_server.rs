//! `deflex cell --sim`: the digital twin served on loopback over the protocols of a real cell.
//! It plays the robot of `robot.kind` (a KUKA sending RSI telegrams, an ABB streaming EGM, the
//! Stäubli VAL3 program, a UR script on the simple UDP/TCP line links) at the twin's robot cycle
//! and the ATI Net F/T streaming its readings while the twin forms the cone, so `deflex run` can
//! be tried end to end with no hardware. It reads the same `CELL.toml` as `deflex run`.

use crate::args::{CliResult, print_json};
use crate::cmd_control::{calibration, load_cell_file, rsi_mode, stats_json};
use clap::Args;
use deflex_control::config::{CellFile, RobotKind};
use deflex_control::stats::{CycleStats, StatsSummary};
use deflex_io::egm::EgmRobotEndpoint;
use deflex_io::netft::NetFtSensorServer;
use deflex_io::rsi::RsiRobotEndpoint;
use deflex_io::simple_tcp::SimpleTcpRobotEndpoint;
use deflex_io::simple_udp::SimpleUdpRobotEndpoint;
use deflex_io::staubli::StaubliRobotEndpoint;
use deflex_io::{RobotSideLink, RobotState};
use deflex_sim::{Cell, CellConfig, ConeParams, ToolPath};
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
    /// Twin settings (`[cell]` TOML of `deflex sim`); default: the paper's cell.
    #[arg(long)]
    pub twin: Option<PathBuf>,
    /// Tool path: `cone` (the paper's cone, as `deflex sim isf`) or `helical`.
    #[arg(long, default_value = "cone")]
    pub path: String,
    /// Only the first part of the path (mm).
    #[arg(long)]
    pub length_mm: Option<f64>,
    /// Time scale: cycles run N times faster than the robot's 4 ms in wall time.
    #[arg(long, default_value_t = 1.0)]
    pub speed: f64,
    /// Random seed of the twin.
    #[arg(long, default_value_t = 1)]
    pub seed: u64,
    /// How long to wait for the controller's first answer (s).
    #[arg(long, default_value_t = 60.0)]
    pub wait_s: f64,
    /// Dwell at the start pose, out of contact, once the controller answers and the sensor
    /// streams, before the path starts (s of robot time): the controller tares its sensor there,
    /// as a robot program that waits for the correction to be ready.
    #[arg(long, default_value_t = 0.5)]
    pub dwell_s: f64,
}

/// What the served twin did.
pub struct CellOutcome {
    pub summary: deflex_sim::forming::RunningStats,
    pub round_trip: StatsSummary,
    pub cycles: u64,
    pub late: u64,
    pub duration_s: f64,
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

pub fn twin_config(args: &CellArgs) -> Result<CellConfig, String> {
    match &args.twin {
        Some(p) => CellConfig::load(p).map_err(|e| format!("{}: {e}", p.display())),
        None => Ok(CellConfig::default()),
    }
}

/// The robot side of `robot.kind`, played by the twin, and whether its replies echo the state's
/// cycle id (RSI's IPOC, the Stäubli acknowledgement), so a late reply is never taken for the
/// current one. The other protocols carry no echo: the first reply after a state is its answer.
fn robot_endpoint(
    file: &CellFile,
    wait: Duration,
    stop: &AtomicBool,
) -> Result<(Box<dyn RobotSideLink>, bool), String> {
    let pc = file.robot.bind;
    let local = "127.0.0.1:0";
    let err = |e: deflex_io::LinkError| {
        format!(
            "simulated {} robot towards {pc}: {e}",
            file.robot.kind.name()
        )
    };
    Ok(match file.robot.kind {
        RobotKind::KukaRsi => (
            Box::new(RsiRobotEndpoint::new(local, pc, rsi_mode(file)).map_err(err)?),
            true,
        ),
        RobotKind::AbbEgm => (
            Box::new(EgmRobotEndpoint::new(local, pc).map_err(err)?),
            false,
        ),
        RobotKind::Staubli => (
            Box::new(
                // The VAL3 program's watchdog: the robot's own timeout.
                StaubliRobotEndpoint::new(
                    local,
                    pc,
                    Duration::from_secs_f64(file.robot.timeout_s.clamp(1e-3, 10.0)),
                )
                .map_err(err)?,
            ),
            true,
        ),
        RobotKind::SimpleUdp => (
            Box::new(SimpleUdpRobotEndpoint::new(local, pc).map_err(err)?),
            false,
        ),
        RobotKind::SimpleTcp => {
            // The robot's script connects to the PC: retry until `deflex run` listens.
            let start = Instant::now();
            loop {
                match SimpleTcpRobotEndpoint::connect(pc, Duration::from_millis(200)) {
                    Ok(ep) => break (Box::new(ep), false),
                    Err(e) if start.elapsed() > wait || stop.load(Ordering::SeqCst) => {
                        return Err(err(e));
                    }
                    Err(_) => std::thread::sleep(Duration::from_millis(50)),
                }
            }
        }
    })
}

/// Serves the twin until the path is done (or `stop`).
pub fn cell_session(args: &CellArgs, stop: &AtomicBool) -> Result<CellOutcome, String> {
    if !args.sim {
        return Err("cell: only the simulated cell exists; pass --sim".into());
    }
    if !(args.speed > 0.0 && args.speed.is_finite()) {
        return Err(format!("--speed: must be positive, got {}", args.speed));
    }
    if !(args.dwell_s >= 0.0 && args.dwell_s <= 3600.0) {
        return Err(format!(
            "--dwell-s: expected 0 to 3600 s, got {}",
            args.dwell_s
        ));
    }
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
    let twin = twin_config(args)?;
    let mut cell = Cell::new(&twin, twin_path(args)?, args.seed).map_err(|e| e.to_string())?;
    let mut server = NetFtSensorServer::bind(file.sensor.address, calibration(&file))
        .map_err(|e| format!("sensor.address {}: {e}", file.sensor.address))?;
    let wait = Duration::from_secs_f64(args.wait_s.clamp(0.0, 3600.0));
    let (mut robot, echoes_cycle) = robot_endpoint(&file, wait, stop)?;
    let period = Duration::from_secs_f64(cell.robot_period_s() / args.speed);
    let mut round_trip = CycleStats::new(period);
    let mut step = cell.step();
    let (mut ipoc, mut cycles, mut late) = (0u64, 0u64, 0u64);
    let mut serving = false;
    // Robot cycles still to hold the start pose once the controller answers and the sensor
    // streams.
    let mut dwell_cycles = (args.dwell_s / cell.robot_period_s()).ceil() as u64;
    let start = Instant::now();
    let mut next = Instant::now();
    loop {
        if stop.load(Ordering::SeqCst) {
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
        let state = RobotState {
            cycle_id: ipoc,
            ..RobotState::with_joints(&step.q_measured_rad)
        };
        let sent = Instant::now();
        let _ = robot.send_state(&state);
        next += period;
        loop {
            let wait = next.saturating_duration_since(Instant::now());
            if wait.is_zero() {
                if serving {
                    late += 1;
                    round_trip.record_miss();
                }
                break;
            }
            match robot.receive_correction(wait) {
                Ok(Some(r)) if r.cycle_id == ipoc || !echoes_cycle => {
                    let c = r.correction;
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
                    cell.set_correction(c.to_array());
                    break;
                }
                Ok(Some(_)) | Err(_) => continue,
                Ok(None) => {}
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
        std::thread::sleep(next.saturating_duration_since(Instant::now()));
    }
    Ok(CellOutcome {
        summary: cell.stats().clone(),
        round_trip: round_trip.summary(),
        cycles,
        late,
        duration_s: step.time_s,
    })
}

pub fn cell(args: CellArgs, json_out: bool) -> CliResult {
    let stop = deflex_control::rt::interrupt_flag();
    if !json_out {
        eprintln!(
            "SIMULATED cell serving the robot link of the config and an ATI Net F/T on loopback; \
             waiting for `deflex run`…"
        );
    }
    let o = cell_session(&args, stop)?;
    let s = &o.summary;
    if json_out {
        let value = json!({
            "simulated": true, "cycles": o.cycles, "late_replies": o.late, "duration_s": o.duration_s,
            "round_trip": stats_json(&o.round_trip),
            "max_error_norm_mm": s.max_error_norm_m * 1e3, "rms_error_norm_mm": s.rms_error_norm_m() * 1e3,
            "max_force_norm_n": s.max_force_norm_n, "max_fz_n": s.max_fz_n,
            "max_correction_mm": s.max_correction_m * 1e3,
        });
        print_json(&value);
    } else {
        println!(
            "deflex cell (SIMULATED): {:.1} s simulated, {} robot cycles, {} replies late or missing",
            o.duration_s, o.cycles, o.late
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
            path: "cone".into(),
            length_mm: None,
            speed: 1.0,
            seed: 1,
            wait_s: 1.0,
            dwell_s: 0.5,
        };
        let e = cell_session(&args, &AtomicBool::new(false))
            .err()
            .unwrap_or_default();
        assert!(e.contains("loopback") && e.contains("robot.bind"), "{e}");
        let _ = std::fs::remove_dir_all(&dir);
    }
}
