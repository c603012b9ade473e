//! Bad data gets a clear message, never a panic.

mod common;

use deflex_calib::data::parse_rows;
use deflex_calib::fit::{Status, Structure, calibrate_fixed};
use deflex_calib::search::{SearchOptions, search_structure};
use deflex_calib::synthetic::{SyntheticOptions, measure, random_campaign};
use deflex_model::builtin;

fn rows() -> Vec<deflex_calib::MeasurementRow> {
    let robot = builtin("tx200-1edof").unwrap();
    let plan = random_campaign(&robot, 10, (600.0, 1400.0), 4);
    measure(&robot, &plan, &SyntheticOptions::default()).unwrap()
}

fn fixed_error(rows: &[deflex_calib::MeasurementRow]) -> String {
    let robot = builtin("tx200-1edof").unwrap();
    calibrate_fixed(&robot, rows, &Structure::from_robot(&robot))
        .unwrap_err()
        .to_string()
}

#[test]
fn nan_in_file_and_in_rows() {
    let text = deflex_calib::data::format_rows(&rows());
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
    let text = deflex_calib::data::format_rows(&rows());
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
    let err = search_structure(&robot, &r, &SearchOptions::default(), &mut |_, _, _| {})
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
