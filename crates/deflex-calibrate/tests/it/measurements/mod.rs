//! The tests of `deflex_calibrate::measurements` (the old `deflex-measurements`): round trips
//! and error messages of the format.

use deflex_calibrate::measurements::*;

fn sample() -> Vec<MeasurementRow> {
    vec![MeasurementRow {
        load_case: "L1".into(),
        q_rad: vec![0.0, std::f64::consts::FRAC_PI_2, 0.0, 0.0, 0.0, 0.0],
        wrench: [0.0, 1400.0, 0.0, 0.0, 0.0, 0.0],
        load_link: 6,
        load_point_m: [2.194, 0.0, 0.0],
        point: "M2, elbow".into(),
        point_link: 3,
        point_m: [1.2, 0.1, 0.0],
        displacement_m: Some([1.25e-4, -3.5e-4, 2e-6]),
        sigma_m: Some(1.5e-5),
        rotation_rad: None,
        purpose: Some("J1.z".into()),
    }]
}

#[test]
fn round_trip_is_exact() {
    let rows = sample();
    let text = format_rows(&rows);
    assert_eq!(parse_rows(&text, "t.csv", true).unwrap(), rows);
}

#[test]
fn bad_rows_name_line_and_column() {
    let text = format_rows(&sample());
    let bad = text.replace("1400.0", "NaN");
    let err = parse_rows(&bad, "t.csv", true).unwrap_err().to_string();
    assert!(err.contains("t.csv:2") && err.contains("fy_N"), "{err}");
    let bad = text.replace("1400.0", "12x");
    let err = parse_rows(&bad, "t.csv", true).unwrap_err().to_string();
    assert!(
        err.contains("expected a number") && err.contains("\"12x\""),
        "{err}"
    );
    let short = format!("{}{}", text, "L2,0,0\n");
    let err = parse_rows(&short, "t.csv", true).unwrap_err().to_string();
    assert!(err.contains("t.csv:3") && err.contains("fields"), "{err}");
    let no_dx = text.replacen("dx_m", "dq_m", 1);
    let err = parse_rows(&no_dx, "t.csv", true).unwrap_err().to_string();
    assert!(
        err.contains("missing column") && err.contains("dx_m"),
        "{err}"
    );
    let bad_link = text.replace(",6,2.194", ",9,2.194");
    let err = parse_rows(&bad_link, "t.csv", true)
        .unwrap_err()
        .to_string();
    assert!(
        err.contains("load_link") && err.contains("does not exist"),
        "{err}"
    );
}

#[test]
fn plan_needs_no_displacement() {
    let mut rows = sample();
    rows[0].displacement_m = None;
    rows[0].sigma_m = None;
    let text = format_rows(&rows);
    assert!(!text.contains("dx_m"));
    assert_eq!(parse_rows(&text, "p.csv", false).unwrap(), rows);
    assert!(parse_rows(&text, "p.csv", true).is_err());
}

#[test]
fn rotation_and_sigma_rad_round_trip() {
    let mut rows = sample();
    rows.push(rows[0].clone());
    rows.push(rows[0].clone());
    rows[0].rotation_rad = Some(MeasuredRotation {
        value_rad: [1.25e-5, -3.0e-6, 7.1e-7],
        sigma_rad: Some(2.5e-5),
    });
    rows[1].rotation_rad = Some(MeasuredRotation::new([-2e-6, 0.0, 4.5e-5]));
    rows[2].point = "TCP".into();
    let text = format_rows(&rows);
    let header = text.lines().next().unwrap();
    assert!(
        header.ends_with("drx_rad,dry_rad,drz_rad,sigma_rad,purpose"),
        "{header}"
    );
    let back = parse_rows(&text, "t.csv", true).unwrap();
    assert_eq!(back, rows);
    assert_eq!(back[0].rotation_rad.unwrap().sigma(), 2.5e-5);
    assert_eq!(
        back[1].rotation_rad.unwrap().sigma(),
        deflex_calibrate::measurements::DEFAULT_SIGMA_RAD
    );
    // Without any sigma_rad the column is not written.
    rows[0].rotation_rad = Some(MeasuredRotation::new([1.0e-5, 0.0, 0.0]));
    let text = format_rows(&rows);
    assert!(!text.contains("sigma_rad") && text.contains("drz_rad"));
    assert_eq!(parse_rows(&text, "t.csv", true).unwrap(), rows);
    // A bad sigma_rad names the column.
    let mut rows = sample();
    rows[0].rotation_rad = Some(MeasuredRotation {
        value_rad: [0.0; 3],
        sigma_rad: Some(-1.0),
    });
    let err = parse_rows(&format_rows(&rows), "t.csv", true)
        .unwrap_err()
        .to_string();
    assert!(
        err.contains("sigma_rad") && err.contains("positive"),
        "{err}"
    );
}

/// `text` with one more column `name` holding `value` on every row.
fn with_column(text: &str, name: &str, value: &str) -> String {
    let mut lines = text.lines();
    let mut out = format!("{},{name}\n", lines.next().unwrap());
    for line in lines {
        out += &format!("{line},{value}\n");
    }
    out
}

#[test]
fn an_extra_column_is_an_error_unless_ignored_by_name() {
    let rows = sample();
    let text = with_column(&format_rows(&rows), "operator", "ann");
    let err = parse_rows(&text, "t.csv", true).unwrap_err().to_string();
    assert!(
        err.contains("t.csv")
            && err.contains("unknown column `operator`")
            && err.contains("--ignore-column operator"),
        "{err}"
    );
    let ignored = ["operator".to_string()];
    let file = parse_file_ignoring(&text, "t.csv", true, &ignored).unwrap();
    assert_eq!(file.rows, rows);
    // A typo still names its closest column, even with another column ignored.
    let typo = with_column(&text, "sigma_mm", "0.01");
    let err = parse_file_ignoring(&typo, "t.csv", true, &ignored)
        .unwrap_err()
        .to_string();
    assert!(err.contains("did you mean `sigma_m`?"), "{err}");
    // Only unknown columns can be ignored; a misspelt ignored name leaves the column unknown.
    for (name, expected) in [
        ("sigma_m", "cannot be ignored"),
        ("q1_rad", "cannot be ignored"),
        ("q7_rad", "cannot be ignored"),
        ("operater", "unknown column `operator`"),
    ] {
        let err = parse_file_ignoring(&text, "t.csv", true, &[name.to_string()])
            .unwrap_err()
            .to_string();
        assert!(err.contains(expected), "{name}: {err}");
    }
}

#[test]
fn a_duplicated_column_is_an_error_even_when_ignored() {
    let text = format_rows(&sample());
    let dup = with_column(&text, "fy_N", "0.0");
    let err = parse_rows(&dup, "t.csv", true).unwrap_err().to_string();
    assert!(err.contains("column `fy_N` appears twice"), "{err}");
    let extra = with_column(&with_column(&text, "note", "a"), "note", "b");
    let err = parse_file_ignoring(&extra, "t.csv", true, &["note".to_string()])
        .unwrap_err()
        .to_string();
    assert!(err.contains("column `note` appears twice"), "{err}");
}

#[test]
fn one_load_case_holding_two_configurations_is_refused() {
    let mut rows = sample();
    rows.push(rows[0].clone());
    rows[1].point = "TCP".into();
    // Same load case, same configuration: fine.
    parse_rows(&format_rows(&rows), "t.csv", true).unwrap();
    rows.push(rows[0].clone());
    rows[2].point = "M3".into();
    rows[2].q_rad[2] = 0.25;
    let err = parse_rows(&format_rows(&rows), "t.csv", true)
        .unwrap_err()
        .to_string();
    assert!(
        err.contains("t.csv")
            && err.contains("load case `L1`")
            && err.contains("line 2")
            && err.contains("line 4")
            && err.contains("q3_rad"),
        "{err}"
    );
    // The same configuration under another label is a separate load case.
    rows[2].load_case = "L2".into();
    parse_rows(&format_rows(&rows), "t.csv", true).unwrap();
}
