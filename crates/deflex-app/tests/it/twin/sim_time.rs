//! `deflex run`'s threads in the twin's simulated time (SIMULATED).

use crate::twin::common;
use deflex_runtime::session::SessionEnd;
use deflex_sim::twin::{controller_config_for, run_closed_loop, run_runtime_in_sim_time};
use deflex_sim::{CellConfig, ToolPath};
use std::time::Instant;

/// The same threads as `deflex run`, paced by a driven simulated clock against the twin,
/// agree with the in-process run, and the run ends on the robot's silence alone (the
/// sensor streams on). The wall time is printed, not asserted: timing belongs in benches.
#[test]
fn runtime_threads_in_simulated_time_agree_with_in_process() {
    let _turn = crate::twin::cores_alone();
    let cell = CellConfig::default();
    let model = common::calibrated_model();
    let path = ToolPath::paper_cone().truncated(400.0);
    let config = controller_config_for(&cell);
    let wall = Instant::now();
    let (summary, stats) =
        run_runtime_in_sim_time(&cell, path.clone(), 5, model.clone(), config, None).unwrap();
    let wall_s = wall.elapsed().as_secs_f64();
    let inproc = run_closed_loop(&cell, path, 5, model, config, false, &mut |_| {}).unwrap();
    let (a, b) = (
        stats.max_error_norm_m * 1e3,
        inproc.forming.summary.max_error_norm_mm,
    );
    eprintln!(
        "runtime in simulated time: {} cycles in {wall_s:.2} s wall, max error {a:.4} mm \
         (in-process {b:.4} mm), max F {:.0} N, fault {:?}",
        summary.cycles, stats.max_force_norm_n, summary.fault
    );
    assert!(summary.error.is_none(), "{:?}", summary.error);
    assert!(summary.cycles > 3000);
    // Normal forming does not trip the contact-runaway guard (on by default).
    assert_eq!(summary.runaway_events, 0, "{:?}", summary.first_runaway);
    assert!((a - b).abs() <= 0.1 * b + 0.005, "{a} vs {b}");
    // The end of the robot's telegrams is the end of its program, not a fault.
    assert_eq!(summary.fault, None);
    assert_eq!(summary.end, SessionEnd::RobotFinished);
}
