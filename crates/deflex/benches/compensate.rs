//! Compensation of a 100 000-point path (the paper's TX200, a helix around its forming point)
//! with one process-model iteration: the desired path's IK, one process pass, one compensation
//! pass and the final process pass. The process model here is the closed-form
//! [`DepthProportional`]; the twin's forming model is benched in `compensate_forming.rs`.

use criterion::{Criterion, criterion_group, criterion_main};
use deflex_compensate::{
    CompensationOptions, DepthProportional, TcpPath, WrenchSource, compensate,
};
use deflex_model::{Pose, TX200_FORMING_Q_DEG, builtin};
use nalgebra::{Translation3, Vector3};
use std::hint::black_box;

fn helix(points: usize) -> TcpPath {
    let robot = builtin("tx200").unwrap();
    let start = robot
        .tcp_pose(&TX200_FORMING_Q_DEG.map(f64::to_radians))
        .unwrap();
    let turns = 60.0;
    let poses = (0..points).map(|i| {
        let t = i as f64 / points as f64;
        let a = 2.0 * std::f64::consts::PI * turns * t;
        let r = 0.020 - 0.015 * t;
        let p = start.translation.vector + Vector3::new(r * a.cos(), r * a.sin(), -0.015 * t);
        (
            Pose::from_parts(Translation3::from(p), start.rotation),
            Some(0.01),
        )
    });
    TcpPath::new("helix", poses, 0.05).unwrap()
}

fn bench(c: &mut Criterion) {
    let robot = builtin("tx200").unwrap();
    let seed = TX200_FORMING_Q_DEG.map(f64::to_radians);
    let path = helix(100_000);
    let surface = path.points()[0].pose.translation.vector.z;
    let options = CompensationOptions {
        max_iterations: 1,
        ..CompensationOptions::default()
    };
    let mut group = c.benchmark_group("compensate");
    group.sample_size(10);
    group.bench_function(
        "100k points, one process iteration, depth-proportional",
        |b| {
            b.iter(|| {
                let mut model = DepthProportional {
                    direction: Vector3::z(),
                    surface_m: surface,
                    stiffness_n_m: 1.0e5,
                };
                let result = compensate(
                    &robot,
                    black_box(&path),
                    &seed,
                    WrenchSource::Process(&mut model),
                    &options,
                    &mut |_| {},
                )
                .unwrap();
                assert_eq!(result.failure_count(), 0);
                black_box(result.max_compensation_m)
            })
        },
    );
    group.finish();
}

criterion_group!(benches, bench);
criterion_main!(benches);
