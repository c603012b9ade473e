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

/// The same cycle with a feed-forward table of 100 000 points (arc-length tracking by forward
/// kinematics of the reported joints, a 30 ms lead), the robot moving 10 µm per cycle along the
/// table's path (joint 1 turning, the TCP on a 1.5 m arc).
fn bench_cycle_feedforward(c: &mut Criterion) {
    use deflex_compensate::table::TableRow;
    use deflex_control::{FeedForward, FeedForwardConfig, FeedForwardTable};
    use deflex_model::{Data, Displacement, Wrench};
    let robot = builtin("tx200").expect("built-in tx200");
    let q0 = TX200_FORMING_Q_DEG.map(f64::to_radians);
    const POINTS: usize = 100_000;
    // 0.1 mm between table points, 10 µm per control cycle.
    let step = 1e-4 / 1.5;
    let mut data = Data::new();
    let mut s = 0.0;
    let mut previous: Option<nalgebra::Vector3<f64>> = None;
    let rows: Vec<TableRow> = (0..POINTS)
        .map(|i| {
            let mut q = q0;
            q[0] += i as f64 * step;
            robot.forward_kinematics(&mut data, &q).unwrap();
            let p = data.tcp_position();
            if let Some(prev) = previous {
                s += (p - prev).norm();
            }
            previous = Some(p);
            let d = (i as f64 * 0.01).sin() * 1e-3;
            TableRow {
                line: i + 2,
                arc_length_m: s,
                time_s: s / 0.01,
                desired: data.tcp,
                compensation: Displacement::new(0.0, 0.0, -d, 0.0, 0.0, 0.0),
                wrench: Wrench::zeros(),
                deflection: Displacement::new(0.0, 0.0, d, 0.0, 0.0, 0.0),
                status: "ok".into(),
            }
        })
        .collect();
    let table = FeedForwardTable::from_rows(&rows, &robot, "bench").unwrap();
    let ff = FeedForward::new(
        table,
        FeedForwardConfig {
            lead_s: 0.03,
            ..FeedForwardConfig::default()
        },
    )
    .unwrap();
    let config = ControllerConfig {
        bias: Some([1.0, -2.0, 3.0, 0.1, 0.2, -0.1]),
        ..ControllerConfig::default()
    };
    let mut ctrl = Controller::new(robot, config).expect("controller");
    ctrl.set_feedforward(Some(ff));
    ctrl.start(0.0);
    let cycles = (POINTS - 1) * 10;
    let mut t = 0.0;
    let mut k = 0usize;
    c.bench_function("control_cycle_feedforward", |b| {
        b.iter(|| {
            t += 0.01;
            k += 1;
            if k == cycles {
                // A new run of the program (once per 10⁶ cycles).
                k = 0;
                if let Some(ff) = ctrl.feedforward_mut() {
                    ff.reset();
                }
            }
            let mut q = q0;
            q[0] += k as f64 * step * 0.1;
            let w = [10.0, -5.0, -600.0, 1.0, -0.3, 0.5];
            black_box(ctrl.cycle(black_box(t), black_box(&q), black_box(&w)))
        })
    });
}

criterion_group!(
    benches,
    bench_cycle,
    bench_cycle_feedforward,
    bench_link_extras
);
criterion_main!(benches);
