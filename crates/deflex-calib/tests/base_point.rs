//! The base reflector M0 of the planner lets the structure search tell a baseplate tilt from the
//! x/y eDoFs of joint 1: both rotate the TCP about axes through the same point, but only the tilt
//! moves the base casting.

use deflex_calib::plan::{BasePoint, PlanOptions, plan_experiments};
use deflex_calib::search::{SearchOptions, search_structure};
use deflex_calib::synthetic::{SyntheticOptions, measure};
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
    let result =
        search_structure(&start, &rows, &SearchOptions::default(), &mut |_, _, _| {}).unwrap();
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
