//! Campaign tests: the paper's grid, measuring the plant, the spiral.

use deflex_model::{Pose, Wrench};
use deflex_sim::cell_config::CellConfig;
use deflex_sim::plant::Plant;
use deflex_sim::twin_campaign::{GridParams, SpiralParams, run_campaign, spiral, validation_grid};
use nalgebra::Vector3;

#[test]
fn grid_has_200_poses_on_the_paper_plane() {
    let config = CellConfig::default();
    let plan = validation_grid(&config, &GridParams::for_cell(&config).unwrap()).unwrap();
    assert_eq!(plan.len(), 400);
    let robot = config.nominal_robot().unwrap();
    for row in plan.iter().step_by(37) {
        let p = robot.tcp_pose(&row.q_rad).unwrap().translation.vector;
        assert!((p - Vector3::from(row.point_m)).norm() < 1e-8);
        assert!(
            (p.z - 0.1).abs() < 1e-8 && (p.x - 1.5).abs() <= 0.3 + 1e-9 && p.y.abs() <= 0.3 + 1e-9
        );
    }
}

#[test]
fn campaign_measures_the_plant_not_the_model() {
    let config = CellConfig::default();
    let plan: Vec<_> = validation_grid(&config, &GridParams::paper())
        .unwrap()
        .into_iter()
        .take(20)
        .collect();
    let meas = run_campaign(&config, &plan, 5).unwrap();
    assert_eq!(meas.len(), plan.len());
    let nominal = config.nominal_robot().unwrap();
    let mut plant = Plant::new(&config.plant, &nominal, &Pose::identity(), true).unwrap();
    for (m, p) in meas.iter().zip(&plan) {
        let d = m.displacement_m.unwrap();
        // Downward load: the TCP goes down by about a millimetre.
        assert!(d[2] < -0.5e-3 && d[2] > -5e-3, "{d:?}");
        let mut q = [0.0; 6];
        q.copy_from_slice(&p.q_rad);
        plant.set_configuration(&q);
        let tcp = plant.tcp_pose().translation.vector;
        let truth = plant.point_displacement(&tcp, 6, &tcp, 6, &Wrench::from_row_slice(&p.wrench));
        let s = m.sigma_m.unwrap();
        assert!(
            (d[2] - truth[2]).abs() < 6.0 * s + 2e-6,
            "{} vs {}",
            d[2],
            truth[2]
        );
    }
    // Deterministic under the seed.
    assert_eq!(run_campaign(&config, &plan, 5).unwrap(), meas);
    assert_ne!(run_campaign(&config, &plan, 6).unwrap(), meas);
}

#[test]
fn spiral_is_2_7_m_at_50_hz() {
    let config = CellConfig::default();
    let short = SpiralParams {
        length_m: 0.05,
        ..SpiralParams::default()
    };
    let rows = spiral(&config, &short, 1).unwrap();
    assert_eq!(rows.len(), 251);
    let a = Vector3::from(rows[0].point_m);
    let b = Vector3::from(rows[250].point_m);
    assert!(((a - b).norm() - 0.05).abs() < 1e-3);
    // Tracked points: the plant's geometry error and the tracker's registration and noise
    // keep them within a millimetre of the programmed ones.
    assert!((a.z - 0.3).abs() < 1e-3 && (a.x - 1.75).abs() < 1e-3, "{a}");
    let full = SpiralParams::default();
    assert_eq!((full.length_m / full.speed_m_s * 50.0) as usize, 13_500);
}
