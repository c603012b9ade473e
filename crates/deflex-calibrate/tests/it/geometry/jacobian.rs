//! Every analytic Jacobian column (position and orientation) against central finite differences
//! of the full prediction,
//! and the model's gravity sag against deflex-model's own `gravity_displacement`.

use deflex_calibrate::geometry::model::Conditions;
use deflex_calibrate::geometry::params::{EgModel, Param, TorsionShape, TorsionTerm};
use deflex_model::spatial::rotation_log;
use deflex_model::{NamedPoint, NamedPose, builtin, spatial::pose_from_xyz_rpy};
use nalgebra::Vector3;

fn model(name: &str, compliance_factor: f64) -> EgModel {
    let mut robot = builtin(name).unwrap();
    for j in &mut robot.joints {
        if j.inertia.is_none() {
            j.inertia = Some(deflex_model::LinkInertia {
                mass_kg: 20.0,
                com: Vector3::new(0.05, -0.02, 0.1),
            });
        }
    }
    let mut m = EgModel::from_robot(&robot);
    m.setups.push(NamedPose {
        name: "A".into(),
        pose: pose_from_xyz_rpy([2.1, -1.3, 0.2], [0.02, -0.03, 2.4]),
    });
    m.targets.push(NamedPoint {
        name: "probe".into(),
        position: Vector3::new(0.01, -0.02, 0.093),
        rotation: Some(nalgebra::Rotation3::from_euler_angles(0.3, -0.2, 1.1)),
    });
    for c in &mut m.compliance {
        *c *= compliance_factor;
    }
    // Nonlinear torsion on every eDoF of an elastic model (the turn's slope then differs from
    // its compliance, which every column that moves a torque must use).
    for (e, c) in m.compliance.clone().into_iter().enumerate() {
        for (shape, factor) in [(TorsionShape::Cubic, -0.3), (TorsionShape::Soft(40), 0.5)] {
            m.torsion.push(TorsionTerm {
                edof: e,
                shape,
                value: factor * c,
            });
        }
    }
    let mut params = m.geometric_params();
    params.push(Param::Harmonic {
        joint: 1,
        order: 1,
        sine: false,
    });
    params.push(Param::Harmonic {
        joint: 2,
        order: 2,
        sine: true,
    });
    let deltas: Vec<f64> = (0..params.len())
        .map(|k| 1e-3 * ((k as f64) * 0.77).sin())
        .collect();
    m.apply(&params, &deltas);
    m
}

fn all_params(m: &EgModel) -> Vec<Param> {
    let mut params = m.registration_params(true);
    params.extend(m.geometric_params());
    params.extend((0..m.compliance.len()).map(Param::Compliance));
    for b in 0..m.robot.joint_count() {
        params.push(Param::Mass(b));
        for k in 0..3 {
            params.push(Param::FirstMoment(b, k));
        }
    }
    params.extend((0..m.robot.joint_count()).map(Param::Backlash));
    for edof in 0..m.compliance.len() {
        for shape in [TorsionShape::Cubic, TorsionShape::Soft(40)] {
            params.push(Param::Torsion { edof, shape });
        }
    }
    for j in 0..m.robot.joint_count() {
        for order in [1, 2, 101] {
            for sine in [false, true] {
                params.push(Param::Harmonic {
                    joint: j,
                    order,
                    sine,
                });
            }
        }
    }
    params
}

/// Every column, rigid (`compliance_factor` 0, with an external wrench) and elastic (10× the
/// built-in compliances, payload), to differencing precision.
fn check(name: &str, compliance_factor: f64, relative_tolerance: f64) {
    let m = model(name, compliance_factor);
    let loads = Conditions {
        payload: Some((3.0, Vector3::new(0.0, 0.02, 0.05))),
        wrench: Some([30.0, -50.0, 120.0, 2.0, -1.0, 0.5]),
        approach_rad: [0.1, -0.2, 0.0, 1e-3, -0.5, 2.0, 0.0, 0.0],
    };
    let params = all_params(&m);
    for q in [
        [0.3, -1.2, 1.1, -0.4, 1.3, 0.7],
        [-2.0, -0.6, -1.9, 0.9, -0.4, 2.5],
    ] {
        let ev = m.evaluate(&q, 0, &loads);
        for &p in &params {
            let analytic = m.tracker_column(&ev, 0, p);
            let h = match EgModel::unit(p) {
                deflex_calibrate::geometry::params::Unit::Compliance => 1e-6,
                deflex_calibrate::geometry::params::Unit::Kilogram
                | deflex_calibrate::geometry::params::Unit::KilogramMetre => 1e-3,
                _ => 1e-6,
            };
            let mut plus = m.clone();
            plus.apply(&[p], &[h]);
            let mut minus = m.clone();
            minus.apply(&[p], &[-h]);
            let numeric = (plus.predict_tracker(&q, 0, 0, &loads)
                - minus.predict_tracker(&q, 0, 0, &loads))
                / (2.0 * h);
            let analytic_p = analytic.position;
            let tolerance = relative_tolerance * numeric.norm().max(analytic_p.norm()) + 1e-9;
            assert!(
                (analytic_p - numeric).norm() <= tolerance,
                "{name} {} at {q:?}: position analytic {analytic_p:?} numeric {numeric:?}",
                m.param_name(p)
            );
            // Orientation: ω with dR·Rᵀ = [ω]×, from log(R₊ R₋ᵀ)/(2h).
            let numeric = rotation_log(
                &(plus.predict_orientation(&q, 0, 0, &loads)
                    * minus.predict_orientation(&q, 0, 0, &loads).inverse()),
            ) / (2.0 * h);
            let analytic_r = analytic.rotation;
            let tolerance = relative_tolerance * numeric.norm().max(analytic_r.norm()) + 1e-9;
            assert!(
                (analytic_r - numeric).norm() <= tolerance,
                "{name} {} at {q:?}: rotation analytic {analytic_r:?} numeric {numeric:?}",
                m.param_name(p)
            );
        }
    }
}

#[test]
fn columns_match_finite_differences_standard_dh() {
    check("ur10", 0.0, 1e-6);
    check("ur10", 10.0, 1e-6);
}

#[test]
fn columns_match_finite_differences_modified_dh() {
    check("tx200", 0.0, 1e-6);
    check("tx200", 10.0, 1e-6);
}

#[test]
fn sag_matches_the_model_crate() {
    let mut m = model("ur10", 3.0);
    m.harmonics.clear();
    m.torsion.clear();
    // The model crate's gravity uses the robot's stiffness and inertias: make them match.
    let robot = m.to_robot();
    let m = EgModel {
        robot: robot.clone(),
        ..m
    };
    let q = [0.3, -1.2, 1.1, -0.4, 1.3, 0.7];
    let ev = m.evaluate(&q, 0, &Conditions::default());
    let mut data = deflex_model::Data::new();
    robot.forward_kinematics(&mut data, &q).unwrap();
    let p = ev.target_world;
    let expected = robot.gravity_displacement(&data, &p, robot.joint_count());
    let sag = ev.sag_world;
    assert!(sag.norm() > 1e-4, "{sag:?}");
    assert!(
        (sag - Vector3::new(expected[0], expected[1], expected[2])).norm()
            < 1e-12 * 1e3 * sag.norm()
    );
}
