//! One control cycle: wrench processing (bias, gravity, low-pass, move to the TCP) + deflection
//! estimate δŝ = J K_θ⁻¹ Jᵀ w (eq. 15) + the PID of eq. 17 with limiter, safety and the
//! contact-runaway guard. Target: ≤ 1 µs median. The same with a feed-forward table
//! (`control_cycle_feedforward`, 100 000 points 0.1 mm apart, arc-length tracking and a lead;
//! `feedforward_update`: the tracking and lookup alone). Also the joint-correction map the
//! runtime sends with RSI `AK` answers (the per-answer send shaper is benched in the `link`
//! bench).

use criterion::{Criterion, black_box, criterion_group, criterion_main};
use deflex_control::{Controller, ControllerConfig, WrenchConfig};
use deflex_model::ToolLoad;
use deflex_model::spatial::pose_from_xyz_rpy;
use deflex_model::{TX200_FORMING_Q_DEG, Wrench, builtin};

fn bench_cycle(c: &mut Criterion) {
    let robot = builtin("tx200").expect("built-in tx200");
    let config = ControllerConfig {
        bias: Some([1.0, -2.0, 3.0, 0.1, 0.2, -0.1]),
        wrench: WrenchConfig {
            sensor_in_flange: pose_from_xyz_rpy([0.0, 0.0, 0.05], [0.0, 0.0, 0.2]),
            tool_in_sensor: ToolLoad {
                mass_kg: 6.0,
                centre_of_mass_m: nalgebra::Vector3::new(0.0, 0.0, 0.1),
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
            let w = Wrench::new(100.0 + s, -50.0, -600.0 - s * 1e3, 5.0, -3.0, 0.5);
            black_box(ctrl.cycle(black_box(t), black_box(&q), black_box(&w)))
        })
    });
}

fn bench_link_extras(c: &mut Criterion) {
    let robot = builtin("tx200").expect("built-in tx200");
    let mut ctrl = Controller::new(robot, ControllerConfig::default()).expect("controller");
    let q0 = TX200_FORMING_Q_DEG.map(f64::to_radians);
    ctrl.cycle(0.01, &q0, &Wrench::zeros());
    c.bench_function("joint_correction_map", |b| {
        b.iter(|| black_box(ctrl.joint_correction_map()))
    });
}

/// The same cycle with a feed-forward table of 100 000 points (arc-length tracking by forward
/// kinematics of the reported joints, a 30 ms lead), the robot moving 10 µm per cycle along the
/// table's path (joint 1 turning, the TCP on a 1.5 m arc).
fn bench_cycle_feedforward(c: &mut Criterion) {
    use deflex_control::{FeedForward, FeedForwardConfig, FeedForwardPoint, FeedForwardTable};
    use deflex_model::{Data, Displacement};
    let robot = builtin("tx200").expect("built-in tx200");
    let q0 = TX200_FORMING_Q_DEG.map(f64::to_radians);
    const POINTS: usize = 100_000;
    // 0.1 mm between table points, 10 µm per control cycle.
    let step = 1e-4 / 1.5;
    let mut data = Data::new();
    let mut s = 0.0;
    let mut previous: Option<nalgebra::Vector3<f64>> = None;
    let rows: Vec<FeedForwardPoint> = (0..POINTS)
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
            FeedForwardPoint {
                arc_length_m: s,
                time_s: s / 0.01,
                desired_m: data.tcp_position(),
                compensation: Displacement::new(0.0, 0.0, -d, 0.0, 0.0, 0.0),
                deflection: Displacement::new(0.0, 0.0, d, 0.0, 0.0, 0.0),
            }
        })
        .collect();
    let table = FeedForwardTable::from_points(&rows, &robot).unwrap();
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
    let mut fresh = Controller::new(robot, config).expect("controller");
    fresh.set_feedforward(Some(ff));
    // One run of the program is (POINTS − 1) × 10 cycles; a new run (a fresh controller: the
    // joints jump back to the start) is set up outside the timed loop.
    let cycles = (POINTS - 1) * 10;
    // What is timed does the work: the law is active and the robot on the table's path.
    let mut check = fresh.clone();
    check.start(0.0);
    for k in 0..2000 {
        let mut q = q0;
        q[0] += k as f64 * step * 0.1;
        let w = Wrench::new(10.0, -5.0, -600.0, 1.0, -0.3, 0.5);
        let out = check.cycle(k as f64 * 0.01, &q, &w);
        if k > 100 {
            assert!(out.flags.has(deflex_telemetry::Flags::ACTIVE), "{k}");
            assert!(
                !out.flags.has(deflex_telemetry::Flags::FEEDFORWARD_OFF_PATH),
                "{k}"
            );
        }
    }
    // The tracking and lookup alone.
    if let Some(ff) = fresh.feedforward() {
        let mut data = Data::new();
        let tcps: Vec<nalgebra::Vector3<f64>> = (0..cycles)
            .map(|k| {
                let mut q = q0;
                q[0] += k as f64 * step * 0.1;
                robot_fk(&fresh, &mut data, &q)
            })
            .collect();
        let template = ff.clone();
        c.bench_function("feedforward_update", |b| {
            b.iter_custom(|iters| {
                let mut total = std::time::Duration::ZERO;
                let mut done = 0u64;
                while done < iters {
                    let mut ff = template.clone();
                    ff.start(0.0);
                    let n = (iters - done).min(cycles as u64) as usize;
                    let start = std::time::Instant::now();
                    for (k, x) in tcps[..n].iter().enumerate() {
                        black_box(ff.update(black_box(x), k as f64 * 0.01));
                    }
                    total += start.elapsed();
                    done += n as u64;
                }
                total
            })
        });
    }
    c.bench_function("control_cycle_feedforward", |b| {
        b.iter_custom(|iters| {
            let mut total = std::time::Duration::ZERO;
            let mut done = 0u64;
            while done < iters {
                let mut ctrl = fresh.clone();
                ctrl.start(0.0);
                let n = (iters - done).min(cycles as u64);
                let start = std::time::Instant::now();
                for k in 0..n {
                    let t = k as f64 * 0.01;
                    let mut q = q0;
                    q[0] += k as f64 * step * 0.1;
                    let w = Wrench::new(10.0, -5.0, -600.0, 1.0, -0.3, 0.5);
                    black_box(ctrl.cycle(black_box(t), black_box(&q), black_box(&w)));
                }
                total += start.elapsed();
                done += n;
            }
            total
        })
    });
}

fn robot_fk(ctrl: &Controller, data: &mut deflex_model::Data, q: &[f64]) -> nalgebra::Vector3<f64> {
    ctrl.robot().forward_kinematics(data, q).unwrap();
    data.tcp_position()
}

criterion_group!(
    benches,
    bench_cycle,
    bench_cycle_feedforward,
    bench_link_extras
);
criterion_main!(benches);
