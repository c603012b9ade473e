//! The wrench path: bias, tool gravity, low-pass, TCP wrench ([`deflex_control::wrench`]).

use deflex_control::wrench::*;
use deflex_model::spatial::pose_from_xyz_rpy;
use deflex_model::{ToolLoad, Wrench};

#[test]
fn gravity_compensation_is_exact_over_many_orientations() {
    let config = WrenchConfig {
        sensor_in_flange: pose_from_xyz_rpy([0.0, 0.0, 0.05], [0.0, 0.0, 0.3]),
        tool_in_sensor: ToolLoad {
            mass_kg: 7.5,
            centre_of_mass_m: nalgebra::Vector3::new(0.01, -0.02, 0.12),
        },
        ..WrenchConfig::default()
    };
    let mut p = WrenchProcessor::new(config);
    let bias = [3.0, -2.0, 5.0, 0.1, -0.2, 0.05];
    // Tare at one orientation (reading = bias + gravity there).
    let tare_pose = pose_from_xyz_rpy([1.0, 0.0, 1.0], [0.2, 2.8, -0.4]);
    let g0 = p.gravity_in_sensor(&tare_pose);
    let raw0 = Wrench::from_fn(|i, _| bias[i] + g0[i]);
    p.tare_add(&raw0, &tare_pose);
    assert!(p.tare_finish());
    let mut worst: f64 = 0.0;
    for k in 0..500 {
        let t = k as f64;
        let pose = pose_from_xyz_rpy(
            [0.0; 3],
            [(t * 0.37).sin() * 3.0, (t * 0.11).cos() * 1.5, t * 0.73],
        );
        let g = p.gravity_in_sensor(&pose);
        let raw = Wrench::from_fn(|i, _| bias[i] + g[i]);
        let out = p.compensate(&raw, &pose);
        worst = out.iter().fold(worst, |a, v| a.max(v.abs()));
    }
    assert!(worst < 1e-12, "residual {worst}");
}

#[test]
fn lowpass_converges_and_is_off_by_default() {
    let mut off = WrenchProcessor::new(WrenchConfig::default());
    let ones = Wrench::repeat(1.0);
    assert_eq!(off.filter(&ones, 0.01), ones);
    let mut on = WrenchProcessor::new(WrenchConfig {
        lowpass_hz: Some(10.0),
        ..WrenchConfig::default()
    });
    on.filter(&Wrench::zeros(), 0.01);
    let y = on.filter(&ones, 0.01);
    let alpha = 1.0 - (-2.0 * std::f64::consts::PI * 10.0 * 0.01f64).exp();
    assert!((y[0] - alpha).abs() < 1e-12);
    for _ in 0..200 {
        on.filter(&ones, 0.01);
    }
    assert!((on.filter(&ones, 0.01)[5] - 1.0).abs() < 1e-9);
}
