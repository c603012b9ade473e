//! K-fold cross-validation by load case: the out-of-sample prediction error of a model
//! structure, for the structure search (the "cross-validated RMS" alternative to BIC) and for
//! the honest column of its iteration table.
//!
//! The load cases are dealt round-robin, in the order they first appear in the data, into `k`
//! folds (rows of one load case never straddle folds: a load case shares its pose and wrench,
//! so splitting it would leak). For each fold the structure's compliances (NNLS, c ≥ 0) and
//! its free centre shifts (variable projection, started from the given shifts) are fitted on
//! the other folds, and the held-out fold is predicted with the same linear model as the fit
//! (eq. 13–15 through [`crate::design`]).

use crate::data::MeasurementRow;
use crate::design::{Design, EdofId};
use crate::shift;
use crate::stiffness_fit::Structure;
use crate::uncertainty::residual_stats;
use crate::{CalibError, RowsError, StructureError};
use deflex_model::Robot;

/// Default number of folds.
pub const DEFAULT_FOLDS: usize = 5;

/// Training and held-out designs of every fold.
#[derive(Clone, Debug)]
pub struct CrossValidation {
    folds: Vec<(Design, Design)>,
}

/// Out-of-sample prediction error of a structure.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct CvScore {
    /// RMS over every held-out position component (m).
    pub rms_all_m: f64,
    /// Weighted residual sum of squares over every held-out equation (positions and measured
    /// rotations, each divided by its σ): the search's criterion.
    pub chi2: f64,
}

/// Fold (0-based) of every row: load cases in order of first appearance, dealt round-robin
/// into `min(folds, load cases)` folds. Returns the assignment and the number of folds.
pub fn fold_assignment(rows: &[MeasurementRow], folds: usize) -> (Vec<usize>, usize) {
    let mut cases: Vec<&str> = Vec::new();
    for r in rows {
        if !cases.contains(&r.load_case.as_str()) {
            cases.push(&r.load_case);
        }
    }
    let k = folds.min(cases.len()).max(1);
    let assignment = rows
        .iter()
        .map(|r| cases.iter().position(|c| *c == r.load_case).unwrap_or(0) % k)
        .collect();
    (assignment, k)
}

impl CrossValidation {
    /// Folds of `rows` for the candidate eDoFs (the same candidates as the search's design, so a
    /// structure fits in every fold). Needs at least two load cases; a fold whose training part
    /// cannot be used (e.g. no load at all) is an error naming the fold.
    pub fn new(
        robot: &Robot,
        rows: &[MeasurementRow],
        candidates: &[EdofId],
        folds: usize,
    ) -> Result<Self, CalibError> {
        if folds < 2 {
            return Err(StructureError::TooFewFolds { folds }.into());
        }
        let (assignment, k) = fold_assignment(rows, folds);
        if k < 2 {
            return Err(RowsError::TooFewLoadCases.into());
        }
        let mut out = Vec::with_capacity(k);
        for f in 0..k {
            let (test, train): (Vec<_>, Vec<_>) =
                rows.iter().zip(&assignment).partition(|(_, a)| **a == f);
            let train: Vec<MeasurementRow> = train.into_iter().map(|(r, _)| r.clone()).collect();
            let test: Vec<MeasurementRow> = test.into_iter().map(|(r, _)| r.clone()).collect();
            let context = |e: CalibError| CalibError::Fold {
                fold: f + 1,
                folds: k,
                source: Box::new(e),
            };
            let train = Design::build(robot, &train, candidates, true).map_err(context)?;
            let test = Design::build(robot, &test, candidates, true).map_err(context)?;
            out.push((train, test));
        }
        Ok(CrossValidation { folds: out })
    }

    /// Number of folds.
    pub fn fold_count(&self) -> usize {
        self.folds.len()
    }

    /// Fit `structure` on each training part and score it on the held-out part. `None` when an
    /// eDoF of the structure is not among the candidates.
    pub fn score(&self, structure: &Structure) -> Option<CvScore> {
        let (mut sum_sq, mut components, mut chi2) = (0.0, 0usize, 0.0);
        for (train, test) in &self.folds {
            let idx: Vec<usize> = structure
                .edofs
                .iter()
                .map(|id| train.index_of(*id))
                .collect::<Option<_>>()?;
            let free = structure.free_shift_joints();
            let mut shifts = structure.shifts_m.clone();
            let sol = shift::optimize(train, &idx, &mut shifts, &free);
            let beta = shift::basis_coefficients(train, &idx, &sol.c, &shifts);
            let predicted = test.predict(&beta);
            let stats = residual_stats(test, &predicted);
            sum_sq += stats.rms_all_m.powi(2) * (3 * test.rows) as f64;
            components += 3 * test.rows;
            chi2 += (&test.y - &predicted).norm_squared();
        }
        Some(CvScore {
            rms_all_m: (sum_sq / components.max(1) as f64).sqrt(),
            chi2,
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::design::all_edofs;
    use crate::stiffness_fit::calibrate_fixed;
    use crate::synthetic::{SyntheticOptions, measure, random_campaign};
    use crate::validation::predict_full;

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
}
