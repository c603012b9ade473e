//! The robot controller's emulation: the correction pipeline's delay and first-order response,
//! interpolation and correction, look-ahead and servo lag, size and speed bounds.

use deflex_sim::cell_config::RobotControllerConfig;
use deflex_sim::controller_emulation::{ControllerEmulation, CorrectionPipeline};
use deflex_sim::toolpath::ToolPath;

fn step_response(config: &RobotControllerConfig, cycles: usize) -> Vec<[f64; 6]> {
    let mut pipe = CorrectionPipeline::new(config, false);
    pipe.set([0.001, 0.0, 0.0, 0.0, 0.0, 0.0]);
    (0..cycles).map(|_| pipe.advance()).collect()
}

#[test]
fn delay_then_first_order_response() {
    let config = RobotControllerConfig {
        correction_delay_s: 0.008,
        correction_filter_s: 0.02,
        max_correction_speed_m_s: 10.0,
        ..RobotControllerConfig::default()
    };
    let out = step_response(&config, 200);
    // 8 ms at 250 Hz = 2 cycles of pure delay.
    assert_eq!(out[0][0], 0.0);
    assert_eq!(out[1][0], 0.0);
    assert!(out[2][0] > 0.0);
    // First-order: after one time constant (5 cycles after the delay) ≈ 63 %.
    let a = 1.0 - (-0.004f64 / 0.02).exp();
    let expected = 0.001 * (1.0 - (1.0 - a).powi(5));
    assert!(
        (out[6][0] - expected).abs() < 1e-12,
        "{} vs {expected}",
        out[6][0]
    );
    assert!((out[6][0] / 0.001 - 0.632).abs() < 0.01);
    assert!((out[199][0] - 0.001).abs() < 1e-9);
}

#[test]
fn look_ahead_and_servo_slow_a_step_down() {
    // UR-like: 500 Hz, 4 ms delay, 0.1 s look-ahead, 15 Hz servo.
    let config = RobotControllerConfig {
        rate_hz: 500.0,
        correction_delay_s: 0.004,
        correction_filter_s: 0.0,
        servo_bandwidth_hz: 15.0,
        lookahead_s: 0.1,
        max_correction_speed_m_s: 10.0,
        ..RobotControllerConfig::default()
    };
    let mut ideal = CorrectionPipeline::new(&config, false);
    let mut real = CorrectionPipeline::new(&config, true);
    ideal.set([0.001, 0.0, 0.0, 0.0, 0.0, 0.0]);
    real.set([0.001, 0.0, 0.0, 0.0, 0.0, 0.0]);
    let a: Vec<f64> = (0..400).map(|_| ideal.advance()[0]).collect();
    let b: Vec<f64> = (0..400).map(|_| real.advance()[0]).collect();
    // Without servo and look-ahead: the step after 2 cycles of delay.
    assert_eq!(a[1], 0.0);
    assert!((a[2] - 0.001).abs() < 1e-15);
    // With them: the moving average ramps over 50 cycles, the servo lags and settles at 1.
    assert!(
        b[2] < 0.1 * 0.001 && b[26] < 0.6 * 0.001 && b[26] > 0.3 * 0.001,
        "{}",
        b[26]
    );
    assert!((b[399] - 0.001).abs() < 1e-9);
    // Second order with damping 0.7: a small overshoot (≤ 5 %).
    let peak = b.iter().cloned().fold(0.0, f64::max);
    assert!(peak < 1.05 * 0.001, "{peak}");
}

#[test]
fn size_and_speed_bounds() {
    let config = RobotControllerConfig {
        correction_delay_s: 0.0,
        correction_filter_s: 0.0,
        max_correction_m: 0.002,
        max_correction_speed_m_s: 0.025, // 0.1 mm per 4 ms cycle
        ..RobotControllerConfig::default()
    };
    let mut pipe = CorrectionPipeline::new(&config, false);
    pipe.set([0.003, 0.004, 0.0, 0.0, 0.0, 0.0]); // 5 mm requested
    let first = pipe.advance();
    let n = (first[0].powi(2) + first[1].powi(2)).sqrt();
    assert!((n - 1e-4).abs() < 1e-12, "speed-limited step {n}");
    let mut last = first;
    for _ in 0..100 {
        last = pipe.advance();
    }
    let n = (last[0].powi(2) + last[1].powi(2)).sqrt();
    assert!((n - 0.002).abs() < 1e-12, "size-limited {n}");
    // Direction kept.
    assert!((last[1] / last[0] - 4.0 / 3.0).abs() < 1e-9);
    // NaN requests are ignored.
    pipe.set([f64::NAN; 6]);
    assert_eq!(pipe.advance(), last);
}

#[test]
fn interpolation_follows_the_path_and_correction_moves_the_tcp() {
    let robot = deflex_model::builtin("tx200").unwrap();
    let path = ToolPath::paper_cone().truncated(30.0);
    let config = RobotControllerConfig::default();
    let part = deflex_model::spatial::pose_from_xyz_rpy([1.5, 0.0, -0.183], [0.0; 3]);
    let seed = deflex_model::TX200_FORMING_Q_DEG.map(f64::to_radians);
    let mut ctrl = ControllerEmulation::new(&robot, &config, true, &path, &part, &seed).unwrap();
    assert!((ctrl.duration_s() - path.duration_s(50.0)).abs() < 1e-9);
    let mut worst: f64 = 0.0;
    let mut cycle = ctrl.advance();
    while !cycle.finished {
        let tcp = robot.tcp_pose(&cycle.q_command).unwrap().translation.vector;
        worst = worst.max((tcp - cycle.desired_m).norm());
        cycle = ctrl.advance();
    }
    assert!(worst < 1e-6, "joint vs Cartesian interpolation {worst}");
    // A 2 mm correction along y moves the commanded TCP by 2 mm (after delay and filter).
    ctrl.set_correction([0.0, 0.002, 0.0, 0.0, 0.0, 0.0]);
    for _ in 0..100 {
        cycle = ctrl.advance();
    }
    let tcp = robot.tcp_pose(&cycle.q_command).unwrap().translation.vector;
    let d = tcp - cycle.desired_m;
    assert!((d.y - 0.002).abs() < 2e-6 && d.x.abs() < 2e-6, "{d}");
}
