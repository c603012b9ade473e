//! One control cycle: wrench processing (bias, gravity, low-pass, move to the TCP) + deflection
//! estimate δŝ = J K_θ⁻¹ Jᵀ w (eq. 15) + the PID of eq. 17 with limiter, safety and the
//! contact-runaway guard. Target: ≤ 1 µs median. Also the per-cycle extras of the runtime: the
//! joint-correction map (RSI `AK` answers) and the per-answer send shaper.

use criterion::{Criterion, black_box, criterion_group, criterion_main};
use deflex_control::{Controller, ControllerConfig, ToolLoad, WrenchConfig};
use deflex_model::spatial::pose_from_xyz_rpy;
use deflex_model::{TX200_FORMING_Q_DEG, builtin};

fn bench_cycle(c: &mut Criterion) {
    let robot = builtin("tx200").expect("built-in tx200");
    let config = ControllerConfig {
        bias: Some([1.0, -2.0, 3.0, 0.1, 0.2, -0.1]),
        wrench: WrenchConfig {
            sensor_in_flange: pose_from_xyz_rpy([0.0, 0.0, 0.05], [0.0, 0.0, 0.2]),
            tool: ToolLoad {
                mass_kg: 6.0,
                com_in_sensor_m: [0.0, 0.0, 0.1],
            },
            lowpass_hz: Some(30.0),
            ..WrenchConfig::default()
        },
        ..ControllerConfig::default()
    };
    let mut ctrl = Controller::new(robot, config).expect("controller");
    let q0 = TX200_FORMING_Q_DEG.map(f64::to_radians);
    ctrl.start(0.0);
    let mut t = 0.0;
    let mut k = 0u64;
    c.bench_function("control_cycle", |b| {
        b.iter(|| {
            t += 0.01;
            k += 1;
            let s = (k % 100) as f64 * 1e-4;
            let q = [q0[0] + s, q0[1], q0[2] - s, q0[3], q0[4] + s, q0[5]];
            let w = [100.0 + s, -50.0, -600.0 - s * 1e3, 5.0, -3.0, 0.5];
            black_box(ctrl.cycle(black_box(t), black_box(&q), black_box(&w)))
        })
    });
}

fn bench_link_extras(c: &mut Criterion) {
    use deflex_control::send_shaper::{LinkDirective, SendShaper, SendShaperConfig};
    let robot = builtin("tx200").expect("built-in tx200");
    let mut ctrl = Controller::new(robot, ControllerConfig::default()).expect("controller");
    let q0 = TX200_FORMING_Q_DEG.map(f64::to_radians);
    ctrl.cycle(0.01, &q0, &[0.0; 6]);
    c.bench_function("joint_correction_map", |b| {
        b.iter(|| black_box(ctrl.joint_correction_map()))
    });
    let mut shaper = SendShaper::new(SendShaperConfig::new([0.02; 6], [0.008; 6], 0.004, 0.5));
    let mut k = 0u64;
    c.bench_function("send_shaper_next", |b| {
        b.iter(|| {
            k += 1;
            let t = [(k % 7) as f64 * 1e-3; 6];
            black_box(shaper.next(black_box(&t), LinkDirective::Follow))
        })
    });
}

criterion_group!(benches, bench_cycle, bench_link_extras);
criterion_main!(benches);
