//! G-code reading into a tool path: modes, units, feeds, comments, arcs and errors.

use deflex_sim::gcode::parse_gcode;

#[test]
fn absolute_relative_units_feeds_and_comments() {
    let text = "%\n(square test) ; header\nN10 G21 G90\nG0 X10 Y0 Z5\nG1 Z0 F600 (plunge)\n\
                G91\nX-5 Y5\nG20 G1 X1 F60\nM30\nG1 X1000\n";
    let path = parse_gcode(text, "t.nc").unwrap();
    let p: Vec<[f64; 3]> = path.waypoints.iter().map(|w| w.p_mm).collect();
    // The path starts at the first commanded position, not at the part origin.
    assert_eq!(p[0], [10.0, 0.0, 5.0]);
    assert_eq!(path.waypoints[0].feed_mm_s, None);
    assert_eq!(p[1], [10.0, 0.0, 0.0]);
    assert!((path.waypoints[1].feed_mm_s.unwrap() - 10.0).abs() < 1e-12);
    assert_eq!(p[2], [5.0, 5.0, 0.0]);
    assert!((p[3][0] - 30.4).abs() < 1e-12);
    // F60 in/min = 25.4 mm/s.
    assert!((path.waypoints[3].feed_mm_s.unwrap() - 25.4).abs() < 1e-12);
    assert_eq!(p.len(), 4, "M30 ends the program");
}

#[test]
fn arcs_are_read_and_errors_name_the_line() {
    let path = parse_gcode("G0 X10 Y0 Z0\nG3 X10 Y0 I-10 J0 F600\n", "c.nc").unwrap();
    assert!(path.waypoints.len() > 100);
    for w in &path.waypoints {
        assert!((w.p_mm[0].hypot(w.p_mm[1]) - 10.0).abs() < 1e-9);
    }
    let cases = [
        ("G0 X0 Y0 Z0\nG1 X1\n", 2, "feed"),
        ("G0 X0 Y0 Z0\nG41 X1\n", 2, "compensation"),
        ("G0 X1\n\nE1000\n", 3, "a word outside"),
        ("X5\n", 1, "motion mode"),
        ("G0 X1 (open\n", 1, "unbalanced"),
        ("G0 X1 X2\n", 1, "X1"),
        ("G0 X0 Y0 Z0\nG1 X2 F0\n", 2, "feed 0 mm/min"),
        ("G0 X20000\n", 1, "beyond"),
        ("G20 G1 X1 F100000\n", 1, "feed"),
    ];
    for (text, line, needle) in cases {
        let e = parse_gcode(text, "p.nc").unwrap_err().to_string();
        assert!(e.starts_with(&format!("p.nc:{line}:")), "{e}");
        assert!(e.contains(needle), "{e} should mention {needle}");
    }
    let e = parse_gcode("(nothing)\n", "p.nc").unwrap_err().to_string();
    assert!(e.contains("no move"), "{e}");
}
