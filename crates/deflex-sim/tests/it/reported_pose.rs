//! The TCP pose the twin's robot controller reports (`CellStep::tcp_reported`, sent as KUKA RSI
//! `RIst` and ABB EGM feedback by `deflex cell --sim`): its own rigid kinematics at the measured
//! joints (the plant's chain, geometry errors included, no deflection), in the robot base frame.
//! Against the nominal model (deflex-model's forward kinematics, no code shared) it differs by
//! the plant's geometry errors only: a calibration's difference, far below the model check's
//! default tolerance (5 mm, 10 mrad) on every built-in robot's cell.

use deflex_control::{ModelCheckConfig, tcp_pose_mismatch};
use deflex_model::Data;
use deflex_sim::{Cell, CellConfig, ToolPath};

#[test]
fn the_reported_pose_is_the_model_s_within_a_calibration_s_difference() {
    let tolerance = ModelCheckConfig::default();
    for robot in [
        "tx200",
        "ur10",
        "ur10e",
        "kr210-r2700",
        "irb4600",
        "r2000ic-165f",
        "gp180",
    ] {
        let config = CellConfig::for_robot(robot).unwrap();
        let model = config.nominal_robot().unwrap();
        let path = ToolPath::paper_cone().truncated(20.0);
        let mut cell = Cell::new(&config, path, 1).unwrap();
        let mut data = Data::new();
        let (mut position, mut orientation) = (0.0f64, 0.0f64);
        let mut cycles = 0;
        while !cell.is_finished() && cycles < 2000 {
            let step = cell.step();
            let m = tcp_pose_mismatch(&model, &mut data, &step.q_measured_rad, &step.tcp_reported)
                .unwrap();
            position = position.max(m.position_m);
            orientation = orientation.max(m.orientation_rad);
            cycles += 1;
        }
        println!(
            "{robot}: reported vs nominal model: {:.4} mm, {:.4} mrad over {cycles} cycles",
            position * 1e3,
            orientation * 1e3
        );
        // The geometry errors are there (the controller is not the model) ...
        assert!(position > 1e-6, "{robot}: {position}");
        // ... and far inside the tolerance.
        assert!(
            position < tolerance.position_tolerance_m / 10.0
                && orientation < tolerance.orientation_tolerance_rad / 10.0,
            "{robot}: {position} m, {orientation} rad"
        );
    }
}
