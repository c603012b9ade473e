//! The bounds on a calibration's geometric changes ([`deflex_calibrate::geometry::plausible`]):
//! angles compared modulo 2π, lengths scaled by the arm's size, physical quantities unbounded,
//! the largest excess first.

use deflex_calibrate::geometry::fit::Estimate;
use deflex_calibrate::geometry::params::{DhField, Param, Unit};
use deflex_calibrate::geometry::plausible::{ChangeBounds, arm_size_m, change_of, large_changes};
use std::f64::consts::PI;

fn estimate(param: Param, name: &str, unit: Unit, start: f64, value: f64) -> Estimate {
    Estimate {
        param,
        name: name.into(),
        unit,
        start,
        value,
        standard_error: 0.0,
        bootstrap_se: None,
    }
}

/// The UR10's size from its DH table by hand: the placements (a_{i−1}, d_i) of the standard
/// table as the model chains them are (0, 0.1273), (0, 0), (0.612, 0), (0.5723, 0.163941),
/// (0, 0.1157), (0, 0.0922), the tool at the flange.
#[test]
fn the_arm_size_is_the_length_of_its_chain() {
    let ur10 = deflex_model::builtin("ur10").unwrap();
    let by_hand = 0.1273 + 0.612 + 0.5723f64.hypot(0.163941) + 0.1157 + 0.0922;
    assert!(
        (arm_size_m(&ur10) - by_hand).abs() < 1e-9,
        "{}",
        arm_size_m(&ur10)
    );
    let tx200 = deflex_model::builtin("tx200").unwrap();
    assert!(arm_size_m(&tx200) > arm_size_m(&ur10));
    let bounds = ChangeBounds::for_robot(&ur10);
    assert!((bounds.dh_length_m - (0.02 * by_hand + 0.010)).abs() < 1e-12);
    assert!((bounds.setup_translation_m - (0.05 * by_hand + 0.020)).abs() < 1e-12);
}

#[test]
fn an_angle_moved_by_whole_turns_is_no_change() {
    let turn = estimate(
        Param::Dh(4, DhField::Alpha),
        "J5.alpha",
        Unit::Radian,
        0.3,
        0.3 + 2.0 * PI + 0.01,
    );
    assert!((change_of(&turn) - 0.01).abs() < 1e-12);
    let back = estimate(
        Param::Dh(2, DhField::Theta),
        "J3.theta",
        Unit::Radian,
        0.0,
        -3.0 * PI / 2.0,
    );
    assert!(
        (change_of(&back) - PI / 2.0).abs() < 1e-12,
        "{}",
        change_of(&back)
    );
    // Lengths are not wrapped.
    let long = estimate(Param::Dh(1, DhField::D), "J2.d", Unit::Metre, 0.0, 7.0);
    assert_eq!(change_of(&long), 7.0);
}

#[test]
fn the_changes_beyond_their_bounds_are_listed_largest_excess_first() {
    let ur10 = deflex_model::builtin("ur10").unwrap();
    let bounds = ChangeBounds::for_robot(&ur10);
    let estimates = [
        // Within: a millimetre, a milliradian, a whole turn.
        estimate(
            Param::Dh(1, DhField::A),
            "J2.a",
            Unit::Metre,
            -0.612,
            -0.613,
        ),
        estimate(
            Param::Dh(1, DhField::Theta),
            "J2.theta",
            Unit::Radian,
            0.0,
            2.0 * PI + 1e-3,
        ),
        // Beyond: a quarter turn (15.7 × its bound), 0.925 m (about 21 ×), 0.25 m (about 6 ×).
        estimate(
            Param::Dh(2, DhField::Theta),
            "J3.theta",
            Unit::Radian,
            0.0,
            PI / 2.0,
        ),
        estimate(Param::Dh(1, DhField::D), "J2.d", Unit::Metre, 0.0, 0.925),
        estimate(
            Param::Dh(2, DhField::A),
            "J3.a",
            Unit::Metre,
            -0.5723,
            -0.8223,
        ),
        // Physical quantities are not bounded here, however large.
        estimate(Param::Compliance(0), "c[J1.z]", Unit::Compliance, 1e-6, 1.0),
        estimate(Param::Mass(1), "body2.m", Unit::Kilogram, 12.7, 100.0),
        // A set-up 5 m away from its registration.
        estimate(
            Param::SetupTranslation(0, 0),
            "setup[A].tx",
            Unit::Metre,
            1.0,
            6.0,
        ),
        // Not finite: beyond every bound, named first.
        estimate(
            Param::Target(0, 2),
            "target[tmac].z",
            Unit::Metre,
            0.05,
            f64::NAN,
        ),
    ];
    let large = large_changes(&estimates, &bounds);
    let names: Vec<&str> = large.iter().map(|c| c.name.as_str()).collect();
    assert_eq!(
        names,
        ["target[tmac].z", "setup[A].tx", "J2.d", "J3.theta", "J3.a"],
        "{names:?}"
    );
    assert_eq!(
        large[2].to_string(),
        format!("J2.d +925 mm (bound ±{:.0} mm)", bounds.dh_length_m * 1e3)
    );
    assert_eq!(
        large[3].to_string(),
        "J3.theta +1571 mrad (bound ±100 mrad)"
    );
}
