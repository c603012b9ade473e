//! The feed-forward table read from `compensated_path.csv` rows: rotated into the model's base
//! axes, every failure named by the table, its line and its CSV column (the law's checks name
//! the point and the quantity; the application layer names the file's); the law's lookups of
//! an offline compensation by time and by arc length.

use deflex_app::cell::feedforward::{TableLoadError, table_of};
use deflex_compensate::table::TableRow;
use deflex_model::{Displacement, Pose, Wrench};
use nalgebra::{Rotation3, Translation3, Vector3};

/// Rows along x every millimetre, deflection −compensation growing with the arc length.
fn rows(points: usize) -> Vec<TableRow> {
    (0..points)
        .map(|i| {
            let s = i as f64 * 1e-3;
            TableRow {
                line: i + 2,
                arc_length_m: s,
                time_s: s / 0.01,
                desired: Pose::from_parts(
                    Translation3::new(1.5 + s, 0.0, -0.18),
                    Rotation3::identity(),
                ),
                compensation: Displacement::new(0.0, 0.0, -s * 1e-3, 0.0, 0.0, 0.0),
                wrench: Wrench::zeros(),
                deflection: Displacement::new(0.0, 0.0, s * 1e-3, 0.0, 0.0, 0.0),
                status: "ok".into(),
            }
        })
        .collect()
}

fn fails(rows: Vec<TableRow>) -> String {
    let robot = deflex_model::builtin("tx200").unwrap();
    table_of(&rows, &robot, "t.csv").unwrap_err().to_string()
}

#[test]
fn table_errors_name_the_file_line_and_column() {
    let robot = deflex_model::builtin("tx200").unwrap();
    let table = table_of(&rows(5), &robot, "t.csv").unwrap();
    assert_eq!(table.len(), 5);
    assert!((table.length_m() - 0.004).abs() < 1e-12);
    let mut bad = rows(5);
    bad[3].status = "compensated:joint_limit:J3".into();
    let e = fails(bad);
    assert!(e.contains("t.csv:5") && e.contains("joint_limit"), "{e}");
    let mut bad = rows(5);
    bad[3].time_s = 0.0;
    let e = fails(bad);
    assert!(e.contains("t.csv:5") && e.contains("t_s"), "{e}");
    let mut bad = rows(5);
    bad[1].deflection[4] = 0.5;
    let e = fails(bad);
    assert!(e.contains("t.csv:3") && e.contains("defl_ry_rad"), "{e}");
    let mut bad = rows(5);
    bad[1].compensation[0] = -0.2;
    let e = fails(bad);
    assert!(e.contains("t.csv:3") && e.contains("dx_m"), "{e}");
    let mut bad = rows(5);
    bad[2].desired.translation.vector = Vector3::new(200.0, 0.0, 0.0);
    let e = fails(bad);
    assert!(e.contains("t.csv:4") && e.contains("x_m"), "{e}");
    let e = fails(rows(1));
    assert!(
        e.contains("t.csv") && e.contains("at least two rows"),
        "{e}"
    );
    // Typed: the failed point's status, line and index.
    let mut bad = rows(5);
    bad[3].status = "compensated:out_of_reach".into();
    match table_of(&bad, &robot, "t.csv") {
        Err(TableLoadError::NotCompensated {
            line,
            index,
            status,
            ..
        }) => assert_eq!(
            (line, index, status.as_str()),
            (5, 3, "compensated:out_of_reach")
        ),
        other => panic!("{other:?}"),
    }
}

/// A 20-point line compensated under growing wrenches: deflex-compensate's test fixture,
/// compiled here rather than copied.
#[path = "../../../../deflex-compensate/tests/it/compensated_line.rs"]
mod compensated_line;

/// The compensation's points as the rows of its table, unrounded.
fn rows_of(
    path: &deflex_compensate::TcpPath,
    result: &deflex_compensate::Compensation,
) -> Vec<TableRow> {
    path.points()
        .iter()
        .zip(&result.points)
        .enumerate()
        .map(|(i, (point, computed))| TableRow {
            line: i + 2,
            arc_length_m: point.arc_length_m,
            time_s: point.time_s,
            desired: point.pose,
            compensation: computed.compensation,
            wrench: computed.wrench,
            deflection: computed.deflection,
            status: "ok".into(),
        })
        .collect()
}

/// The law's table looks a compensation up by time and by arc length (the one feed-forward
/// lookup; formerly also `deflex_compensate::table::FeedForward`, checked here through the law
/// with the same tolerances): a point's own values at its time, the mean of the neighbours
/// half-way, the same by arc length as by time, clamped outside the path, a NaN time giving
/// the first point, the compensation cancelling the prediction, and the same from the table's
/// text.
#[test]
fn the_law_s_table_interpolates_a_compensation_by_time_and_arc_length() {
    use deflex_control::{FeedForward, FeedForwardConfig, FeedForwardMode, PathIndex};
    let (robot, path, result) = compensated_line::compensated_line();
    let table = table_of(&rows_of(&path, &result), &robot, "t.csv").unwrap();
    let to_base = robot.base.rotation.inverse();
    // A world-frame quantity in the robot's base axes, as the table holds it.
    let base = |v: &Displacement| -> Displacement {
        let a = to_base * Vector3::new(v[0], v[1], v[2]);
        let b = to_base * Vector3::new(v[3], v[4], v[5]);
        Displacement::new(a.x, a.y, a.z, b.x, b.y, b.z)
    };
    let p = path.points();
    let desired = |k: usize| p[k].pose.translation.vector;
    let commanded = |k: usize| {
        let c = &result.points[k].compensation;
        desired(k) + Vector3::new(c[0], c[1], c[2])
    };
    let config = |mode, index| FeedForwardConfig {
        mode,
        index,
        max_offset_m: 0.1,
        window_m: 1.0,
        ..FeedForwardConfig::default()
    };
    // The prior at `place` (on the program) at table time `t`, from a fresh start: −δ_pred in
    // feed-forward mode, the compensation in pre-compensated mode (base axes).
    let prior =
        |table: &deflex_control::FeedForwardTable, mode, index, place: Vector3<f64>, t: f64| {
            let mut ff = FeedForward::new(table.clone(), config(mode, index)).unwrap();
            ff.start(0.0);
            let step = ff.update(&place, t);
            assert_eq!(
                step.state,
                deflex_control::feedforward::TrackState::OnPath,
                "at {t} s"
            );
            Displacement::from(step.prior)
        };
    let by_time = |mode, t: f64| {
        let (k, u) = table.locate_time(t, 0);
        let place = desired(k) + (desired(k + 1) - desired(k)) * u;
        prior(&table, mode, PathIndex::Time, place, t)
    };
    let deflection_at = |t: f64| -by_time(FeedForwardMode::FeedForward, t);
    let compensation_at = |t: f64| by_time(FeedForwardMode::Precompensated, t);

    // At a point: that point's values; half-way: the mean of the neighbours.
    let at = deflection_at(p[5].time_s);
    assert!((at - base(&result.points[5].deflection)).amax() < 1e-15);
    assert_eq!(
        Displacement::from(table.deflections()[5]),
        base(&result.points[5].deflection)
    );
    let mid_t = 0.5 * (p[5].time_s + p[6].time_s);
    let mid = deflection_at(mid_t);
    let mean = (base(&result.points[5].deflection) + base(&result.points[6].deflection)) * 0.5;
    assert!((mid - mean).amax() < 1e-15);
    // By arc length (the law's tracking, on the program's polyline) as by time.
    let mid_s = prior(
        &table,
        FeedForwardMode::Precompensated,
        PathIndex::ArcLength,
        0.5 * (commanded(5) + commanded(6)),
        0.0,
    );
    let mid_compensation = compensation_at(mid_t);
    assert!((mid_s - mid_compensation).amax() < 1e-15);
    let mid_s_deflection = -prior(
        &table,
        FeedForwardMode::FeedForward,
        PathIndex::ArcLength,
        0.5 * (desired(5) + desired(6)),
        0.0,
    );
    assert!((mid_s_deflection - mid).amax() < 1e-15);
    // Clamped outside the path, and NaN gives the first point rather than NaN.
    assert_eq!(table.locate_time(-3.0, 0), table.locate_time(0.0, 0));
    assert_eq!(deflection_at(-3.0), deflection_at(0.0));
    assert_eq!(
        table.locate_time(1e9, 0),
        table.locate_time(table.duration_s(), 0)
    );
    assert_eq!(deflection_at(1e9), deflection_at(table.duration_s()));
    assert_eq!(table.locate_time(f64::NAN, 0), (0, 0.0));
    let at_nan = deflection_at(f64::NAN);
    assert!(at_nan.iter().all(|v| v.is_finite()));
    assert_eq!(at_nan, deflection_at(0.0));
    // A compensated program cancels the prediction: deflection + compensation ≈ 0 (world).
    let sum = mid + mid_compensation;
    let position = robot.base.rotation * Vector3::new(sum[0], sum[1], sum[2]);
    let rotation = robot.base.rotation * Vector3::new(sum[3], sum[4], sum[5]);
    assert!(position.amax().max(rotation.amax()) < 1e-6, "{sum}");
    // The same lookup from the table's text.
    let text = deflex_compensate::table::write_csv(&path, &result, 6, &[]);
    let rows = deflex_compensate::table::read_csv(&text, "t.csv").unwrap();
    let from_text = table_of(&rows, &robot, "t.csv").unwrap();
    let (k, u) = from_text.locate_time(mid_t, 0);
    let place = desired(k) + (desired(k + 1) - desired(k)) * u;
    let mid_from_text = -prior(
        &from_text,
        FeedForwardMode::FeedForward,
        PathIndex::Time,
        place,
        mid_t,
    );
    assert!((mid_from_text - mid).amax() < 1e-9);
    let e = table_of(&rows[..1], &robot, "t.csv")
        .unwrap_err()
        .to_string();
    assert!(
        e.contains("t.csv") && e.contains("at least two rows"),
        "{e}"
    );
}
