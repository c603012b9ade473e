//! FANUC Stream Motion on the twin (SIMULATED): `deflex cell --sim` plays the FANUC controller
//! of the FANUC-like built-in arm (`r2000ic-165f`), following the joints `deflex run` streams
//! from `deflex compensate`'s `compensated_path.csv` with the online correction added; the same
//! cell and path over KUKA RSI beside it, and the open loop in-process.
//!
//! The error of each run is measured the one way that suits all three: the distance of the
//! true tool from the programmed path (each logged true point against the open loop's desired
//! polyline), since a streamed path has no clock of the twin's to compare with.

use deflex_app::cell::cell_run::{CellRun, CellRunOutcome};
use deflex_app::cell::config::CellFile;
use deflex_app::cell::sim_cell::SimCellPath;
use deflex_sim::twin::cell_server::{CellOutcome, ServeOptions, serve_cell};
use deflex_sim::{CellConfig, FormingLog, ToolPath};
use nalgebra::Vector3;
use std::path::Path;
use std::sync::atomic::AtomicBool;

/// The FANUC-like built-in arm.
const ARM: &str = "r2000ic-165f";

fn free_port() -> u16 {
    std::net::UdpSocket::bind("127.0.0.1:0")
        .and_then(|s| s.local_addr())
        .map(|a| a.port())
        .unwrap()
}

/// The `CELL.toml` of a session with robot lines `robot` (after `kind`) and `extra` sections,
/// for the twin `twin`, as the RSI loopback sessions write it.
fn cell_toml(robot: &str, twin: &CellConfig, extra: &str) -> String {
    let s = &twin.sensor;
    format!(
        "[robot]\n{robot}\nbind = \"127.0.0.1:{}\"\ntimeout_s = 1.0\ncycle_s = {}\n\
         [sensor]\nkind = \"netft\"\naddress = \"127.0.0.1:{}\"\nbind = \"127.0.0.1:0\"\n\
         timeout_s = 2.0\nrange = {:?}\n\
         [mounting]\nsensor_xyz_m = {:?}\nsensor_rpy_rad = {:?}\ntool_mass_kg = {}\ntool_com_m = {:?}\n\
         gravity_m_s2 = [0.0, 0.0, {}]\n\
         [model]\nfile = \"{ARM}\"\n[control]\nrealtime = false\nlock_memory = false\n\
         [log]\npath = \"run.csv\"\n{extra}",
        free_port(),
        twin.robot_period_s(),
        free_port(),
        s.range,
        s.sensor_in_flange_xyz_m,
        s.sensor_in_flange_rpy,
        s.tool_mass_kg,
        s.tool_com_in_sensor_m,
        -s.gravity_m_s2,
    )
}

/// `deflex compensate --robot r2000ic-165f --path cone --length-mm L` into `dir`.
fn compensated_path(dir: &Path, length_mm: f64) {
    let csv = crate::cell::stream_path::compensated_cone(ARM, length_mm);
    std::fs::write(dir.join("compensated_path.csv"), csv).unwrap();
}

/// The twin served over the `CELL.toml` `toml` in `dir` and `deflex run` against it.
fn session(
    dir: &Path,
    toml: &str,
    twin: &CellConfig,
    path: &ToolPath,
) -> (CellRunOutcome, CellOutcome) {
    let config = dir.join("cell.toml");
    std::fs::write(&config, toml).unwrap();
    let file = CellFile::load(&config).unwrap();
    let options = ServeOptions {
        twin: twin.clone(),
        path: path.clone(),
        seed: 7,
        speed: 1.0,
        wait_s: 30.0,
        dwell_s: 0.5,
        pose_jump: None,
    };
    let sides = file.cell_sides(twin).unwrap();
    let cell_thread = std::thread::spawn(move || {
        serve_cell(&sides, &options, &AtomicBool::new(false), &mut |_| {})
    });
    let run = CellRun::start(&file, 30.0, Some(0.5)).unwrap();
    while !run.runtime.is_finished() {
        std::thread::sleep(std::time::Duration::from_millis(20));
    }
    let run = run.finish().unwrap();
    (run, cell_thread.join().unwrap().unwrap())
}

/// Max and RMS distance (mm) of a log's true tool points from the polyline `path` (R_p, m),
/// over the rows the path is being formed (from its first to its last point's time).
fn distance_from_path(log: &FormingLog, path: &[Vector3<f64>]) -> (f64, f64) {
    let (mut max, mut sum, mut n) = (0.0f64, 0.0, 0usize);
    for row in &log.rows {
        let p = row.truth.true_m;
        let d = path
            .windows(2)
            .map(|w| {
                let ab = w[1] - w[0];
                let f = if ab.norm_squared() > 0.0 {
                    ((p - w[0]).dot(&ab) / ab.norm_squared()).clamp(0.0, 1.0)
                } else {
                    0.0
                };
                (p - (w[0] + ab * f)).norm()
            })
            .fold(f64::INFINITY, f64::min);
        max = max.max(d);
        sum += d * d;
        n += 1;
    }
    (max * 1e3, (sum / n.max(1) as f64).sqrt() * 1e3)
}

/// A short closed-loop Stream Motion session on the FANUC-like twin: deflex streams the
/// compensated cone (40 mm) with its correction, the twin follows, the session ends as the
/// program's end (the last command, the stop packet), the robot never refused a command, and
/// the tool ends closer to the path than in the open loop. KUKA RSI runs the same cell and path
/// at the same time (both sleep most of every cycle), for the comparison. A status may come
/// late by up to 1 s (`robot.stream_late_after_s`), and the jerk threshold is 2000 rad/s³
/// (default 100): a loaded 2-core machine without real-time scheduling holds a thread back now
/// and then, and one command that misses its cycle makes a step of about 300 rad/s³ at this
/// feed, which the simulated controller would refuse with its error bit, stopping the stream
/// (the late-status and threshold rules have their own tests in deflex-io).
#[test]
fn stream_motion_closes_the_loop_on_the_fanuc_like_twin() {
    let _turn = crate::twin::session_turn();
    let length_mm = 40.0;
    let twin = CellConfig::for_robot(ARM).unwrap();
    let path = SimCellPath::Cone.tool_path(Some(length_mm)).unwrap();
    let open = deflex_sim::run_forming(&twin, path.clone(), 7, None).unwrap();
    let polyline: Vec<Vector3<f64>> = open.log.rows.iter().map(|r| r.truth.desired_m).collect();
    let open_mm = distance_from_path(&open.log, &polyline);

    let root =
        std::env::temp_dir().join(format!("deflex-twin-fanuc-stream-{}", std::process::id()));
    let (stream_dir, rsi_dir) = (root.join("stream"), root.join("rsi"));
    for d in [&stream_dir, &rsi_dir] {
        std::fs::create_dir_all(d).unwrap();
    }
    compensated_path(&stream_dir, length_mm);
    let stream_toml = cell_toml(
        &format!(
            "kind = \"fanuc-stream\"\npeer = \"127.0.0.1:{}\"\nstream_path = \"compensated_path.csv\"\n\
             stream_ramp_s = 0.3\nstream_late_after_s = 1.0\n\
             stream_jerk_rad_s3 = [2000.0, 2000.0, 2000.0, 2000.0, 2000.0, 2000.0]",
            free_port()
        ),
        &twin,
        "[feedforward]\ntable = \"compensated_path.csv\"\nmode = \"precompensated\"\n",
    );
    let rsi_toml = cell_toml("kind = \"kuka-rsi\"", &twin, "");
    let ((stream_run, stream_cell), (rsi_run, rsi_cell)) = std::thread::scope(|scope| {
        let s = scope.spawn(|| session(&stream_dir, &stream_toml, &twin, &path));
        let r = scope.spawn(|| session(&rsi_dir, &rsi_toml, &twin, &path));
        (s.join().unwrap(), r.join().unwrap())
    });
    let stream_mm = distance_from_path(&stream_cell.log, &polyline);
    let rsi_mm = distance_from_path(&rsi_cell.log, &polyline);
    eprintln!(
        "{ARM}, cone {length_mm} mm (SIMULATED), distance of the true tool from the path, max / RMS: \
         open loop {:.4} / {:.4} mm (time-based {:.4} mm max); Stream Motion {:.4} / {:.4} mm \
         ({} cycles, {} late, max force {:.0} N, max xi {:.4} mm, {:.1} s); KUKA RSI {:.4} / {:.4} mm \
         (time-based {:.4} / {:.4} mm; {} cycles, {} late, max force {:.0} N)",
        open_mm.0,
        open_mm.1,
        open.summary.max_error_norm_mm,
        stream_mm.0,
        stream_mm.1,
        stream_cell.cycles,
        stream_cell.late,
        stream_cell.summary.max_force_norm_n,
        stream_run.summary.max_xi_m * 1e3,
        stream_cell.duration_s,
        rsi_mm.0,
        rsi_mm.1,
        rsi_cell.summary.max_error_norm_m * 1e3,
        rsi_cell.summary.rms_error_norm_m() * 1e3,
        rsi_cell.cycles,
        rsi_cell.late,
        rsi_cell.summary.max_force_norm_n,
    );
    let s = &stream_run.summary;
    assert!(s.error.is_none(), "{:?}", s.error);
    assert_eq!(
        s.phase_text(),
        "ended (robot program finished)",
        "{:?}",
        s.fault
    );
    assert!(
        rsi_run.summary.error.is_none(),
        "{:?}",
        rsi_run.summary.error
    );
    // The twin followed the whole stream: the path's end reached (within its error). Should a
    // thread be held back for longer than the allowances above on a loaded machine, the
    // simulated controller refuses the step and deflex stops the stream safely before the end
    // (the session still ends as the program's end): the end is checked when at most 10 % of
    // the answers were late, as the comparison below.
    let last = stream_cell.log.rows.last().unwrap().truth;
    let end = *polyline.last().unwrap();
    let reached = (last.true_m - end).norm() < 1e-3;
    if stream_cell.late * 10 <= stream_cell.cycles {
        assert!(
            reached,
            "{:?} vs {end:?}; twin: {} cycles, {:?}; run: {:?}",
            last.true_m, stream_cell.cycles, stream_cell.end, stream_run.summary
        );
    } else if !reached {
        eprintln!(
            "{} of {} answers late on this loaded machine: the stream stopped {:.1} mm before the \
             path's end",
            stream_cell.late,
            stream_cell.cycles,
            (last.true_m - end).norm() * 1e3
        );
    }
    // The correction cut the error (when the answers arrived in time: a loaded 2-core machine
    // without real-time scheduling may hold a cycle back; the late ones are counted).
    if stream_cell.late * 10 <= stream_cell.cycles {
        assert!(stream_mm.0 < open_mm.0, "{stream_mm:?} vs open {open_mm:?}");
    }
    let _ = std::fs::remove_dir_all(&root);
}

/// A Stream Motion cell whose `robot.cycle_s` is not the cycle of the controller the twin plays
/// is refused before anything is bound: deflex would stream one cycle's path per status at
/// another pace.
#[test]
fn a_stream_at_another_cycle_than_the_twin_s_is_refused() {
    use deflex_sim::twin::cell_server::CellServeError;
    let twin = CellConfig::for_robot(ARM).unwrap();
    assert_eq!(twin.robot_period_s(), 0.004);
    let dir = std::env::temp_dir().join(format!("deflex-twin-fanuc-cycle-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let toml = cell_toml(
        &format!(
            "kind = \"fanuc-stream\"\npeer = \"127.0.0.1:{}\"\nstream_path = \"compensated_path.csv\"",
            free_port()
        ),
        &twin,
        "",
    )
    .replace("cycle_s = 0.004", "cycle_s = 0.008");
    let config = dir.join("cell.toml");
    std::fs::write(&config, toml).unwrap();
    let file = CellFile::load(&config).unwrap();
    let sides = file.cell_sides(&twin).unwrap();
    let options = ServeOptions {
        twin: twin.clone(),
        path: SimCellPath::Cone.tool_path(Some(5.0)).unwrap(),
        seed: 1,
        speed: 1.0,
        wait_s: 1.0,
        dwell_s: 0.0,
        pose_jump: None,
    };
    match serve_cell(&sides, &options, &AtomicBool::new(false), &mut |_| {}) {
        Err(e @ CellServeError::StreamCycleMismatch { .. }) => {
            let text = e.to_string();
            assert!(
                text.contains("robot.cycle_s = 0.008 s") && text.contains("every 0.004 s"),
                "{text}"
            );
        }
        other => panic!("{:?}", other.map(|o| o.cycles)),
    }
    let _ = std::fs::remove_dir_all(&dir);
}
