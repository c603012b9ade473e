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

/// [`WrenchProcessor::raw_reading`] is the inverse of the path: over many joint values, the
/// reading it gives for a TCP wrench comes back through [`WrenchProcessor::process`] (filter
/// off) as that wrench, and its parts are those written out here (force `Rᵀ f`, moment about the
/// sensor origin `Rᵀ (m + (p_tcp − p_S) × f)`, plus bias and tool weight).
#[test]
fn raw_reading_is_the_inverse_of_the_path() {
    use deflex_model::{Data, builtin};
    let robot = builtin("tx200").unwrap();
    let config = WrenchConfig {
        sensor_in_flange: pose_from_xyz_rpy([0.01, 0.0, 0.05], [0.1, 0.0, 0.3]),
        tool_in_sensor: ToolLoad {
            mass_kg: 7.5,
            centre_of_mass_m: nalgebra::Vector3::new(0.01, -0.02, 0.12),
        },
        ..WrenchConfig::default()
    };
    let mut p = WrenchProcessor::new(config);
    let bias = Wrench::new(3.0, -2.0, 5.0, 0.1, -0.2, 0.05);
    p.set_bias(bias);
    let mut data = Data::new();
    let mut worst: f64 = 0.0;
    for k in 0..200 {
        let t = k as f64;
        let q = [
            (t * 0.37).sin(),
            0.6 + 0.4 * (t * 0.11).cos(),
            1.2 + 0.3 * (t * 0.23).sin(),
            (t * 0.53).cos(),
            0.7 + 0.5 * (t * 0.19).sin(),
            t * 0.29,
        ];
        robot.forward_kinematics(&mut data, &q).unwrap();
        let w = Wrench::new(
            300.0 * (t * 0.7).sin(),
            -200.0,
            900.0 * (t * 0.13).cos(),
            1.0,
            2.0 * (t * 0.31).sin(),
            -1.0,
        );
        let raw = p.raw_reading(&w, &data);
        // Written out: the sensor's frame, the contact moved to its origin and axes.
        let sensor = data.flange * config.sensor_in_flange;
        let r_t = sensor.rotation.inverse();
        let f = nalgebra::Vector3::new(w[0], w[1], w[2]);
        let m = nalgebra::Vector3::new(w[3], w[4], w[5])
            + (data.tcp_position() - sensor.translation.vector).cross(&f);
        let (f_s, m_s) = (r_t * f, r_t * m);
        let g = p.gravity_in_sensor(&sensor);
        let expected =
            Wrench::from_fn(|i, _| bias[i] + g[i] + if i < 3 { f_s[i] } else { m_s[i - 3] });
        let back = p.process(&raw, &data, 0.01).tcp_world;
        for i in 0..6 {
            worst = worst
                .max((raw[i] - expected[i]).abs())
                .max((back[i] - w[i]).abs());
        }
    }
    assert!(worst < 1e-9, "residual {worst}");
}
