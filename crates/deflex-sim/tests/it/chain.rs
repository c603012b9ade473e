//! The plant's product-of-exponentials chain: against a hand-written DH product and closed
//! forms, its small-angle series, a spring's carried axis, and the twists as its derivative.

use deflex_model::{Pose, builtin};
use deflex_sim::chain::{Chain, ChainState, GeometryErrors, JOINTS, Screw, SpringSpec};
use nalgebra::{Rotation3, Vector3};

fn tx200_chain(springs: &[SpringSpec]) -> Chain {
    let robot = builtin("tx200").unwrap();
    Chain::new(
        &robot,
        &GeometryErrors::default(),
        springs,
        &[0.0; JOINTS],
        &Vector3::zeros(),
        &Pose::identity(),
    )
}

/// The modified-DH product written out with plain 4×4 matrices from the TX200's DH table
/// (an oracle separate from both the plant's exponentials and deflex-model's placements).
fn tx200_dh_oracle(q: &[f64; 6]) -> nalgebra::Matrix4<f64> {
    use std::f64::consts::{FRAC_PI_2, PI};
    let table = [
        (0.0, 0.0, 0.0, 0.0),
        (-FRAC_PI_2, 0.250, 0.0, -FRAC_PI_2),
        (0.0, 0.950, 0.0, -FRAC_PI_2),
        (-FRAC_PI_2, 0.0, 0.800, 0.0),
        (FRAC_PI_2, 0.0, 0.0, 0.0),
        (-FRAC_PI_2, 0.0, 0.194, PI),
    ];
    let mut t = nalgebra::Matrix4::identity();
    for (i, (alpha, a, d, offset)) in table.iter().enumerate() {
        let (sa, ca) = (alpha as &f64).sin_cos();
        let (st, ct) = (q[i] + offset).sin_cos();
        // RotX(α) TransX(a) RotZ(θ) TransZ(d) (Craig 3.6).
        #[rustfmt::skip]
        let m = nalgebra::Matrix4::new(
            ct,       -st,       0.0,  *a,
            st * ca,  ct * ca,  -sa,  -sa * d,
            st * sa,  ct * sa,   ca,   ca * d,
            0.0,      0.0,       0.0,  1.0,
        );
        t *= m;
    }
    t
}

#[test]
fn product_of_exponentials_matches_the_dh_product_and_a_hand_closed_form() {
    let chain = tx200_chain(&[]);
    let mut state = ChainState::default();
    // Hand closed form: q2 = 90° stretches the arm horizontally along x0 at shoulder height:
    // x = a2 + a3 + d4 + d6 = 0.25 + 0.95 + 0.8 + 0.194 = 2.194 m (the TX200's reach).
    chain.evaluate(
        &[0.0, 90f64.to_radians(), 0.0, 0.0, 0.0, 0.0],
        &[],
        &mut state,
    );
    let p = state.tcp.translation.vector;
    assert!((p - Vector3::new(2.194, 0.0, 0.0)).norm() < 1e-12, "{p}");
    // Hand closed form at q = 0: upper arm and forearm straight up above J2:
    // x = a2 = 0.25 m, z = a3 + d4 + d6 = 0.95 + 0.8 + 0.194 = 1.944 m.
    chain.evaluate(&[0.0; 6], &[], &mut state);
    let p = state.tcp.translation.vector;
    assert!((p - Vector3::new(0.25, 0.0, 1.944)).norm() < 1e-12, "{p}");
    // Arbitrary configurations against the matrix product.
    let configs = [
        [0.3, -0.4, 1.1, 0.7, -0.9, 2.0],
        [-2.0, 1.2, -0.5, -1.5, 1.7, -0.3],
        deflex_model::TX200_FORMING_Q_DEG.map(f64::to_radians),
    ];
    for q in configs {
        chain.evaluate(&q, &[], &mut state);
        let oracle = tx200_dh_oracle(&q);
        let m = state.tcp.to_homogeneous();
        assert!((m - oracle).abs().max() < 1e-12, "{q:?}: {m} vs {oracle}");
    }
}

/// The small-angle series of the springs' `(sin x, cos x)` (|x| < 0.01 rad) agree with the
/// library. Read through `Screw::exp`, which uses them: about z through the origin, Rodrigues'
/// matrix holds `cos x` at (0, 0) and `sin x` at (1, 0) exactly (the other terms are zeros).
#[test]
fn the_small_angle_series_agree_with_the_library() {
    let about_z = Screw {
        axis: Vector3::z(),
        point: Vector3::zeros(),
    };
    for x in [0.0, 1e-12, -3e-7, 1e-4, -2.5e-3, 0.0099999, 0.01, -0.3, 2.0] {
        let m = *about_z.exp(x).rotation.matrix();
        let (s, c) = (m[(1, 0)], m[(0, 0)]);
        assert!((s - x.sin()).abs() <= 1e-18 + 2e-16 * x.abs(), "{x}");
        assert!((c - x.cos()).abs() <= 2e-16, "{x}");
    }
}

#[test]
fn a_spring_turns_everything_beyond_it_about_its_carried_axis() {
    // J3.x spring with its centre at the frame origin: turning it by θ rotates the TCP about
    // the current x3 axis through O3 (checked against an explicit rotation of the rigid TCP).
    let springs = [SpringSpec { link: 3, axis: 0 }];
    let chain = tx200_chain(&springs);
    let q = [0.2, 0.7, 1.3, 0.4, 0.6, -0.2];
    let mut rigid = ChainState::default();
    chain.evaluate(&q, &[0.0], &mut rigid);
    let mut bent = ChainState::default();
    let theta = 0.05;
    chain.evaluate(&q, &[theta], &mut bent);
    let frame3 = rigid.links[3];
    let axis = frame3.rotation.matrix().column(0).into_owned();
    let o3 = frame3.translation.vector;
    let r = Rotation3::from_axis_angle(&nalgebra::Unit::new_normalize(axis), theta);
    let expected = o3 + r * (rigid.tcp.translation.vector - o3);
    assert!((bent.tcp.translation.vector - expected).norm() < 1e-12);
    // Links before the spring do not move.
    for k in 0..3 {
        assert!((bent.links[k].to_homogeneous() - rigid.links[k].to_homogeneous()).norm() < 1e-14);
    }
    // The spring's current screw is x3 through O3.
    assert!((bent.springs[0].axis - axis).norm() < 1e-14);
    assert!((bent.springs[0].point - o3).norm() < 1e-14);
}

#[test]
fn twists_are_the_derivative_of_the_chain() {
    // Finite differences of the TCP position and orientation with respect to each spring
    // angle, at a deformed configuration, against the carried screws' twists.
    let mut springs = Vec::new();
    for link in 0..=6 {
        for axis in 0..3 {
            springs.push(SpringSpec { link, axis });
        }
    }
    let robot = builtin("tx200").unwrap();
    let shifts = [0.0, 0.0, 0.4, 0.0, 0.0, 0.0];
    let chain = Chain::new(
        &robot,
        &GeometryErrors::default(),
        &springs,
        &shifts,
        &Vector3::new(0.0, 0.0, -0.642),
        &Pose::identity(),
    );
    let q = deflex_model::TX200_FORMING_Q_DEG.map(f64::to_radians);
    let theta: Vec<f64> = (0..springs.len())
        .map(|i| 1e-3 * ((i as f64) * 0.7).sin())
        .collect();
    let mut state = ChainState::default();
    chain.evaluate(&q, &theta, &mut state);
    let p = state.tcp.translation.vector;
    let h = 1e-6;
    for s in 0..springs.len() {
        let mut plus = theta.clone();
        plus[s] += h;
        let mut minus = theta.clone();
        minus[s] -= h;
        let (mut a, mut b) = (ChainState::default(), ChainState::default());
        chain.evaluate(&q, &plus, &mut a);
        chain.evaluate(&q, &minus, &mut b);
        let dp = (a.tcp.translation.vector - b.tcp.translation.vector) / (2.0 * h);
        let dr = deflex_model::spatial::rotation_log(&(a.tcp.rotation * b.tcp.rotation.inverse()))
            / (2.0 * h);
        let twist = state.springs[s].twist_at(&p);
        let linear = Vector3::new(twist[0], twist[1], twist[2]);
        let angular = Vector3::new(twist[3], twist[4], twist[5]);
        assert!((dp - linear).norm() < 1e-7, "spring {s}: {dp} vs {linear}");
        assert!(
            (dr - angular).norm() < 1e-7,
            "spring {s}: {dr} vs {angular}"
        );
    }
}
