//! Twin configuration tests: overrides, bounds named by field, nominal vs true mounting.

use deflex_sim::cell_config::{CellConfig, ErrorSources, TrackerConfig};

#[test]
fn toml_cell_sections_override_defaults() {
    let text = "[cell.controller]\nrate_hz = 500.0\n[cell.sensor]\nrate_hz = 7000.0\ntool_mass_kg = 5.0\n\
                [cell.sheet]\nrm_mpa = 250.0\n[cell.plant]\nj2_j3_coupling = 0.0\n[cell.errors]\nservo = false\n";
    let config = CellConfig::from_toml_str(text).unwrap();
    assert_eq!(config.controller.rate_hz, 500.0);
    assert_eq!(config.robot_period_s(), 0.002);
    assert_eq!(config.sensor.rate_hz, 7000.0);
    assert_eq!(config.tool_mass_kg(), 5.0);
    assert_eq!(config.sheet.rm_mpa, 250.0);
    assert!(!config.errors.servo && config.errors.geometry);
    assert_eq!(config.tracker, TrackerConfig::default());
    assert_eq!(
        CellConfig::from_toml_str("").unwrap(),
        CellConfig::default()
    );
    let sensor = config.sensor_in_flange();
    assert!((sensor.translation.vector.z - 0.030).abs() < 1e-12);
}

#[test]
fn bad_values_are_refused_with_the_field_name() {
    let cases = [
        ("[cell.sensor]\nrate_hz = 20000.0\n", "sensor.rate_hz"),
        ("[cell.sensor]\nrate = 1.0\n", "rate"),
        ("[cell.tracker]\nrate_hz = 100.0\n", "tracker.rate_hz"),
        // Issue 12: absurd magnitudes and NaN, each named.
        ("[cell.controller]\nrate_hz = 1e300\n", "controller.rate_hz"),
        (
            "[cell.controller]\nrate_hz = 1e-300\n",
            "controller.rate_hz",
        ),
        (
            "[cell.tracker]\nsamples_per_reading = 1000000000000\n",
            "samples_per_reading",
        ),
        (
            "[cell.tracker]\nsamples_per_reading = 1e12\n",
            "samples_per_reading",
        ),
        (
            "[cell.sensor]\nbias = [nan, 0.0, 0.0, 0.0, 0.0, 0.0]\n",
            "sensor.bias[0]",
        ),
        (
            "[cell.sensor]\nsensor_in_flange_xyz_m = [0.0, nan, 0.0]\n",
            "sensor.sensor_in_flange_xyz_m[1]",
        ),
        (
            "[cell.tracker]\nposition_m = [nan, 0.0, 0.0]\n",
            "tracker.position_m[0]",
        ),
        (
            "[cell.tracker]\nposition_m = [1e300, 0.0, 0.0]\n",
            "tracker.position_m[0]",
        ),
        (
            "[cell.plant]\nbase_stiffness = [5e-324, 0.0, 0.0]\n",
            "plant.base_stiffness[0]",
        ),
        (
            "[cell.plant]\ncenter_shift_m = [0.0, 0.0, 1e308, 0.0, 0.0, 0.0]\n",
            "plant.center_shift_m[2]",
        ),
        ("[cell.log]\nrate_hz = 1e9\n", "log.rate_hz"),
        (
            "[cell.controller]\nlookahead_s = inf\n",
            "controller.lookahead_s",
        ),
        (
            "[cell.process]\nfixture_stiffness_n_m = 1e20\n",
            "process.fixture_stiffness_n_m",
        ),
        ("[cell.sheet]\nsectors = 100000000\n", "sheet.sectors"),
        (
            "[cell.sheet]\nradial_step_mm = 1e-9\n",
            "sheet.radial_step_mm",
        ),
        (
            "[cell.part]\norigin_mm = [nan, 0.0, 0.0]\n",
            "part.origin_mm[0]",
        ),
        ("other = 1\n", "other"),
    ];
    for (text, field) in cases {
        let e = CellConfig::from_toml_str(text).unwrap_err().to_string();
        assert!(e.contains(field), "{text:?}: {e}");
    }
}

#[test]
fn the_controller_is_told_the_nominal_mounting_and_the_sensor_sits_elsewhere() {
    let config = CellConfig::default();
    let nominal = config.sensor_in_flange();
    let truth = config.true_sensor_in_flange();
    let offset = (truth.translation.vector - nominal.translation.vector).norm();
    assert!(offset > 0.5e-3 && offset < 2e-3, "{offset}");
    let (mass, _) = config.true_tool_load();
    assert!((mass - config.tool_mass_kg() - 0.15).abs() < 1e-12);
    let mut ideal = config.clone();
    ideal.errors = ErrorSources::all(false);
    assert_eq!(ideal.true_sensor_in_flange(), ideal.sensor_in_flange());
    assert_eq!(ideal.true_tool_load().0, ideal.tool_mass_kg());
}
