//! The in-process twin publishes the same telemetry as `deflex run`: one sample per control
//! cycle, labelled SIMULATED, matching what the controller produced.

use crate::common;
use deflex_runtime::telemetry::{Source, Telemetry};
use deflex_sim::{CellConfig, ToolPath};
use deflex_twin::{Program, TwinController, controller_config_for, run_twin_controller};

#[test]
fn the_twin_publishes_one_sample_per_cycle() {
    let cell = CellConfig::default();
    let mut twin = TwinController::new(
        common::calibrated_model(),
        controller_config_for(&cell),
        true,
    )
    .unwrap();
    let info = twin.session_info(cell.robot_period_s());
    assert_eq!(info.source, Source::Twin);
    assert!(info.simulated);
    assert_eq!(info.protocol, "in-process");
    let telemetry = Telemetry::new(info, 1 << 16);
    let mut sink = telemetry.subscribe();
    let (publisher, ring, _info) = telemetry.into_parts();
    twin.set_telemetry(Some(publisher));
    let program = Program {
        path: ToolPath::paper_cone().truncated(150.0),
        reference: None,
    };
    let run = run_twin_controller(&cell, &program, 3, twin, &mut |_| {}).unwrap();
    assert!(ring.is_closed(), "the stream ends with the run");
    let mut samples = Vec::new();
    sink.drain(|s| samples.push(*s));
    assert_eq!(sink.lost(), 0);
    assert_eq!(samples.len(), run.trace.len());
    assert!(samples.len() > 100);
    for (k, (s, out)) in samples.iter().zip(&run.trace).enumerate() {
        assert_eq!(s.cycle, k as u64 + 1);
        assert_eq!(s.time_s, out.time_s);
        assert_eq!(s.correction, out.xi);
        assert_eq!(s.deflection, out.delta_s_hat);
        assert_eq!(s.wrench_tcp, out.wrench_tcp);
        assert_eq!(s.q().len(), 6);
        // The truth is the twin's, not the controller's: not in this adapter's samples.
        assert!(s.truth_error_m.iter().all(|v| v.is_nan()));
    }
    let last = samples.last().unwrap();
    assert_eq!(last.phase(), run.phase);
    assert!(last.sensor_samples > 0 && last.tcp_position().norm() > 0.5);
}
