//! Exact fixtures and independent cross-checks of the model (issue: robot model).

use deflex_model::spatial::pose_from_xyz_rpy;
use deflex_model::{Axis, Data, EdofSite, IkOptions, Robot, TX200_FORMING_Q_DEG, Wrench, builtin};
use nalgebra::{Matrix6, Vector3, Vector6};

fn deg(v: &[f64]) -> Vec<f64> {
    v.iter().map(|d| d.to_radians()).collect()
}

fn forming_q() -> Vec<f64> {
    deg(&TX200_FORMING_Q_DEG)
}

#[test]
fn tx200_flange_at_zero_configuration() {
    let robot = builtin("tx200").unwrap();
    let pose = robot.tcp_pose(&[0.0; 6]).unwrap();
    let p = pose.translation.vector;
    assert!((p - Vector3::new(0.250, 0.0, 1.944)).norm() < 1e-12, "{p}");
}

#[test]
fn tx200_forming_configuration_reaches_part_origin_tool_down() {
    let robot = builtin("tx200").unwrap();
    let pose = robot.tcp_pose(&forming_q()).unwrap();
    let p = pose.translation.vector;
    assert!(
        (p.x - 1.4994).abs() < 5e-4 && p.y.abs() < 1e-9 && (p.z + 0.1833).abs() < 5e-4,
        "{p}"
    );
    let tool_axis = pose.rotation.matrix().column(2).into_owned();
    assert!(
        (tool_axis - Vector3::new(0.0, 0.0, -1.0)).norm() < 1e-2,
        "{tool_axis}"
    );
}

/// Finite-difference check of the geometric Jacobian against forward kinematics.
#[test]
fn geometric_jacobian_matches_finite_differences() {
    let robot = builtin("tx200").unwrap();
    let q = deg(&[10.0, 40.0, 70.0, -20.0, 35.0, 15.0]);
    let mut data = Data::new();
    robot.forward_kinematics(&mut data, &q).unwrap();
    let jacobian = robot.geometric_jacobian(&data, &data.tcp_position());
    let h = 1e-6;
    let base = data.tcp;
    for i in 0..6 {
        let mut qp = q.clone();
        qp[i] += h;
        let moved = robot.tcp_pose(&qp).unwrap();
        let dp = (moved.translation.vector - base.translation.vector) / h;
        let dr =
            deflex_model::spatial::rotation_log(&(moved.rotation * base.rotation.inverse())) / h;
        let column = jacobian.column(i);
        for r in 0..3 {
            assert!((column[r] - dp[r]).abs() < 1e-5, "joint {i} linear {r}");
            assert!(
                (column[r + 3] - dr[r]).abs() < 1e-5,
                "joint {i} angular {r}"
            );
        }
    }
}

fn all_edofs_robot() -> Robot {
    let mut robot = builtin("tx200").unwrap();
    for i in 1..=6 {
        for (n, axis) in Axis::ALL.into_iter().enumerate() {
            if robot.stiffness(EdofSite::Joint(i), axis).is_none() {
                robot.set_stiffness(
                    EdofSite::Joint(i),
                    axis,
                    Some(1.0e6 * (1.0 + i as f64 + n as f64)),
                );
            }
        }
    }
    robot.set_stiffness(EdofSite::Base, Axis::X, Some(4.0e7));
    robot.set_stiffness(EdofSite::Base, Axis::Y, Some(6.0e7));
    robot.base = pose_from_xyz_rpy([0.3, -0.2, 0.5], [0.02, -0.03, 0.4]);
    robot
}

/// The eDoF Jacobian column of an x/y/z spring equals the finite-difference displacement of the
/// TCP when that spring is given a small rotation (an independent construction: the rotated chain
/// is recomputed by composing the joint placements by hand).
#[test]
fn edof_columns_match_perturbed_chain() {
    let robot = all_edofs_robot();
    let q = deg(&[5.0, 30.0, 80.0, 10.0, 40.0, -5.0]);
    let mut data = Data::new();
    robot.forward_kinematics(&mut data, &q).unwrap();
    let columns = robot.edof_columns(&data, &data.tcp_position(), 6);
    let h = 1e-6;
    for c in 0..columns.count {
        let edof = columns.edofs[c].unwrap();
        // Rebuild the TCP with a small rotation h about the eDoF axis through its centre.
        let mut frame = robot.base;
        if edof.site == EdofSite::Base {
            // About the base pivot (0.642 m below R0 on the TX200).
            let pivot = translation_pose(robot.base_pivot);
            let mut axis = Vector3::zeros();
            axis[edof.axis.index()] = 1.0;
            frame = frame * pivot * rotation_pose(axis * h) * pivot.inverse();
        }
        for (i, joint) in robot.joints.iter().enumerate() {
            frame =
                frame * joint.placement * deflex_model::spatial::rot_z(q[i] + joint.theta_offset);
            if edof.site == EdofSite::Joint(i + 1) {
                let shift = translation_pose(Vector3::new(0.0, 0.0, joint.center_shift));
                let mut axis = Vector3::zeros();
                axis[edof.axis.index()] = 1.0;
                frame = frame * shift * rotation_pose(axis * h) * shift.inverse();
            }
        }
        let tcp = frame * robot.flange * robot.tool;
        let dp = (tcp.translation.vector - data.tcp.translation.vector) / h;
        let dr =
            deflex_model::spatial::rotation_log(&(tcp.rotation * data.tcp.rotation.inverse())) / h;
        let expected = Vector6::new(dp.x, dp.y, dp.z, dr.x, dr.y, dr.z);
        assert!(
            (columns.columns[c] - expected).norm() < 1e-5,
            "{}: {} vs {}",
            edof.label(),
            columns.columns[c],
            expected
        );
    }
}

fn rotation_pose(v: Vector3<f64>) -> deflex_model::Pose {
    deflex_model::Pose::from_parts(
        nalgebra::Translation3::identity(),
        nalgebra::Rotation3::new(v),
    )
}

fn translation_pose(v: Vector3<f64>) -> deflex_model::Pose {
    deflex_model::Pose::from_parts(
        nalgebra::Translation3::from(v),
        nalgebra::Rotation3::identity(),
    )
}

#[test]
fn z_edof_columns_equal_geometric_jacobian_even_with_center_shift() {
    let robot = all_edofs_robot();
    let q = deg(&[12.0, 45.0, 95.0, -30.0, 20.0, 60.0]);
    let mut data = Data::new();
    robot.forward_kinematics(&mut data, &q).unwrap();
    let jacobian = robot.geometric_jacobian(&data, &data.tcp_position());
    let columns = robot.edof_columns(&data, &data.tcp_position(), 6);
    for c in 0..columns.count {
        let edof = columns.edofs[c].unwrap();
        if let (EdofSite::Joint(i), Axis::Z) = (edof.site, edof.axis) {
            let expected = jacobian.column(i - 1).into_owned();
            assert!((columns.columns[c] - expected).norm() < 1e-12);
        }
    }
}

#[test]
fn compliance_is_symmetric_psd_and_matches_deflection() {
    let robot = all_edofs_robot();
    let mut data = Data::new();
    robot.forward_kinematics(&mut data, &forming_q()).unwrap();
    let c: Matrix6<f64> = robot.compliance_matrix(&data);
    assert!((c - c.transpose()).norm() < 1e-18);
    let eigen = c.symmetric_eigen();
    assert!(
        eigen.eigenvalues.iter().all(|&l| l > -1e-18),
        "{}",
        eigen.eigenvalues
    );
    // J K⁻¹ Jᵀ built as matrices agrees with the rank-one sum.
    let j = robot.edof_jacobian(&data);
    let k = robot.stiffness_matrix();
    let c_dense = &j * k.try_inverse().unwrap() * j.transpose();
    for r in 0..6 {
        for col in 0..6 {
            assert!((c_dense[(r, col)] - c[(r, col)]).abs() < 1e-18);
        }
    }
    let w = Wrench::new(100.0, -400.0, 1200.0, 5.0, -3.0, 1.0);
    assert!((c * w - robot.tcp_deflection(&data, &w)).norm() < 1e-15);
    // Energy identity: wᵀ δs = Σ τ² / k ≥ 0.
    let ds = robot.tcp_deflection(&data, &w);
    assert!(w.dot(&ds) > 0.0);
}

/// Maxwell–Betti: the displacement at P (along u) caused by a unit force at A (along v) equals
/// the displacement at A (along v) caused by a unit force at P (along u).
#[test]
fn maxwell_betti_reciprocity_between_two_points() {
    let robot = all_edofs_robot();
    let mut data = Data::new();
    robot
        .forward_kinematics(&mut data, &deg(&[0.0, 90.0, 0.0, 0.0, 0.0, 0.0]))
        .unwrap();
    let p = data.joint_frames[2].translation.vector + Vector3::new(0.1, 0.05, 0.2); // on link 3
    let a = data.tcp_position(); // on link 6
    let u = Vector3::new(0.3, -0.5, 0.8).normalize();
    let v = Vector3::new(-0.6, 0.7, 0.2).normalize();
    let force = |dir: Vector3<f64>| Wrench::new(dir.x, dir.y, dir.z, 0.0, 0.0, 0.0);
    let at_p = robot.point_displacement(&data, &p, 3, &a, 6, &force(v));
    let at_a = robot.point_displacement(&data, &a, 6, &p, 3, &force(u));
    let lhs = at_p.fixed_rows::<3>(0).dot(&u);
    let rhs = at_a.fixed_rows::<3>(0).dot(&v);
    assert!(lhs.abs() > 1e-9);
    assert!((lhs - rhs).abs() < 1e-15 * 1e3, "{lhs} vs {rhs}");
    // Both at the TCP it reduces to eq. 15.
    let w = Wrench::new(10.0, 20.0, -30.0, 1.0, 2.0, 3.0);
    let general = robot.point_displacement(&data, &a, 6, &a, 6, &w);
    assert!((general - robot.tcp_deflection(&data, &w)).norm() < 1e-18);
}

#[test]
fn points_on_early_links_only_see_early_edofs() {
    let robot = all_edofs_robot();
    let mut data = Data::new();
    robot.forward_kinematics(&mut data, &forming_q()).unwrap();
    let p = data.joint_frames[0].translation.vector + Vector3::new(0.0, 0.0, 0.3); // link 1
    let w = Wrench::new(0.0, 1000.0, 0.0, 0.0, 0.0, 0.0);
    let tcp = data.tcp_position();
    let full = robot.point_displacement(&data, &p, 1, &tcp, 6, &w);
    // Removing every eDoF of joints ≥ 2 leaves the displacement of a link-1 point unchanged.
    let mut reduced = robot.clone();
    for i in 2..=6 {
        for axis in Axis::ALL {
            reduced.set_stiffness(EdofSite::Joint(i), axis, None);
        }
    }
    let only_early = reduced.point_displacement(&data, &p, 1, &tcp, 6, &w);
    assert!((full - only_early).norm() < 1e-18);
    assert!(full.norm() > 0.0);
}

/// The paper's Figure 7: q = [0, 90, 0, 0, 0, 0]°, fy = 1400 N. The one-eDoF model predicts no
/// x-displacement at the end effector; the enhanced model (x-eDoF on joint 3 shifted 400 mm)
/// does, and both agree on the y-displacement driven by joint 1.
#[test]
fn figure7_enhanced_model_shows_x_displacement() {
    let q = deg(&[0.0, 90.0, 0.0, 0.0, 0.0, 0.0]);
    let w = Wrench::new(0.0, 1400.0, 0.0, 0.0, 0.0, 0.0);
    let mut data = Data::new();
    let enhanced = builtin("tx200").unwrap();
    enhanced.forward_kinematics(&mut data, &q).unwrap();
    let d_enh = enhanced.tcp_deflection(&data, &w);
    let one = builtin("tx200-1edof").unwrap();
    one.forward_kinematics(&mut data, &q).unwrap();
    let d_one = one.tcp_deflection(&data, &w);
    // Hand check, one-eDoF: pure y displacement, δy = Fy·r²/k1 + wrist terms; x and z are zero.
    assert!(d_one[0].abs() < 1e-12, "one-eDoF x = {}", d_one[0]);
    assert!(d_one[1] > 0.0);
    // Arm horizontal along x0: TCP at x = 0.25 + 0.95 + 0.8 + 0.194 = 2.194 m, y = 0.
    let tcp = data.tcp_position();
    assert!((tcp - Vector3::new(2.194, 0.0, 0.0)).norm() < 1e-9, "{tcp}");
    // Joint-1 contribution alone: Fy r² / k1.
    let j1 = 1400.0 * 2.194f64.powi(2) / 2.32e6;
    assert!(d_one[1] >= j1 - 1e-12);
    // Enhanced: the joint-3 x-eDoF (axis along the arm, centre 0.4 m off the arm line) turns the
    // y force into an x displacement.
    assert!(d_enh[0].abs() > 1e-5, "enhanced x = {}", d_enh[0]);
}

#[test]
fn ik_round_trip_on_grid_and_unreachable_error() {
    let robot = builtin("tx200").unwrap();
    let seed = forming_q();
    let target_q = deg(&[8.0, 45.0, 95.0, 3.0, 38.0, -4.0]);
    let target = robot.tcp_pose(&target_q).unwrap();
    let solution = robot
        .inverse_kinematics(&target, &seed, &IkOptions::default())
        .unwrap();
    let reached = robot.tcp_pose(&solution.q).unwrap();
    assert!((reached.translation.vector - target.translation.vector).norm() < 1e-8);
    assert!(
        deflex_model::spatial::rotation_log(&(reached.rotation * target.rotation.inverse())).norm()
            < 1e-8
    );
    let far = pose_from_xyz_rpy([5.0, 0.0, 0.0], [0.0, std::f64::consts::PI, 0.0]);
    let err = robot
        .inverse_kinematics(&far, &seed, &IkOptions::default())
        .unwrap_err();
    assert!(err.to_string().contains("unreachable"), "{err}");
}

#[test]
fn toml_round_trip_preserves_the_model() {
    let mut robot = all_edofs_robot();
    robot.tool = pose_from_xyz_rpy([0.01, 0.0, 0.15], [0.0, 0.1, 0.0]);
    let text = deflex_model::robot_to_toml(&robot);
    let back = deflex_model::robot_from_toml_str(&text, "roundtrip", None).unwrap();
    let q = deg(&[3.0, 50.0, 85.0, 1.0, 40.0, 2.0]);
    let mut a = Data::new();
    let mut b = Data::new();
    robot.forward_kinematics(&mut a, &q).unwrap();
    back.forward_kinematics(&mut b, &q).unwrap();
    assert!((a.tcp.to_homogeneous() - b.tcp.to_homogeneous()).norm() < 1e-12);
    assert!((robot.compliance_matrix(&a) - back.compliance_matrix(&b)).norm() < 1e-18);
    assert_eq!(robot.edof_count(), back.edof_count());
}

/// An off-diagonal joint compliance (J2.z–J3.z): the Cartesian compliance, eq. 15's deflection,
/// the point-to-point transfer and the gravity deflection all equal `J C_θ Jᵀ` with the full
/// (non-diagonal) joint compliance built as a dense matrix here; the robot file round-trips it;
/// a coupling that is not a spring is refused.
#[test]
fn a_coupled_joint_compliance_is_j_c_theta_j_transposed() {
    let mut robot = all_edofs_robot();
    let (k2, k3) = (
        robot.stiffness(EdofSite::Joint(2), Axis::Z).unwrap(),
        robot.stiffness(EdofSite::Joint(3), Axis::Z).unwrap(),
    );
    let c23 = 0.3 / (k2 * k3).sqrt();
    robot.couplings = vec![deflex_model::ComplianceCoupling {
        a: (EdofSite::Joint(2), Axis::Z),
        b: (EdofSite::Joint(3), Axis::Z),
        compliance: c23,
    }];
    robot.validate("test").unwrap();
    let mut data = Data::new();
    robot
        .forward_kinematics(&mut data, &deg(&[10.0, -30.0, 60.0, 20.0, 40.0, -15.0]))
        .unwrap();
    // Dense C_θ: the diagonal 1/k plus c23 at (J2.z, J3.z) and (J3.z, J2.z).
    let edofs: Vec<_> = robot.edofs().collect();
    let index = |site, axis| {
        edofs
            .iter()
            .position(|e| e.site == site && e.axis == axis)
            .unwrap()
    };
    let (i2, i3) = (
        index(EdofSite::Joint(2), Axis::Z),
        index(EdofSite::Joint(3), Axis::Z),
    );
    let mut c_theta = robot.stiffness_matrix().try_inverse().unwrap();
    c_theta[(i2, i3)] = c23;
    c_theta[(i3, i2)] = c23;
    let j = robot.edof_jacobian(&data);
    let dense = &j * &c_theta * j.transpose();
    let c = robot.compliance_matrix(&data);
    for r in 0..6 {
        for col in 0..6 {
            assert!(
                (dense[(r, col)] - c[(r, col)]).abs() < 1e-18,
                "({r}, {col}): {} vs {}",
                dense[(r, col)],
                c[(r, col)]
            );
        }
    }
    let w = Wrench::new(300.0, -500.0, 1100.0, 8.0, -6.0, 2.0);
    assert!((c * w - robot.tcp_deflection(&data, &w)).norm() < 1e-15);
    let tcp = data.tcp_position();
    let point = robot.point_displacement(&data, &tcp, 6, &tcp, 6, &w);
    assert!((point - c * w).norm() < 1e-15);
    // A marker on the upper arm (link 2) under a load at the TCP, and the other way round, in
    // joint space: τ = J_Aᵀ w over the eDoFs below the load's link, θ = C_θ τ, δ = J_P θ over
    // the eDoFs below the point's link. J3 carries a torque that turns J2 through the coupling,
    // which moves the marker although J3 lies above it.
    let marker = data.link_frame(2).translation.vector + nalgebra::Vector3::new(0.1, -0.05, 0.2);
    let screws = |at: &nalgebra::Vector3<f64>, link: usize| {
        nalgebra::DMatrix::from_fn(6, edofs.len(), |r, k| {
            let e = &edofs[k];
            if e.site.link_index() > link {
                return 0.0;
            }
            let (v, o) = data.edof_axis_center(&robot, e.site, e.axis);
            deflex_model::edof_screw(&v, &o, at)[r]
        })
    };
    let wd = nalgebra::DVector::from_column_slice(w.as_slice());
    for (p, pl, a, al) in [(marker, 2, tcp, 6), (tcp, 6, marker, 2)] {
        let theta = &c_theta * (screws(&a, al).transpose() * &wd);
        let joint_space = screws(&p, pl) * theta;
        let transfer = robot.point_displacement(&data, &p, pl, &a, al, &w);
        assert!(
            (0..6).all(|r| (joint_space[r] - transfer[r]).abs() < 1e-15),
            "point on link {pl}, load on link {al}: {joint_space} vs {transfer}"
        );
    }
    let mut uncoupled = robot.clone();
    uncoupled.couplings.clear();
    let on_marker = |r: &deflex_model::Robot| r.point_displacement(&data, &marker, 2, &tcp, 6, &w);
    assert!((on_marker(&robot) - on_marker(&uncoupled)).norm() > 1e-7);
    // The coupling changes the answer (the test is not blind to it).
    let mut diagonal = robot.clone();
    diagonal.couplings.clear();
    assert!((diagonal.tcp_deflection(&data, &w) - c * w).norm() > 1e-7);
    // Round trip through the robot file.
    let text = deflex_model::robot_to_toml(&robot);
    assert!(text.contains("[[coupling]]"), "{text}");
    let back = deflex_model::robot_from_toml_str(&text, "roundtrip", None).unwrap();
    assert_eq!(back.couplings.len(), 1);
    assert!((back.couplings[0].compliance / c23 - 1.0).abs() < 1e-12);
    assert_eq!(back.couplings[0].a, (EdofSite::Joint(2), Axis::Z));
    // Not a spring: |c| ≥ √(c_a c_b).
    let mut bad = robot.clone();
    bad.couplings[0].compliance = 1.01 / (k2 * k3).sqrt();
    let message = bad.validate("bad.toml").unwrap_err().to_string();
    assert!(
        message.contains("coupling[1]") && message.contains("positive definite"),
        "{message}"
    );
    // An eDoF the robot does not have.
    let mut missing = robot.clone();
    missing.couplings[0].b = (EdofSite::Base, Axis::Z);
    assert!(missing.validate("bad.toml").is_err());
    let unknown = text.replace("b = \"J3.z\"", "b = \"J3.w\"");
    let message = deflex_model::robot_from_toml_str(&unknown, "bad.toml", None)
        .unwrap_err()
        .to_string();
    assert!(message.contains("coupling[1].b"), "{message}");
}
