use deflex_calibrate::geometry::data::*;

fn sample() -> Vec<AbsoluteRow> {
    vec![
        AbsoluteRow {
            line: 0,
            setup: "A".into(),
            target: "tmac".into(),
            config: Some("c1".into()),
            q_rad: vec![0.1, -1.2, 0.5, 0.0, 1.5, -0.25],
            position_m: [2.361, -1.3685, 0.1194],
            sigma_m: Some(2.1e-5),
            orientation: Some(RowOrientation {
                rotation_vector_rad: [0.1, -0.2, 1.3],
                sigma_rad: Some(3e-5),
            }),
            payload: Some(RowPayload {
                mass_kg: 2.5,
                com_m: [0.0, 0.01, 0.05],
            }),
            wrench: Some([0.0, 0.0, -100.0, 0.0, 1.0, 0.0]),
            temperature_c: Some(22.5),
            time_s: Some(1.5e9),
            approach_rad: Some(vec![0.0, 0.5, -0.25, 0.0, 1e-3, -2.0]),
        },
        AbsoluteRow::position(0, "B", "tmac", vec![0.0; 6], [1.0, 2.0, 3.0]),
    ]
}

#[test]
fn round_trip_is_exact() {
    let rows = sample();
    let text = format_absolute(&rows, &["made by a test".into()]);
    let mut back = parse_absolute(&text, "t.csv", 6).unwrap();
    assert_eq!(back[0].line, 3);
    for r in &mut back {
        r.line = 0;
    }
    assert_eq!(back, rows);
}

#[test]
fn bad_values_name_line_and_column() {
    let text = format_absolute(&sample(), &[]);
    let cases = [
        ("2.361", "NaN", "x_m", "finite"),
        ("2.361", "1e9", "x_m", "within"),
        ("2.1e-5", "-1e-5", "sigma_m", "positive"),
        ("22.5", "900.0", "temperature_C", "°C"),
        ("2.5", "-2.5", "payload_kg", "negative"),
        ("-100.0", "12x", "fz_N", "expected a number"),
    ];
    for (from, to, column, words) in cases {
        let bad = text.replacen(from, to, 1);
        let err = parse_absolute(&bad, "t.csv", 6).unwrap_err().to_string();
        assert!(
            err.contains("t.csv:2") && err.contains(column) && err.contains(words),
            "{from}->{to}: {err}"
        );
    }
    let err = parse_absolute(&text, "t.csv", 7).unwrap_err().to_string();
    assert!(
        err.contains("6 joint columns") && err.contains("7 joints"),
        "{err}"
    );
    // A renamed column is an unknown one, named with the column it most likely meant;
    // ignored knowingly, the orientation group it left is incomplete.
    let renamed = text.replacen("ry_rad", "ry_rod", 1);
    let err = parse_absolute(&renamed, "t.csv", 6)
        .unwrap_err()
        .to_string();
    assert!(
        err.contains("unknown column `ry_rod` (did you mean `ry_rad`?)")
            && err.contains("--ignore-column ry_rod"),
        "{err}"
    );
    let err = parse_absolute_ignoring(&renamed, "t.csv", 6, &["ry_rod".to_string()])
        .unwrap_err()
        .to_string();
    assert!(err.contains("go together"), "{err}");
    let err = parse_absolute(
        &text.replacen(",B,", ",,", 1).replacen("\nB,", "\n,", 1),
        "t.csv",
        6,
    )
    .unwrap_err()
    .to_string();
    assert!(err.contains("t.csv:3") && err.contains("setup"), "{err}");
}

#[test]
fn an_extra_column_is_an_error_unless_ignored_and_known_ones_cannot_be() {
    let rows = sample();
    let text = format_absolute(&rows, &[]);
    let mut lines: Vec<String> = text.lines().map(String::from).collect();
    lines[0] += ",operator";
    for line in &mut lines[1..] {
        *line += ",ann";
    }
    let extra = lines.join("\n") + "\n";
    let err = parse_absolute(&extra, "t.csv", 6).unwrap_err().to_string();
    assert!(
        err.contains("t.csv: header: unknown column `operator`"),
        "{err}"
    );
    let mut back = parse_absolute_ignoring(&extra, "t.csv", 6, &["operator".into()]).unwrap();
    for r in &mut back {
        r.line = 0;
    }
    assert_eq!(back, rows);
    for known in ["sigma_m", "q3_rad", "q9_rad", "approach_q1_rad", "time_s"] {
        let err = parse_absolute_ignoring(&extra, "t.csv", 6, &[known.into()])
            .unwrap_err()
            .to_string();
        assert!(err.contains("cannot be ignored"), "{known}: {err}");
    }
    let dup = text.replacen("setup,target", "setup,target,target", 1);
    let err = parse_absolute(&dup, "t.csv", 6).unwrap_err().to_string();
    assert!(err.contains("column `target` appears twice"), "{err}");
}

#[test]
fn labels_that_would_not_read_back_are_named() {
    assert_eq!(check_label("A"), Ok(()));
    assert_eq!(check_label("T-Mac #2, \"east\""), Ok(()));
    assert_eq!(check_label(""), Err(LabelProblem::Empty));
    assert_eq!(check_label(" A"), Err(LabelProblem::Whitespace));
    assert_eq!(check_label("#A"), Err(LabelProblem::Comment));
    assert_eq!(
        check_label("A\u{1b}"),
        Err(LabelProblem::Control { code: 0x1b })
    );
    assert_eq!(
        check_label(&"é".repeat(101)),
        Err(LabelProblem::TooLong {
            bytes: 202,
            max: limits::MAX_LABEL_BYTES
        })
    );
    // What it accepts, the reader reads back the same.
    let mut rows = sample();
    for label in ["T-Mac #2, \"east\"", &"é".repeat(100), "Ωµ°"] {
        assert_eq!(check_label(label), Ok(()));
        rows[0].setup = label.to_string();
        let back = parse_absolute(&format_absolute(&rows, &[]), "t.csv", 6).unwrap();
        assert_eq!(back[0].setup, label);
    }
}

#[test]
fn configurations_group_equal_joint_values() {
    let mut rows = sample();
    rows[0].config = None;
    rows.push(rows[1].clone());
    rows.push(rows[0].clone());
    let (index, count) = configuration_index(&rows);
    assert_eq!(count, 2);
    assert_eq!(index, vec![0, 1, 1, 0]);
}
