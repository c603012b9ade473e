//! The PID of eq. 17 per axis ([`deflex_control::pid`]).

use deflex_control::pid::*;

#[test]
fn step_response_matches_hand_computation() {
    // Unit step of ε, h = 10 ms, paper gains, unfiltered derivative (N = 0).
    let gains = PidGains {
        derivative_filter_n: 0.0,
        ..PidGains::default()
    };
    let mut pid = Pid::new(gains);
    let h = 0.01;
    // k = 0: P + I = 0.8 + 0.8·0.01/0.048 = 0.966 667 (no derivative kick on the first sample).
    let xi0 = pid.step_error(0, 1.0, h);
    assert!((xi0 - (0.8 + 0.8 * 0.01 / 0.048)).abs() < 1e-12);
    // k = 1: ε unchanged → D = 0, I doubles: 0.8 + 2·0.166 667 = 1.133 333.
    let xi1 = pid.step_error(0, 1.0, h);
    assert!((xi1 - (0.8 + 2.0 * 0.8 * 0.01 / 0.048)).abs() < 1e-12);
    // Error falls to 0.5: P = 0.4, I = 0.333 333 + 0.083 333, D = 0.8·0.012·(−0.5)/0.01 = −0.48.
    let xi2 = pid.step_error(0, 0.5, h);
    let expected = 0.4 + (2.0 + 0.5) * 0.8 * 0.01 / 0.048 - 0.48;
    assert!((xi2 - expected).abs() < 1e-12, "{xi2} vs {expected}");
}

/// Scalar plant: δŝ_k = −(1 − g) ξ_{k−1} + d (contact of relative compliance g = 1/(1+ck)).
fn closed_loop(g: f64, steps: usize) -> Vec<f64> {
    let mut pid = Pid::new(PidGains::default());
    let (h, d) = (0.01, 1e-3);
    let mut xi: f64 = 0.0;
    (0..steps)
        .map(|_| {
            let ds = -(1.0 - g) * xi + d;
            let sol = pid.solve(0, ds, h);
            pid.commit(0, &sol, sol.xi, h, 1.0, false);
            xi = sol.xi;
            xi
        })
        .collect()
}

#[test]
fn loop_converges_without_overshoot_for_any_contact_stiffness() {
    for g in [1.0, 0.7, 0.3, 0.1] {
        let xs = closed_loop(g, 1500);
        let target = -1e-3 / g;
        assert!(
            (xs.last().unwrap() - target).abs() < 1e-3 * target.abs(),
            "g {g}"
        );
        for x in &xs {
            assert!(
                *x <= 1e-15 && *x >= target * 1.0001,
                "g {g}: {x} overshoots {target}"
            );
        }
    }
}

#[test]
fn first_loop_sample_matches_hand_computation() {
    // ξ₀ = −A δŝ/(1 + A), A = K_c(1 + h/T_i) = 0.966 667.
    let pid = Pid::new(PidGains::default());
    let a = 0.8 * (1.0 + 0.01 / 0.048);
    let sol = pid.solve(2, 1.0, 0.01);
    assert!((sol.xi + a / (1.0 + a)).abs() < 1e-12);
    assert!((sol.epsilon - (-sol.xi - 1.0)).abs() < 1e-15);
}

#[test]
fn back_calculation_limits_windup() {
    let mut pid = Pid::new(PidGains::default());
    // Correction clamped at 1 mm while the model asks for 5 mm, for 10 s.
    for _ in 0..1000 {
        let sol = pid.solve(0, 5e-3, 0.01);
        let applied = sol.xi.clamp(-1e-3, 1e-3);
        pid.commit(0, &sol, applied, 0.01, 2e-3, false);
    }
    assert!(pid.axes[0].integral.abs() <= 2e-3 + 1e-15);
    // Once the demand drops, the correction leaves the limit promptly.
    let mut steps = 0;
    loop {
        let sol = pid.solve(0, 0.5e-3, 0.01);
        let applied = sol.xi.clamp(-1e-3, 1e-3);
        pid.commit(0, &sol, applied, 0.01, 2e-3, false);
        steps += 1;
        if applied > -0.99e-3 || steps > 100 {
            break;
        }
    }
    assert!(steps < 20, "stuck at the limit for {steps} samples");
}
