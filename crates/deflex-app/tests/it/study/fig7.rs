//! The paper's Fig. 7 test ([`deflex_app::study::fig7`]): where its points sit on the arm.

use deflex_app::study::fig7::fig7_rows;

/// The points lie along the arm in the order of the paper's Fig. 7, on the links named, and
/// the load is the paper's lateral 1400 N at the TCP (2194 mm along x0 on the TX200).
#[test]
fn fig7_points_follow_the_arm() {
    let robot = deflex_model::builtin("tx200").unwrap();
    let rows = fig7_rows(&robot).unwrap();
    let names: Vec<&str> = rows.iter().map(|r| r.point.as_str()).collect();
    assert_eq!(names, ["M1", "M2", "M3", "TCP"]);
    let x: Vec<f64> = rows.iter().map(|r| r.point_m[0]).collect();
    assert!(x.windows(2).all(|w| w[1] > w[0]), "{x:?}");
    assert!((x[3] - 2.194).abs() < 1e-9, "{x:?}");
    // Hand check on the TX200 table: J2 at x = 0.25 m, J3 at 1.20 m, wrist at 2.00 m.
    assert!((x[0] - (0.25 + 0.4 * 0.95)).abs() < 1e-9);
    assert!((x[1] - 1.35).abs() < 1e-9);
    assert!((x[2] - 1.80).abs() < 1e-9);
    assert!(
        rows.iter()
            .all(|r| r.wrench == [0.0, 1400.0, 0.0, 0.0, 0.0, 0.0])
    );
    let links: Vec<usize> = rows.iter().map(|r| r.point_link).collect();
    assert_eq!(links, [2, 3, 4, 6]);
}
