//! A 20-point line compensated under growing wrenches: an offline compensation's own points.
//!
//! One definition for every test binary that needs such a compensation: this package's table
//! tests and deflex-app's feed-forward table tests (which compile this file by `#[path]`; it uses
//! nothing but deflex-compensate, deflex-model and nalgebra).

use deflex_compensate::{Compensation, CompensationOptions, TcpPath, WrenchSource, compensate};
use deflex_model::{Pose, Robot, TX200_FORMING_Q_DEG, Wrench, builtin};
use nalgebra::{Translation3, Vector3};

/// The TX200, a 20-point line from its forming pose (1 mm along x and 0.5 mm along y per point,
/// 10 ms apart) and its compensation from that pose under wrenches growing along it.
pub fn compensated_line() -> (Robot, TcpPath, Compensation) {
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
    (robot, path, result)
}
