//! The twin's own telemetry stream (ground truth, no controller) at the rows of its log, and a
//! watched run's stop (the controller's telemetry with a model identified from the twin's
//! campaign is in deflex-app's tests).

use deflex_sim::{CellConfig, ToolPath};

/// The twin's own stream (open loop, no controller): one sample per log row, at the row's time,
/// carrying the row's ground truth; watching does not change the run.
#[test]
fn the_twin_stream_samples_every_log_row_and_changes_nothing() {
    use deflex_sim::twin::{RunWatch, TwinCellStream};
    use std::sync::{Arc, Mutex};
    let cell = CellConfig::default();
    let path = ToolPath::paper_cone().truncated(120.0);
    let samples = Arc::new(Mutex::new(Vec::new()));
    let store = samples.clone();
    let stream = TwinCellStream::new(cell.nominal_robot().unwrap())
        .with_sink(Box::new(move |s| store.lock().unwrap().push(*s)));
    let mut watch = RunWatch::new(Some(stream), None, None);
    let watched = deflex_sim::run_program_observed(
        &cell,
        path.clone(),
        None,
        4,
        None,
        Some(&mut watch),
        &mut |_| {},
    )
    .unwrap();
    drop(watch);
    let plain = deflex_sim::run_forming(&cell, path, 4, None).unwrap();
    assert_eq!(watched.log.to_csv(), plain.log.to_csv());
    let samples = samples.lock().unwrap();
    assert_eq!(samples.len(), watched.log.rows.len());
    for (s, row) in samples.iter().zip(&watched.log.rows) {
        assert_eq!(s.time_s, row.time_s);
        let e = nalgebra::Vector3::from(s.truth_error_m);
        assert!((e - row.truth.path_error_m()).norm() < 1e-15);
        assert_eq!(s.wrench_raw, row.sensor.wrench_sensor);
        assert!((nalgebra::Vector6::from(s.wrench_tcp) - row.truth.wrench).norm() < 1e-9);
        assert_eq!(s.correction, row.truth.correction);
        // No controller: no tracking error.
        assert!(s.error.iter().all(|v| v.is_nan()));
    }
    let last = samples.last().unwrap();
    assert_eq!(
        deflex_telemetry::StreamSource::TwinCell.phase_name(last.phase_code),
        "finished"
    );
    // The TCP is the forward kinematics of the reported joints: the program position (TCP −
    // applied ξ) stays within a millimetre of the desired path point plus the part origin.
    let origin = cell.part_frame().translation.vector;
    for (s, row) in samples.iter().zip(&watched.log.rows).step_by(50) {
        let desired = origin + row.truth.desired_m;
        assert!((s.program_position_m() - desired).norm() < 1e-3);
    }
}

/// A watch's stop flag ends the run before the end of its path.
#[test]
fn a_stop_flag_ends_a_watched_run() {
    use std::sync::atomic::AtomicBool;
    static STOP: AtomicBool = AtomicBool::new(true);
    let mut watch = deflex_sim::twin::RunWatch::new(None, None, Some(&STOP));
    let e = deflex_sim::run_program_observed(
        &CellConfig::default(),
        ToolPath::paper_cone().truncated(50.0),
        None,
        1,
        None,
        Some(&mut watch),
        &mut |_| {},
    )
    .expect_err("stopped");
    assert!(matches!(e, deflex_sim::SimError::Stopped { .. }), "{e}");
}
