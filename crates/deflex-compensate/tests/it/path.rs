//! The TCP path: arc length, time, location, and refused paths ([`deflex_compensate::path`]).

use deflex_compensate::PathError;
use deflex_compensate::path::*;
use deflex_model::Pose;
use nalgebra::Vector3;

fn line(n: usize) -> Vec<(Pose, Option<f64>)> {
    (0..n)
        .map(|i| (Pose::translation(0.001 * i as f64, 0.0, 0.0), Some(0.01)))
        .collect()
}

#[test]
fn arc_length_time_and_location() {
    let path = TcpPath::new("line", line(11), 0.05).unwrap();
    assert!((path.length_m() - 0.010).abs() < 1e-15);
    assert!((path.duration_s() - 1.0).abs() < 1e-12);
    assert_eq!(path.points()[0].feed_m_s, None);
    let (i, f) = path.locate(0.0025);
    assert_eq!(i, 2);
    assert!((f - 0.5).abs() < 1e-9);
    assert_eq!(path.locate(-1.0), (0, 0.0));
    assert_eq!(path.locate(1.0), (9, 1.0));
    assert_eq!(path.travel_direction(0), Vector3::x());
    assert_eq!(path.travel_direction(5), Vector3::x());
}

#[test]
fn bad_paths_are_refused_with_the_point_named() {
    assert!(matches!(
        TcpPath::new("one", line(1), 0.05),
        Err(PathError::TooFewPoints { points: 1, .. })
    ));
    let mut points = line(5);
    points[3].0.translation.vector.z = f64::NAN;
    let e = TcpPath::new("p", points, 0.05).unwrap_err();
    assert!(e.to_string().contains("point 3: z_m"), "{e}");
    let mut points = line(5);
    points[2].1 = Some(0.0);
    let e = TcpPath::new("p", points, 0.05).unwrap_err();
    assert!(e.to_string().contains("point 2: feed"), "{e}");
    let mut points = line(5);
    points[4].0.rotation =
        nalgebra::Rotation3::from_matrix_unchecked(nalgebra::Matrix3::identity() * 2.0);
    assert!(matches!(
        TcpPath::new("p", points, 0.05),
        Err(PathError::BadRotation { index: 4, .. })
    ));
    assert!(TcpPath::new("p", line(3), f64::INFINITY).is_err());
}
