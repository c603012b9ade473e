//! The F/T sensor: a contact wrench read as a lever moment, bias and tool gravity, contact and
//! saturation, gain error, drift and the true mounting, noise and rate.

use deflex_model::spatial::pose_from_xyz_rpy;
use deflex_model::{Pose, Wrench};
use deflex_sim::cell_config::{CellConfig, SensorConfig};
use deflex_sim::sensor::{ForceSensor, contact_in_sensor};
use nalgebra::Vector3;
use rand::SeedableRng;
use rand_chacha::ChaCha8Rng;

#[test]
fn a_contact_force_below_the_sensor_reads_as_a_lever_moment_by_hand() {
    // Sensor 0.2 m above the tool tip, axes turned by 90° about z (x_s = y_world). A force
    // of 100 N along world x at the tip: f_s = (0, −100, 0); about the sensor origin the
    // moment is (tip − S) × f = (0, 0, −0.2) × (100, 0, 0) = (0, −20, 0) N·m in world axes,
    // i.e. (−20, 0, 0) N·m in sensor axes.
    let sensor = pose_from_xyz_rpy([1.0, 0.5, 0.3], [0.0, 0.0, std::f64::consts::FRAC_PI_2]);
    let tip = Vector3::new(1.0, 0.5, 0.1);
    let reading = contact_in_sensor(&Wrench::new(100.0, 0.0, 0.0, 0.0, 0.0, 0.0), &tip, &sensor);
    let expected = Wrench::new(0.0, -100.0, 0.0, -20.0, 0.0, 0.0);
    assert!((reading - expected).norm() < 1e-12, "{reading}");
}

fn quiet() -> SensorConfig {
    SensorConfig {
        noise_sigma: [0.0; 6],
        ..SensorConfig::default()
    }
}

#[test]
fn unloaded_reading_is_bias_plus_gravity_and_rotates_with_the_tool() {
    let config = quiet();
    let mut sensor = ForceSensor::new(&config, Pose::identity(), ChaCha8Rng::seed_from_u64(1));
    let at = Vector3::zeros();
    // Tool pointing down (flange z = −world z): gravity reads +m g along sensor z.
    let down = pose_from_xyz_rpy([1.5, 0.0, 0.0], [std::f64::consts::PI, 0.0, 0.0]);
    let s = sensor.sample(0.0, &down, &Wrench::zeros(), &at);
    let mg = config.tool_mass_kg * config.gravity_m_s2;
    assert!((s.wrench_sensor[2] - (mg + config.bias[2])).abs() < 1e-9);
    assert!((s.wrench_sensor[0] - config.bias[0]).abs() < 1e-9);
    // Tool horizontal along world x: gravity now along sensor x (world −z = sensor x).
    let side = pose_from_xyz_rpy([1.5, 0.0, 0.0], [0.0, std::f64::consts::FRAC_PI_2, 0.0]);
    let s = sensor.sample(0.0, &side, &Wrench::zeros(), &at);
    assert!(
        (s.wrench_sensor[0] - (mg + config.bias[0])).abs() < 1e-9,
        "{s:?}"
    );
    assert!((s.wrench_sensor[2] - config.bias[2]).abs() < 1e-9);
    // The COM offset along sensor z gives a moment about sensor y: com × f.
    let expected_ty = config.tool_com_in_sensor_m[2] * mg + config.bias[4];
    assert!((s.wrench_sensor[4] - expected_ty).abs() < 1e-9, "{s:?}");
}

#[test]
fn contact_wrench_appears_and_saturates() {
    let config = quiet();
    let mut sensor = ForceSensor::new(&config, Pose::identity(), ChaCha8Rng::seed_from_u64(1));
    let down = pose_from_xyz_rpy([1.5, 0.0, 0.0], [std::f64::consts::PI, 0.0, 0.0]);
    let at = Vector3::new(1.5, 0.0, 0.0);
    let up = Wrench::new(0.0, 0.0, 1000.0, 0.0, 0.0, 0.0);
    let s = sensor.sample(0.0, &down, &up, &at);
    let mg = config.tool_mass_kg * config.gravity_m_s2;
    // World +z is sensor −z when pointing down.
    assert!((s.wrench_sensor[2] - (-1000.0 + mg + config.bias[2])).abs() < 1e-9);
    assert!(!s.saturated);
    let huge = Wrench::new(5000.0, 0.0, 0.0, 0.0, 0.0, 0.0);
    let s = sensor.sample(0.0, &down, &huge, &at);
    assert!(s.saturated);
    assert!(s.wrench_sensor[0].abs() <= config.range[0] + 1e-12);
}

#[test]
fn gain_error_drift_and_true_mounting_reach_the_reading() {
    let mut cell = CellConfig::default();
    cell.sensor.noise_sigma = [0.0; 6];
    let mut sensor = ForceSensor::for_cell(&cell, ChaCha8Rng::seed_from_u64(1));
    let down = pose_from_xyz_rpy([1.5, 0.0, 0.0], [std::f64::consts::PI, 0.0, 0.0]);
    let at = Vector3::new(1.5, 0.0, -0.2);
    let push = Wrench::new(0.0, 0.0, 1000.0, 0.0, 0.0, 0.0);
    let unloaded = sensor.sample(0.0, &down, &Wrench::zeros(), &at);
    let loaded = sensor.sample(0.0, &down, &push, &at);
    // The contact part of Fz reads (1 + gain) × 1000 N (up to the 0.1° tilt of the mounting).
    let fz = unloaded.wrench_sensor[2] - loaded.wrench_sensor[2];
    let expected = 1000.0 * (1.0 + cell.sensor.gain_error[2]);
    assert!((fz - expected).abs() < 0.01, "{fz} vs {expected}");
    // The bias drifts linearly in time.
    let later = sensor.sample(100.0, &down, &Wrench::zeros(), &at);
    let drift = later.wrench_sensor[2] - unloaded.wrench_sensor[2];
    assert!((drift - 100.0 * cell.sensor.bias_drift_per_s[2]).abs() < 1e-9);
    // Every error off: the ideal sensor of the nominal mounting.
    cell.errors = deflex_sim::cell_config::ErrorSources::all(false);
    let mut ideal = ForceSensor::for_cell(&cell, ChaCha8Rng::seed_from_u64(1));
    let plain = ForceSensor::new(
        &cell.sensor,
        cell.sensor_in_flange(),
        ChaCha8Rng::seed_from_u64(1),
    )
    .ideal_reading(&down, &push, &at);
    let got = ideal.sample(50.0, &down, &push, &at);
    for i in 0..6 {
        assert!((got.wrench_sensor[i] - plain[i] - cell.sensor.bias[i]).abs() < 1e-9);
    }
}

#[test]
fn noise_has_the_configured_spread_and_rate_is_kept() {
    let config = SensorConfig::default();
    let mut sensor = ForceSensor::new(&config, Pose::identity(), ChaCha8Rng::seed_from_u64(7));
    let mut out = Vec::new();
    sensor.samples_until(
        1.0 - 1e-6,
        &Pose::identity(),
        &Wrench::zeros(),
        &Vector3::zeros(),
        &mut out,
    );
    assert_eq!(out.len(), 1000);
    let mean: f64 = out.iter().map(|s| s.wrench_sensor[0]).sum::<f64>() / 1000.0;
    let var: f64 = out
        .iter()
        .map(|s| (s.wrench_sensor[0] - mean).powi(2))
        .sum::<f64>()
        / 999.0;
    assert!((mean - config.bias[0]).abs() < 0.05, "{mean}");
    assert!((var.sqrt() / config.noise_sigma[0] - 1.0).abs() < 0.1);
}
