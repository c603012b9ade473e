//! Off-diagonal joint compliances fitted with the eDoF compliances (`fit_couplings`): recovery
//! from noise-free data, and standard errors that match the scatter over noisy campaigns.

use deflex_calibrate::stiffness::synthetic::{
    Coupling, SyntheticOptions, measure, random_campaign,
};
use deflex_calibrate::stiffness::validation::predict_full;
use deflex_calibrate::stiffness::{EdofId, fit_couplings};
use deflex_model::{Axis, EdofSite, Robot, builtin};
use nalgebra::Vector3;

/// The TX200 and its J2.z and J3.z eDoFs.
fn tx200_j2_j3() -> (Robot, EdofId, EdofId) {
    let truth = builtin("tx200").unwrap();
    (
        truth,
        (EdofSite::Joint(2), Axis::Z),
        (EdofSite::Joint(3), Axis::Z),
    )
}

/// The default synthetic measurement with a coupling of compliance `c` (rad/N·m) between the
/// eDoFs `a` and `b`.
fn coupled(a: EdofId, b: EdofId, c: f64) -> SyntheticOptions {
    SyntheticOptions {
        coupling: vec![Coupling {
            a,
            b,
            compliance: c,
        }],
        ..SyntheticOptions::default()
    }
}

/// Noise-free measurements of a robot with a J2.z–J3.z coupling (made by the synthetic
/// module's own coupling code): the fit recovers the coupling and every stiffness from a
/// start 50 % off, and the fitted model's deflection (deflex-model's coupling code)
/// reproduces the measurements.
#[test]
fn a_coupling_and_the_stiffnesses_are_recovered() {
    let (truth, j2, j3) = tx200_j2_j3();
    let (k2, k3) = (
        truth.stiffness(j2.0, j2.1).unwrap(),
        truth.stiffness(j3.0, j3.1).unwrap(),
    );
    let c23 = 0.3 / (k2 * k3).sqrt();
    let plan = random_campaign(&truth, 40, (200.0, 1500.0), 3);
    let rows = measure(
        &truth,
        &plan,
        &SyntheticOptions {
            noise_sigma_m: 0.0,
            record_sigma: false,
            ..coupled(j2, j3, c23)
        },
    )
    .unwrap();
    let mut start = truth.clone();
    for e in truth.edofs() {
        start.set_stiffness(e.site, e.axis, Some(e.stiffness * 1.5));
    }
    let fit = fit_couplings(&start, &rows, &[(j2, j3)]).unwrap();
    let found = fit.robot.couplings[0].compliance;
    assert!((found / c23 - 1.0).abs() < 1e-6, "{found:e} vs {c23:e}");
    assert!((fit.correlations[0] - 0.3).abs() < 1e-6);
    for e in truth.edofs() {
        let k = fit.robot.stiffness(e.site, e.axis).unwrap();
        assert!((k / e.stiffness - 1.0).abs() < 1e-6, "{}: {k}", e.label());
    }
    assert!(fit.rms_m < 1e-12 && fit.rms_before_m > 1e-5, "{fit:?}");
    let checked = &rows[..rows.len().min(50)];
    for (row, d) in checked
        .iter()
        .zip(predict_full(&fit.robot, checked).unwrap())
    {
        let measured = Vector3::from(row.displacement_m.unwrap());
        assert!((Vector3::new(d[0], d[1], d[2]) - measured).norm() < 1e-12);
    }
    // Refused: a pair that is not in the model (named, with the model's eDoFs), and no
    // pair at all.
    let base = (EdofSite::Base, Axis::Z);
    let refused = fit_couplings(&start, &rows, &[(j2, base)])
        .unwrap_err()
        .to_string();
    assert!(
        refused.contains("J2.z–base.z") && refused.contains("its eDoFs: J1.z"),
        "{refused}"
    );
    assert!(fit_couplings(&start, &rows, &[]).is_err());
}

/// The stated standard errors against the scatter they claim (an oracle independent of the
/// covariance algebra): 40 noisy campaigns (15 µm per axis, σ recorded) of a coupled robot
/// and of an uncoupled one. The coupling's standard deviation over the campaigns matches the
/// mean stated SE within 35 %, about 95 % of the intervals hold the truth, and the uncoupled
/// robot's estimates are consistent with zero.
#[test]
fn the_stated_standard_errors_are_the_scatter() {
    let (truth, j2, j3) = tx200_j2_j3();
    let (k2, k3) = (
        truth.stiffness(j2.0, j2.1).unwrap(),
        truth.stiffness(j3.0, j3.1).unwrap(),
    );
    let plan = random_campaign(&truth, 20, (200.0, 1500.0), 5);
    for rho in [0.2, 0.0] {
        let c23 = rho / (k2 * k3).sqrt();
        let (mut values, mut ses, mut covered) = (Vec::new(), Vec::new(), 0);
        let runs = 40;
        for seed in 0..runs {
            let rows = measure(
                &truth,
                &plan,
                &SyntheticOptions {
                    seed,
                    ..coupled(j2, j3, c23)
                },
            )
            .unwrap();
            let fit = fit_couplings(&truth, &rows, &[(j2, j3)]).unwrap();
            let (lo, hi) = fit.interval95(0);
            covered += usize::from(lo <= c23 && c23 <= hi);
            values.push(fit.robot.couplings[0].compliance);
            ses.push(fit.coupling_se[0]);
            assert!(fit.correlation_se[0] > 0.0 && fit.correlation_se[0] < 0.1);
            assert!(fit.compliance_se.iter().all(|s| s.is_finite() && *s > 0.0));
        }
        let n = runs as f64;
        let mean = values.iter().sum::<f64>() / n;
        let scatter = (values.iter().map(|v| (v - mean).powi(2)).sum::<f64>() / (n - 1.0)).sqrt();
        let stated = ses.iter().sum::<f64>() / n;
        println!(
            "ρ {rho}: c23 {c23:e}, mean {mean:e}, scatter {scatter:e}, stated SE {stated:e}, {covered} of {runs} 95 % intervals hold the truth"
        );
        assert!(
            (scatter / stated - 1.0).abs() < 0.35,
            "ρ {rho}: scatter {scatter:e}, stated SE {stated:e}"
        );
        assert!(
            covered >= 34,
            "ρ {rho}: {covered} of {runs} intervals hold the truth"
        );
        assert!(
            (mean - c23).abs() < 3.0 * stated / n.sqrt(),
            "ρ {rho}: mean {mean:e} vs {c23:e}"
        );
    }
}
