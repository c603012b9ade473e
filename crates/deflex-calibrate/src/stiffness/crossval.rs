//! K-fold cross-validation by load case: the out-of-sample prediction error of a model
//! structure, for the structure search (the "cross-validated RMS" alternative to BIC) and for
//! the honest column of its iteration table.
//!
//! The load cases are dealt round-robin, in the order they first appear in the data, into `k`
//! folds (rows of one load case never straddle folds: a load case shares its pose and wrench,
//! so splitting it would leak). For each fold the structure's compliances (NNLS, c ≥ 0) and
//! its free centre shifts (variable projection, started from the given shifts) are fitted on
//! the other folds, and the held-out fold is predicted with the same linear model as the fit
//! (eq. 13–15 through [`crate::stiffness::design`]).

use crate::measurements::MeasurementRow;
use crate::stiffness::design::{Design, EdofId};
use crate::stiffness::shift;
use crate::stiffness::stiffness_fit::Structure;
use crate::stiffness::uncertainty::residual_stats;
use crate::stiffness::{CalibError, RowsError, StructureError};
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
