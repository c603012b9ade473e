//! Tool paths: subdivision, the paper's cone, contour cones, pyramids, refused parameters.

use deflex_sim::toolpath::{ConeParams, PyramidParams, ToolPath, Waypoint};

#[test]
fn subdividing_keeps_geometry_timing_and_feeds() {
    let path = ToolPath {
        name: "p".into(),
        waypoints: vec![
            Waypoint {
                p_mm: [0.0, 0.0, 2.0],
                feed_mm_s: None,
            },
            Waypoint {
                p_mm: [0.0, 0.0, -0.4],
                feed_mm_s: Some(2.0),
            },
            Waypoint {
                p_mm: [0.3, 0.0, -0.4],
                feed_mm_s: Some(15.0),
            },
            Waypoint {
                p_mm: [0.3, 0.0, 5.0],
                feed_mm_s: None,
            },
        ],
        step_down_mm: Some(0.4),
        wall_angle_deg: None,
    };
    let fine = path.subdivided(0.5).unwrap();
    // 2.4 mm → 5 moves of 0.48 mm, 0.3 mm stays one, the 5.4 mm rapid stays one.
    assert_eq!(fine.waypoints.len(), 1 + 5 + 1 + 1);
    assert!((fine.length_mm() - path.length_mm()).abs() < 1e-12);
    assert!((fine.duration_s(50.0) - path.duration_s(50.0)).abs() < 1e-12);
    assert_eq!(fine.waypoints[3].p_mm, [0.0, 0.0, 2.0 - 3.0 * 0.48]);
    assert_eq!(fine.waypoints[3].feed_mm_s, Some(2.0));
    assert_eq!(fine.waypoints[6].feed_mm_s, Some(15.0));
    assert_eq!(fine.waypoints[7].feed_mm_s, None);
    assert_eq!(fine.waypoints[7].p_mm, [0.3, 0.0, 5.0]);
    assert_eq!(fine.step_down_mm, Some(0.4));
    assert!(path.subdivided(0.0).is_err());
    assert!(path.subdivided(f64::NAN).is_err());
    // Bounded: a 1 m move in 1 µm pieces is refused, not allocated.
    let long = ToolPath {
        waypoints: vec![
            path.waypoints[0],
            Waypoint {
                p_mm: [1000.0, 0.0, 2.0],
                feed_mm_s: Some(10.0),
            },
        ],
        ..path.clone()
    };
    assert!(long.subdivided(0.001).is_err());
}

#[test]
fn paper_cone_geometry_and_duration() {
    let path = ToolPath::paper_cone();
    let first = path.waypoints[0].p_mm;
    assert!((first[0] - 20.0).abs() < 1e-12 && first[2] == 0.0);
    let last = path.waypoints.last().unwrap().p_mm;
    assert!((last[2] + 15.0).abs() < 1e-12, "{last:?}");
    // Every point lies on the 45° cone r = 20 − depth.
    for w in &path.waypoints {
        let r = w.p_mm[0].hypot(w.p_mm[1]);
        assert!((r - (20.0 + w.p_mm[2])).abs() < 1e-9, "{w:?}");
    }
    // Top diameter 40 mm, bottom diameter 10 mm.
    let rmin = path
        .waypoints
        .iter()
        .map(|w| w.p_mm[0].hypot(w.p_mm[1]))
        .fold(f64::MAX, f64::min);
    assert!((rmin - 5.0).abs() < 1e-9);
    let length = path.length_mm();
    assert!((4700.0..5300.0).contains(&length), "length {length}");
    let duration = path.duration_s(50.0);
    assert!((470.0..530.0).contains(&duration), "{duration}");
}

#[test]
fn contour_cone_has_constant_z_circles() {
    let path = ToolPath::cone(&ConeParams {
        helical: false,
        step_down_mm: 1.0,
        ..ConeParams::default()
    })
    .unwrap();
    let levels: std::collections::BTreeSet<i64> = path
        .waypoints
        .iter()
        .map(|w| (w.p_mm[2] * 1000.0).round() as i64)
        .collect();
    assert_eq!(levels.len(), 16);
}

#[test]
fn pyramid_is_square_and_deep() {
    let path = ToolPath::pyramid(&PyramidParams::default()).unwrap();
    for w in &path.waypoints {
        let half = 20.0 + w.p_mm[2];
        let m = w.p_mm[0].abs().max(w.p_mm[1].abs());
        assert!((m - half).abs() < 1e-9, "{w:?}");
    }
    assert!((path.waypoints.last().unwrap().p_mm[2] + 15.0).abs() < 1e-12);
}

#[test]
fn bad_parameters_are_refused() {
    let too_deep = ConeParams {
        depth_mm: 25.0,
        ..ConeParams::default()
    };
    assert!(
        ToolPath::cone(&too_deep)
            .unwrap_err()
            .to_string()
            .contains("closes")
    );
    let flat = ConeParams {
        wall_angle_deg: 90.0,
        ..ConeParams::default()
    };
    assert!(ToolPath::cone(&flat).is_err());
}
