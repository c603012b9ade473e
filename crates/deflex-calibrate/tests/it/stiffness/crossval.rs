//! K-fold cross-validation by load case: the fold score against an independent refit and
//! prediction, a missing eDoF seen out of sample, and folds that never split a load case.

use deflex_calibrate::measurements::MeasurementRow;
use deflex_calibrate::stiffness::crossval::{CrossValidation, fold_assignment};
use deflex_calibrate::stiffness::design::all_edofs;
use deflex_calibrate::stiffness::stiffness_fit::{Structure, calibrate_fixed};
use deflex_calibrate::stiffness::synthetic::{SyntheticOptions, measure, random_campaign};
use deflex_calibrate::stiffness::validation::predict_full;

/// The fold score equals an independent computation: calibrate on the training rows with
/// the public fixed-structure calibration, write the robot, and predict every held-out row
/// with `validate::predict_full` (the model crate's point displacement).
#[test]
fn score_matches_an_independent_refit_and_prediction() {
    let truth = deflex_model::builtin("tx200").unwrap();
    let plan = random_campaign(&truth, 12, (600.0, 1400.0), 5);
    let rows = measure(&truth, &plan, &SyntheticOptions::default()).unwrap();
    let structure = Structure::from_robot(&truth);
    let cv = CrossValidation::new(&truth, &rows, &all_edofs(6), 4).unwrap();
    assert_eq!(cv.fold_count(), 4);
    let score = cv.score(&structure).unwrap();

    let (assignment, k) = fold_assignment(&rows, 4);
    let (mut sum_sq, mut n) = (0.0, 0usize);
    for f in 0..k {
        let pick = |want: bool| -> Vec<MeasurementRow> {
            rows.iter()
                .zip(&assignment)
                .filter(|(_, a)| (**a == f) == want)
                .map(|(r, _)| r.clone())
                .collect()
        };
        let cal = calibrate_fixed(&truth, &pick(false), &structure).unwrap();
        let held_out = pick(true);
        let predicted = predict_full(&cal.to_robot(&truth), &held_out).unwrap();
        for (r, d) in held_out.iter().zip(&predicted) {
            let measured = r.displacement_m.unwrap();
            for ax in 0..3 {
                sum_sq += (measured[ax] - d[ax]).powi(2);
                n += 1;
            }
        }
    }
    let independent = (sum_sq / n as f64).sqrt();
    eprintln!(
        "cv rms {:.3} µm, independent {:.3} µm",
        score.rms_all_m * 1e6,
        independent * 1e6
    );
    assert!(
        (score.rms_all_m - independent).abs() < 1e-3 * independent,
        "{} vs {independent}",
        score.rms_all_m
    );
    // The truth's structure predicts held-out data at the noise level (15 µm).
    assert!(
        score.rms_all_m > 10e-6 && score.rms_all_m < 20e-6,
        "{}",
        score.rms_all_m
    );
}

/// A structure missing the x-eDoF of joint 3 predicts held-out data worse than the truth's.
#[test]
fn a_missing_edof_shows_out_of_sample() {
    let truth = deflex_model::builtin("tx200").unwrap();
    let plan = random_campaign(&truth, 16, (600.0, 1400.0), 9);
    let rows = measure(&truth, &plan, &SyntheticOptions::default()).unwrap();
    let cv = CrossValidation::new(&truth, &rows, &all_edofs(6), 5).unwrap();
    let full = Structure::from_robot(&truth);
    let one = Structure::one_z_per_joint(6);
    let (a, b) = (cv.score(&full).unwrap(), cv.score(&one).unwrap());
    assert!(b.rms_all_m > 2.0 * a.rms_all_m, "{b:?} vs {a:?}");
}

#[test]
fn folds_never_split_a_load_case_and_need_two_cases() {
    let truth = deflex_model::builtin("tx200").unwrap();
    let plan = random_campaign(&truth, 7, (600.0, 1400.0), 2);
    let rows = measure(&truth, &plan, &SyntheticOptions::default()).unwrap();
    let (assignment, k) = fold_assignment(&rows, 10);
    assert_eq!(k, 7);
    for (r, a) in rows.iter().zip(&assignment) {
        for (s, b) in rows.iter().zip(&assignment) {
            if r.load_case == s.load_case {
                assert_eq!(a, b);
            }
        }
    }
    let one_case: Vec<_> = rows
        .iter()
        .filter(|r| r.load_case == rows[0].load_case)
        .cloned()
        .collect();
    let e = CrossValidation::new(&truth, &one_case, &all_edofs(6), 5).unwrap_err();
    assert!(e.to_string().contains("2 load cases"), "{e}");
}
