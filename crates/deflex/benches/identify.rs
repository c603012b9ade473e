//! Identification speed (the acceptance): a 10,000-row fixed-structure fit (< 50 ms) and
//! the full structure search on 2,000 rows (< 5 s). Data: synthetic TX200 (Table 1 + base tilt),
//! 15 µm noise, 600–1400 N.
use criterion::{Criterion, criterion_group, criterion_main};
use deflex_calibrate::stiffness::search::{SearchOptions, search_structure};
use deflex_calibrate::stiffness::stiffness_fit::{Structure, calibrate_fixed};
use deflex_calibrate::stiffness::synthetic::{
    SyntheticOptions, measure, measure_with_rotations, random_campaign,
};
use deflex_model::{Axis, EdofSite, builtin};
use std::hint::black_box;

fn identify(c: &mut Criterion) {
    let mut truth = builtin("tx200").unwrap();
    truth.set_stiffness(EdofSite::Base, Axis::Y, Some(6.0e6));
    // 3 rows per load case.
    let big = measure(
        &truth,
        &random_campaign(&truth, 3334, (600.0, 1400.0), 1),
        &SyntheticOptions::default(),
    )
    .unwrap();
    let big = &big[..10_000];
    let small = measure(
        &truth,
        &random_campaign(&truth, 667, (600.0, 1400.0), 2),
        &SyntheticOptions::default(),
    )
    .unwrap();
    let small = &small[..2_000];
    let fixed = Structure::from_robot(&truth);
    c.bench_function("fixed_fit_10k_rows", |b| {
        b.iter(|| calibrate_fixed(&truth, black_box(big), &fixed).unwrap())
    });
    let free = Structure::from_robot(&truth).with_free_shifts();
    c.bench_function("fixed_fit_10k_rows_free_shift", |b| {
        b.iter(|| calibrate_fixed(&truth, black_box(big), &free).unwrap())
    });
    // The same rows with measured link rotations (20 µrad): 6 equations per row.
    let plan = random_campaign(&truth, 3334, (600.0, 1400.0), 1);
    let rot = measure_with_rotations(&truth, &plan[..10_000], &SyntheticOptions::default(), 20e-6)
        .unwrap();
    c.bench_function("fixed_fit_10k_rows_with_rotations", |b| {
        b.iter(|| calibrate_fixed(&truth, black_box(&rot), &free).unwrap())
    });
    let mut group = c.benchmark_group("search");
    group.sample_size(10);
    group.bench_function("full_search_2k_rows", |b| {
        b.iter(|| {
            search_structure(
                &truth,
                black_box(small),
                &SearchOptions::default(),
                &mut |_| {},
            )
            .unwrap()
        })
    });
    group.bench_function("full_search_2k_rows_cross_validated", |b| {
        b.iter(|| {
            search_structure(
                &truth,
                black_box(small),
                &SearchOptions {
                    criterion: deflex_calibrate::stiffness::Criterion::cross_validated(),
                    ..SearchOptions::default()
                },
                &mut |_| {},
            )
            .unwrap()
        })
    });
    group.finish();
}

criterion_group!(benches, identify);
criterion_main!(benches);
