use deflex_plot::{ImageFormat, finite_extent, padded, tick_formatter};
use std::path::Path;

#[test]
fn tick_labels_snap_rounding_noise_to_zero() {
    let f = tick_formatter((-0.45, 0.45));
    assert_eq!(f(&-5.55e-17), "0");
    assert_eq!(f(&0.2), "0.2");
    assert_eq!(f(&-0.4), "-0.4");
    let g = tick_formatter((400.0, 700.0));
    assert_eq!(g(&450.0), "450");
    let h = tick_formatter((0.0, 2e-5));
    assert_eq!(h(&1.5e-5), "1.5e-5");
}

#[test]
fn padding_and_extents() {
    assert_eq!(
        finite_extent(&[f64::NAN, 2.0, -1.0, f64::INFINITY]),
        Some((-1.0, 2.0))
    );
    assert_eq!(finite_extent(&[f64::NAN]), None);
    assert_eq!(padded((0.0, 10.0), 0.1), (-1.0, 11.0));
    assert_eq!(padded((0.0, 0.0), 0.1), (-1.0, 1.0));
    assert_eq!(padded((5.0, 5.0), 0.1), (4.5, 5.5));
}

#[test]
fn format_by_extension() {
    assert_eq!(
        ImageFormat::from_path(Path::new("a/b.PNG")).unwrap(),
        ImageFormat::Png
    );
    assert_eq!(
        ImageFormat::from_path(Path::new("b.svg")).unwrap(),
        ImageFormat::Svg
    );
    assert!(ImageFormat::from_path(Path::new("b")).is_err());
}
