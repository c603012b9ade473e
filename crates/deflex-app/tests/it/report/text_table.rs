//! Text tables (`deflex_app::report::text_table`): in every build, with or without reports.

use deflex_app::report::text_table::{render_table, table_csv};

#[test]
fn a_table_is_aligned_text_and_quoted_csv() {
    let rows = vec![
        vec!["J1".to_string(), "1.5".to_string()],
        vec!["J2, z".to_string(), "10".to_string()],
    ];
    assert_eq!(
        render_table(&["eDoF", "k"], &rows),
        "eDoF   k\n----------\nJ1     1.5\nJ2, z  10\n"
    );
    assert_eq!(
        table_csv(&["eDoF", "k"], &rows).unwrap(),
        "eDoF,k\nJ1,1.5\n\"J2, z\",10\n"
    );
}

#[test]
fn a_csv_row_of_another_length_than_the_header_is_an_error() {
    let rows = vec![vec!["1".to_string()]];
    assert!(table_csv(&["a", "b"], &rows).is_err());
}
