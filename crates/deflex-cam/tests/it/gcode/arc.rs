//! The arc geometry (`deflex_cam::gcode::arc`): `R` centres, sweeps, full circles and turns,
//! mismatched radii, and the steps of the chord tolerance.

use deflex_cam::gcode::Plane;
use deflex_cam::gcode::arc::{center_from_radius, point, steps, sweep};

#[test]
fn r_centres_lie_where_the_convention_says() {
    // G2 under 180° from (0,0) to (10,0): centre below the chord, arc bulging up (+Y).
    let c = center_from_radius(&[0.0; 3], &[10.0, 0.0, 0.0], 10.0, Plane::Xy, false).unwrap();
    assert!((c[0] - 5.0).abs() < 1e-12 && (c[1] + 75f64.sqrt()).abs() < 1e-12);
    let s = sweep(&[0.0; 3], &[10.0, 0.0, 0.0], &c, Plane::Xy, false, 1).unwrap();
    assert!(
        (s.sweep + std::f64::consts::FRAC_PI_3).abs() < 1e-12,
        "{s:?}"
    );
    let mid = point(&s, &[0.0; 3], &[10.0, 0.0, 0.0], &c, Plane::Xy, 1, 2);
    assert!((mid[1] - (10.0 - 75f64.sqrt())).abs() < 1e-12, "{mid:?}");
    // Negative R: the long way round, centre above.
    let c = center_from_radius(&[0.0; 3], &[10.0, 0.0, 0.0], -10.0, Plane::Xy, false).unwrap();
    assert!(c[1] > 0.0);
    let s = sweep(&[0.0; 3], &[10.0, 0.0, 0.0], &c, Plane::Xy, false, 1).unwrap();
    assert!((s.sweep + 5.0 * std::f64::consts::FRAC_PI_3).abs() < 1e-12);
    assert!(center_from_radius(&[0.0; 3], &[10.0, 0.0, 0.0], 4.0, Plane::Xy, true).is_err());
    assert!(center_from_radius(&[0.0; 3], &[0.0; 3], 4.0, Plane::Xy, true).is_err());
}

#[test]
fn full_circles_turns_and_mismatched_radii() {
    let start = [10.0, 0.0, 0.0];
    let c = [0.0; 3];
    let s = sweep(&start, &start, &c, Plane::Xy, true, 3).unwrap();
    assert!((s.sweep - 3.0 * std::f64::consts::TAU).abs() < 1e-12);
    let s = sweep(&start, &start, &c, Plane::Xy, false, 1).unwrap();
    assert!((s.sweep + std::f64::consts::TAU).abs() < 1e-12);
    let e = sweep(&start, &[0.0, 10.5, 0.0], &c, Plane::Xy, true, 1).unwrap_err();
    assert!(e.to_string().contains("differ by 0.5000 mm"), "{e}");
    assert!(sweep(&start, &start, &start, Plane::Xy, true, 1).is_err());
    // Steps: sagitta within the tolerance.
    let s = sweep(&start, &start, &c, Plane::Xy, true, 1).unwrap();
    let n = steps(&s, 0.01);
    let step = std::f64::consts::TAU / n;
    assert!(10.0 * (1.0 - (step / 2.0).cos()) <= 0.01 + 1e-12);
    let fewer = step * n / (n - 1.0);
    assert!(10.0 * (1.0 - (fewer / 2.0).cos()) > 0.01);
}
