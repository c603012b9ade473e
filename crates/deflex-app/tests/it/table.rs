//! The table reader ([`deflex_app::table`]): numbers, text, empty cells, comments, ragged rows.

use deflex_app::table::*;

#[test]
fn numbers_text_empty_cells_and_comments() {
    let t = parse(
        "# SIMULATED run\n# second\ntime_s,status,x_m\n0.0,ok,1.5\n0.01,fault,\n",
        "t",
    )
    .unwrap();
    assert!(t.simulated());
    assert_eq!(t.comments, ["SIMULATED run", "second"]);
    assert_eq!(t.rows, 2);
    assert_eq!(t.columns[0].1, TableColumn::Number(vec![0.0, 0.01]));
    assert_eq!(
        t.columns[1].1,
        TableColumn::Text(vec!["ok".into(), "fault".into()])
    );
    match &t.columns[2].1 {
        TableColumn::Number(v) => assert!(v[0] == 1.5 && v[1].is_nan()),
        other => panic!("{other:?}"),
    }
}

#[test]
fn a_ragged_row_names_its_line() {
    let e = parse("a,b\n1,2\n3\n", "f.csv").unwrap_err();
    assert!(e.to_string().starts_with("f.csv:3:"), "{e}");
}
