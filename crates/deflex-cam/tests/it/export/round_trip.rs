use deflex_cam::export::{
    dh_table, read_dh_table, read_ur_calibration, ur_calibration, urdf, urdf_robot_toml,
};
use deflex_model::{Robot, builtin, robot_from_toml_and_urdf_str};
use nalgebra::{Matrix3, Matrix4, Vector3};

/// Deterministic configurations within the joint limits (xorshift).
fn configurations(robot: &Robot, count: usize) -> Vec<Vec<f64>> {
    let mut state: u64 = 0x2545f4914f6cdd1d;
    let mut next = || {
        state ^= state << 13;
        state ^= state >> 7;
        state ^= state << 17;
        (state >> 11) as f64 / (1u64 << 53) as f64
    };
    (0..count)
        .map(|_| {
            robot
                .joints
                .iter()
                .map(|j| {
                    let [lo, hi] = j.limits.unwrap_or([-3.0, 3.0]);
                    let (lo, hi) = (lo.max(-3.0), hi.min(3.0));
                    lo + (hi - lo) * next()
                })
                .collect()
        })
        .collect()
}

/// A "calibrated" robot: the nominal one with its DH rows, θ offsets, base and tool moved by
/// up to a few millimetres and milliradians.
fn calibrated(name: &str) -> Robot {
    let mut robot = builtin(name).unwrap();
    let last = robot.joints.len() - 1;
    for (i, joint) in robot.joints.iter_mut().enumerate() {
        let k = i as f64 + 1.0;
        if let Some(dh) = joint.dh.as_mut() {
            dh.d += 0.9e-3 * (k * 1.3).cos();
            // The last row's a, α, β place the flange off the last joint's axis in a standard
            // table, which UR's calibration cannot hold (tested separately): keep them.
            if i < last {
                dh.a += 1.3e-3 * (k * 0.7).sin();
                dh.alpha += 0.8e-3 * (k * 0.4).sin();
                dh.beta += 0.2e-3 * k.cos();
            }
        }
        joint.theta_offset += 0.5e-3 * (k * 2.1).sin();
    }
    robot.rebuild_dh_geometry();
    robot.tool = deflex_model::spatial::pose_from_xyz_rpy([0.002, -0.001, 0.2], [0.01, -0.02, 0.3]);
    robot
}

fn rx(a: f64) -> Matrix3<f64> {
    let (s, c) = a.sin_cos();
    Matrix3::new(1.0, 0.0, 0.0, 0.0, c, -s, 0.0, s, c)
}
fn ry(a: f64) -> Matrix3<f64> {
    let (s, c) = a.sin_cos();
    Matrix3::new(c, 0.0, s, 0.0, 1.0, 0.0, -s, 0.0, c)
}
fn rz(a: f64) -> Matrix3<f64> {
    let (s, c) = a.sin_cos();
    Matrix3::new(c, -s, 0.0, s, c, 0.0, 0.0, 0.0, 1.0)
}
fn homogeneous(r: Matrix3<f64>, t: Vector3<f64>) -> Matrix4<f64> {
    let mut m = Matrix4::identity();
    m.fixed_view_mut::<3, 3>(0, 0).copy_from(&r);
    m.fixed_view_mut::<3, 1>(0, 3).copy_from(&t);
    m
}
fn pose_matrix(p: &deflex_model::Pose) -> Matrix4<f64> {
    homogeneous(*p.rotation.matrix(), p.translation.vector)
}
fn gap(a: &Matrix4<f64>, b: &Matrix4<f64>) -> (f64, f64) {
    let dp = (a.fixed_view::<3, 1>(0, 3) - b.fixed_view::<3, 1>(0, 3)).norm();
    let dr = (a.fixed_view::<3, 3>(0, 0) - b.fixed_view::<3, 3>(0, 0)).amax();
    (dp, dr)
}

#[test]
fn urdf_reads_back_through_deflex_with_the_same_kinematics() {
    for name in ["tx200", "ur10e", "kr210-r2700", "irb4600"] {
        for robot in [builtin(name).unwrap(), calibrated(name)] {
            let xml = urdf(&robot);
            let toml = urdf_robot_toml(&robot, "robot.urdf");
            let back = robot_from_toml_and_urdf_str(&toml, &xml, "robot.toml").unwrap();
            assert_eq!(back.joint_count(), robot.joint_count());
            for (a, b) in back.joints.iter().zip(&robot.joints) {
                assert_eq!(a.limits.is_some(), b.limits.is_some());
                if let (Some(x), Some(y)) = (a.limits, b.limits) {
                    assert!((x[0] - y[0]).abs() < 1e-12 && (x[1] - y[1]).abs() < 1e-12);
                }
            }
            let mut worst: f64 = 0.0;
            for q in configurations(&robot, 300) {
                let (dp, dr) = gap(
                    &pose_matrix(&robot.tcp_pose(&q).unwrap()),
                    &pose_matrix(&back.tcp_pose(&q).unwrap()),
                );
                assert!(dr < 1e-9, "{name}: rotation {dr}");
                worst = worst.max(dp);
            }
            assert!(worst < 1e-6, "{name}: {worst} m");
        }
    }
}

#[test]
fn ur_calibration_matches_the_model_through_ur_descriptions_chain() {
    for robot in [
        builtin("ur10e").unwrap(),
        calibrated("ur10e"),
        builtin("ur10").unwrap(),
    ] {
        let mut flange_robot = robot.clone();
        flange_robot.tool = deflex_model::Pose::identity();
        let yaml = ur_calibration(&flange_robot).unwrap();
        assert!(yaml.contains("kinematics:\n  shoulder:\n    x: "), "{yaml}");
        assert!(yaml.contains("  hash: calib_deflex_"));
        let segments = read_ur_calibration(&yaml, "calibration.yaml").unwrap();
        // The nominal UR10e: shoulder z = d1 = 0.1807 m, forearm x = a2 = −0.6127 m.
        if robot.name.contains("UR10e") && robot == builtin("ur10e").unwrap() {
            assert!((segments[0][2] - 0.1807).abs() < 1e-12, "{segments:?}");
            assert!((segments[2][0] + 0.6127).abs() < 1e-12, "{segments:?}");
        }
        let mut worst: f64 = 0.0;
        for q in configurations(&robot, 300) {
            // ur_description: base_link_inertia → Π (origin_i · RotZ(q_i)) → wrist_3_link = tool0
            // (its flange and tool0 rotations multiply to the identity).
            let mut t = Matrix4::identity();
            for (s, qi) in segments.iter().zip(&q) {
                let origin = homogeneous(
                    rz(s[5]) * ry(s[4]) * rx(s[3]),
                    Vector3::new(s[0], s[1], s[2]),
                );
                t = t * origin * homogeneous(rz(*qi), Vector3::zeros());
            }
            let (dp, dr) = gap(&t, &pose_matrix(&flange_robot.tcp_pose(&q).unwrap()));
            assert!(dr < 1e-9);
            worst = worst.max(dp);
        }
        assert!(worst < 1e-6, "{worst} m");
    }
    // A robot whose flange is not UR's tool0 up to z, or that has a base, is refused.
    let mut tx = builtin("tx200").unwrap();
    tx.base = deflex_model::Pose::translation(0.0, 0.0, 0.5);
    assert!(
        ur_calibration(&tx)
            .unwrap_err()
            .to_string()
            .contains("[base]")
    );
    assert!(ur_calibration(&builtin("kr210-r2700").unwrap()).is_err());
    let mut off_axis = builtin("ur10e").unwrap();
    off_axis.joints[5].dh.as_mut().unwrap().a = 0.001;
    off_axis.rebuild_dh_geometry();
    let e = ur_calibration(&off_axis).unwrap_err().to_string();
    assert!(e.contains("flange") && e.contains("--format urdf"), "{e}");
}

#[test]
fn dh_table_rebuilds_the_joint_frames_and_lists_the_corrections() {
    for name in ["ur10e", "kr210-r2700", "tx200"] {
        let nominal = builtin(name).unwrap();
        let robot = calibrated(name);
        let text = dh_table(&robot, Some(&nominal)).unwrap();
        assert!(text.lines().any(|l| {
            l.starts_with("joint,convention,alpha_rad,a_m,beta_rad,d_m,theta_offset_rad,")
        }));
        let rows = read_dh_table(&text, "dh.csv").unwrap();
        assert_eq!(rows.len(), robot.joint_count());
        let standard = matches!(
            robot.dh_convention,
            Some(deflex_model::DhConvention::Standard)
        );
        for q in configurations(&robot, 100) {
            let mut data = deflex_model::Data::new();
            robot.forward_kinematics(&mut data, &q).unwrap();
            let mut t = pose_matrix(&robot.base);
            for (i, (row, qi)) in rows.iter().zip(&q).enumerate() {
                let d = &row.dh;
                let th = qi + row.theta_offset;
                let joint_frame = if standard {
                    // R_i = F_{i−1} · TransZ(d_i) · RotZ(q + θ); F_i = R_i · TransX(a)·RotX(α)·RotY(β).
                    let r = t
                        * homogeneous(Matrix3::identity(), Vector3::new(0.0, 0.0, d.d))
                        * homogeneous(rz(th), Vector3::zeros());
                    t = r
                        * homogeneous(Matrix3::identity(), Vector3::new(d.a, 0.0, 0.0))
                        * homogeneous(rx(d.alpha) * ry(d.beta), Vector3::zeros());
                    r
                } else {
                    t = t
                        * homogeneous(rx(d.alpha) * ry(d.beta), Vector3::zeros())
                        * homogeneous(Matrix3::identity(), Vector3::new(d.a, 0.0, d.d))
                        * homogeneous(rz(th), Vector3::zeros());
                    t
                };
                let (dp, dr) = gap(&joint_frame, &pose_matrix(data.link_frame(i + 1)));
                assert!(dp < 1e-9 && dr < 1e-9, "{name} joint {}: {dp} {dr}", i + 1);
            }
        }
        // The corrections are the calibrated minus the nominal values.
        for ((row, nominal_joint), joint) in rows.iter().zip(&nominal.joints).zip(&robot.joints) {
            let delta = row.delta.unwrap();
            let (c, n) = (joint.dh.unwrap(), nominal_joint.dh.unwrap());
            assert!((delta[1] - (c.a - n.a)).abs() < 1e-15);
            assert!((delta[3] - (c.d - n.d)).abs() < 1e-15);
            assert!((delta[4] - (joint.theta_offset - nominal_joint.theta_offset)).abs() < 1e-15);
        }
        // Without a nominal robot: the values only.
        let plain = dh_table(&robot, None).unwrap();
        assert!(read_dh_table(&plain, "dh.csv").unwrap()[0].delta.is_none());
    }
}
