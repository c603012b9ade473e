//! The limiter: size, rate, per-axis enable, ramps ([`deflex_control::limiter`]).

use deflex_control::limiter::*;

fn on_limiter(cfg: LimiterConfig) -> Limiter {
    let mut l = Limiter::new(LimiterConfig {
        ramp_in_s: 0.0,
        ..cfg
    });
    l.start(0.0);
    l
}

#[test]
fn size_and_rate_bounds_hold() {
    let mut l = on_limiter(LimiterConfig::default());
    let cfg = l.config;
    let demand = [1.0, -1.0, 0.5, 1.0, -1.0, 0.2];
    let mut previous = [0.0; 6];
    for k in 0..2000 {
        let out = l.apply(&demand, k as f64 * 0.01, 0.01);
        for i in 0..6 {
            assert!(out.xi[i].abs() <= cfg.max_abs[i] + 1e-15);
            assert!((out.xi[i] - previous[i]).abs() <= cfg.max_rate[i] * 0.01 + 1e-15);
        }
        previous = out.xi;
    }
    assert_eq!(previous[0], cfg.max_abs[0]);
    assert_eq!(previous[1], -cfg.max_abs[1]);
}

#[test]
fn disabled_axes_stay_zero() {
    let mut l = on_limiter(LimiterConfig {
        enabled: [true, true, true, false, false, false],
        ..LimiterConfig::default()
    });
    for k in 0..100 {
        let out = l.apply(&[1e-3; 6], k as f64 * 0.01, 0.01);
        assert_eq!(&out.xi[3..], &[0.0; 3]);
    }
    assert!(l.output()[0] > 0.0);
}

#[test]
fn ramp_in_and_out_are_smooth_and_end_at_zero() {
    let cfg = LimiterConfig {
        max_rate: [1.0; 6],
        ramp_in_s: 0.5,
        ramp_out_s: 0.5,
        ..LimiterConfig::default()
    };
    let mut l = Limiter::new(cfg);
    l.start(0.0);
    let demand = [2e-3; 6];
    let mut t = 0.0;
    let mut last = 0.0;
    while t < 1.0 {
        t += 0.01;
        let out = l.apply(&demand, t, 0.01);
        assert!(out.xi[0] >= last - 1e-15, "ramp-in not monotonic");
        assert!(
            out.xi[0] - last <= 2e-3 * 1.5 * 0.01 / 0.5 + 1e-12,
            "ramp-in too steep"
        );
        last = out.xi[0];
    }
    assert_eq!(l.state(), RampState::On);
    assert!((last - 2e-3).abs() < 1e-12);
    l.ramp_out(t);
    let t_out = t;
    while !l.is_off() {
        t += 0.01;
        let out = l.apply(&demand, t, 0.01);
        assert!(out.xi[0] <= last + 1e-15, "ramp-out grew");
        last = out.xi[0];
        assert!(t - t_out < 0.6);
    }
    assert_eq!(l.output(), [0.0; 6]);
}

#[test]
fn hold_keeps_the_value_and_non_finite_demands_go_to_zero() {
    let mut l = on_limiter(LimiterConfig::default());
    for k in 0..50 {
        l.apply(&[1e-3; 6], k as f64 * 0.01, 0.01);
    }
    let held = l.output();
    l.hold();
    for k in 50..100 {
        assert_eq!(l.apply(&[5e-3; 6], k as f64 * 0.01, 0.01).xi, held);
    }
    let mut l = on_limiter(LimiterConfig::default());
    let out = l.apply(&[f64::NAN; 6], 0.0, 0.01);
    assert_eq!(out.xi, [0.0; 6]);
}
