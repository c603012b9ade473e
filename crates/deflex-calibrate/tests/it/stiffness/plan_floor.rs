//! `deflex plan --floor-z-m`: every planned configuration keeps the arm above the floor.

use deflex_calibrate::stiffness::plan::{Floor, PlanOptions, lowest_point_z, plan_experiments};
use deflex_model::Data;

fn lowest_of_plan(options: &PlanOptions) -> f64 {
    let robot = deflex_model::builtin("tx200").unwrap();
    let plan = plan_experiments(&robot, options).unwrap();
    let mut data = Data::new();
    plan.rows
        .iter()
        .map(|r| {
            robot.forward_kinematics(&mut data, &r.q_rad).unwrap();
            lowest_point_z(&robot, &data)
        })
        .fold(f64::INFINITY, f64::min)
}

#[test]
fn planned_configurations_stay_above_the_floor() {
    let floor = -0.2;
    let free = lowest_of_plan(&PlanOptions {
        full_family: true,
        ..PlanOptions::default()
    });
    // Without a floor the planner does go below it (so the check below can fail).
    assert!(free < floor, "lowest point without a floor: {free} m");
    let guarded = lowest_of_plan(&PlanOptions {
        full_family: true,
        floor: Floor::At(floor),
        clearance_m: 0.0,
        ..PlanOptions::default()
    });
    eprintln!("lowest point: {free:.3} m without a floor, {guarded:.3} m with z ≥ {floor} m");
    assert!(guarded >= floor, "{guarded}");
}

#[test]
fn an_unreachable_floor_is_a_clear_error() {
    let robot = deflex_model::builtin("tx200").unwrap();
    let e = plan_experiments(
        &robot,
        &PlanOptions {
            floor: Floor::At(3.0),
            configurations: 50,
            ..PlanOptions::default()
        },
    )
    .unwrap_err()
    .to_string();
    assert!(e.contains("floor") && e.contains("3.000 m"), "{e}");
}
