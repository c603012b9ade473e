//! The feed-forward table read from `compensated_path.csv` rows: rotated into the model's base
//! axes, every failure named by the table, its line and its CSV column (the law's checks name
//! the point and the quantity; the application layer names the file's).

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
