//! No allocation on deflex-compensate's per-point path: a compensation run makes the same number
//! of heap allocations for a 100-point and a 2000-point path (the buffers are allocated once per
//! run), with fixed wrenches and with a process model. Counted by this binary's global
//! allocator, which counts only the test thread's allocations.

use super::allocations;
use deflex_compensate::{
    CompensationOptions, DepthProportional, TcpPath, WrenchSource, compensate,
};
use deflex_model::{Pose, TX200_FORMING_Q_DEG, Wrench, builtin};
use nalgebra::{Translation3, Vector3};

fn path(points: usize) -> TcpPath {
    let robot = builtin("tx200").unwrap();
    let start = robot
        .tcp_pose(&TX200_FORMING_Q_DEG.map(f64::to_radians))
        .unwrap();
    let poses = (0..points).map(|i| {
        let a = 2.0 * std::f64::consts::PI * i as f64 / points as f64;
        let p = start.translation.vector + Vector3::new(0.02 * a.cos(), 0.02 * a.sin(), -0.002);
        (
            Pose::from_parts(Translation3::from(p), start.rotation),
            Some(0.01),
        )
    });
    TcpPath::new("circle", poses, 0.05).unwrap()
}

fn count(points: usize, process: bool) -> u64 {
    let robot = builtin("tx200").unwrap();
    let seed = TX200_FORMING_Q_DEG.map(f64::to_radians);
    let path = path(points);
    let wrenches = vec![Wrench::new(50.0, -20.0, 1000.0, 0.0, 0.0, 0.0); points];
    let mut model = DepthProportional {
        direction: Vector3::z(),
        surface_m: path.points()[0].pose.translation.vector.z + 0.001,
        stiffness_n_m: 4e5,
    };
    // Three iterations exactly, for both lengths.
    let options = CompensationOptions {
        max_iterations: 3,
        tolerance_m: 1e-9,
        tolerance_rad: 1e-9,
        ..CompensationOptions::default()
    };
    let before = allocations();
    let source = if process {
        WrenchSource::Process(&mut model)
    } else {
        WrenchSource::Fixed {
            label: String::new(),
            simulated: false,
            wrenches: &wrenches,
        }
    };
    let result = compensate(&robot, &path, &seed, source, &options, &mut |_| {}).unwrap();
    let used = allocations() - before;
    assert_eq!(result.failure_count(), 0);
    assert_eq!(result.iterations.len(), if process { 3 } else { 1 });
    drop(result);
    used
}

#[test]
fn allocations_do_not_grow_with_the_path() {
    for process in [false, true] {
        let small = count(100, process);
        let large = count(2000, process);
        assert_eq!(small, large, "process model: {process}");
    }
}
