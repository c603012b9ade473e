use deflex_calibrate::geometry::ur10_tracker::*;
use nalgebra::{Rotation3, Vector3};

const HEADER: &str = "Timestamp;Goal x;shoulder_pan_joint;shoulder_lift_joint;elbow_joint;wrist_1_joint;wrist_2_joint;wrist_3_joint;measurement_temperature;measurement_x;measurement_std_x;measurement_y;measurement_std_y;measurement_z;measurement_std_z;measurement_rx;measurement_ry;measurement_rz";

fn options() -> ImportOptions {
    ImportOptions {
        setup: "A".into(),
        target: "tmac".into(),
        tracker_sigma: true,
    }
}

#[test]
// 1.5708 is the file's own rounded value, not π/2.
#[allow(clippy::approx_constant)]
fn decimal_commas_units_and_rotation() {
    let text = format!(
        "{HEADER}\r\n20200714163904;0,365;-1,5708;-1,5708;0,0;-1,5708;0,0;0,0;23,68;2361,9831;0,03;-1368,5474;0,0;119,39713;0,0;90;0;90\r\n2,02011E+13;0;0;0;0;0;0;0;21,5;1;0;2;0;3;0;0;0;0"
    );
    let (rows, summary) = parse_series(&text, "s.csv", &options()).unwrap();
    assert_eq!(rows.len(), 2);
    assert_eq!(
        rows[0].q_rad,
        vec![-1.5708, -1.5708, 0.0, -1.5708, 0.0, 0.0]
    );
    assert!((rows[0].position_m[0] - 2.3619831).abs() < 1e-12);
    assert!((rows[0].position_m[1] + 1.3685474).abs() < 1e-12);
    // std: RMS of (0.03, 0, 0) mm.
    assert!((rows[0].sigma_m.unwrap() - 0.03e-3 / 3f64.sqrt()).abs() < 1e-15);
    // Intrinsic X-Y-Z 90°, 0, 90°: R = Rx(90°)·Rz(90°), by hand rows (0,-1,0), (0,0,-1), (1,0,0).
    let v = rows[0].orientation.unwrap().rotation_vector_rad;
    let r = Rotation3::from_scaled_axis(Vector3::from(v));
    let expected = nalgebra::Matrix3::new(0.0, -1.0, 0.0, 0.0, 0.0, -1.0, 1.0, 0.0, 0.0);
    assert!((r.matrix() - expected).abs().max() < 1e-12, "{r}");
    assert_eq!(rows[0].time_s, Some(1_594_744_744.0));
    assert_eq!(rows[1].time_s, None);
    assert_eq!(summary.rows_without_time, 1);
    assert_eq!(summary.temperature_range_c, Some([21.5, 23.68]));
}

#[test]
fn bad_rows_are_named() {
    let text = format!("{HEADER}\n1;0;0;0;0;0;0;0;21;1;0;2x;0;3;0;0;0;0");
    let err = parse_series(&text, "s.csv", &options())
        .unwrap_err()
        .to_string();
    assert!(
        err.contains("s.csv:2") && err.contains("measurement_y"),
        "{err}"
    );
    let err = parse_series("Timestamp;x\n1;2", "s.csv", &options())
        .unwrap_err()
        .to_string();
    assert!(err.contains("shoulder_pan_joint"), "{err}");
    let text = format!("{HEADER}\n1;0;0");
    let err = parse_series(&text, "s.csv", &options())
        .unwrap_err()
        .to_string();
    assert!(err.contains("fields"), "{err}");
}
