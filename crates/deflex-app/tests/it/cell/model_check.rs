//! The model checked against the robot, end to end (SIMULATED): `deflex cell --sim` plays the
//! example cell's KUKA, whose `RIst` is its controller's own kinematics at the measured joints
//! (the twin's plant, with its geometry errors), and `deflex run` compares it with the model of
//! `CELL.toml` — a robot file whose tool is 60 mm too long is refused before the first
//! correction with the difference in mm; the right model runs, its summary giving the largest
//! difference (a calibration's tenths of a millimetre); a jump of the reported pose during the
//! session latches `model_mismatch` and ramps the correction out.

use crate::example_cell::example_cell_file;
use deflex_app::cell::run_session::{RunOptions, RunPlan, RunReport};
use deflex_app::cell::run_summary::OutletLines;
use deflex_app::cell::sim_cell::{SimCellPath, SimCellPlan};
use deflex_runtime::session::SessionError;
use deflex_sim::CellConfig;
use deflex_sim::twin::cell_server::{PoseJump, ServeOptions};
use deflex_telemetry::FaultKind;
use std::path::{Path, PathBuf};
use std::sync::Arc;
use std::sync::atomic::{AtomicBool, Ordering};

fn scratch(name: &str) -> PathBuf {
    let dir = std::env::temp_dir().join(format!(
        "deflex-app-model-check-{name}-{}",
        std::process::id()
    ));
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(&dir).unwrap();
    dir
}

/// The twin serving the example cell of `config` (a 20 mm cone: 2 s of forming) while `deflex
/// run` runs from it; the run's report once it ended (the twin is then stopped).
fn run_against_the_twin(config: &Path, pose_jump: Option<PoseJump>) -> RunReport {
    let twin = SimCellPlan::load(config)
        .unwrap()
        .start(
            ServeOptions {
                twin: CellConfig::default(),
                path: SimCellPath::Cone.tool_path(Some(20.0)).unwrap(),
                seed: 1,
                speed: 1.0,
                wait_s: 60.0,
                dwell_s: 0.5,
                pose_jump,
            },
            None,
        )
        .unwrap();
    let stop = Arc::new(AtomicBool::new(false));
    let cell_thread = {
        let stop = stop.clone();
        std::thread::spawn(move || twin.serve(&stop, &mut |_| {}))
    };
    let options = RunOptions {
        startup_timeout_s: 60.0,
        idle_exit_s: 0.5,
        duration_s: None,
    };
    let session = RunPlan::load(config)
        .unwrap()
        .start(&options, None, &mut |_| {})
        .unwrap()
        .record()
        .unwrap();
    session.wait(&AtomicBool::new(false), &mut |_| {});
    let run = session.finish().unwrap();
    stop.store(true, Ordering::SeqCst);
    let _ = cell_thread.join().unwrap();
    run
}

#[test]
fn a_tool_60_mm_too_long_is_refused_before_the_first_correction() {
    let _turn = crate::twin::session_turn();
    let dir = scratch("long-tool");
    let config = example_cell_file(&dir);
    let model = dir.join("tx200_cell.toml");
    let text = std::fs::read_to_string(&model).unwrap();
    let long = text.replace("xyz = [0.0, 0.0, 0.2]", "xyz = [0.0, 0.0, 0.26]");
    assert_ne!(long, text);
    std::fs::write(&model, long).unwrap();
    let run = run_against_the_twin(&config, None);
    let s = &run.session.summary;
    let Some(SessionError::ModelMismatch { mismatch, .. }) = &s.error else {
        panic!("not refused for the model: {:?}", s.error);
    };
    assert!(
        (mismatch.position_m - 0.06).abs() < 1e-3,
        "{} mm",
        mismatch.position_m * 1e3
    );
    assert_eq!(s.cycles, 0, "a control cycle ran");
    assert_eq!(s.max_xi_m, 0.0);
    let error = s.error.as_ref().unwrap().to_string();
    println!("{error}");
    assert!(
        error.starts_with(&format!(
            "model_mismatch: the TCP pose the robot reports is {:.2} mm and",
            mismatch.position_m * 1e3
        )) && error.contains("60.")
            && error.contains("tolerance 5.00 mm, 10.00 mrad")
            && error.contains("the model's flange → TCP is [0.0, 0.0, 260.0] mm")
            && error.contains("Likely causes: the tool"),
        "{error}"
    );
    assert_eq!(
        s.error.as_ref().unwrap().fault_kind(),
        Some(FaultKind::ModelMismatch)
    );
    assert_eq!(run.summary_json()["error"], error.as_str());
    let _ = std::fs::remove_dir_all(&dir);
}

#[test]
fn the_right_model_runs_and_a_jump_of_the_reported_pose_latches_a_fault() {
    let _turn = crate::twin::session_turn();
    let dir = scratch("right-model");
    let config = example_cell_file(&dir);
    let run = run_against_the_twin(&config, None);
    let s = &run.session.summary;
    assert!(
        s.error.is_none() && s.fault.is_none(),
        "{:?} {:?}",
        s.error,
        s.fault
    );
    let m = s.pose_mismatch_max.expect("the KUKA reported its pose");
    println!(
        "largest difference: {:.4} mm, {:.4} mrad",
        m.position_m * 1e3,
        m.orientation_rad * 1e3
    );
    assert!(m.position_m < 0.5e-3 && m.orientation_rad < 0.5e-3, "{m:?}");
    let text = run.summary_text(&OutletLines::default());
    assert!(
        text.contains("  model check: largest difference between the robot's reported TCP and the model's at the same joints 0.")
            && text.contains("(tolerance 5.00 mm, 10.00 mrad)"),
        "{text}"
    );
    let json = run.summary_json();
    assert_eq!(json["model_check"]["enabled"], true, "{json}");
    assert!(json["model_check"]["max_position_m"].as_f64().unwrap() < 0.5e-3);

    // The controller's reported pose jumps by 20 mm 1 s into the path.
    let dir = scratch("jump");
    let config = example_cell_file(&dir);
    let jump = PoseJump {
        after_s: 1.0,
        offset_m: [0.0, 0.0, 0.02],
    };
    let run = run_against_the_twin(&config, Some(jump));
    let s = &run.session.summary;
    assert!(s.error.is_none(), "{:?}", s.error);
    let fault = s.fault.expect("a fault latched");
    assert_eq!(fault.kind, FaultKind::ModelMismatch, "{fault}");
    assert!((fault.value - 0.02).abs() < 1e-3, "{fault}");
    assert!(run.session.log_rows > 0);
    let text = run.summary_text(&OutletLines::default());
    assert!(
        text.contains("  fault: model_mismatch: TCP position reported 20.")
            && text.contains("the correction was ramped to its safe value"),
        "{text}"
    );
    // Ramped out: the run's last correction is zero.
    let log = std::fs::read_to_string(dir.join("run.csv")).unwrap();
    let last = log.lines().rev().find(|l| !l.starts_with('#')).unwrap();
    assert!(
        last.ends_with("model_mismatch|latched|stale_wrench")
            || last.contains("model_mismatch|latched"),
        "{last}"
    );
    let _ = std::fs::remove_dir_all(&dir);
}
