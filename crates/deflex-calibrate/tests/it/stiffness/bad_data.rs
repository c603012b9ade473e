//! Bad data gets a clear message, never a panic.

use deflex_calibrate::measurements::parse_rows;
use deflex_calibrate::stiffness::search::{SearchOptions, search_structure};
use deflex_calibrate::stiffness::stiffness_fit::{Status, Structure, calibrate_fixed};
use deflex_calibrate::stiffness::synthetic::{SyntheticOptions, measure, random_campaign};
use deflex_model::builtin;

fn rows() -> Vec<deflex_calibrate::measurements::MeasurementRow> {
    let robot = builtin("tx200-1edof").unwrap();
    let plan = random_campaign(&robot, 10, (600.0, 1400.0), 4);
    measure(&robot, &plan, &SyntheticOptions::default()).unwrap()
}

fn fixed_error(rows: &[deflex_calibrate::measurements::MeasurementRow]) -> String {
    let robot = builtin("tx200-1edof").unwrap();
    calibrate_fixed(&robot, rows, &Structure::from_robot(&robot))
        .unwrap_err()
        .to_string()
}

#[test]
fn nan_in_file_and_in_rows() {
    let text = deflex_calibrate::measurements::format_rows(&rows());
    let first_data_line = text.lines().nth(1).unwrap();
    let fields: Vec<&str> = first_data_line.split(',').collect();
    let mut fields: Vec<String> = fields.iter().map(|s| s.to_string()).collect();
    let n = fields.len();
    fields[n - 2] = "NaN".into(); // dy_m ... sigma: second to last is dz or sigma; either is numeric
    let bad = text.replacen(first_data_line, &fields.join(","), 1);
    let err = parse_rows(&bad, "d.csv", true).unwrap_err().to_string();
    assert!(err.contains("d.csv:2") && err.contains("finite"), "{err}");

    let mut r = rows();
    r[3].displacement_m = Some([0.0, f64::NAN, 0.0]);
    let err = fixed_error(&r);
    assert!(err.contains("row 4") && err.contains("NaN"), "{err}");
}

#[test]
fn wrong_column_count() {
    let text = deflex_calibrate::measurements::format_rows(&rows());
    let short = format!("{text}R9,1,2,3\n");
    let err = parse_rows(&short, "d.csv", true).unwrap_err().to_string();
    assert!(err.contains("fields"), "{err}");
    // Five joint columns for a six-joint robot.
    let mut r = rows();
    for row in &mut r {
        row.q_rad.pop();
    }
    let err = fixed_error(&r);
    assert!(
        err.contains("5 joint columns") && err.contains("6 joints"),
        "{err}"
    );
}

#[test]
fn zero_load_everywhere() {
    let mut r = rows();
    for row in &mut r {
        row.wrench = [0.0; 6];
    }
    let err = fixed_error(&r);
    assert_eq!(err, "every load is zero: nothing to identify");
    let robot = builtin("tx200-1edof").unwrap();
    let err = search_structure(&robot, &r, &SearchOptions::default(), &mut |_| {})
        .unwrap_err()
        .to_string();
    assert!(err.contains("every load is zero"), "{err}");
}

#[test]
fn all_points_on_one_link() {
    let robot = builtin("tx200-1edof").unwrap();
    let plan: Vec<_> = random_campaign(&robot, 20, (600.0, 1400.0), 8)
        .into_iter()
        .filter(|r| r.point_link == 2)
        .collect();
    let r = measure(&robot, &plan, &SyntheticOptions::default()).unwrap();
    let cal = calibrate_fixed(&robot, &r, &Structure::from_robot(&robot)).unwrap();
    let warning = cal.warnings.join("\n");
    assert!(
        warning.contains("all measured points are on link 2") && warning.contains("J3.z"),
        "{warning}"
    );
    for e in &cal.edofs {
        let observable = e.id.0.link_index() <= 2;
        assert_eq!(
            matches!(e.status, Status::Identified),
            observable,
            "{}: {:?}",
            e.label,
            e.status
        );
    }
    // Nothing observable at all: points on the base.
    let mut base_only = r.clone();
    for row in &mut base_only {
        row.point_link = 0;
    }
    let err = fixed_error(&base_only);
    assert!(
        err.contains("no eDoF of the structure is observable") && err.contains("J1.z"),
        "{err}"
    );
}

/// Issue 12: degenerate data gets an error, never a panic.
#[test]
fn all_displacements_zero_is_an_error() {
    let mut r = rows();
    for row in &mut r {
        row.displacement_m = Some([0.0; 3]);
    }
    let err = fixed_error(&r);
    assert!(
        err.contains("every measured displacement is exactly zero"),
        "{err}"
    );
    let robot = builtin("tx200-1edof").unwrap();
    let err = search_structure(&robot, &r, &SearchOptions::default(), &mut |_| {})
        .unwrap_err()
        .to_string();
    assert!(err.contains("exactly zero"), "{err}");
}

/// Issue 12: `fx_N = 1e308` (finite, absurd) is refused with the column named, in a file and
/// in rows built in code.
#[test]
fn absurd_magnitudes_are_refused_with_the_column_named() {
    let mut r = rows();
    r[2].wrench[0] = 1e308;
    let err = fixed_error(&r);
    assert!(err.contains("row 3") && err.contains("fx_N"), "{err}");
    let text = deflex_calibrate::measurements::format_rows(&r);
    let err = parse_rows(&text, "d.csv", true).unwrap_err().to_string();
    assert!(
        err.contains("d.csv:4") && err.contains("fx_N") && err.contains("1e308"),
        "{err}"
    );
    let mut r = rows();
    r[0].sigma_m = Some(5e-324);
    let err = fixed_error(&r);
    assert!(err.contains("sigma_m"), "{err}");
    let mut r = rows();
    r[1].displacement_m = Some([2.0, 0.0, 0.0]);
    let err = fixed_error(&r);
    assert!(err.contains("dx_m"), "{err}");
}

/// Displacements against every spring (all compliances at the c ≥ 0 bound, nothing free):
/// once a `symmetric_eigen` of a 0 × 0 matrix; now every eDoF is reported not identifiable.
#[test]
fn data_that_pins_every_compliance_at_zero_does_not_panic() {
    let mut r = rows();
    for row in &mut r {
        let d = row.displacement_m.unwrap();
        row.displacement_m = Some([-d[0], -d[1], -d[2]]);
    }
    let robot = builtin("tx200-1edof").unwrap();
    let cal = calibrate_fixed(&robot, &r, &Structure::from_robot(&robot)).unwrap();
    assert!(
        cal.edofs
            .iter()
            .all(|e| matches!(e.status, Status::NotIdentifiable(_))),
        "{:?}",
        cal.edofs.iter().map(|e| &e.status).collect::<Vec<_>>()
    );
    let _ = search_structure(&robot, &r, &SearchOptions::default(), &mut |_| {});
}

/// Issue 12: `plan --max-force-N 1e308` once spun in an SVD on NaN; now refused at once.
#[test]
fn an_absurd_plan_force_is_refused() {
    let robot = builtin("tx200").unwrap();
    for force in [1e308, f64::INFINITY, f64::NAN, -5.0, 0.0] {
        let err = deflex_calibrate::stiffness::plan::plan_experiments(
            &robot,
            &deflex_calibrate::stiffness::plan::PlanOptions {
                max_force_n: force,
                ..Default::default()
            },
        )
        .unwrap_err()
        .to_string();
        assert!(err.contains("--max-force-N"), "{err}");
    }
}
