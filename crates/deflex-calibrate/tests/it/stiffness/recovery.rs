//! Recovery tests (the acceptance): data from a known model with 15 µm tracker noise and
//! 600–1400 N loads; the structure search must find the true structure, the stiffnesses must lie
//! in their reported 95 % intervals, and predictions on a separate validation set must be within
//! 1.5× the noise floor.

use crate::stiffness::common;

use common::{campaign, kr_like, tx200_truth};
use deflex_calibrate::stiffness::design::edof_label;
use deflex_calibrate::stiffness::search::{Criterion, SearchOptions, search_structure};
use deflex_calibrate::stiffness::stiffness_fit::{Status, Structure, calibrate_fixed};
use deflex_calibrate::stiffness::synthetic::{
    Coupling, SyntheticOptions, measure, random_campaign,
};
use deflex_calibrate::stiffness::validation::validate;
use deflex_model::{Axis, EdofSite, Robot};

const SIGMA: f64 = 15e-6;

fn check_recovery(truth: &Robot, seed: u64, criterion: Criterion) {
    let plan = campaign(truth, 30, 40, seed);
    let rows = measure(
        truth,
        &plan,
        &SyntheticOptions {
            noise_sigma_m: SIGMA,
            seed,
            ..Default::default()
        },
    )
    .unwrap();
    let options = SearchOptions {
        criterion,
        ..SearchOptions::default()
    };
    let result = search_structure(truth, &rows, &options, &mut |_| {}).unwrap();
    let cal = &result.calibration;
    let steps: Vec<(&str, f64)> = result
        .steps
        .iter()
        .map(|s| (s.change.as_str(), s.residuals.rms_all_m))
        .collect();
    let stiff: Vec<(&str, Option<f64>)> = cal
        .edofs
        .iter()
        .map(|e| (e.label.as_str(), e.stiffness))
        .collect();
    eprintln!(
        "{}\n{steps:?}\n{stiff:?}\nstop: {}",
        truth.name, result.stop_reason
    );

    // Structure: exactly the true eDoFs.
    let mut want: Vec<String> = truth.edofs().map(|e| e.label()).collect();
    let mut got: Vec<String> = cal.structure.edofs.iter().map(|e| edof_label(*e)).collect();
    want.sort();
    got.sort();
    assert_eq!(got, want, "structure found by the search");

    // Stiffnesses within their 95 % intervals.
    for e in truth.edofs() {
        let est = cal.edof((e.site, e.axis)).unwrap();
        assert!(
            matches!(est.status, Status::Identified),
            "{}: {:?}",
            e.label(),
            est.status
        );
        let (lo, hi) = est.interval95.unwrap();
        assert!(
            lo <= e.stiffness && e.stiffness <= hi,
            "{}: true {:.4e} outside [{lo:.4e}, {hi:.4e}]",
            e.label(),
            e.stiffness
        );
    }
    // Centre shifts of joints with x/y eDoFs, within 3 SE.
    for (i, joint) in truth.joints.iter().enumerate() {
        if joint.stiffness.get(Axis::X).is_some() || joint.stiffness.get(Axis::Y).is_some() {
            let s = cal.shifts.iter().find(|s| s.joint == i + 1).unwrap();
            let se = s.se_m.expect("fitted shift has an SE");
            assert!(
                (s.value_m - joint.center_shift).abs() <= 3.0 * se,
                "δr{}: {} ± {} vs true {}",
                i + 1,
                s.value_m,
                se,
                joint.center_shift
            );
        }
    }
    assert!(cal.reduced_chi2 < 1.3, "χ²/dof {}", cal.reduced_chi2);
    // Held-out load cases are predicted at the noise level by the final structure, and far
    // worse by the one-eDoF start.
    let cv_final = result.steps.last().unwrap().cv_rms_m.unwrap();
    let cv_start = result.steps[0].cv_rms_m.unwrap();
    assert!(cv_final <= 1.5 * SIGMA, "cross-validated RMS {cv_final:e}");
    assert!(cv_start > 2.0 * cv_final, "{cv_start:e} vs {cv_final:e}");

    // Separate validation set.
    let model = cal.to_robot(truth);
    let vplan = random_campaign(truth, 60, (600.0, 1400.0), seed + 77);
    let vrows = measure(
        truth,
        &vplan,
        &SyntheticOptions {
            noise_sigma_m: SIGMA,
            seed: seed + 78,
            ..Default::default()
        },
    )
    .unwrap();
    let v = validate(&model, None, &vrows).unwrap();
    let rms_all = (v.model.stats.norm.rms.powi(2) / 3.0).sqrt();
    eprintln!("validation RMS per component {:.2} µm", rms_all * 1e6);
    assert!(rms_all <= 1.5 * SIGMA, "validation RMS {rms_all:e}");
    for ax in 0..3 {
        assert!(
            v.model.stats.rms[ax] <= 1.5 * SIGMA,
            "axis {ax}: {:e}",
            v.model.stats.rms[ax]
        );
    }
}

#[test]
fn tx200_search_recovers_structure_and_stiffness() {
    check_recovery(&tx200_truth(), 11, Criterion::Bic);
}

#[test]
fn kr_like_search_recovers_structure_and_stiffness() {
    check_recovery(&kr_like(), 23, Criterion::Bic);
}

/// The cross-validated criterion finds the same true structures.
#[test]
fn cross_validated_search_recovers_structure_and_stiffness() {
    check_recovery(&tx200_truth(), 11, Criterion::cross_validated());
    check_recovery(&kr_like(), 23, Criterion::cross_validated());
}

#[test]
fn unrepresentable_truth_gives_honest_residual() {
    let truth = tx200_truth();
    let plan = campaign(&truth, 24, 30, 5);
    let c2: f64 = 1.0 / 1.76e6;
    let c3 = 1.0 / 2.04e6;
    let rows = measure(
        &truth,
        &plan,
        &SyntheticOptions {
            noise_sigma_m: SIGMA,
            seed: 5,
            coupling: vec![Coupling {
                a: (EdofSite::Joint(2), Axis::Z),
                b: (EdofSite::Joint(3), Axis::Z),
                compliance: 0.3 * (c2 * c3).sqrt(),
            }],
            record_sigma: true,
        },
    )
    .unwrap();
    // Fixed true structure: residual clearly above the noise, intervals finite, reduced χ² large.
    let cal = calibrate_fixed(&truth, &rows, &Structure::from_robot(&truth)).unwrap();
    eprintln!("{:?}", cal.residuals);
    assert!(cal.residuals.rms_all_m > 1.2 * SIGMA, "{:?}", cal.residuals);
    assert!(cal.reduced_chi2 > 1.5);
    for e in &cal.edofs {
        if let Some((lo, hi)) = e.interval95 {
            assert!(
                lo.is_finite() && lo > 0.0 && hi > lo,
                "{}: [{lo}, {hi}]",
                e.label
            );
        }
    }
    // The search does not fail either and reports its residual honestly.
    let result = search_structure(&truth, &rows, &SearchOptions::default(), &mut |_| {}).unwrap();
    assert!(result.calibration.residuals.rms_all_m > SIGMA);
    assert!(
        result
            .calibration
            .edofs
            .iter()
            .all(|e| e.stiffness_se.is_none_or(|s| s.is_finite()))
    );
}

#[test]
fn covariance_matches_monte_carlo_scatter() {
    let truth = deflex_model::builtin("tx200-1edof").unwrap();
    let plan = random_campaign(&truth, 25, (600.0, 1400.0), 3);
    let structure = Structure::from_robot(&truth);
    let p = structure.edofs.len();
    let mut samples: Vec<Vec<f64>> = vec![Vec::new(); p];
    let mut reported = vec![0.0; p];
    let runs = 150;
    for run in 0..runs {
        let rows = measure(
            &truth,
            &plan,
            &SyntheticOptions {
                noise_sigma_m: SIGMA,
                seed: 1000 + run,
                ..Default::default()
            },
        )
        .unwrap();
        let cal = calibrate_fixed(&truth, &rows, &structure).unwrap();
        for (k, e) in cal.edofs.iter().enumerate() {
            samples[k].push(e.compliance);
            reported[k] += e.compliance_se / runs as f64;
        }
    }
    for k in 0..p {
        let n = samples[k].len() as f64;
        let mean = samples[k].iter().sum::<f64>() / n;
        let sd = (samples[k].iter().map(|v| (v - mean).powi(2)).sum::<f64>() / (n - 1.0)).sqrt();
        let ratio = reported[k] / sd;
        eprintln!(
            "{}: reported SE / MC sd = {ratio:.3}",
            edof_label(structure.edofs[k])
        );
        assert!((0.75..1.3).contains(&ratio), "eDoF {k}: ratio {ratio}");
    }
}
