//! The model ([`deflex_app::robot`]): batches against single calls, inverse kinematics, non-
//! finite input, the reports of `deflex pose`, `deflect`, `ik`, `model show` and the map.

use deflex_app::robot::*;

fn configurations(rows: usize) -> Vec<f64> {
    // A deterministic spread over the TX200's workspace.
    (0..rows * 6)
        .map(|k| ((k as f64 * 0.6180339887).fract() - 0.5) * 2.0)
        .collect()
}

#[test]
fn batches_equal_single_calls_bit_for_bit_across_the_parallel_split() {
    let robot = builtin("tx200").unwrap();
    let rows = 3 * ROWS_PER_TASK + 17;
    let q = configurations(rows);
    let w = [10.0, -200.0, -1000.0, 3.0, 1.0, -2.0];
    let batch = deflections(&robot, &q, rows, &w).unwrap();
    for i in [0, 1, ROWS_PER_TASK - 1, ROWS_PER_TASK, rows - 1] {
        let single = deflections(&robot, row(&q, 6, i), 1, &w).unwrap();
        assert_eq!(&batch[i * 6..i * 6 + 6], single.as_slice(), "row {i}");
    }
    let c = compliances(&robot, &q, rows).unwrap();
    let i = rows - 2;
    let single = compliances(&robot, row(&q, 6, i), 1).unwrap();
    assert_eq!(&c[i * 36..i * 36 + 36], single.as_slice());
}

#[test]
fn ik_reaches_the_pose_of_forward_kinematics_and_reports_failures() {
    let robot = builtin("tx200").unwrap();
    let q0 = default_seed(&robot);
    let mut q = q0.clone();
    q[0] += 0.2;
    q[1] -= 0.1;
    let pose = poses(&robot, &q, 1).unwrap();
    let solved = inverse_kinematics(&robot, &pose, 1, &q0, OnFailure::Raise).unwrap();
    let back = poses(&robot, &solved, 1).unwrap();
    for (a, b) in pose.iter().zip(&back) {
        assert!((a - b).abs() < 1e-8);
    }
    let mut far = pose.clone();
    far[3] = 50.0;
    let e = inverse_kinematics(&robot, &far, 1, &q0, OnFailure::Raise).unwrap_err();
    assert!(e.to_string().contains("out of reach"), "{e}");
    let nan = inverse_kinematics(&robot, &far, 1, &q0, OnFailure::Nan).unwrap();
    assert!(nan.iter().all(|v| v.is_nan()));
    let mut skew = pose;
    skew[0] = 2.0;
    let e = inverse_kinematics(&robot, &skew, 1, &q0, OnFailure::Raise).unwrap_err();
    assert!(e.to_string().contains("not a rotation"), "{e}");
}

#[test]
fn non_finite_values_are_named_by_row_and_column() {
    let e = check_finite("q", &[0.0, 1.0, 2.0, f64::NAN], Some(2)).unwrap_err();
    assert_eq!(
        e.to_string(),
        "q[1, 1] is NaN: every value must be a finite number"
    );
}

#[test]
fn on_failure_is_parsed_by_its_python_names() {
    use std::str::FromStr;
    assert_eq!(OnFailure::from_str("raise").unwrap(), OnFailure::Raise);
    assert_eq!(OnFailure::from_str("nan").unwrap(), OnFailure::Nan);
    assert_eq!(
        OnFailure::from_str("skip").unwrap_err().to_string(),
        "on_failure: expected \"raise\" or \"nan\", got \"skip\""
    );
}

#[test]
fn one_configurations_reports_agree_with_the_batched_maths() {
    use deflex_app::robot::single::{DeflectionReport, IkReport, PoseReport};
    let robot = builtin("tx200").unwrap();
    let q = default_seed(&robot);
    let report = PoseReport::at(&robot, &q).unwrap();
    let batch = poses(&robot, &q, 1).unwrap();
    let mut single = vec![0.0; 16];
    write_pose(&report.pose, &mut single);
    assert_eq!(single, batch);
    let text = report.text();
    assert!(text.starts_with("TCP position (mm): x "), "{text}");
    assert!(text.contains("tool axis z_t: ["), "{text}");
    let json = report.to_json();
    assert_eq!(json["tcp_m"][0], batch[3]);
    assert_eq!(json["rotation"].as_array().unwrap().len(), 3);
    // The TX200 has no masses: no sag; a UR10e has, and its sag is the batch's.
    assert!(json["gravity_sag_m"].is_null());
    assert!(!text.contains("sag under the arm's own weight"), "{text}");
    let ur = builtin("ur10e").unwrap();
    let q_ur = default_seed(&ur);
    let with_masses = PoseReport::at(&ur, &q_ur).unwrap();
    let sag = gravity_sags(&ur, &q_ur, 1).unwrap().unwrap();
    assert_eq!(with_masses.to_json()["gravity_sag_m"][2], sag[2]);
    assert!(
        with_masses
            .text()
            .contains("sag under the arm's own weight (mm)")
    );

    let w = [10.0, -200.0, -1000.0, 3.0, 1.0, -2.0];
    let deflection = DeflectionReport::at(&robot, &q, w).unwrap();
    let batch = deflections(&robot, &q, 1, &w).unwrap();
    assert_eq!(deflection.deflection.as_slice(), batch.as_slice());
    let json = deflection.to_json();
    assert_eq!(json["dp_m"][2], batch[2]);
    assert_eq!(json["compliance"].as_array().unwrap().len(), 6);
    assert!(deflection.text().contains("deflection δp (mm):"));

    let solved = IkReport::solve(&robot, &report.pose, &q).unwrap();
    let back = poses(&robot, &solved.solution.q, 1).unwrap();
    for (a, b) in back.iter().zip(&single) {
        assert!((a - b).abs() < 1e-8);
    }
    assert!(solved.text().starts_with("q (deg): "));
    assert_eq!(solved.to_json()["q_rad"].as_array().unwrap().len(), 6);
    let mut far = report.pose;
    far.translation.vector.x = 50.0;
    let e = IkReport::solve(&robot, &far, &q).unwrap_err();
    assert!(matches!(e, deflex_app::Error::Model(_)), "{e}");
}

#[test]
fn model_show_describes_the_robot_and_its_twin_cell() {
    use deflex_app::robot::describe::ModelShow;
    let shown = ModelShow::load("tx200").unwrap();
    let text = shown.text();
    assert!(text.starts_with(&shown.robot.name), "{text}");
    assert!(text.contains("eDoFs: "), "{text}");
    assert!(shown.cell.is_ok());
    let json = shown.to_json();
    assert_eq!(json["joints"].as_array().unwrap().len(), 6);
    assert!(json["cell"].is_object());
    assert!(json["cell"].get("error").is_none());
    let e = ModelShow::load("no-such-robot").err().unwrap();
    assert!(e.to_string().contains("no-such-robot"), "{e}");
}

#[cfg(feature = "report")]
#[test]
fn a_deflection_map_is_written_whole_and_its_grid_checked() {
    use deflex_app::robot::map::{MapGrid, deflection_grid, write_map};
    let robot = builtin("tx200").unwrap();
    let grid = MapGrid {
        z_m: 0.1,
        center_m: [1.5, 0.0],
        size_m: 0.08,
        step_m: 0.04,
        wrench: [0.0, 0.0, -1100.0, 0.0, 0.0, 0.0],
    };
    let out = std::env::temp_dir().join(format!("deflex-app-map-{}", std::process::id()));
    let map = write_map(&robot, &grid, &out).unwrap();
    assert_eq!(map.nodes.len() + map.unreachable, 9);
    let csv = std::fs::read_to_string(out.join("deflection_map.csv")).unwrap();
    assert_eq!(csv.lines().count(), map.nodes.len() + 1);
    assert!(csv.starts_with("x_m,y_m,z_m,q1_rad,"), "{csv}");
    assert_eq!(map.png.len(), 2);
    assert!(map.png.iter().all(|p| p.exists()));
    let json = map.to_json();
    assert_eq!(json["nodes"], map.nodes.len());
    assert!(json["max_dp_norm_m"].as_f64().unwrap() > 0.0);
    assert!(map.text().contains("wrote "));
    let _ = std::fs::remove_dir_all(&out);

    let bad = |grid: MapGrid| deflection_grid(&robot, &grid).err().unwrap().to_string();
    let e = bad(MapGrid {
        step_m: 0.0,
        ..grid.clone()
    });
    assert!(e.starts_with("step_m: "), "{e}");
    let e = bad(MapGrid {
        size_m: 25.0,
        ..grid.clone()
    });
    assert!(e.starts_with("size_m: "), "{e}");
    let e = bad(MapGrid {
        step_m: 1e-6,
        ..grid.clone()
    });
    assert!(e.contains("1001 nodes per side"), "{e}");
    // A plane far above the arm: no node reachable, nothing written.
    let far = std::env::temp_dir().join(format!("deflex-app-map-far-{}", std::process::id()));
    let e = write_map(&robot, &MapGrid { z_m: 50.0, ..grid }, &far)
        .err()
        .unwrap();
    assert!(matches!(e, deflex_app::Error::NoReachableNode), "{e}");
    assert!(!far.exists());
}
