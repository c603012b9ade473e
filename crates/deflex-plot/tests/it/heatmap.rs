use deflex_plot::{cell_edges, cell_value_text};

#[test]
fn edges_are_midpoints() {
    assert_eq!(cell_edges(&[0.0, 1.0, 3.0]), vec![-0.5, 0.5, 2.0, 4.0]);
    assert_eq!(cell_edges(&[2.0]), vec![1.9, 2.1]);
}

#[test]
fn value_labels_have_three_significant_digits() {
    assert_eq!(cell_value_text(0.12345), "0.123");
    assert_eq!(cell_value_text(1.2345), "1.23");
    assert_eq!(cell_value_text(123.45), "123");
    assert_eq!(cell_value_text(0.0), "0.000");
}
