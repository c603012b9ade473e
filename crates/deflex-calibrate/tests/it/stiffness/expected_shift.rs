//! The planner's expected standard error of a centre shift (`deflex plan`) against Monte Carlo:
//! measure the planned campaign many times with tracker noise, calibrate each with the shift
//! free, and compare the spread of the fitted shifts with the prediction.

use deflex_calibrate::stiffness::plan::{PlanOptions, plan_experiments};
use deflex_calibrate::stiffness::stiffness_fit::{Structure, calibrate_fixed};
use deflex_calibrate::stiffness::synthetic::{SyntheticOptions, measure};

#[test]
fn expected_shift_se_matches_monte_carlo_spread() {
    let truth = deflex_model::builtin("tx200").unwrap();
    let sigma = 15e-6;
    let plan = plan_experiments(
        &truth,
        &PlanOptions {
            load_cases: 12,
            noise_sigma_m: sigma,
            ..PlanOptions::default()
        },
    )
    .unwrap();
    assert_eq!(plan.expected_shifts.len(), 1, "{:?}", plan.expected_shifts);
    let expected = &plan.expected_shifts[0];
    assert_eq!(expected.joint, 3);
    assert!((expected.nominal_m - 0.4).abs() < 1e-12);
    assert!(expected.se_m.is_finite() && expected.se_m > 0.0);

    let structure = Structure::from_robot(&truth).with_free_shifts();
    let runs = 40;
    let fitted: Vec<f64> = (0..runs)
        .map(|seed| {
            let rows = measure(
                &truth,
                &plan.rows,
                &SyntheticOptions {
                    noise_sigma_m: sigma,
                    seed: 1000 + seed,
                    ..Default::default()
                },
            )
            .unwrap();
            let cal = calibrate_fixed(&truth, &rows, &structure).unwrap();
            cal.shifts.iter().find(|s| s.joint == 3).unwrap().value_m
        })
        .collect();
    let mean = fitted.iter().sum::<f64>() / runs as f64;
    let spread =
        (fitted.iter().map(|v| (v - mean).powi(2)).sum::<f64>() / (runs - 1) as f64).sqrt();
    eprintln!(
        "δr3: expected SE {:.3} mm, Monte Carlo spread {:.3} mm over {runs} campaigns (mean {:.2} mm)",
        expected.se_m * 1e3,
        spread * 1e3,
        mean * 1e3
    );
    // A sample standard deviation of 40 draws is within ±35 % of the truth with > 99 % odds.
    let ratio = spread / expected.se_m;
    assert!((0.65..1.35).contains(&ratio), "spread / expected = {ratio}");
    // Unbiased to well within one expected SE of the mean.
    assert!((mean - 0.4).abs() < 3.0 * expected.se_m / (runs as f64).sqrt() + 1e-4);
}
