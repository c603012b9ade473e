//! The loop-gain analysis of the runaway guard ([`deflex_control::runaway::analysis`]).

use deflex_control::pid::{Pid, PidGains};
use deflex_control::runaway::{
    closed_loop_spectral_radius, critical_gain, force_amplification, static_loop_gain,
};

/// The scalar discrete loop simulated with the real [`Pid`] (solve + commit): δŝ_k =
/// s₀ − g ξ_{k−d}. Returns the largest |ξ| over the last quarter relative to the first
/// quarter's, i.e. growth > 1 means divergence.
fn simulate(g: f64, delay: usize, steps: usize) -> f64 {
    let gains = PidGains::default();
    let mut pid = Pid::new(gains);
    let h = 0.01;
    let mut history = vec![0.0; delay + 1];
    let mut xs = Vec::with_capacity(steps);
    for k in 0..steps {
        let delayed = history[(k + history.len() - delay) % history.len()];
        let ds = 1e-4 - g * delayed;
        let sol = pid.solve(0, ds, h);
        pid.commit(0, &sol, sol.xi, h, 1e9, false);
        let slot = k % history.len();
        history[slot] = sol.xi;
        xs.push(sol.xi);
    }
    // Distance from the equilibrium −s₀/(1−g) (or growth when there is none).
    let eq = if g < 1.0 { -1e-4 / (1.0 - g) } else { 0.0 };
    let dev = |s: &[f64]| s.iter().map(|x| (x - eq).abs()).fold(0.0, f64::max);
    dev(&xs[3 * steps / 4..]) / dev(&xs[steps / 4..steps / 2]).max(1e-300)
}

#[test]
fn characteristic_polynomial_predicts_the_simulated_loop() {
    let gains = PidGains::default();
    for delay in [1usize, 2, 3] {
        let g_star = critical_gain(&gains, 0.01, delay);
        eprintln!("paper gains, h = 10 ms, delay {delay}: critical loop gain {g_star:.4}");
        assert!((g_star - 1.0).abs() < 1e-3, "delay {delay}: {g_star}");
        for (g, stable) in [(0.9 * g_star, true), (1.05 * g_star, false)] {
            let rho = closed_loop_spectral_radius(g, &gains, 0.01, delay);
            assert_eq!(rho < 1.0, stable, "delay {delay} g {g}: radius {rho}");
            let growth = simulate(g, delay, 4000);
            assert_eq!(growth < 1.0, stable, "delay {delay} g {g}: growth {growth}");
        }
    }
    // Hotter gains and longer delays: still g* = 1 (|T| ≤ 1 on the unit circle).
    for (kc, ti_s, td_s) in [(8.0, 0.048, 0.012), (0.8, 0.002, 0.0), (3.0, 0.01, 0.05)] {
        let hot = PidGains {
            kc,
            ti_s,
            td_s,
            ..PidGains::default()
        };
        for delay in [1usize, 5] {
            let g_star = critical_gain(&hot, 0.01, delay);
            assert!(
                (g_star - 1.0).abs() < 1e-3,
                "{kc} {ti_s} {td_s} d {delay}: {g_star}"
            );
        }
    }
}

#[test]
fn static_gain_and_amplification() {
    // Exact model against a contact taking 20 % of the deflection: g = 0.8, force × 5.
    let c_r = 3e-6;
    let g = static_loop_gain(c_r, c_r, 1.0 / (0.25 * c_r));
    assert!((g - 0.8).abs() < 1e-12);
    assert!((force_amplification(g) - 5.0).abs() < 1e-9);
    // A model 1.3× too soft against a rigid fixture: no equilibrium.
    assert!(force_amplification(static_loop_gain(1.3 * c_r, c_r, 1e12)).is_infinite());
}
