//! The compensated-path table round-trips, and the feed-forward lookup interpolates it.

use deflex_compensate::table::{FeedForward, read_csv, write_csv};
use deflex_compensate::{CompensationOptions, TcpPath, WrenchSource, compensate};
use deflex_model::{Pose, TX200_FORMING_Q_DEG, Wrench, builtin};
use nalgebra::{Translation3, Vector3};

fn setup() -> (TcpPath, deflex_compensate::Compensation) {
    let robot = builtin("tx200").unwrap();
    let seed = TX200_FORMING_Q_DEG.map(f64::to_radians);
    let start = robot.tcp_pose(&seed).unwrap();
    let poses = (0..20).map(|i| {
        let p = start.translation.vector + Vector3::new(0.001 * i as f64, 0.0005 * i as f64, 0.0);
        (
            Pose::from_parts(Translation3::from(p), start.rotation),
            Some(0.01),
        )
    });
    let path = TcpPath::new("line", poses, 0.05).unwrap();
    let wrenches: Vec<Wrench> = (0..20)
        .map(|i| {
            Wrench::new(
                10.0 * i as f64,
                -50.0,
                900.0 + 20.0 * i as f64,
                0.0,
                1.0,
                0.0,
            )
        })
        .collect();
    let result = compensate(
        &robot,
        &path,
        &seed,
        WrenchSource::Fixed {
            label: "t".into(),
            simulated: true,
            wrenches: &wrenches,
        },
        &CompensationOptions::default(),
        &mut |_| {},
    )
    .unwrap();
    (path, result)
}

#[test]
fn the_table_round_trips_to_its_printed_precision() {
    let (path, result) = setup();
    let text = write_csv(
        &path,
        &result,
        6,
        &["SIMULATED wrenches".into(), "two\nlines".into()],
    );
    assert!(text.starts_with("# SIMULATED wrenches\n# two\n# lines\nindex,s_m,t_s,x_m,"));
    let header = text.lines().nth(3).unwrap();
    for column in ["dx_m", "fz_N", "defl_z_m", "err_m", "q6_rad", "status"] {
        assert!(header.split(',').any(|c| c == column), "{column}");
    }
    let rows = read_csv(&text, "t.csv").unwrap();
    assert_eq!(rows.len(), path.len());
    for ((row, point), computed) in rows.iter().zip(path.points()).zip(&result.points) {
        assert!((row.arc_length_m - point.arc_length_m).abs() < 1e-9);
        assert!((row.desired.translation.vector - point.pose.translation.vector).norm() < 1e-9);
        let angle =
            deflex_model::spatial::orientation_error(&row.desired.rotation, &point.pose.rotation);
        assert!(angle.norm() < 1e-8);
        assert!((row.compensation - computed.compensation).amax() < 1e-9);
        assert!((row.wrench - computed.wrench).amax() < 1e-4);
        assert!((row.deflection - computed.deflection).amax() < 1e-9);
        assert_eq!(row.status, "ok");
    }
    let e = read_csv("index,s_m\n0,0\n", "bad.csv").unwrap_err();
    assert!(
        e.to_string()
            .starts_with("bad.csv: not a compensated path: missing column(s) t_s"),
        "{e}"
    );
    let broken = text.replace("\n2,", "\n2,x");
    let e = read_csv(&broken, "b.csv").unwrap_err();
    assert!(e.to_string().contains("b.csv:7: column `s_m`"), "{e}");
}

#[test]
fn feed_forward_interpolates_by_time_and_arc_length() {
    let (path, result) = setup();
    let ff = FeedForward::from_compensation(&path, &result);
    let p = path.points();
    // At a point: that point's values; half-way: the mean of the neighbours.
    let at = ff.at_time(p[5].time_s);
    assert!((at.deflection - result.points[5].deflection).amax() < 1e-15);
    let mid_t = 0.5 * (p[5].time_s + p[6].time_s);
    let mid = ff.at_time(mid_t);
    let mean = (result.points[5].deflection + result.points[6].deflection) * 0.5;
    assert!((mid.deflection - mean).amax() < 1e-15);
    let mid_s = ff.at_arc_length(0.5 * (p[5].arc_length_m + p[6].arc_length_m));
    assert!((mid_s.compensation - mid.compensation).amax() < 1e-15);
    // Clamped outside the path, and NaN gives the first point rather than NaN.
    assert_eq!(ff.at_time(-3.0), ff.at_time(0.0));
    assert_eq!(ff.at_time(1e9), ff.at_time(ff.duration_s()));
    assert!(
        ff.at_time(f64::NAN)
            .deflection
            .iter()
            .all(|v| v.is_finite())
    );
    // A compensated program cancels the prediction: deflection + compensation ≈ 0.
    assert!((mid.deflection + mid.compensation).amax() < 1e-6);
    // The same lookup from the table text.
    let rows = read_csv(&write_csv(&path, &result, 6, &[]), "t.csv").unwrap();
    let from_rows = FeedForward::from_rows(&rows).unwrap();
    assert!((from_rows.at_time(mid_t).deflection - mid.deflection).amax() < 1e-9);
    assert!(FeedForward::from_rows(&rows[..1]).is_none());
}
