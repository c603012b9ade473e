//! The planner for a real cell: every built-in robot, the floor and the table, joint values
//! wrapped into the limits, cable and dead-weight loads, configurable measured points, the
//! off-axis bracket that makes the wrist identifiable (with a Monte Carlo check of its expected
//! standard error), and a technician's sheet that agrees with the identifiability table.

use deflex_calibrate::measurements::points::{PointSpec, parse_points};
use deflex_calibrate::stiffness::campaign_cell::{
    LoadKind, PointSet, default_floor_z, default_force_n, wrapped,
};
use deflex_calibrate::stiffness::plan::{
    BasePoint, Floor, Plan, PlanOptions, TableOption, plan_experiments,
};
use deflex_calibrate::stiffness::stiffness_fit::{Structure, calibrate_fixed};
use deflex_calibrate::stiffness::synthetic::{SyntheticOptions, measure};
use deflex_model::{Axis, BUILTIN_ROBOTS, Data, EdofSite, Robot, builtin};
use nalgebra::{Point3, Vector3};

/// Independent check of one plan against its cell: limits, wrapping, floor, table, loads.
fn check_cell(robot: &Robot, plan: &Plan, clearance: f64) {
    let setup = &plan.setup;
    let mut data = Data::new();
    for row in &plan.rows {
        for (q, joint) in row.q_rad.iter().zip(&robot.joints) {
            let [lo, hi] = joint.limits.unwrap();
            assert!(
                *q >= lo && *q <= hi,
                "{}: {q} outside [{lo}, {hi}]",
                robot.name
            );
            // Wrapped: no equivalent value of smaller magnitude within the limits.
            for k in [-1.0, 1.0] {
                let other = q + k * std::f64::consts::TAU;
                assert!(
                    !(other >= lo && other <= hi && other.abs() < q.abs() - 1e-9),
                    "{}: {:.1}° could be {:.1}°",
                    robot.name,
                    q.to_degrees(),
                    other.to_degrees()
                );
            }
        }
        robot.forward_kinematics(&mut data, &row.q_rad).unwrap();
        let mut heights: Vec<Vector3<f64>> = (1..=robot.joint_count())
            .map(|i| data.link_frame(i).translation.vector)
            .collect();
        heights.push(data.tcp_position());
        heights.push(Vector3::from(row.point_m));
        heights.push(Vector3::from(row.load_point_m));
        if let Some(floor) = setup.floor_z_m {
            for p in &heights {
                assert!(
                    p.z >= floor + clearance - 1e-9,
                    "{}: z {} below floor {floor}",
                    robot.name,
                    p.z
                );
            }
        }
        if let Some(t) = setup.table {
            for p in &heights {
                let over = p.x >= t.x_m[0] && p.x <= t.x_m[1] && p.y >= t.y_m[0] && p.y <= t.y_m[1];
                assert!(
                    !over || p.z >= t.top_z_m,
                    "{}: {p:?} inside the table",
                    robot.name
                );
            }
        }
        let f = Vector3::new(row.wrench[0], row.wrench[1], row.wrench[2]);
        assert!(
            (f.norm() - setup.force_n).abs() < 1e-9 * setup.force_n,
            "{}",
            f.norm()
        );
    }
}

#[test]
fn every_builtin_robot_gets_a_plan_for_a_real_cell() {
    for (name, _) in BUILTIN_ROBOTS {
        let robot = builtin(name).unwrap();
        let force = default_force_n(&robot).unwrap();
        let plan = plan_experiments(
            &robot,
            &PlanOptions {
                max_force_n: force,
                load_cases: 12,
                configurations: 200,
                full_family: true,
                ..PlanOptions::for_a_real_cell()
            },
        )
        .unwrap();
        let floor = plan.setup.floor_z_m.unwrap();
        eprintln!(
            "{name}: default force {force} N, floor z {floor:.3} m, {} of {} configurations clear, {} load cases",
            plan.setup.configurations_kept,
            plan.setup.configurations_drawn,
            deflex_calibrate::measurements::load_case_count(&plan.rows)
        );
        check_cell(&robot, &plan, 0.05);
        // The mounting face: below a shoulder-height R0 for the TX200 and the FANUC-like and
        // Motoman-like arms (R0 at J2's height, as their controllers' frames), else R0's plane.
        let expected_floor = match *name {
            n if n.starts_with("tx200") => -0.642,
            "r2000ic-165f" => -0.670,
            "gp180" => -0.650,
            _ => 0.0,
        };
        assert!((floor - expected_floor).abs() < 1e-9, "{name}: {floor}");
        assert!(plan.rows.iter().any(|r| r.point == "M0"));
        // M0 clears the floor for every robot (it used to sit 0.3 m below R0 whatever the robot).
        let m0 = plan.rows.iter().find(|r| r.point == "M0").unwrap();
        assert!(
            m0.point_m[2] >= floor + 0.05,
            "{name}: M0 at {:?}",
            m0.point_m
        );
    }
    assert_eq!(default_force_n(&builtin("tx200").unwrap()).unwrap(), 1400.0);
    assert_eq!(default_force_n(&builtin("ur10e").unwrap()).unwrap(), 140.0);
}

#[test]
fn the_floor_keeps_the_tx200_off_the_ground_and_an_unknown_floor_is_asked_for() {
    let robot = builtin("tx200").unwrap();
    let free = plan_experiments(&robot, &PlanOptions::default()).unwrap();
    let lowest = |plan: &Plan| {
        let mut data = Data::new();
        plan.rows
            .iter()
            .map(|r| {
                robot.forward_kinematics(&mut data, &r.q_rad).unwrap();
                data.tcp_position().z
            })
            .fold(f64::INFINITY, f64::min)
    };
    // Without the checks the TCP goes below the TX200's floor (0.642 m under its shoulder).
    assert!(lowest(&free) < -0.642, "{}", lowest(&free));
    let real = plan_experiments(&robot, &PlanOptions::for_a_real_cell()).unwrap();
    assert!(lowest(&real) >= -0.642 + 0.05, "{}", lowest(&real));

    // A robot whose R0 is at its shoulder and whose floor the file does not give.
    let mut shoulder = builtin("irb4600").unwrap();
    shoulder.base.translation.vector.z = 0.0;
    shoulder.joints[0].placement.translation.vector.z = 0.0;
    let e = default_floor_z(&shoulder).unwrap_err().to_string();
    assert!(e.contains("--floor-z-m") && e.contains("--no-floor"), "{e}");
    let e = plan_experiments(&shoulder, &PlanOptions::for_a_real_cell())
        .unwrap_err()
        .to_string();
    assert!(e.contains("--floor-z-m"), "{e}");
    let plan = plan_experiments(
        &shoulder,
        &PlanOptions {
            floor: Floor::At(-0.5),
            table: TableOption::Off,
            ..PlanOptions::for_a_real_cell()
        },
    )
    .unwrap();
    check_cell(&shoulder, &plan, 0.05);
}

#[test]
fn joint_values_are_wrapped_into_the_limits() {
    let deg = f64::to_radians;
    let wide = [deg(-270.0), deg(270.0)];
    assert!((wrapped(deg(-259.0), wide) - deg(101.0)).abs() < 1e-12);
    assert!((wrapped(deg(250.6), wide) - deg(-109.4)).abs() < 1e-12);
    assert_eq!(wrapped(deg(30.0), wide), deg(30.0));
    // No equivalent within the limits: unchanged; one only outside zero: taken.
    assert_eq!(
        wrapped(deg(200.0), [deg(-180.0), deg(190.0)]),
        deg(200.0) - std::f64::consts::TAU
    );
    assert!((wrapped(deg(-10.0), [0.0, deg(360.0)]) - deg(350.0)).abs() < 1e-12);
    // UR joints (±360°) planned over their whole range come out within ±180°.
    let ur = builtin("ur10e").unwrap();
    let plan = plan_experiments(
        &ur,
        &PlanOptions {
            max_force_n: 140.0,
            ..PlanOptions::for_a_real_cell()
        },
    )
    .unwrap();
    for row in &plan.rows {
        assert!(
            row.q_rad
                .iter()
                .all(|q| q.abs() <= std::f64::consts::PI + 1e-9),
            "{:?}",
            row.q_rad
        );
    }
    // As the technician's sheet prints them (degrees, one decimal).
    for row in &plan.rows {
        for q in &row.q_rad {
            let v: f64 = format!("{:.1}", q.to_degrees()).parse().unwrap();
            assert!(v.abs() <= 180.0, "{:?}", row.q_rad);
        }
    }
}

// The technician's sheet against the identifiability table: deflex-report (plan_tables).

/// Expected SE of J6.z: infinite with loads at the TCP (on J6's axis), finite with a bracket.
#[test]
fn a_bracket_makes_joint_six_identifiable() {
    let robot = builtin("tx200").unwrap();
    let se = |bracket: Option<[f64; 3]>| {
        let plan = plan_experiments(
            &robot,
            &PlanOptions {
                max_force_n: 1400.0,
                full_family: true,
                bracket_m: bracket,
                ..PlanOptions::for_a_real_cell()
            },
        )
        .unwrap();
        let of = |axis| {
            plan.expected
                .iter()
                .find(|e| e.id == (EdofSite::Joint(6), axis))
                .unwrap()
                .relative
        };
        (of(Axis::X), of(Axis::Y), of(Axis::Z), plan)
    };
    let (x0, y0, z0, _) = se(None);
    let (x1, y1, z1, plan) = se(Some([0.2, 0.0, 0.1]));
    eprintln!(
        "J6 relative expected SE without bracket: x {x0} y {y0} z {z0}; with a (0.2, 0, 0.1) m bracket: x {:.4} y {:.4} z {:.4}",
        x1, y1, z1
    );
    assert!(z0.is_infinite() && x0.is_infinite() && y0.is_infinite());
    assert!(z1.is_finite() && z1 < 0.5, "{z1}");
    assert!(x1.is_finite() && y1.is_finite());
    assert!(plan.rows.iter().any(|r| r.point == "BR"));
    assert!(plan.rows.iter().any(|r| {
        r.purpose
            .as_deref()
            .is_some_and(|p| p.contains("at the bracket"))
    }));
    check_cell(&robot, &plan, 0.05);
}

/// The planner's expected SE of J6.z with a bracket against the spread of the calibrated J6.z
/// over 40 simulated campaigns of the same plan (an oracle independent of the planner's
/// information matrix: NNLS fits of noisy data).
#[test]
fn bracket_expected_se_matches_monte_carlo() {
    let mut truth = builtin("tx200").unwrap();
    truth.set_stiffness(EdofSite::Joint(6), Axis::Z, Some(1.5e4));
    let sigma = 15e-6;
    let plan = plan_experiments(
        &truth,
        &PlanOptions {
            max_force_n: 200.0,
            load_cases: 10,
            noise_sigma_m: sigma,
            bracket_m: Some([0.1, 0.0, 0.0]),
            ..PlanOptions::for_a_real_cell()
        },
    )
    .unwrap();
    let expected = plan
        .expected
        .iter()
        .find(|e| e.id == (EdofSite::Joint(6), Axis::Z))
        .unwrap()
        .se_k;
    assert!(expected.is_finite());
    let structure = Structure::from_robot(&truth);
    let runs = 40;
    let fitted: Vec<f64> = (0..runs)
        .map(|seed| {
            let rows = measure(
                &truth,
                &plan.rows,
                &SyntheticOptions {
                    noise_sigma_m: sigma,
                    seed: 500 + seed,
                    ..Default::default()
                },
            )
            .unwrap();
            let cal = calibrate_fixed(&truth, &rows, &structure).unwrap();
            cal.edof((EdofSite::Joint(6), Axis::Z))
                .unwrap()
                .stiffness
                .unwrap()
        })
        .collect();
    let mean = fitted.iter().sum::<f64>() / runs as f64;
    let spread =
        (fitted.iter().map(|v| (v - mean).powi(2)).sum::<f64>() / (runs - 1) as f64).sqrt();
    eprintln!(
        "J6.z: expected SE {expected:.1} N·m/rad, Monte Carlo spread {spread:.1} N·m/rad over {runs} campaigns (mean {mean:.0})"
    );
    let ratio = spread / expected;
    assert!((0.65..1.35).contains(&ratio), "spread / expected = {ratio}");
    assert!((mean - 1.5e4).abs() < 4.0 * expected / (runs as f64).sqrt());
}

#[test]
fn dead_weights_hang_along_gravity_clear_of_floor_and_table() {
    let robot = builtin("tx200").unwrap();
    let options = PlanOptions {
        load: LoadKind::DeadWeight {
            masses_kg: vec![60.0, 140.0],
        },
        load_cases: 16,
        full_family: true,
        ..PlanOptions::for_a_real_cell()
    };
    let plan = plan_experiments(&robot, &options).unwrap();
    let g = robot.gravity;
    let floor = plan.setup.floor_z_m.unwrap();
    let table = plan.setup.table.unwrap();
    let mut masses = std::collections::BTreeSet::new();
    for r in &plan.rows {
        let f = Vector3::new(r.wrench[0], r.wrench[1], r.wrench[2]);
        let m = f.norm() / g.norm();
        assert!((f - g * m).norm() < 1e-9, "{f:?} is not along gravity");
        masses.insert((m * 1e6).round() as i64);
        let a = Vector3::from(r.load_point_m);
        assert!(
            a.z - 0.3 >= floor + 0.05 - 1e-9,
            "the weight hits the floor: {a:?}"
        );
        let over = a.x >= table.x_m[0] - 0.05
            && a.x <= table.x_m[1] + 0.05
            && a.y >= table.y_m[0] - 0.05
            && a.y <= table.y_m[1] + 0.05;
        assert!(
            !over || a.z - 0.3 >= table.top_z_m + 0.05 - 1e-9,
            "the weight hits the table: {a:?}"
        );
        assert!(r.purpose.as_deref().unwrap().contains("dead weight"));
    }
    assert_eq!(masses.len(), 2, "both weights are used: {masses:?}");
}

#[test]
fn cables_pull_only_along_the_allowed_directions() {
    let robot = builtin("ur10e").unwrap();
    let plan = plan_experiments(
        &robot,
        &PlanOptions {
            max_force_n: 150.0,
            load: LoadKind::Cable {
                directions: vec![[0.0, 0.0, -1.0], [1.0, 0.0, 0.0]],
            },
            ..PlanOptions::for_a_real_cell()
        },
    )
    .unwrap();
    for r in &plan.rows {
        let f = [r.wrench[0], r.wrench[1], r.wrench[2]];
        assert!(f == [0.0, 0.0, -150.0] || f == [150.0, 0.0, 0.0], "{f:?}");
    }
}

#[test]
fn measured_points_are_configurable() {
    let robot = builtin("ur10e").unwrap();
    let base = PlanOptions {
        max_force_n: 150.0,
        load_cases: 8,
        ..PlanOptions::for_a_real_cell()
    };
    // None: the TCP and M0 only.
    let plan = plan_experiments(
        &robot,
        &PlanOptions {
            points: PointSet::Custom(Vec::new()),
            ..base.clone()
        },
    )
    .unwrap();
    assert!(
        plan.rows
            .iter()
            .all(|r| r.point == "TCP" || r.point == "M0")
    );
    // A reflector on link 3 and a base point given in R0, checked against FK by hand.
    let text = "# reflectors\nname,link,x_m,y_m,z_m\nR3,3,0.30,0.0,0.05\n";
    let points = parse_points(text, "p.csv", 6).unwrap();
    assert_eq!(
        points,
        vec![PointSpec {
            name: "R3".into(),
            link: 3,
            position_m: [0.3, 0.0, 0.05]
        }]
    );
    let plan = plan_experiments(
        &robot,
        &PlanOptions {
            points: PointSet::Custom(points),
            base_point: BasePoint::At([0.25, 0.1, 0.05]),
            ..base.clone()
        },
    )
    .unwrap();
    let mut data = Data::new();
    for r in &plan.rows {
        robot.forward_kinematics(&mut data, &r.q_rad).unwrap();
        let expected = match r.point.as_str() {
            "TCP" => data.tcp_position(),
            "R3" => {
                data.link_frame(3)
                    .transform_point(&Point3::new(0.3, 0.0, 0.05))
                    .coords
            }
            "M0" => Vector3::new(0.25, 0.1, 0.05),
            other => panic!("unexpected point {other}"),
        };
        assert!(
            (Vector3::from(r.point_m) - expected).norm() < 1e-12,
            "{}",
            r.point
        );
    }
    // No base point.
    let plan = plan_experiments(
        &robot,
        &PlanOptions {
            base_point: BasePoint::Off,
            ..base
        },
    )
    .unwrap();
    assert!(!plan.rows.iter().any(|r| r.point == "M0"));
    // Bad points files name the line and the column.
    for (text, wanted) in [
        ("name,link,x_m,y_m,z_m\nR3,9,0,0,0\n", "p.csv:2: `link`"),
        ("name,link,x_m,y_m,z_m\nR3,2,nan,0,0\n", "p.csv:2: `x_m`"),
        ("name,link,x_m,y_m,z_m\nTCP,2,0,0,0\n", "reserved"),
        ("name,link,x\nR3,2,0\n", "expected the columns"),
    ] {
        let e = parse_points(text, "p.csv", 6).unwrap_err().to_string();
        assert!(e.contains(wanted), "{e}");
    }
}

#[test]
fn every_option_is_bounded_and_named() {
    let robot = builtin("tx200").unwrap();
    let cases: Vec<(PlanOptions, &str)> = vec![
        (
            PlanOptions {
                max_force_n: 1e308,
                ..Default::default()
            },
            "--max-force-N",
        ),
        (
            PlanOptions {
                max_force_n: f64::NAN,
                ..Default::default()
            },
            "--max-force-N",
        ),
        (
            PlanOptions {
                load_cases: 0,
                ..Default::default()
            },
            "--load-cases",
        ),
        (
            PlanOptions {
                configurations: 1_000_000_000,
                ..Default::default()
            },
            "--configurations",
        ),
        (
            PlanOptions {
                noise_sigma_m: f64::NAN,
                ..Default::default()
            },
            "--noise-um",
        ),
        (
            PlanOptions {
                clearance_m: f64::INFINITY,
                ..Default::default()
            },
            "--clearance-m",
        ),
        (
            PlanOptions {
                hanging_drop_m: -1.0,
                ..Default::default()
            },
            "--hanging-drop-m",
        ),
        (
            PlanOptions {
                floor: Floor::At(f64::NAN),
                ..Default::default()
            },
            "--floor-z-m",
        ),
        (
            PlanOptions {
                bracket_m: Some([f64::NAN, 0.0, 0.0]),
                ..Default::default()
            },
            "--bracket-m",
        ),
        (
            PlanOptions {
                bracket_m: Some([5.0, 0.0, 0.0]),
                ..Default::default()
            },
            "--bracket-m",
        ),
        (
            PlanOptions {
                base_point: BasePoint::At([1e9, 0.0, 0.0]),
                ..Default::default()
            },
            "--base-point-m",
        ),
        (
            PlanOptions {
                load: LoadKind::DeadWeight {
                    masses_kg: vec![f64::NAN],
                },
                ..Default::default()
            },
            "--masses-kg",
        ),
        (
            PlanOptions {
                load: LoadKind::DeadWeight {
                    masses_kg: vec![10.0; 9],
                },
                ..Default::default()
            },
            "--masses-kg",
        ),
        (
            PlanOptions {
                load: LoadKind::Cable { directions: vec![] },
                ..Default::default()
            },
            "--cable-directions",
        ),
    ];
    for (options, flag) in cases {
        let e = plan_experiments(&robot, &options).unwrap_err().to_string();
        assert!(e.contains(flag), "{flag}: {e}");
    }
    // Joint limits are required.
    let mut free = robot.clone();
    free.joints[3].limits = None;
    let e = plan_experiments(&free, &PlanOptions::default())
        .unwrap_err()
        .to_string();
    assert!(e.contains("joint 4") && e.contains("limits"), "{e}");
}
