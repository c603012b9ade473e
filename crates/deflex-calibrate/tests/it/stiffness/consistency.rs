//! Do a file's coordinates belong to the robot? Checked against hand-computed forward
//! kinematics of a planar two-link arm, and on the acceptance case: a UR10e measurement file
//! given with the TX200's model is refused, naming the rows and the distances.

use deflex_calibrate::measurements::format_rows_for;
use deflex_calibrate::measurements::{FileHeader, MeasurementRow, parse_file};
use deflex_calibrate::stiffness::CalibError;
use deflex_calibrate::stiffness::consistency::{Reference, check_geometry, enforce};
use deflex_calibrate::stiffness::plan::{PlanOptions, plan_experiments};
use deflex_calibrate::stiffness::synthetic::{SyntheticOptions, measure};
use deflex_model::{builtin, robot_from_toml_str};

/// Two links in a horizontal plane: joint 1 at the origin, joint 2 0.5 m along x1, the TCP
/// 0.4 m along x2.
const PLANAR: &str = r#"
name = "planar two-link arm"
[[joint]]
alpha = 0.0
a = 0.0
d = 0.0
theta_offset = 0.0
limits = [-3.0, 3.0]
stiffness = { z = 1.0e5 }
[[joint]]
a = 0.5
alpha = 0.0
d = 0.0
theta_offset = 0.0
limits = [-3.0, 3.0]
stiffness = { z = 1.0e5 }
[tool]
xyz = [0.4, 0.0, 0.0]
"#;

/// By hand: TCP = (0.5 c1 + 0.4 c12, 0.5 s1 + 0.4 s12, 0).
fn tcp(q: [f64; 2]) -> [f64; 3] {
    let (a, b) = (q[0], q[0] + q[1]);
    [
        0.5 * a.cos() + 0.4 * b.cos(),
        0.5 * a.sin() + 0.4 * b.sin(),
        0.0,
    ]
}

/// By hand: the point (0.2, 0.1, 0.05) of link 2's frame (origin 0.5 m along x1, turned by
/// q1 + q2 about z).
fn on_link_2(q: [f64; 2]) -> [f64; 3] {
    let (a, b) = (q[0], q[0] + q[1]);
    [
        0.5 * a.cos() + 0.2 * b.cos() - 0.1 * b.sin(),
        0.5 * a.sin() + 0.2 * b.sin() + 0.1 * b.cos(),
        0.05,
    ]
}

fn row(
    case: &str,
    q: [f64; 2],
    point: &str,
    link: usize,
    p: [f64; 3],
    load: [f64; 3],
) -> MeasurementRow {
    MeasurementRow {
        load_case: case.into(),
        q_rad: q.to_vec(),
        wrench: [10.0, 20.0, 0.0, 0.0, 0.0, 0.0],
        load_link: 2,
        load_point_m: load,
        point: point.into(),
        point_link: link,
        point_m: p,
        displacement_m: Some([0.0; 3]),
        sigma_m: None,
        rotation_rad: None,
        purpose: None,
    }
}

const QS: [[f64; 2]; 3] = [[0.3, -0.7], [1.2, 0.4], [-0.9, 1.5]];

fn good_rows() -> Vec<MeasurementRow> {
    let mut rows = Vec::new();
    for (i, q) in QS.iter().enumerate() {
        let case = format!("L{i}");
        rows.push(row(&case, *q, "TCP", 2, tcp(*q), tcp(*q)));
        rows.push(row(&case, *q, "P2", 2, on_link_2(*q), tcp(*q)));
        rows.push(row(&case, *q, "M0", 0, [0.3, 0.0, -0.2], tcp(*q)));
    }
    rows
}

#[test]
fn rows_that_match_hand_computed_kinematics_pass() {
    let robot = robot_from_toml_str(PLANAR, "planar", None).unwrap();
    let check = check_geometry(&robot, &good_rows(), None, None, 1e-3).unwrap();
    assert!(check.passed(), "{:?}", check.disagreements);
    assert!(check.max_distance_m < 1e-12, "{}", check.max_distance_m);
    // TCP and P2 checked (P2 by consistency over three configurations), M0 on the base not.
    assert_eq!(check.checked_points, 6);
    assert_eq!(check.checked_loads, 9);
    assert_eq!(check.unchecked.len(), 1);
    assert!(check.unchecked[0].contains("M0"), "{:?}", check.unchecked);
}

#[test]
fn a_moved_tcp_and_a_moved_link_point_are_named_with_their_distance() {
    let robot = robot_from_toml_str(PLANAR, "planar", None).unwrap();
    let mut rows = good_rows();
    // Row 4 (L1's TCP) 2 mm off along world y; row 8 (L2's P2) 5 mm off along a skew axis.
    rows[3].point_m[1] += 0.002;
    rows[3].load_point_m[1] += 0.002;
    rows[7].point_m[0] += 0.003;
    rows[7].point_m[2] += 0.004;
    let lines: Vec<u64> = (0..rows.len() as u64).map(|i| i + 10).collect();
    let check = check_geometry(&robot, &rows, Some(&lines), None, 1e-3).unwrap();
    assert_eq!(check.disagreements.len(), 2, "{:?}", check.disagreements);
    let first = &check.disagreements[0];
    assert_eq!((first.row, first.line), (3, Some(13)));
    assert_eq!(first.reference, Reference::Tcp);
    assert!(
        (first.distance_m - 0.002).abs() < 1e-12,
        "{}",
        first.distance_m
    );
    let second = &check.disagreements[1];
    assert_eq!(second.row, 7);
    assert_eq!(second.reference, Reference::LinkPoint { link: 2 });
    assert!(
        (second.distance_m - 0.005).abs() < 1e-12,
        "{}",
        second.distance_m
    );
    let text = check.describe("m.csv");
    assert!(
        text.contains("2 of 9 rows")
            && text.contains("line 13 (load case L1, point TCP): 2.000 mm")
            && text.contains("line 17 (load case L2, point P2 on link 2): 5.000 mm"),
        "{text}"
    );
    // A wider tolerance accepts both.
    assert!(
        check_geometry(&robot, &rows, None, None, 6e-3)
            .unwrap()
            .passed()
    );
}

#[test]
fn load_points_off_the_tcp_are_checked_in_their_link_frame() {
    let robot = robot_from_toml_str(PLANAR, "planar", None).unwrap();
    // Loads at a bracket on link 2, the TCP measured: the bracket point is checked for
    // consistency in link 2's frame.
    let mut rows: Vec<MeasurementRow> = QS
        .iter()
        .enumerate()
        .map(|(i, q)| row(&format!("L{i}"), *q, "TCP", 2, tcp(*q), on_link_2(*q)))
        .collect();
    let check = check_geometry(&robot, &rows, None, None, 1e-3).unwrap();
    assert!(check.passed() && check.checked_loads == 3, "{check:?}");
    rows[1].load_point_m[2] += 0.01;
    let check = check_geometry(&robot, &rows, None, None, 1e-3).unwrap();
    assert_eq!(check.disagreements.len(), 1);
    assert_eq!(
        check.disagreements[0].reference,
        Reference::LoadPoint { link: 2 }
    );
    assert!((check.disagreements[0].distance_m - 0.01).abs() < 1e-12);
}

#[test]
fn tolerance_is_bounded() {
    let robot = robot_from_toml_str(PLANAR, "planar", None).unwrap();
    for bad in [0.0, f64::NAN, 2.0, -1e-3] {
        assert!(check_geometry(&robot, &good_rows(), None, None, bad).is_err());
    }
}

/// The acceptance case: a UR10e campaign (planned for the UR10e, measured on a simulated
/// UR10e, written with its header) given with the TX200's model.
#[test]
fn a_ur10e_file_given_with_the_tx200_is_refused_naming_rows_and_distances() {
    let ur = builtin("ur10e").unwrap();
    let plan = plan_experiments(
        &ur,
        &PlanOptions {
            max_force_n: 150.0,
            load_cases: 12,
            ..PlanOptions::for_a_real_cell()
        },
    )
    .unwrap();
    let rows = measure(&ur, &plan.rows, &SyntheticOptions::default()).unwrap();
    let text = format_rows_for(&ur, &rows, &["SIMULATED test campaign"]);
    assert!(text.starts_with("# SIMULATED test campaign\n# robot: Universal Robots UR10e"));
    let file = parse_file(&text, "meas_ur.csv", true).unwrap();
    assert_eq!(file.header.geometry, Some(ur.geometry_fingerprint()));
    assert_eq!(
        file.lines[0], 5,
        "three comment lines and the column names come first"
    );

    // Its own robot accepts it, with nothing to say.
    let check =
        check_geometry(&ur, &file.rows, Some(&file.lines), Some(&file.header), 1e-3).unwrap();
    assert!(
        check.passed() && check.header_mismatch.is_none(),
        "{check:?}"
    );
    assert!(
        enforce(&check, "meas_ur.csv", false, "")
            .unwrap()
            .is_empty()
    );

    // The TX200 refuses it.
    let tx = builtin("tx200").unwrap();
    let check =
        check_geometry(&tx, &file.rows, Some(&file.lines), Some(&file.header), 1e-3).unwrap();
    assert!(!check.passed());
    assert!(
        check.disagreeing_rows() * 2 > file.rows.len(),
        "{}",
        check.disagreeing_rows()
    );
    let err = enforce(&check, "meas_ur.csv", false, "use --ignore-fk-check").unwrap_err();
    assert!(matches!(err, CalibError::GeometryMismatch(_)));
    let message = err.to_string();
    eprintln!("{message}");
    assert!(
        message.contains("meas_ur.csv:")
            && message.contains("line 5 (load case A01, point TCP)")
            && message.contains(" mm from the TCP its joint values give")
            && message.contains("robot \"Universal Robots UR10e")
            && message.contains(&ur.geometry_fingerprint())
            && message.contains("use --ignore-fk-check"),
        "{message}"
    );
    // The first named distance is the hand-checkable one: the TX200's TCP at the row's joints.
    let first = &check.disagreements[0];
    let tcp_tx = tx
        .tcp_pose(&file.rows[first.row].q_rad)
        .unwrap()
        .translation
        .vector;
    let expected = (nalgebra::Vector3::from(file.rows[first.row].point_m) - tcp_tx).norm();
    assert!((first.distance_m - expected).abs() < 1e-12);
    // Overridden, it is a warning.
    let warnings = enforce(&check, "meas_ur.csv", true, "").unwrap();
    assert_eq!(warnings.len(), 1);
}

#[test]
fn a_header_naming_another_geometry_alone_is_a_warning() {
    let robot = robot_from_toml_str(PLANAR, "planar", None).unwrap();
    let header = FileHeader {
        robot: Some("some other arm".into()),
        geometry: Some("0123456789abcdef".into()),
        notes: Vec::new(),
    };
    let check = check_geometry(&robot, &good_rows(), None, Some(&header), 1e-3).unwrap();
    assert!(check.passed());
    let warnings = enforce(&check, "m.csv", false, "").unwrap();
    assert_eq!(warnings.len(), 1);
    assert!(
        warnings[0].contains("some other arm") && warnings[0].contains("0123456789abcdef"),
        "{}",
        warnings[0]
    );
    // The same robot's own fingerprint says nothing.
    let own = FileHeader::for_robot(&robot);
    let check = check_geometry(&robot, &good_rows(), None, Some(&own), 1e-3).unwrap();
    assert!(check.header_mismatch.is_none());
}
