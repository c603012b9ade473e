//! Offline compensation of a 100 000-point path against the twin's forming model (SIMULATED),
//! one process-model iteration: the paper's cone at 0.2° steps (the first 100 000 waypoints),
//! the desired path's IK, a process pass (sheet equilibrium and flow at every point), a
//! compensation pass and the final process pass.

use criterion::{Criterion, criterion_group, criterion_main};
use deflex_compensate::{CompensationOptions, WrenchSource, compensate};
use deflex_sim::{CellConfig, ConeParams, FormingProcess, ToolPath, tcp_path};
use std::hint::black_box;

fn bench(c: &mut Criterion) {
    let config = CellConfig::default();
    let robot = config.nominal_robot().unwrap();
    let seed = config.seed_q_rad();
    let mut path = ToolPath::cone(&ConeParams {
        angle_step_deg: 0.2,
        ..ConeParams::default()
    })
    .unwrap();
    path.waypoints.truncate(100_000);
    let rotation = robot.tcp_pose(&seed).unwrap().rotation;
    let tcp = tcp_path(
        &path,
        &config.part_frame(),
        &rotation,
        config.controller.rapid_feed_mm_s,
    )
    .unwrap();
    assert_eq!(tcp.len(), 100_000);
    let options = CompensationOptions {
        max_iterations: 1,
        ..CompensationOptions::default()
    };
    let mut group = c.benchmark_group("compensate");
    group.sample_size(10);
    group.bench_function("100k-point cone, one iteration, twin forming model", |b| {
        b.iter(|| {
            let mut process = FormingProcess::from_cell(&config, &path).unwrap();
            let result = compensate(
                &robot,
                black_box(&tcp),
                &seed,
                WrenchSource::Process(&mut process),
                &options,
                &mut |_| {},
            )
            .unwrap();
            assert_eq!(result.failure_count(), 0);
            black_box(result.max_compensation_m)
        })
    });
    group.finish();
}

criterion_group!(benches, bench);
criterion_main!(benches);
