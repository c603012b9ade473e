//! Structure search: the paper's coupled test-model loop (Fig. 6, Tables A1/A2) automated.
//!
//! Start from one z-eDoF per joint. At each step try every candidate refinement — an x or y
//! eDoF on any joint (alone, or together with a free centre shift of that joint, the paper's
//! "k_θ3,x with δr3" step), a base tilt eDoF, freeing a centre shift, or removing an eDoF — fit
//! each (NNLS + variable projection on the precomputed Gram matrix, so a candidate costs
//! O(p³) regardless of the number of rows), and keep the one that lowers the criterion most:
//!
//! * [`Criterion::Bic`] (default): `n ln(χ²/n) + p ln n`; an addition must lower it by at least
//!   [`SearchOptions::min_bic_gain`] ("significantly");
//! * [`Criterion::CrossValidated`]: the held-out χ² of k-fold cross-validation by load case
//!   ([`crate::stiffness::crossval`]); an addition must lower it by a given fraction.
//!
//! A removal is kept when it lowers the criterion by any amount. Stop when the target RMS is met
//! or nothing qualifies. Whatever the criterion, every row of the iteration table carries the
//! cross-validated RMS (when the data has at least two load cases), the out-of-sample number an
//! engineer should trust over the in-sample RMS.

use crate::measurements::MeasurementRow;
use crate::stiffness::crossval::{CrossValidation, CvScore, DEFAULT_FOLDS};
use crate::stiffness::design::{Design, EdofId, all_edofs, edof_label};
use crate::stiffness::shift::{self, Inner, normal_system, scales};
use crate::stiffness::stiffness_fit::{
    Calibration, ResidualStats, Structure, bic, fit_in_design, residual_stats,
};
use crate::stiffness::{CalibError, StructureError};
use deflex_model::{Axis, Data, EdofSite, Robot};
use deflex_telemetry::{OnProgress, Progress};
use nalgebra::DMatrix;

/// How [`search_structure`] ranks structures.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Criterion {
    /// Bayesian information criterion; an addition must lower it by
    /// [`SearchOptions::min_bic_gain`].
    Bic,
    /// Held-out χ² of `folds`-fold cross-validation by load case; an addition must lower it by
    /// the fraction `min_relative_gain` (e.g. 0.02).
    CrossValidated {
        /// Number of folds (at most the number of load cases is used).
        folds: usize,
        /// Smallest relative decrease for an addition to count.
        min_relative_gain: f64,
    },
}

impl Criterion {
    /// Cross-validation with [`DEFAULT_FOLDS`] folds and a 2 % minimum gain.
    pub fn cross_validated() -> Self {
        Criterion::CrossValidated {
            folds: DEFAULT_FOLDS,
            min_relative_gain: 0.02,
        }
    }
}

/// Settings of [`search_structure`].
#[derive(Clone, Debug)]
pub struct SearchOptions {
    /// How structures are ranked.
    pub criterion: Criterion,
    /// Folds of the cross-validated RMS column when the criterion is BIC (0: no column).
    pub report_folds: usize,
    /// Stop as soon as the RMS residual (all components) is at most this (m).
    pub target_rms_m: Option<f64>,
    /// Smallest BIC decrease for an addition to count as significant.
    pub min_bic_gain: f64,
    /// Largest number of accepted changes.
    pub max_steps: usize,
    /// Consider base tilt eDoFs.
    pub allow_base: bool,
    /// Consider removing eDoFs that the data does not need.
    pub allow_removal: bool,
    /// Start structure (default: one z-eDoF per joint).
    pub start: Option<Structure>,
}

impl Default for SearchOptions {
    fn default() -> Self {
        SearchOptions {
            criterion: Criterion::Bic,
            report_folds: DEFAULT_FOLDS,
            target_rms_m: None,
            min_bic_gain: 10.0,
            max_steps: 40,
            allow_base: true,
            allow_removal: true,
            start: None,
        }
    }
}

/// One row of the iteration table.
#[derive(Clone, Debug)]
pub struct SearchStep {
    /// 0 for the start.
    pub iteration: usize,
    /// What changed (`+ J3.x, δr3 free`).
    pub change: String,
    /// Structure label after the change.
    pub structure: String,
    /// Number of parameters.
    pub parameters: usize,
    /// Residuals after the change.
    pub residuals: ResidualStats,
    /// BIC after the change.
    pub bic: f64,
    /// BIC change (negative = better).
    pub delta_bic: f64,
    /// Cross-validated RMS over every held-out position component (m), when the data has at
    /// least two load cases.
    pub cv_rms_m: Option<f64>,
    /// Candidates evaluated at this step.
    pub candidates_tried: usize,
}

/// Outcome of the search.
#[derive(Clone, Debug)]
pub struct SearchResult {
    /// The iteration table.
    pub steps: Vec<SearchStep>,
    /// Full calibration of the final structure.
    pub calibration: Calibration,
    /// Why the search stopped.
    pub stop_reason: String,
}

#[derive(Clone)]
enum Change {
    Add(EdofId),
    AddWithShift(EdofId),
    FreeShift(usize),
    Remove(EdofId),
}

impl Change {
    fn describe(&self) -> String {
        match self {
            Change::Add(id) => format!("+ {}", edof_label(*id)),
            Change::AddWithShift(id) => {
                format!("+ {}, free δr{}", edof_label(*id), id.0.link_index())
            }
            Change::FreeShift(j) => format!("free δr{j}"),
            Change::Remove(id) => format!("− {}", edof_label(*id)),
        }
    }
    fn is_addition(&self) -> bool {
        !matches!(self, Change::Remove(_))
    }
}

/// Run the structure search on measurement rows. `progress` hears of every step (a
/// [`Progress::Stage`] named `step N`, its number of steps not known in advance) and, after every
/// candidate, of the candidates done at this step ([`Progress::Work`]).
pub fn search_structure(
    robot: &Robot,
    rows: &[MeasurementRow],
    options: &SearchOptions,
    progress: OnProgress<'_>,
) -> Result<SearchResult, CalibError> {
    let n_joints = robot.joint_count();
    let candidates: Vec<EdofId> = all_edofs(n_joints)
        .into_iter()
        .filter(|c| options.allow_base || c.0 != EdofSite::Base)
        .collect();
    let design = Design::build(robot, rows, &candidates, true)?;
    let scale = robot_scale(robot);
    let n = design.equations();

    let requested = options
        .start
        .clone()
        .unwrap_or_else(|| Structure::one_z_per_joint(n_joints));
    let start_cal = fit_in_design(&design, &requested)?;
    let mut current = start_cal.structure.clone();
    let mut dropped_note = String::new();
    let dropped: Vec<String> = requested
        .edofs
        .iter()
        .filter(|e| !current.edofs.contains(e))
        .map(|e| edof_label(*e))
        .collect();
    if !dropped.is_empty() {
        dropped_note = format!(" ({} not identifiable, dropped)", dropped.join(", "));
    }
    let cv = match options.criterion {
        Criterion::CrossValidated { folds, .. } => {
            Some(CrossValidation::new(robot, rows, &candidates, folds)?)
        }
        Criterion::Bic if options.report_folds >= 2 => {
            CrossValidation::new(robot, rows, &candidates, options.report_folds).ok()
        }
        Criterion::Bic => None,
    };
    let cv_score = |st: &Structure| cv.as_ref().and_then(|cv| cv.score(st));
    let mut current_bic = bic(start_cal.chi2, n, current.parameter_count());
    let start_cv = cv_score(&current);
    // The criterion's value of the current structure (BIC, or held-out χ²).
    let criterion_of = |b: f64, score: Option<CvScore>| match options.criterion {
        Criterion::Bic => Some(b),
        Criterion::CrossValidated { .. } => score.map(|s| s.chi2),
    };
    let Some(mut current_value) = criterion_of(current_bic, start_cv) else {
        return Err(StructureError::UnscoredStart.into());
    };
    let mut steps = vec![SearchStep {
        iteration: 0,
        change: format!(
            "start: {}{dropped_note}",
            if options.start.is_some() {
                "given structure"
            } else {
                "one z-eDoF per joint"
            }
        ),
        structure: current.label(),
        parameters: current.parameter_count(),
        residuals: start_cal.residuals,
        bic: current_bic,
        delta_bic: 0.0,
        cv_rms_m: start_cv.map(|s| s.rms_all_m),
        candidates_tried: 1,
    }];
    let mut stop_reason = String::from("maximum number of steps reached");
    let target_met = |r: &ResidualStats| options.target_rms_m.is_some_and(|t| r.rms_all_m <= t);
    if target_met(&start_cal.residuals) {
        stop_reason = "target RMS met by the start structure".into();
    } else {
        for iteration in 1..=options.max_steps {
            let changes = candidate_changes(&current, &candidates, options);
            let total = changes.len();
            progress(Progress::Stage {
                index: iteration,
                count: None,
                name: &format!("step {iteration}"),
            });
            let mut best: Option<(f64, f64, Option<CvScore>, Change, Structure, Inner)> = None;
            for (done, change) in changes.into_iter().enumerate() {
                let outcome = evaluate(&design, &current, &change, scale);
                progress(Progress::Work {
                    done: done + 1,
                    total,
                });
                let Some((structure, sol)) = outcome else {
                    continue;
                };
                let b = bic(sol.chi2, n, structure.parameter_count());
                let score = match options.criterion {
                    Criterion::Bic => None,
                    Criterion::CrossValidated { .. } => cv_score(&structure),
                };
                let Some(value) = criterion_of(b, score) else {
                    continue;
                };
                let needed = match (options.criterion, change.is_addition()) {
                    (Criterion::Bic, true) => current_value - options.min_bic_gain,
                    (
                        Criterion::CrossValidated {
                            min_relative_gain, ..
                        },
                        true,
                    ) => current_value * (1.0 - min_relative_gain),
                    (_, false) => current_value - 1e-9 * current_value.abs().max(1.0),
                };
                if value < needed && best.as_ref().is_none_or(|(v, ..)| value < *v) {
                    best = Some((value, b, score, change, structure, sol));
                }
            }
            let Some((value, b, score, change, structure, sol)) = best else {
                stop_reason = match options.criterion {
                    Criterion::Bic => format!(
                        "no candidate lowers the BIC by {} or more",
                        options.min_bic_gain
                    ),
                    Criterion::CrossValidated {
                        min_relative_gain, ..
                    } => format!(
                        "no candidate lowers the cross-validated χ² by {:.0} % or more",
                        100.0 * min_relative_gain
                    ),
                };
                break;
            };
            let residuals = quick_residuals(&design, &structure, &sol);
            let score = score.or_else(|| cv_score(&structure));
            steps.push(SearchStep {
                iteration,
                change: change.describe(),
                structure: structure.label(),
                parameters: structure.parameter_count(),
                residuals,
                bic: b,
                delta_bic: b - current_bic,
                cv_rms_m: score.map(|s| s.rms_all_m),
                candidates_tried: total,
            });
            current = structure;
            current_bic = b;
            current_value = value;
            if target_met(&residuals) {
                stop_reason = "target RMS met".into();
                break;
            }
        }
    }
    let calibration = fit_in_design(&design, &current)?;
    Ok(SearchResult {
        steps,
        calibration,
        stop_reason,
    })
}

fn candidate_changes(
    current: &Structure,
    candidates: &[EdofId],
    options: &SearchOptions,
) -> Vec<Change> {
    let mut changes = Vec::new();
    for &id in candidates {
        if current.edofs.contains(&id) {
            continue;
        }
        changes.push(Change::Add(id));
        if let (EdofSite::Joint(j), Axis::X | Axis::Y) = id
            && !current.free_shift[j - 1]
        {
            changes.push(Change::AddWithShift(id));
        }
    }
    for &(site, axis) in &current.edofs {
        if let (EdofSite::Joint(j), Axis::X | Axis::Y) = (site, axis)
            && !current.free_shift[j - 1]
        {
            changes.push(Change::FreeShift(j));
        }
    }
    changes
        .dedup_by(|a, b| matches!((a, b), (Change::FreeShift(x), Change::FreeShift(y)) if x == y));
    if options.allow_removal && current.edofs.len() > 1 {
        for &id in &current.edofs {
            changes.push(Change::Remove(id));
        }
    }
    changes
}

/// Fit a changed structure; `None` when it is not valid (an eDoF unobservable, collinear or at
/// the c ≥ 0 bound).
fn evaluate(
    design: &Design,
    current: &Structure,
    change: &Change,
    scale: f64,
) -> Option<(Structure, Inner)> {
    let mut st = current.clone();
    let mut new_shift = None;
    match *change {
        Change::Add(id) => st.edofs.push(id),
        Change::AddWithShift(id) => {
            st.edofs.push(id);
            let j = id.0.link_index();
            st.free_shift[j - 1] = true;
            new_shift = Some(j);
        }
        Change::FreeShift(j) => {
            st.free_shift[j - 1] = true;
            new_shift = Some(j);
        }
        Change::Remove(id) => {
            st.edofs.retain(|e| *e != id);
            if let (EdofSite::Joint(j), Axis::X | Axis::Y) = id
                && !st
                    .edofs
                    .iter()
                    .any(|e| e.0 == EdofSite::Joint(j) && e.1 != Axis::Z)
            {
                // Without an x/y eDoF the centre shift has no effect (z × z = 0): drop it so
                // the written model carries no meaningless value.
                st.free_shift[j - 1] = false;
                st.shifts_m[j - 1] = 0.0;
            }
        }
    }
    st.normalize();
    let idx: Vec<usize> = st
        .edofs
        .iter()
        .map(|id| design.index_of(*id))
        .collect::<Option<_>>()?;
    // Reject unobservable or collinear structures before fitting.
    let cols = shift::columns(design, &idx, &st.shifts_m);
    let (g, _) = normal_system(design, &cols);
    let d = scales(&g);
    if d.contains(&0.0) {
        return None;
    }
    let p = idx.len();
    let gs = DMatrix::from_fn(p, p, |i, j| g[(i, j)] * d[i] * d[j]);
    if p == 0 || !crate::stiffness::all_finite(&gs) {
        return None;
    }
    let lmin = gs
        .symmetric_eigenvalues()
        .iter()
        .copied()
        .fold(f64::INFINITY, f64::min);
    if lmin < 1e-10 {
        return None;
    }
    let free = st.free_shift_joints();
    let mut shifts = st.shifts_m.clone();
    let sol = match new_shift {
        Some(j) => shift::optimize_multistart(design, &idx, &mut shifts, &free, j, scale),
        None => shift::optimize(design, &idx, &mut shifts, &free),
    };
    if sol.c.iter().any(|&c| c <= 0.0) {
        return None;
    }
    st.shifts_m = shifts;
    Some((st, sol))
}

fn quick_residuals(design: &Design, st: &Structure, sol: &Inner) -> ResidualStats {
    let (idx, c): (Vec<usize>, Vec<f64>) = st
        .edofs
        .iter()
        .zip(&sol.c)
        .filter_map(|(id, &c)| design.index_of(*id).map(|ci| (ci, c)))
        .unzip();
    let beta = shift::basis_coefficients(design, &idx, &c, &st.shifts_m);
    residual_stats(design, &design.predict(&beta))
}

/// Half the largest distance of a joint origin from the base at q = 0 (≥ 0.25 m): the spread
/// of starting values for a newly freed centre shift.
fn robot_scale(robot: &Robot) -> f64 {
    let mut data = Data::new();
    let q = vec![0.0; robot.joint_count()];
    if robot.forward_kinematics(&mut data, &q).is_err() {
        return 0.5;
    }
    let o = data.base_frame.translation.vector;
    let mut max: f64 = 0.0;
    for i in 1..=robot.joint_count() {
        max = max.max((data.link_frame(i).translation.vector - o).norm());
    }
    max = max.max((data.tcp_position() - o).norm());
    (0.5 * max).max(0.25)
}
