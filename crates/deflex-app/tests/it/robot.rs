//! The model engine ([`deflex_app::robot`]): batches against single calls, inverse kinematics, non-
//! finite input.

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
