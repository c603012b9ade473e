//! The compensation against oracles that do not use its own code: the robot model's forward
//! kinematics and eq. 15 evaluated at the returned joint values, a hand-computed single-joint
//! case, the closed-form fixed point of a force linear in the commanded depth, and failures
//! reported with their index and reason.

use deflex_compensate::{
    CompensationOptions, DepthProportional, IkFailure, PointFailure, TcpPath, WrenchSource,
    apply_displacement, compensate,
};
use deflex_model::spatial::orientation_error;
use deflex_model::{Axis, EdofSite, Pose, Robot, TX200_FORMING_Q_DEG, Wrench, builtin};
use nalgebra::{Rotation3, Translation3, Vector3};

fn seed() -> Vec<f64> {
    TX200_FORMING_Q_DEG.iter().map(|d| d.to_radians()).collect()
}

/// A circle of radius `r` (m) around the TX200's forming point, tool down as at the seed,
/// descending `dz` per turn.
fn circle(robot: &Robot, points: usize, r: f64, dz: f64) -> TcpPath {
    let start = robot.tcp_pose(&seed()).unwrap();
    let centre = start.translation.vector;
    let poses = (0..points).map(|i| {
        let t = i as f64 / points as f64;
        let a = 2.0 * std::f64::consts::PI * t;
        let p = centre + Vector3::new(r * a.cos(), r * a.sin(), -dz * t);
        (
            Pose::from_parts(Translation3::from(p), start.rotation),
            Some(0.01),
        )
    });
    TcpPath::new("circle", poses, 0.05).unwrap()
}

fn no_progress() -> impl FnMut(deflex_telemetry::Progress<'_>) {
    |_| {}
}

#[test]
fn with_fixed_wrenches_the_predicted_tool_lands_on_the_desired_path() {
    let robot = builtin("tx200").unwrap();
    let path = circle(&robot, 120, 0.02, 0.005);
    let wrenches: Vec<Wrench> = (0..path.len())
        .map(|i| Wrench::new(-150.0 + i as f64, 300.0, 1200.0, 2.0, -3.0, 1.0))
        .collect();
    let result = compensate(
        &robot,
        &path,
        &seed(),
        WrenchSource::Fixed {
            label: "test".into(),
            simulated: false,
            wrenches: &wrenches,
        },
        &CompensationOptions::default(),
        &mut no_progress(),
    )
    .unwrap();
    assert!(result.converged);
    assert_eq!(
        result.iterations.len(),
        1,
        "fixed wrenches: one pass is exact"
    );
    assert_eq!(result.failure_count(), 0);
    // Uncompensated, the model predicts millimetres of error.
    assert!(result.iterations[0].max_predicted_error_m > 1e-3);
    let mut worst: f64 = 0.0;
    for (i, point) in result.points.iter().enumerate() {
        let desired = &path.points()[i].pose;
        // Oracle: the model's own FK and eq. 15 at the returned joint values.
        let q = &point.q[..6];
        let tcp = robot.tcp_pose(q).unwrap();
        let commanded = point.commanded(desired);
        assert!((tcp.translation.vector - commanded.translation.vector).norm() < 1e-9);
        let mut data = deflex_model::Data::new();
        robot.forward_kinematics(&mut data, q).unwrap();
        let deflection = robot.tcp_deflection(&data, &wrenches[i]);
        let actual = apply_displacement(&tcp, &deflection);
        let dp = (actual.translation.vector - desired.translation.vector).norm();
        let dr = orientation_error(&desired.rotation, &actual.rotation).norm();
        worst = worst.max(dp);
        assert!(dp < 1e-8 && dr < 1e-8, "point {i}: {dp} m, {dr} rad");
        // The compensation is the negative deflection at the commanded configuration.
        assert!((point.compensation + deflection).norm() < 1e-8);
    }
    assert!(worst < 1e-8);
    assert!(result.final_max_error_m < 1e-8);
}

#[test]
fn single_elastic_joint_matches_the_hand_computation() {
    // Only joint 1 is elastic (k about its z axis, through the world origin); the wrench is a
    // pure moment M about z, so the twist θ = M/k is the same everywhere. The model deflects a
    // pose by δp = θ z × p, δφ = θ z. The compensated pose c must satisfy c ⊕ δ = d:
    //   p_c + θ z × p_c = p_d  ⇒  x_c = (x_d + θ y_d)/(1 + θ²), y_c = (y_d − θ x_d)/(1 + θ²),
    //   z_c = z_d, and R_c = Rz(−θ) R_d.
    let mut robot = builtin("tx200").unwrap();
    for j in 1..=6 {
        for axis in Axis::ALL {
            robot.set_stiffness(EdofSite::Joint(j), axis, None);
        }
    }
    let k = 2.32e6;
    robot.set_stiffness(EdofSite::Joint(1), Axis::Z, Some(k));
    let m = 5000.0;
    let theta = m / k;
    let path = circle(&robot, 24, 0.05, 0.0);
    let wrenches = vec![Wrench::new(0.0, 0.0, 0.0, 0.0, 0.0, m); path.len()];
    let result = compensate(
        &robot,
        &path,
        &seed(),
        WrenchSource::Fixed {
            label: "moment".into(),
            simulated: false,
            wrenches: &wrenches,
        },
        &CompensationOptions {
            tolerance_m: 1e-9,
            tolerance_rad: 1e-9,
            ..CompensationOptions::default()
        },
        &mut no_progress(),
    )
    .unwrap();
    for (i, point) in result.points.iter().enumerate() {
        let d = &path.points()[i].pose;
        let (xd, yd, zd) = (
            d.translation.vector.x,
            d.translation.vector.y,
            d.translation.vector.z,
        );
        let c = point.commanded(d);
        let s = 1.0 + theta * theta;
        let want = Vector3::new((xd + theta * yd) / s, (yd - theta * xd) / s, zd);
        assert!(
            (c.translation.vector - want).norm() < 1e-12,
            "point {i}: {} vs {want}",
            c.translation.vector
        );
        let want_rotation = Rotation3::from_axis_angle(&Vector3::z_axis(), -theta) * d.rotation;
        assert!(orientation_error(&want_rotation, &c.rotation).norm() < 1e-12);
        // And the twist is what the hand computation says: about 2.16 mrad, 3.2 mm at 1.5 m.
        assert!((point.compensation[5] + theta).abs() < 1e-12);
    }
    assert!((theta - 2.155e-3).abs() < 1e-6);
}

/// Force per metre of commanded depth of the closed-form case (N/m).
const K: f64 = 4.6e5;

/// The closed-form case: a force K·(h − c_z) along +z on a descending circle.
fn closed_form_case(acceleration: bool) -> (deflex_compensate::Compensation, TcpPath, Robot) {
    let robot = builtin("tx200").unwrap();
    let path = circle(&robot, 60, 0.02, 0.004);
    let surface = path.points()[0].pose.translation.vector.z + 0.001;
    let mut model = DepthProportional {
        direction: Vector3::z(),
        surface_m: surface,
        // C_zz ≈ 1.08e-6 m/N at this configuration: C_zz·k ≈ 0.5 (plain iteration halves the
        // change each time).
        stiffness_n_m: K,
    };
    let options = CompensationOptions {
        tolerance_m: 1e-9,
        tolerance_rad: 1e-9,
        acceleration,
        max_iterations: 60,
        ..CompensationOptions::default()
    };
    let result = compensate(
        &robot,
        &path,
        &seed(),
        WrenchSource::Process(&mut model),
        &options,
        &mut no_progress(),
    )
    .unwrap();
    (result, path, robot)
}

#[test]
fn force_linear_in_depth_converges_to_the_closed_form_fixed_point() {
    for acceleration in [false, true] {
        let (result, path, robot) = closed_form_case(acceleration);
        assert!(result.converged, "acceleration {acceleration}");
        assert_eq!(result.failure_count(), 0);
        let surface = path.points()[0].pose.translation.vector.z + 0.001;
        let k = K;
        for (i, point) in result.points.iter().enumerate() {
            let d = &path.points()[i].pose;
            let c = point.commanded(d);
            let mut data = deflex_model::Data::new();
            robot.forward_kinematics(&mut data, &point.q[..6]).unwrap();
            let compliance = robot.compliance_matrix(&data);
            let czz = compliance[(2, 2)];
            // c_z = d_z − C_zz k (h − c_z)  ⇒  c_z = (d_z − C_zz k h) / (1 − C_zz k)
            let cz = (d.translation.vector.z - czz * k * surface) / (1.0 - czz * k);
            assert!(
                (c.translation.vector.z - cz).abs() < 5e-9,
                "point {i}: {} vs {cz}",
                c.translation.vector.z
            );
            // The other components follow the same force: x = −C[:, z] F.
            let force = k * (surface - c.translation.vector.z);
            for r in [0, 1, 3, 4, 5] {
                let want = -compliance[(r, 2)] * force;
                assert!((point.compensation[r] - want).abs() < 5e-9, "row {r}");
            }
            assert!((point.wrench[2] - force).abs() < 1e-3);
        }
        let its = &result.iterations;
        if acceleration {
            assert!(
                its.len() <= 6,
                "{} iterations with Anderson mixing",
                its.len()
            );
        } else {
            // Plain iteration: each change is C_zz·k ≈ 0.5 of the previous one.
            let mut data = deflex_model::Data::new();
            robot.forward_kinematics(&mut data, &seed()).unwrap();
            let rho = robot.compliance_matrix(&data)[(2, 2)] * k;
            assert!((0.3..0.7).contains(&rho), "C_zz k = {rho}");
            for pair in its.windows(2).skip(1).take(8) {
                let ratio = pair[1].max_change_m / pair[0].max_change_m;
                assert!(
                    (ratio - rho).abs() < 0.05 * rho + 0.02,
                    "ratio {ratio}, C_zz k {rho}"
                );
            }
            assert!(its.len() > 20, "{} iterations", its.len());
        }
        // The first iteration starts from the uncompensated path: the deflection is the error.
        assert!(its[0].max_predicted_error_m > 1e-3);
        assert!(
            result.final_max_error_m < 1e-8,
            "{}",
            result.final_max_error_m
        );
    }
}

#[test]
fn points_that_cannot_be_compensated_are_reported_with_index_and_reason() {
    let mut robot = builtin("tx200").unwrap();
    let path = {
        // A line along x through the forming point: q1 = 0 exactly.
        let start = robot.tcp_pose(&seed()).unwrap();
        let poses = (0..10).map(|i| {
            let p = start.translation.vector + Vector3::new(0.001 * i as f64, 0.0, 0.0);
            (
                Pose::from_parts(Translation3::from(p), start.rotation),
                Some(0.01),
            )
        });
        TcpPath::new("line", poses, 0.05).unwrap()
    };
    // Joint 1 may not leave ±1 µrad: a lateral force on points 3..=5 needs it to.
    robot.joints[0].limits = Some([-1e-6, 1e-6]);
    let mut wrenches = vec![Wrench::zeros(); path.len()];
    for w in &mut wrenches[3..=5] {
        *w = Wrench::new(0.0, 800.0, 0.0, 0.0, 0.0, 0.0);
    }
    let result = compensate(
        &robot,
        &path,
        &seed(),
        WrenchSource::Fixed {
            label: "lateral".into(),
            simulated: false,
            wrenches: &wrenches,
        },
        &CompensationOptions::default(),
        &mut no_progress(),
    )
    .unwrap();
    let failures: Vec<(usize, String)> = result.failures().map(|(i, f)| (i, f.code())).collect();
    assert_eq!(
        failures,
        [3, 4, 5].map(|i| (i, "compensated:joint_limit:J1".to_string()))
    );
    for (i, failure) in result.failures() {
        let PointFailure::Compensated(IkFailure::JointLimit {
            joint, value_rad, ..
        }) = failure
        else {
            panic!("{failure}");
        };
        assert_eq!(*joint, 1);
        assert!(value_rad.abs() > 1e-6, "point {i}");
        // Kept, uncompensated, not dropped.
        assert_eq!(result.points[i].compensation, nalgebra::Vector6::zeros());
    }
    assert_eq!(result.points.len(), path.len());

    // Out of reach: a desired point 5 m away is flagged as such, the others are compensated.
    let robot = builtin("tx200").unwrap();
    let start = robot.tcp_pose(&seed()).unwrap();
    let poses: Vec<(Pose, Option<f64>)> = (0..6)
        .map(|i| {
            let mut p = start.translation.vector + Vector3::new(0.0, 0.001 * i as f64, 0.0);
            if i == 4 {
                p.x += 5.0;
            }
            (
                Pose::from_parts(Translation3::from(p), start.rotation),
                Some(0.01),
            )
        })
        .collect();
    let path = TcpPath::new("reach", poses, 0.05).unwrap();
    let wrenches = vec![Wrench::new(0.0, 0.0, 1000.0, 0.0, 0.0, 0.0); path.len()];
    let result = compensate(
        &robot,
        &path,
        &seed(),
        WrenchSource::Fixed {
            label: "z".into(),
            simulated: false,
            wrenches: &wrenches,
        },
        &CompensationOptions::default(),
        &mut no_progress(),
    )
    .unwrap();
    let failures: Vec<(usize, String)> = result.failures().map(|(i, f)| (i, f.code())).collect();
    assert_eq!(failures, [(4, "desired:not_reached".to_string())]);
    assert!(
        result.points[5].compensation.norm() > 1e-4,
        "the next point is compensated"
    );
}

#[test]
fn options_wrench_counts_and_seeds_are_checked() {
    let robot = builtin("tx200").unwrap();
    let path = circle(&robot, 10, 0.01, 0.0);
    let wrenches = vec![Wrench::zeros(); 9];
    let e = compensate(
        &robot,
        &path,
        &seed(),
        WrenchSource::Fixed {
            label: "x".into(),
            simulated: false,
            wrenches: &wrenches,
        },
        &CompensationOptions::default(),
        &mut no_progress(),
    )
    .unwrap_err();
    assert!(
        e.to_string().contains("9 wrenches for a path of 10 points"),
        "{e}"
    );
    let mut bad = vec![Wrench::zeros(); 10];
    bad[7][2] = f64::NAN;
    let e = compensate(
        &robot,
        &path,
        &seed(),
        WrenchSource::Fixed {
            label: "x".into(),
            simulated: false,
            wrenches: &bad,
        },
        &CompensationOptions::default(),
        &mut no_progress(),
    )
    .unwrap_err();
    assert!(e.to_string().contains("point 7"), "{e}");
    let ok = vec![Wrench::zeros(); 10];
    let e = compensate(
        &robot,
        &path,
        &seed()[..5],
        WrenchSource::Fixed {
            label: "x".into(),
            simulated: false,
            wrenches: &ok,
        },
        &CompensationOptions::default(),
        &mut no_progress(),
    )
    .unwrap_err();
    assert!(
        e.to_string().contains("expected 6 joint values, got 5"),
        "{e}"
    );
    let options = CompensationOptions {
        tolerance_m: 0.0,
        ..CompensationOptions::default()
    };
    let e = compensate(
        &robot,
        &path,
        &seed(),
        WrenchSource::Fixed {
            label: "x".into(),
            simulated: false,
            wrenches: &ok,
        },
        &options,
        &mut no_progress(),
    )
    .unwrap_err();
    assert!(e.to_string().contains("tolerance_m"), "{e}");
}
