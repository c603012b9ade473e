//! The loop through a compliant contact, in numbers: the static loop gain, the force
//! amplification and the closed-loop poles of the discrete law of [`crate::pid`] with a delay
//! (derivation in the documentation of [`crate::runaway`]).

use crate::pid::PidGains;

/// Static loop gain g = ĉ/(c_r + 1/k_c) of the correction through a contact of stiffness
/// `contact_stiffness_n_m` in series with a robot of true compliance `robot_compliance_m_n`,
/// with the model's compliance `model_compliance_m_n` (all along the corrected direction).
pub fn static_loop_gain(
    model_compliance_m_n: f64,
    robot_compliance_m_n: f64,
    contact_stiffness_n_m: f64,
) -> f64 {
    model_compliance_m_n / (robot_compliance_m_n + 1.0 / contact_stiffness_n_m)
}

/// Factor 1/(1 − g) by which the correction multiplies the contact force at equilibrium;
/// infinite for g ≥ 1 (no equilibrium: runaway).
pub fn force_amplification(loop_gain: f64) -> f64 {
    if loop_gain < 1.0 {
        1.0 / (1.0 - loop_gain)
    } else {
        f64::INFINITY
    }
}

/// Coefficients (ascending powers of z) of the characteristic polynomial χ(z) of the module
/// documentation.
fn characteristic_polynomial(g: f64, gains: &PidGains, h: f64, delay: usize) -> Vec<f64> {
    let kc = gains.kc;
    let ai = if gains.ti_s > 0.0 && gains.ti_s.is_finite() {
        kc * h / gains.ti_s
    } else {
        0.0
    };
    let tf = if gains.derivative_filter_n > 0.0 {
        gains.td_s / gains.derivative_filter_n
    } else {
        0.0
    };
    let alpha = h / (tf + h);
    let kd = if gains.td_s > 0.0 {
        kc * gains.td_s * alpha / h
    } else {
        0.0
    };
    let a = kc + ai + kd;
    // Polynomials in z, ascending: (z − 1) = [−1, 1], (z − 1 + α) = [α − 1, 1].
    let mul = |p: &[f64], q: &[f64]| -> Vec<f64> {
        let mut r = vec![0.0; p.len() + q.len() - 1];
        for (i, x) in p.iter().enumerate() {
            for (j, y) in q.iter().enumerate() {
                r[i + j] += x * y;
            }
        }
        r
    };
    let add = |p: &[f64], q: &[f64], s: f64| -> Vec<f64> {
        let mut r = vec![0.0; p.len().max(q.len())];
        for (i, x) in p.iter().enumerate() {
            r[i] += x;
        }
        for (i, y) in q.iter().enumerate() {
            r[i] += s * y;
        }
        r
    };
    let zm1 = [-1.0, 1.0];
    let zma = [alpha - 1.0, 1.0];
    let dq = mul(&zm1, &zma);
    let nq = add(
        &add(
            &zma.map(|c| ai * c),
            &dq.iter().map(|c| a * c).collect::<Vec<_>>(),
            1.0,
        ),
        &zm1.map(|c| kd * alpha * c),
        -1.0,
    );
    let mut zd = vec![0.0; delay + 1];
    zd[delay] = 1.0;
    add(&mul(&zd, &add(&dq, &nq, 1.0)), &nq, -g)
}

/// Largest modulus of the closed-loop poles of the discrete law of [`crate::pid`] (gains
/// `gains`, period `h`) against a contact of static loop gain `g` answering after `delay`
/// periods: the loop is stable when it is below 1.
pub fn closed_loop_spectral_radius(g: f64, gains: &PidGains, h: f64, delay: usize) -> f64 {
    let mut p = characteristic_polynomial(g, gains, h, delay);
    while p.len() > 1 && p.last().is_some_and(|c| c.abs() < 1e-300) {
        p.pop();
    }
    let n = p.len() - 1;
    if n == 0 {
        return 0.0;
    }
    let lead = p[n];
    let companion = nalgebra::DMatrix::from_fn(n, n, |r, c| {
        if r == 0 {
            -p[n - 1 - c] / lead
        } else if r == c + 1 {
            1.0
        } else {
            0.0
        }
    });
    companion
        .complex_eigenvalues()
        .iter()
        .map(|z| z.norm())
        .fold(0.0, f64::max)
}

/// The static loop gain at which the closed loop of [`closed_loop_spectral_radius`] first
/// becomes unstable (bisection on g in [0, 4]; 4 if it never does there).
pub fn critical_gain(gains: &PidGains, h: f64, delay: usize) -> f64 {
    let stable = |g: f64| closed_loop_spectral_radius(g, gains, h, delay) < 1.0 - 1e-12;
    if stable(4.0) {
        return 4.0;
    }
    let (mut lo, mut hi) = (0.0, 4.0);
    // The first crossing: scan coarsely, then bisect.
    let mut g = 0.0;
    while g < 4.0 {
        if !stable(g + 0.01) {
            hi = g + 0.01;
            lo = g;
            break;
        }
        g += 0.01;
    }
    for _ in 0..60 {
        let mid = 0.5 * (lo + hi);
        if stable(mid) {
            lo = mid;
        } else {
            hi = mid;
        }
    }
    0.5 * (lo + hi)
}
