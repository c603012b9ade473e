use deflex_io::link::*;

fn close(a: f64, b: f64, tol: f64) -> bool {
    (a - b).abs() <= tol
}

#[test]
fn zyx_matrix_round_trip() {
    for zyx in [
        [0.1, -0.2, 0.3],
        [3.0, 1.2, -2.9],
        [-1.0, -1.5, 0.7],
        [0.0, 0.0, 0.0],
    ] {
        let back = matrix_to_zyx(&zyx_to_matrix(zyx));
        for i in 0..3 {
            assert!(close(back[i], zyx[i], 1e-12), "{zyx:?} -> {back:?}");
        }
    }
}

#[test]
fn zyx_single_axes() {
    // A about z: x axis goes to y for a = 90°.
    let r = zyx_to_matrix([std::f64::consts::FRAC_PI_2, 0.0, 0.0]);
    assert!(close(r[1][0], 1.0, 1e-15));
    let r = zyx_to_matrix([0.0, 0.0, std::f64::consts::FRAC_PI_2]);
    // C about x: y axis goes to z.
    assert!(close(r[2][1], 1.0, 1e-15));
}

#[test]
fn rotvec_and_quaternion_round_trip() {
    for v in [[0.01, -0.02, 0.03], [1.0, 0.5, -2.0], [0.0, 0.0, 0.0]] {
        let back = matrix_to_rotvec(&rotvec_to_matrix(v));
        for i in 0..3 {
            assert!(close(back[i], v[i], 1e-12));
        }
        let m = rotvec_to_matrix(v);
        let m2 = quaternion_to_matrix(matrix_to_quaternion(&m));
        for i in 0..3 {
            for j in 0..3 {
                assert!(close(m[i][j], m2[i][j], 1e-12));
            }
        }
    }
}

#[test]
fn small_rotation_maps_to_abc_componentwise() {
    let c = Correction {
        dp_m: [0.0; 3],
        dphi_rad: [1e-4, -2e-4, 3e-4],
    };
    let abc = c.zyx_rad();
    assert!(close(abc[0], 3e-4, 1e-7));
    assert!(close(abc[1], -2e-4, 1e-7));
    assert!(close(abc[2], 1e-4, 1e-7));
    let back = Correction::from_zyx(c.dp_m, abc);
    for i in 0..3 {
        assert!(close(back.dphi_rad[i], c.dphi_rad[i], 1e-15));
    }
}

#[test]
fn pose_quaternion_round_trip() {
    let p = Pose6 {
        position_m: [1.0, 2.0, 3.0],
        zyx_rad: [0.4, -0.3, 2.0],
    };
    let q = p.quaternion();
    let p2 = Pose6::from_quaternion(p.position_m, q);
    for i in 0..3 {
        assert!(close(p.zyx_rad[i], p2.zyx_rad[i], 1e-12));
    }
}
