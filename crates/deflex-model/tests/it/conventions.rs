//! The vendors' orientation conventions ([`deflex_model::conventions`]) against independent
//! constructions: elementary rotation matrices written out here element by element, the
//! quaternion → matrix formula written out, Rodrigues' formula for the rotation vector, and
//! published vendor examples. Includes the gimbal-lock neighbourhoods of the three-angle
//! conventions and the quaternion / rotation vector sign choices, and the radian forms the wire
//! protocols use (KUKA RSI, ABB EGM, deflex's Stäubli protocol, the corrections' rotation
//! vectors).

use deflex_model::conventions::*;
use nalgebra::{Matrix3, Rotation3, Vector3};

/// Rotation about x by `deg` degrees, written out.
fn rx(deg: f64) -> Matrix3<f64> {
    let (s, c) = deg.to_radians().sin_cos();
    Matrix3::from_row_slice(&[1.0, 0.0, 0.0, 0.0, c, -s, 0.0, s, c])
}
fn ry(deg: f64) -> Matrix3<f64> {
    let (s, c) = deg.to_radians().sin_cos();
    Matrix3::from_row_slice(&[c, 0.0, s, 0.0, 1.0, 0.0, -s, 0.0, c])
}
fn rz(deg: f64) -> Matrix3<f64> {
    let (s, c) = deg.to_radians().sin_cos();
    Matrix3::from_row_slice(&[c, -s, 0.0, s, c, 0.0, 0.0, 0.0, 1.0])
}

fn rot(m: Matrix3<f64>) -> Rotation3<f64> {
    Rotation3::from_matrix_unchecked(m)
}

/// Quaternion [w, x, y, z] → matrix, the textbook formula written out.
fn quaternion_matrix(q: [f64; 4]) -> Matrix3<f64> {
    let [w, x, y, z] = q;
    Matrix3::from_row_slice(&[
        1.0 - 2.0 * (y * y + z * z),
        2.0 * (x * y - z * w),
        2.0 * (x * z + y * w),
        2.0 * (x * y + z * w),
        1.0 - 2.0 * (x * x + z * z),
        2.0 * (y * z - x * w),
        2.0 * (x * z - y * w),
        2.0 * (y * z + x * w),
        1.0 - 2.0 * (x * x + y * y),
    ])
}

/// Rodrigues: R = I + sin θ K + (1 − cos θ) K², K the skew matrix of the unit axis.
fn rodrigues(r: [f64; 3]) -> Matrix3<f64> {
    let v = Vector3::from(r);
    let angle = v.norm();
    if angle == 0.0 {
        return Matrix3::identity();
    }
    let n = v / angle;
    let k = Matrix3::from_row_slice(&[0.0, -n.z, n.y, n.z, 0.0, -n.x, -n.y, n.x, 0.0]);
    Matrix3::identity() + k * angle.sin() + k * k * (1.0 - angle.cos())
}

/// A spread of test rotations: a grid of three-angle triples plus awkward ones.
fn samples() -> Vec<Matrix3<f64>> {
    let mut out = Vec::new();
    for a in [-170.0, -95.0, -30.0, 0.0, 12.5, 89.0, 135.0, 180.0] {
        for b in [-89.0, -45.0, -1.0, 0.0, 33.0, 88.0] {
            for c in [-179.0, -60.0, 0.0, 7.0, 120.0] {
                out.push(rz(a) * ry(b) * rx(c));
            }
        }
    }
    // Tool pointing down, 180° rotations, identity.
    out.push(rx(180.0));
    out.push(ry(180.0));
    out.push(rz(180.0));
    out.push(Matrix3::identity());
    out
}

fn distance(a: &Matrix3<f64>, b: &Matrix3<f64>) -> f64 {
    rotation_distance(&rot(*a), &rot(*b))
}

#[test]
fn kuka_abc_rebuilds_z_y_x_products_and_known_angles() {
    for m in samples() {
        let abc = kuka_abc_deg(&rot(m), None);
        let rebuilt = rz(abc[0]) * ry(abc[1]) * rx(abc[2]);
        assert!(distance(&m, &rebuilt) < 1e-12, "{abc:?}");
        assert!(abc[1].abs() <= 90.0 && abc[0].abs() <= 180.0 && abc[2].abs() <= 180.0);
        // The crate's inverse agrees with the written-out product.
        let back = rotation_from_kuka_abc_deg(abc);
        assert!(distance(back.matrix(), &rebuilt) < 1e-12);
    }
    // Angles inside the principal range come back unchanged.
    let abc = kuka_abc_deg(&rot(rz(30.0) * ry(90.0 - 1e-3) * rx(-40.0)), None);
    for (got, want) in abc.iter().zip([30.0, 90.0 - 1e-3, -40.0]) {
        assert!((got - want).abs() < 1e-6, "{abc:?}");
    }
    // KUKA's classic "tool x pointing down": A 0, B 90, C 0 turns the tool x axis to −z.
    let m = rotation_from_kuka_abc_deg([0.0, 90.0, 0.0]);
    assert!((m * Vector3::x() - Vector3::new(0.0, 0.0, -1.0)).norm() < 1e-15);
}

#[test]
fn staubli_rxryrz_rebuilds_x_y_z_products() {
    for m in samples() {
        let r = staubli_rxryrz_deg(&rot(m), None);
        let rebuilt = rx(r[0]) * ry(r[1]) * rz(r[2]);
        assert!(distance(&m, &rebuilt) < 1e-12, "{r:?}");
        assert!(r[1].abs() <= 90.0);
        let back = rotation_from_staubli_rxryrz_deg(r);
        assert!(distance(back.matrix(), &rebuilt) < 1e-12);
    }
    let r = staubli_rxryrz_deg(&rot(rx(10.0) * ry(-20.0) * rz(30.0)), None);
    for (got, want) in r.iter().zip([10.0, -20.0, 30.0]) {
        assert!((got - want).abs() < 1e-9, "{r:?}");
    }
    // The two conventions differ: the same angles give different rotations.
    let k = rotation_from_kuka_abc_deg([10.0, -20.0, 30.0]);
    let s = rotation_from_staubli_rxryrz_deg([10.0, -20.0, 30.0]);
    assert!(rotation_distance(&k, &s) > 0.1);
}

#[test]
fn gimbal_lock_neighbourhoods_rebuild_and_printed_values_round_trip() {
    for sign in [1.0, -1.0] {
        for k in 0..=14 {
            let offset = if k == 14 { 0.0 } else { 10f64.powi(-k) };
            let middle = sign * (90.0 - offset);
            // KUKA: B near ±90°.
            let m = rz(40.0) * ry(middle) * rx(-25.0);
            let abc = kuka_abc_deg(&rot(m), Some([40.0, 0.0, 0.0]));
            let rebuilt = rz(abc[0]) * ry(abc[1]) * rx(abc[2]);
            assert!(distance(&m, &rebuilt) < 1e-9, "B {middle}: {abc:?}");
            // Printed to 6 decimals (what the exporters write), still within 1e-6 rad.
            let printed = abc.map(|v| (v * 1e6).round() / 1e6);
            let reread = rotation_from_kuka_abc_deg(printed);
            assert!(rotation_distance(&rot(m), &reread) < 1e-6, "B {middle}");
            // Stäubli: ry near ±90°.
            let m = rx(-15.0) * ry(middle) * rz(70.0);
            let r = staubli_rxryrz_deg(&rot(m), Some([0.0, 0.0, 70.0]));
            let rebuilt = rx(r[0]) * ry(r[1]) * rz(r[2]);
            assert!(distance(&m, &rebuilt) < 1e-9, "ry {middle}: {r:?}");
            let printed = r.map(|v| (v * 1e6).round() / 1e6);
            let reread = rotation_from_staubli_rxryrz_deg(printed);
            assert!(rotation_distance(&rot(m), &reread) < 1e-6, "ry {middle}");
        }
    }
    // Exactly at the lock the first angle follows the previous point: the split is continuous.
    let locked = rot(rz(40.0) * ry(90.0) * rx(-25.0));
    let abc = kuka_abc_deg(&locked, Some([40.0, 90.0, -25.0]));
    assert!(
        (abc[0] - 40.0).abs() < 1e-9 && (abc[2] + 25.0).abs() < 1e-6,
        "{abc:?}"
    );
    let abc = kuka_abc_deg(&locked, None);
    assert!(
        abc[0].abs() < 1e-12,
        "A = 0 without a previous point: {abc:?}"
    );
}

#[test]
#[allow(clippy::approx_constant)] // 0.707107 is the published example as printed
fn abb_quaternion_matches_the_written_out_formula_with_q1_first() {
    for m in samples() {
        let q = abb_quaternion(&rot(m), None);
        let norm: f64 = q.iter().map(|v| v * v).sum();
        assert!((norm - 1.0).abs() < 1e-12);
        assert!(q[0] >= 0.0, "q1 ≥ 0 without a previous point");
        assert!(distance(&m, &quaternion_matrix(q)) < 1e-12);
    }
    // RAPID manual: [1, 0, 0, 0] is no rotation.
    assert!(rotation_from_abb_quaternion([1.0, 0.0, 0.0, 0.0]).angle() < 1e-15);
    // A robtarget published on ABB's forum, [0, 0.707107, -0.707107, 0]: 180° about
    // (1, −1, 0)/√2, i.e. R = 2nnᵀ − I = [[0,−1,0],[−1,0,0],[0,0,−1]] by hand.
    let r = rotation_from_abb_quaternion([0.0, 0.707107, -0.707107, 0.0]);
    let by_hand = Matrix3::from_row_slice(&[0.0, -1.0, 0.0, -1.0, 0.0, 0.0, 0.0, 0.0, -1.0]);
    assert!((r.matrix() - by_hand).amax() < 1e-6);
    // 90° about z: [cos 45°, 0, 0, sin 45°].
    let q = abb_quaternion(&rot(rz(90.0)), None);
    let h = 0.5f64.sqrt();
    for (got, want) in q.iter().zip([h, 0.0, 0.0, h]) {
        assert!((got - want).abs() < 1e-12, "{q:?}");
    }
}

#[test]
fn quaternion_sign_stays_continuous_through_a_half_turn() {
    // A tool pointing down wobbling by ±1 mrad about x: w crosses zero. Canonical (q1 ≥ 0)
    // quaternions would flip sign; the path-continuous choice does not, and every quaternion
    // still is the rotation.
    let mut previous: Option<[f64; 4]> = None;
    for k in -5..=5 {
        let m = rx(180.0 + 0.0573 * f64::from(k)) * rz(0.01 * f64::from(k));
        let q = abb_quaternion(&rot(m), previous);
        assert!(distance(&m, &quaternion_matrix(q)) < 1e-12);
        if let Some(p) = previous {
            let dot: f64 = q.iter().zip(p).map(|(a, b)| a * b).sum();
            assert!(dot > 0.99, "sign flip at {k}: {p:?} → {q:?}");
        }
        previous = Some(q);
    }
    let canonical = abb_quaternion(&rot(rx(180.0 + 0.0573)), None);
    let other = abb_quaternion(&rot(rx(180.0 - 0.0573)), None);
    let dot: f64 = canonical.iter().zip(other).map(|(a, b)| a * b).sum();
    assert!(
        dot < 0.0,
        "the canonical choice does flip: this is why continuity is needed"
    );
}

#[test]
fn ur_rotation_vector_matches_rodrigues_and_stays_continuous_near_pi() {
    for m in samples() {
        let r = rotation_vector(&rot(m), None);
        assert!(Vector3::from(r).norm() <= std::f64::consts::PI + 1e-12);
        assert!(distance(&m, &rodrigues(r)) < 1e-12, "{r:?}");
        let back = rotation_from_rotation_vector(r);
        assert!(distance(back.matrix(), &rodrigues(r)) < 1e-12);
    }
    // Small angles keep their accuracy.
    let r = rotation_vector(&rot(rx(1e-7)), None);
    assert!((r[0] - 1e-7f64.to_radians()).abs() < 1e-20, "{r:?}");
    // UR's usual "tool down": 180° about y is [0, π, 0].
    let r = rotation_vector(&rot(ry(180.0)), None);
    assert!((r[1].abs() - std::f64::consts::PI).abs() < 1e-12 && r[0].abs() < 1e-12);
    // Near π the representative follows the previous point.
    let mut previous: Option<[f64; 3]> = None;
    for k in -5..=5 {
        let m = ry(180.0 + 0.05 * f64::from(k));
        let r = rotation_vector(&rot(m), previous);
        assert!(distance(&m, &rodrigues(r)) < 1e-12);
        if let Some(p) = previous {
            assert!(
                (Vector3::from(r) - Vector3::from(p)).norm() < 0.01,
                "jump at {k}: {p:?} → {r:?}"
            );
        }
        previous = Some(r);
    }
}

#[test]
fn wrapping_keeps_the_half_open_range() {
    for (input, expected) in [
        (0.0, 0.0),
        (180.0, 180.0),
        (-180.0, 180.0),
        (190.0, -170.0),
        (-190.0, 170.0),
        (540.0, 180.0),
        (-359.0, 1.0),
    ] {
        assert!((wrap_deg(input) - expected).abs() < 1e-12, "{input}");
    }
}

// The radian forms the protocols use (formerly `deflex_io::link`'s own Euler, rotation-vector and
// quaternion maths), with the assertions of those tests.

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
        let back = kuka_abc_rad(&rotation_from_kuka_abc_rad(zyx), None);
        for i in 0..3 {
            assert!(close(back[i], zyx[i], 1e-12), "{zyx:?} -> {back:?}");
        }
    }
}

#[test]
fn zyx_single_axes() {
    // A about z: x axis goes to y for a = 90°.
    let r = rotation_from_kuka_abc_rad([std::f64::consts::FRAC_PI_2, 0.0, 0.0]);
    assert!(close(r.matrix()[(1, 0)], 1.0, 1e-15));
    let r = rotation_from_kuka_abc_rad([0.0, 0.0, std::f64::consts::FRAC_PI_2]);
    // C about x: y axis goes to z.
    assert!(close(r.matrix()[(2, 1)], 1.0, 1e-15));
}

#[test]
fn rotvec_and_quaternion_round_trip() {
    for v in [[0.01, -0.02, 0.03], [1.0, 0.5, -2.0], [0.0, 0.0, 0.0]] {
        let back = rotation_vector(&rotation_from_rotation_vector(v), None);
        for i in 0..3 {
            assert!(close(back[i], v[i], 1e-12));
        }
        let m = rotation_from_rotation_vector(v);
        let m2 = rotation_from_abb_quaternion(abb_quaternion(&m, None));
        for i in 0..3 {
            for j in 0..3 {
                assert!(close(m[(i, j)], m2[(i, j)], 1e-12));
            }
        }
    }
}

#[test]
fn pose_quaternion_round_trip() {
    let zyx = [0.4, -0.3, 2.0];
    let q = abb_quaternion(&rotation_from_kuka_abc_rad(zyx), None);
    let back = kuka_abc_rad(&rotation_from_abb_quaternion(q), None);
    for i in 0..3 {
        assert!(close(zyx[i], back[i], 1e-12));
    }
}

#[test]
fn values_that_name_no_rotation() {
    // A quaternion of zero or non-finite norm carries no orientation: the identity (an EGM
    // message may leave it unset).
    for q in [[0.0; 4], [f64::INFINITY, 0.0, 0.0, 0.0]] {
        assert_eq!(rotation_from_abb_quaternion(q), Rotation3::identity());
    }
    // A non-finite rotation vector is not silently the identity: its rotation is non-finite,
    // so a protocol's finiteness check refuses it.
    let r = rotation_from_rotation_vector([f64::NAN, 0.0, 0.0]);
    assert!(r.matrix().iter().all(|v| v.is_nan()));
}

#[test]
fn fanuc_wpr_rebuilds_fixed_xyz_products_and_round_trips() {
    for m in samples() {
        let wpr = fanuc_wpr_deg(&rot(m), None);
        // Fixed axes: W about x first, then P about the fixed y, then R about the fixed z.
        let rebuilt = rz(wpr[2]) * ry(wpr[1]) * rx(wpr[0]);
        assert!(distance(&m, &rebuilt) < 1e-12, "{wpr:?}");
        assert!(wpr[1].abs() <= 90.0 && wpr[0].abs() <= 180.0 && wpr[2].abs() <= 180.0);
        let back = rotation_from_fanuc_wpr_deg(wpr);
        assert!(distance(back.matrix(), &m) < 1e-12, "{wpr:?}");
        // Printed to 6 decimals, as the TP writer does, the rotation comes back within 1e-7 rad.
        let printed = wpr.map(|v| (v * 1e6).round() / 1e6);
        assert!(distance(rotation_from_fanuc_wpr_deg(printed).matrix(), &m) < 1e-7);
    }
    // Known angles come back unchanged, in FANUC's order W, P, R.
    let wpr = fanuc_wpr_deg(&rot(rz(-120.0) * ry(35.0) * rx(170.0)), None);
    for (got, want) in wpr.iter().zip([170.0, 35.0, -120.0]) {
        assert!((got - want).abs() < 1e-9, "{wpr:?}");
    }
    // A tool pointing down (TCP z along −z): W = 180, P = 0, R = 0.
    let down = rotation_from_fanuc_wpr_deg([180.0, 0.0, 0.0]);
    assert!((down * Vector3::z() - Vector3::new(0.0, 0.0, -1.0)).norm() < 1e-15);
    // At the gimbal lock the previous point's R is kept.
    let locked = rot(rz(25.0) * ry(90.0) * rx(0.0));
    let wpr = fanuc_wpr_deg(&locked, Some([0.0, 89.0, 25.0]));
    assert!((wpr[2] - 25.0).abs() < 1e-9, "{wpr:?}");
}

/// Yaskawa's Rx, Ry, Rz as a quaternion `[w, x, y, z]` by the half-angle products Basler
/// publishes for the Yaskawa pose format (written out here, independently of the library).
fn yaskawa_quaternion(rxryrz_deg: [f64; 3]) -> [f64; 4] {
    let [x, y, z] = rxryrz_deg.map(|d| d.to_radians() / 2.0);
    let (sx, cx) = x.sin_cos();
    let (sy, cy) = y.sin_cos();
    let (sz, cz) = z.sin_cos();
    [
        cz * cy * cx + sz * sy * sx,
        cz * cy * sx - sz * sy * cx,
        cz * sy * cx + sz * cy * sx,
        sz * cy * cx - cz * sy * sx,
    ]
}

#[test]
fn yaskawa_rxryrz_rebuilds_fixed_xyz_products_and_the_published_quaternion() {
    for m in samples() {
        let r = yaskawa_rxryrz_deg(&rot(m), None);
        // Fixed axes: Rx about x first, then Ry about the fixed y, then Rz about the fixed z.
        let rebuilt = rz(r[2]) * ry(r[1]) * rx(r[0]);
        assert!(distance(&m, &rebuilt) < 1e-12, "{r:?}");
        assert!(r[1].abs() <= 90.0 && r[0].abs() <= 180.0 && r[2].abs() <= 180.0);
        // The published quaternion of the angles is the rotation's (up to its sign).
        let q = yaskawa_quaternion(r);
        let from_q = nalgebra::UnitQuaternion::from_quaternion(nalgebra::Quaternion::new(
            q[0], q[1], q[2], q[3],
        ))
        .to_rotation_matrix();
        assert!(distance(from_q.matrix(), &m) < 1e-12, "{r:?}: {q:?}");
        let back = rotation_from_yaskawa_rxryrz_deg(r);
        assert!(distance(back.matrix(), &m) < 1e-12, "{r:?}");
        // Printed to 6 decimals, as the INFORM writer does: within 1e-7 rad.
        let printed = r.map(|v| (v * 1e6).round() / 1e6);
        assert!(distance(rotation_from_yaskawa_rxryrz_deg(printed).matrix(), &m) < 1e-7);
    }
    // Known angles come back in Yaskawa's order Rx, Ry, Rz.
    let r = yaskawa_rxryrz_deg(&rot(rz(75.0) * ry(-20.0) * rx(-150.0)), None);
    for (got, want) in r.iter().zip([-150.0, -20.0, 75.0]) {
        assert!((got - want).abs() < 1e-9, "{r:?}");
    }
    // Tool pointing down: Rx = 180.
    let down = rotation_from_yaskawa_rxryrz_deg([180.0, 0.0, 0.0]);
    assert!((down * Vector3::z() - Vector3::new(0.0, 0.0, -1.0)).norm() < 1e-15);
    // At the gimbal lock the previous point's Rz is kept.
    let locked = rot(rz(-40.0) * ry(-90.0) * rx(0.0));
    let r = yaskawa_rxryrz_deg(&locked, Some([0.0, -89.0, -40.0]));
    assert!((r[2] + 40.0).abs() < 1e-9, "{r:?}");
}
