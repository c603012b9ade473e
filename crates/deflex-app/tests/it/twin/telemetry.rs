//! The in-process twin publishes the same telemetry as `deflex run` with a model identified
//! from the twin's campaign: one sample per control cycle, labelled SIMULATED, matching what the
//! controller produced, with the twin's path error (the twin's own stream is in deflex-sim's
//! tests).

use crate::twin::common;
use deflex_runtime::telemetry::{StreamSource, Telemetry};
use deflex_sim::twin::{TwinController, TwinProgram, controller_config_for, run_twin_controller};
use deflex_sim::{CellConfig, ToolPath};

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
    assert_eq!(info.source, StreamSource::Twin);
    assert!(info.simulated);
    assert_eq!(info.protocol, "in-process");
    let telemetry = Telemetry::new(info, 1 << 16);
    let mut sink = telemetry.subscribe();
    let (publisher, ring, _info) = telemetry.into_parts();
    twin.set_telemetry(Some(publisher));
    let program = TwinProgram {
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
        // The twin's path error of the cycle, for the telemetry only (the law never reads it).
        assert!(s.truth_error_m.iter().all(|v| v.is_finite()));
    }
    // Sampled every 10 ms of the 4 ms robot cycles: at most the run's maximum over every
    // cycle (the TX200 cell's base axes are the part frame's), and close to it.
    let largest = samples
        .iter()
        .map(|s| nalgebra::Vector3::from(s.truth_error_m).norm())
        .fold(0.0, f64::max);
    let stats = &run.forming.summary;
    assert!(largest <= stats.max_error_norm_mm * 1e-3 + 1e-12);
    assert!(largest >= 0.8 * stats.max_error_norm_mm * 1e-3, "{largest}");
    let last = samples.last().unwrap();
    assert_eq!(last.phase(), run.phase);
    assert!(last.sensor_samples > 0 && last.tcp_position().norm() > 0.5);
}

/// The law is blind to the truth: the same inputs with and without it give the same
/// corrections, bit for bit; only the telemetry carries it.
#[test]
fn the_truth_reaches_the_telemetry_not_the_law() {
    use deflex_sim::{ControllerInput, CorrectionController, SensorSample};
    let cell = CellConfig::default();
    let make = || {
        TwinController::new(
            common::calibrated_model(),
            controller_config_for(&cell),
            false,
        )
        .unwrap()
    };
    let (mut blind, mut told) = (make(), make());
    let telemetry = Telemetry::new(told.session_info(cell.robot_period_s()), 4096);
    let mut sink = telemetry.subscribe();
    let (publisher, _ring, _) = telemetry.into_parts();
    told.set_telemetry(Some(publisher));
    let q = deflex_model::TX200_FORMING_Q_DEG.map(f64::to_radians);
    let truth = deflex_sim::cell::TruthState {
        desired_m: nalgebra::Vector3::new(0.01, 0.0, -0.002),
        commanded_m: nalgebra::Vector3::zeros(),
        true_m: nalgebra::Vector3::new(0.0105, -0.0002, -0.0012),
        wrench: deflex_model::Wrench::new(0.0, 0.0, 900.0, 0.0, 0.0, 0.0),
        deflection: deflex_model::Displacement::zeros(),
        contact: deflex_sim::sheet::ContactState {
            penetration_m: 0.0,
            depth_m: 0.0,
            flow_n: 0.0,
            force_n: 900.0,
        },
        correction: [0.0; 6],
    };
    for k in 0..200 {
        let t = 0.01 * (k + 1) as f64;
        let fz = if k < 40 { 0.0 } else { -600.0 - k as f64 };
        let samples = [SensorSample {
            time_s: t,
            wrench_sensor: [5.0, -3.0, fz - 31.0, 0.2, 0.1, 0.0],
            saturated: false,
        }];
        let input = ControllerInput {
            time_s: t,
            q_measured_rad: &q,
            wrench_samples: &samples,
            truth: None,
        };
        let a = blind.step(&input);
        let b = told.step(&ControllerInput {
            truth: Some(&truth),
            ..input
        });
        assert_eq!(a, b, "cycle {k}");
    }
    let mut n = 0;
    sink.drain(|s| {
        n += 1;
        let e = nalgebra::Vector3::from(s.truth_error_m);
        assert!((e - truth.path_error_m()).norm() < 1e-15);
    });
    assert_eq!(n, 200);
}
