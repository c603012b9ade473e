//! Plant tests: against deflex-model only where the two must agree (small loads, the same
//! springs), and against independent oracles (a closed-form lever, the stationarity of the
//! potential energy) where they must not.

use deflex_model::{Data, Pose, Robot, Wrench, builtin};
use deflex_sim::chain::ChainState;
use deflex_sim::plant::{Plant, PlantConfig};
use nalgebra::Vector3;

fn paper_q() -> [f64; 6] {
    deflex_model::TX200_FORMING_Q_DEG.map(f64::to_radians)
}

/// The TX200 of the built-in file with a 0.2 m tool.
fn tx200_with_tool() -> Robot {
    let mut robot = builtin("tx200").unwrap();
    robot.tool = deflex_model::spatial::pose_from_xyz_rpy([0.0, 0.0, 0.2], [0.0; 3]);
    robot
}

/// A plant with exactly the model's springs (Table 1, J3.x centre shifted 0.4 m) and nothing
/// else.
fn same_springs_as_the_model(large_rotation: bool) -> PlantConfig {
    PlantConfig {
        joint_stiffness: [
            [0.0, 0.0, 2.32e6],
            [0.0, 0.0, 1.76e6],
            [1.45e6, 0.0, 2.04e6],
            [0.0, 0.0, 0.09e6],
            [0.0, 0.0, 0.02e6],
            [0.0; 3],
        ],
        center_shift_m: [0.0, 0.0, 0.4, 0.0, 0.0, 0.0],
        base_stiffness: [0.0; 3],
        j2_j3_coupling: 0.0,
        wrist_lost_motion_rad: [0.0; 3],
        large_rotation,
        ..PlantConfig::default()
    }
}

#[test]
fn the_model_file_and_the_springs_agree_with_deflex_model_at_small_loads() {
    let robot = tx200_with_tool();
    let configs = [
        paper_q(),
        [0.4, 0.3, 1.2, 0.5, 0.8, -0.4],
        [-0.9, 0.9, 0.6, -1.0, 1.2, 0.3],
    ];
    for large_rotation in [false, true] {
        let config = same_springs_as_the_model(large_rotation);
        let mut plant = Plant::new(&config, &robot, &Pose::identity(), false).unwrap();
        for q in configs {
            plant.set_configuration(&q);
            let mut data = Data::new();
            robot.forward_kinematics(&mut data, &q).unwrap();
            // Same undeformed TCP (two independent kinematics).
            assert!((plant.tcp_pose().to_homogeneous() - data.tcp.to_homogeneous()).norm() < 1e-12);
            // 1 N and 0.1 N·m: the geometric stiffness and the second-order kinematics are
            // ~10⁻⁵ of the first-order answer..
            let w = Wrench::new(0.6, -0.5, 1.0, 0.05, -0.1, 0.02);
            let model = robot.tcp_deflection(&data, &w);
            let ours = plant.solve_tcp(&w);
            let tolerance = 1e-4;
            assert!(
                (ours - model).norm() <= tolerance * model.norm(),
                "large_rotation {large_rotation}, q {q:?}: plant {ours} vs model {model}"
            );
            let first = plant.first_order_deflection(&w);
            assert!((first - model).norm() <= 1e-12 * model.norm());
        }
    }
}

#[test]
fn a_single_spring_lever_matches_its_closed_form_at_large_load() {
    // Only J2.z, soft; arm stretched horizontally along x0 (q2 = 90°): the TCP is a rigid lever
    // of length L = 2.194 − 0.25 + 0.2 (tool along the arm) from the J2 axis. A dead load F
    // along −z at the TCP: equilibrium k θ = F L cos θ (the lever arm shrinks as it turns), TCP
    // at (0.25 + L cos θ, 0, −L sin θ). Solved here by Newton, independently of the plant.
    let mut robot = builtin("tx200").unwrap();
    robot.tool = deflex_model::spatial::pose_from_xyz_rpy([0.0, 0.0, 0.2], [0.0; 3]);
    let k = 1.0e5;
    let config = PlantConfig {
        joint_stiffness: [
            [0.0; 3],
            [0.0, 0.0, k],
            [0.0; 3],
            [0.0; 3],
            [0.0; 3],
            [0.0; 3],
        ],
        center_shift_m: [0.0; 6],
        base_stiffness: [0.0; 3],
        j2_j3_coupling: 0.0,
        wrist_lost_motion_rad: [0.0; 3],
        ..PlantConfig::default()
    };
    let mut plant = Plant::new(&config, &robot, &Pose::identity(), false).unwrap();
    // q5 = 0 keeps the tool along the arm (flange z along x0 at q2 = 90°, q3 = 0).
    let q = [0.0, 90f64.to_radians(), 0.0, 0.0, 0.0, 0.0];
    plant.set_configuration(&q);
    let tcp = plant.tcp_pose().translation.vector;
    let length = tcp.x - 0.25;
    assert!((length - 2.144).abs() < 1e-12, "{tcp}");
    let f = 3000.0;
    let mut theta = f * length / k;
    for _ in 0..50 {
        let g = k * theta - f * length * theta.cos();
        let dg = k + f * length * theta.sin();
        theta -= g / dg;
    }
    let d = plant.solve_tcp(&Wrench::new(0.0, 0.0, -f, 0.0, 0.0, 0.0));
    let expected = Vector3::new(0.25 + length * theta.cos(), 0.0, -length * theta.sin()) - tcp;
    let got = Vector3::new(d[0], d[1], d[2]);
    assert!((got - expected).norm() < 1e-9, "{got} vs {expected}");
    // The first-order answer misses the shortening of the lever arm (0.38 mm here).
    let linear = f * length * length / k;
    assert!((got.z + linear).abs() > 0.2e-3, "{} vs {linear}", got.z);
}

#[test]
fn the_equilibrium_is_a_stationary_point_of_the_potential_energy() {
    // Linear springs, a dead force at the TCP: V(θ) = ½ Σ k θ² − F·p(θ). Its gradient, by
    // central differences of the plant's own chain, vanishes at the solution.
    let config = PlantConfig {
        j2_j3_coupling: 0.0,
        wrist_lost_motion_rad: [0.0; 3],
        ..PlantConfig::default()
    };
    let robot = tx200_with_tool();
    let mut plant = Plant::new(&config, &robot, &Pose::identity(), true).unwrap();
    plant.set_configuration(&paper_q());
    let force = Vector3::new(-450.0, 180.0, 1400.0);
    plant.solve_tcp(&Wrench::new(force.x, force.y, force.z, 0.0, 0.0, 0.0));
    let theta = plant.spring_rotations();
    let stiffness: Vec<f64> = config.springs().iter().map(|(_, k)| *k).collect();
    let n = stiffness.len();
    assert_eq!(theta.len(), n);
    let q = paper_q();
    let energy = |t: &[f64]| -> f64 {
        let mut state = ChainState::default();
        plant.chain().evaluate(&q, t, &mut state);
        let springs: f64 = (0..n).map(|s| 0.5 * stiffness[s] * t[s] * t[s]).sum();
        springs - force.dot(&state.tcp.translation.vector)
    };
    for s in 0..n {
        let h = 1e-7;
        let mut plus = theta[..n].to_vec();
        let mut minus = plus.clone();
        plus[s] += h;
        minus[s] -= h;
        let gradient = (energy(&plus) - energy(&minus)) / (2.0 * h);
        let scale = stiffness[s] * theta[s].abs();
        assert!(
            gradient.abs() < 1e-4 * scale + 1e-3,
            "spring {s}: ∂V/∂θ = {gradient} (k θ = {scale})"
        );
    }
}

#[test]
fn plant_is_softer_than_table_1_and_not_linear() {
    let robot = tx200_with_tool();
    let mut plant = Plant::new(&PlantConfig::default(), &robot, &Pose::identity(), true).unwrap();
    plant.set_configuration(&paper_q());
    let w = Wrench::new(0.0, 0.0, 1250.0, 0.0, 0.0, 0.0);
    let true_dz = plant.solve_tcp(&w)[2];
    let mut data = Data::new();
    robot.forward_kinematics(&mut data, &paper_q()).unwrap();
    let model_dz = robot.tcp_deflection(&data, &w)[2];
    assert!(true_dz > 1.15 * model_dz, "{true_dz} vs {model_dz}");
    // Not linear: doubling a small wrist load does not double the deflection (the lost motion
    // starts outside the hysteresis band).
    let small = Wrench::new(10.0, 0.0, 0.0, 0.0, 0.0, 0.0);
    let d1 = plant.solve_tcp(&small)[0];
    let d2 = plant.solve_tcp(&(small * 2.0))[0];
    assert!((d2 / d1 - 2.0).abs() > 0.02, "{d1} {d2}");
}

#[test]
fn geometric_stiffness_and_the_floor_pivot_are_visible_at_the_forming_wrench() {
    let robot = tx200_with_tool();
    let w = Wrench::new(-430.0, 150.0, 1250.0, 0.0, 0.0, 0.0);
    let deflection = |config: &PlantConfig| {
        let mut plant = Plant::new(config, &robot, &Pose::identity(), false).unwrap();
        plant.set_configuration(&paper_q());
        plant.solve_tcp(&w)
    };
    let large = deflection(&PlantConfig::default());
    let first = deflection(&PlantConfig {
        large_rotation: false,
        ..PlantConfig::default()
    });
    let geometric = (large - first).fixed_rows::<3>(0).norm();
    eprintln!(
        "forming wrench: |δp| {:.3} mm, large-rotation part {:.1} µm",
        large.fixed_rows::<3>(0).norm() * 1e3,
        geometric * 1e6
    );
    assert!(geometric > 5e-6 && geometric < 0.3e-3, "{geometric}");
    // The base tilt pivots on the floor, 0.642 m below R0: R0 itself moves sideways.
    let at_r0 = deflection(&PlantConfig {
        base_pivot_m: [0.0; 3],
        ..PlantConfig::default()
    });
    let pivot_effect = (large - at_r0).fixed_rows::<3>(0).norm();
    assert!(pivot_effect > 100e-6, "{pivot_effect}");
}

#[test]
fn hysteresis_remembers_the_load() {
    let robot = tx200_with_tool();
    let mut plant = Plant::new(&PlantConfig::default(), &robot, &Pose::identity(), true).unwrap();
    plant.set_configuration(&paper_q());
    let zero = Wrench::zeros();
    let before = plant.solve_tcp(&zero);
    let load = Wrench::new(400.0, 300.0, 0.0, 0.0, 0.0, 20.0);
    plant.solve_tcp(&load);
    plant.commit();
    plant.solve_tcp(&zero);
    plant.commit();
    let after = plant.solve_tcp(&zero);
    assert!(before.norm() < 1e-15);
    assert!(after.norm() > 1e-7, "residual {after}");
}

#[test]
fn point_displacement_matches_the_tcp_equilibrium_at_the_tcp() {
    let robot = tx200_with_tool();
    let mut plant = Plant::new(&PlantConfig::default(), &robot, &Pose::identity(), true).unwrap();
    plant.set_configuration(&paper_q());
    let w = Wrench::new(100.0, -200.0, 900.0, 5.0, -3.0, 1.0);
    let tcp = plant.tcp_pose().translation.vector;
    let a = plant.solve_tcp(&w);
    plant.reset_hysteresis();
    let b = plant.point_displacement(&tcp, 6, &tcp, 6, &w);
    assert!((a - b).norm() < 1e-12, "{a} vs {b}");
}

#[test]
fn geometry_errors_move_the_tcp_by_a_calibrated_robots_residual() {
    let robot = tx200_with_tool();
    let config = PlantConfig::default();
    let mut exact = Plant::new(&config, &robot, &Pose::identity(), false).unwrap();
    let mut real = Plant::new(&config, &robot, &Pose::identity(), true).unwrap();
    exact.set_configuration(&paper_q());
    real.set_configuration(&paper_q());
    let error = (real.tcp_pose().translation.vector - exact.tcp_pose().translation.vector).norm();
    assert!(error > 0.05e-3 && error < 0.5e-3, "{error}");
}

#[test]
fn the_equilibrium_converges_in_a_few_iterations_from_the_last_one() {
    let robot = tx200_with_tool();
    let mut plant = Plant::new(&PlantConfig::default(), &robot, &Pose::identity(), true).unwrap();
    plant.set_configuration(&paper_q());
    let w = Wrench::new(-430.0, 150.0, 1250.0, 0.0, 0.0, 0.0);
    plant.solve_tcp(&w);
    let cold = plant.last_iterations();
    plant.solve_tcp(&(w * 1.001));
    let warm = plant.last_iterations();
    assert!(cold < 40 && warm < cold, "cold {cold}, warm {warm}");
}
