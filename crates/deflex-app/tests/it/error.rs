//! The engine's errors ([`deflex_app::error`]): panics caught, bounds named.

use deflex_app::error::*;

#[test]
fn a_panic_becomes_an_internal_error_with_its_message() {
    let e = guard::<()>(|| panic!("boom {}", 7)).unwrap_err();
    assert_eq!(e.kind(), ErrorKind::Internal);
    assert!(e.to_string().contains("boom 7"), "{e}");
}

#[test]
fn bounded_names_the_option_and_the_range() {
    let e = bounded("tolerance_m", f64::NAN, 1e-9, 1e-3, "m").unwrap_err();
    assert_eq!(
        e.to_string(),
        "tolerance_m: expected a number from 1e-9 to 0.001 m, got NaN"
    );
    assert_eq!(bounded("x", 2.0, 0.0, 3.0, "").unwrap(), 2.0);
}
