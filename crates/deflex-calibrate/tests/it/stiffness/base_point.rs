//! The base reflector M0 of the planner lets the structure search tell a baseplate tilt from the
//! x/y eDoFs of joint 1: both rotate the TCP about axes through the same point, but only the tilt
//! moves the base casting.

use deflex_calibrate::stiffness::plan::{BasePoint, PlanOptions, plan_experiments};
use deflex_calibrate::stiffness::search::{SearchOptions, search_structure};
use deflex_calibrate::stiffness::synthetic::{SyntheticOptions, measure};
use deflex_model::{Axis, EdofSite, Robot, builtin};

fn identify(truth: &Robot, base_point: bool) -> Robot {
    let plan = plan_experiments(
        truth,
        &PlanOptions {
            max_force_n: 1400.0,
            load_cases: 40,
            full_family: true,
            base_point: if base_point {
                BasePoint::Default
            } else {
                BasePoint::Off
            },
            ..PlanOptions::default()
        },
    )
    .unwrap();
    assert_eq!(
        plan.rows
            .iter()
            .any(|r| r.point == "M0" && r.point_link == 0),
        base_point
    );
    let rows = measure(truth, &plan.rows, &SyntheticOptions::default()).unwrap();
    let start = builtin("tx200-1edof").unwrap();
    let result = search_structure(&start, &rows, &SearchOptions::default(), &mut |_| {}).unwrap();
    eprintln!(
        "base point {base_point}: {}",
        result.calibration.structure.label()
    );
    result.calibration.to_robot(&start)
}

#[test]
fn base_point_separates_tilt_from_joint_one() {
    let mut truth = builtin("tx200").unwrap();
    truth.set_stiffness(EdofSite::Base, Axis::X, Some(8.0e6));
    truth.set_stiffness(EdofSite::Base, Axis::Y, Some(4.5e6));
    truth.set_stiffness(EdofSite::Joint(1), Axis::X, Some(15e6));
    truth.set_stiffness(EdofSite::Joint(1), Axis::Y, Some(15e6));
    let error = |robot: &Robot, site, axis| {
        let k = robot.stiffness(site, axis).unwrap_or(f64::INFINITY);
        k / truth.stiffness(site, axis).unwrap() - 1.0
    };
    let without = identify(&truth, false);
    let with = identify(&truth, true);
    for (site, axis) in [
        (EdofSite::Base, Axis::X),
        (EdofSite::Base, Axis::Y),
        (EdofSite::Joint(1), Axis::X),
        (EdofSite::Joint(1), Axis::Y),
    ] {
        eprintln!(
            "{site}.{}: without M0 {:+.1} %, with M0 {:+.1} %",
            axis.letter(),
            100.0 * error(&without, site, axis),
            100.0 * error(&with, site, axis)
        );
        assert!(
            error(&with, site, axis).abs() < 0.10,
            "{site}.{:?} with M0",
            axis
        );
    }
}

/// The design tilts the base about the robot's pivot: nearly noise-free data of a robot whose baseplate
/// tilts about the floor (0.642 m below R0, written by the model's `point_displacement`) give
/// back its base stiffness exactly when the start model knows the pivot, and a biased one when
/// it assumes R0.
#[test]
fn the_base_tilts_about_the_robots_pivot_in_the_fit() {
    use deflex_calibrate::stiffness::stiffness_fit::{Structure, calibrate_fixed};
    let mut truth = builtin("tx200").unwrap();
    truth.base_pivot = nalgebra::Vector3::new(0.0, 0.0, -0.642);
    truth.set_stiffness(EdofSite::Base, Axis::X, Some(8.0e6));
    truth.set_stiffness(EdofSite::Base, Axis::Y, Some(4.5e6));
    let plan = plan_experiments(
        &truth,
        &PlanOptions {
            max_force_n: 1400.0,
            load_cases: 24,
            ..PlanOptions::default()
        },
    )
    .unwrap();
    // Noise far below anything the tilt's bias could hide (1 nm).
    let noise_free = SyntheticOptions {
        noise_sigma_m: 1e-9,
        ..SyntheticOptions::default()
    };
    let rows = measure(&truth, &plan.rows, &noise_free).unwrap();
    let structure = Structure::from_robot(&truth);
    let relative_error = |start: &Robot| {
        let calibration = calibrate_fixed(start, &rows, &structure).unwrap();
        let fitted = calibration.to_robot(start);
        let k = fitted.stiffness(EdofSite::Base, Axis::Y).unwrap();
        k / 4.5e6 - 1.0
    };
    let knows = relative_error(&truth);
    let mut at_r0 = truth.clone();
    at_r0.base_pivot = nalgebra::Vector3::zeros();
    let assumes_r0 = relative_error(&at_r0);
    eprintln!("base.y: pivot known {knows:+.2e}, pivot at R0 {assumes_r0:+.2e}");
    assert!(knows.abs() < 1e-6, "{knows}");
    assert!(assumes_r0.abs() > 1e-3, "{assumes_r0}");
}
