//! Hot-path bench: forward kinematics + eDoF screws + TCP deflection (eq. 15) for the TX200 with
//! the Table 1 eDoFs (6), with 7 (plus J6.z) and with all 18 joint eDoFs plus 2 base eDoFs.

use criterion::{Criterion, black_box, criterion_group, criterion_main};
use deflex_model::{Axis, Data, EdofSite, TX200_FORMING_Q_DEG, Wrench, builtin};

fn full_model() -> deflex_model::Robot {
    let mut robot = builtin("tx200").expect("builtin");
    for i in 1..=6 {
        for axis in Axis::ALL {
            if robot.stiffness(EdofSite::Joint(i), axis).is_none() {
                robot.set_stiffness(EdofSite::Joint(i), axis, Some(5.0e6));
            }
        }
    }
    robot.set_stiffness(EdofSite::Base, Axis::X, Some(5.0e7));
    robot.set_stiffness(EdofSite::Base, Axis::Y, Some(5.0e7));
    robot
}

fn bench(c: &mut Criterion) {
    let q = TX200_FORMING_Q_DEG.map(f64::to_radians);
    let wrench = Wrench::new(150.0, -300.0, 1200.0, 0.0, 0.0, 0.0);
    let table1 = builtin("tx200").expect("builtin");
    let mut seven = table1.clone();
    seven.set_stiffness(EdofSite::Joint(6), Axis::Z, Some(0.02e6));
    for (label, robot) in [
        ("tx200_table1_6_edofs", table1),
        ("tx200_7_edofs", seven),
        ("tx200_20_edofs", full_model()),
    ] {
        let mut data = Data::new();
        c.bench_function(&format!("fk_edof_deflection/{label}"), |b| {
            b.iter(|| {
                robot
                    .forward_kinematics(&mut data, black_box(&q))
                    .expect("6 joints");
                black_box(robot.tcp_deflection(&data, black_box(&wrench)))
            })
        });
    }
}

criterion_group!(benches, bench);
criterion_main!(benches);
