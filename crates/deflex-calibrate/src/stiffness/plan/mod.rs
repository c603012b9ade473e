//! Experiment planning: which configurations, loads and points to measure.
//!
//! 1. **Candidates**: random configurations within the joint limits (required; angles rounded
//!    to 0.1° inside the limits and wrapped to their smallest equivalent, so no −259° reaches
//!    the technician), kept only when the arm, the measured points and the loads clear the
//!    floor and the work table ([`crate::stiffness::campaign_cell`]); each loaded by a cable along each allowed
//!    direction or by each dead weight, at the TCP and, with a bracket, at the bracket point.
//! 2. **Axis by axis** (the paper's Fig. 7 and Tables A1/A2, generalised): for every eDoF, the
//!    candidate where that eDoF's share of the predicted displacement (eq. 15, all measured
//!    points) is largest while being clearly visible (≥ 10 σ).
//! 3. **D-optimal completion**: greedily add the candidate that maximises `log det F` of the
//!    Fisher information `F = Σ JᵀJ/σ²` of the relative compliances `c_e / c_e,nominal`, up to
//!    the requested number of load cases.
//!
//! The expected standard error of every stiffness follows from `F⁻¹` (relative SE of k equals
//! relative SE of c to first order); that of every centre shift the calibration fits from the
//! calibration's own covariance `(JᵀWJ)⁻¹` at the nominal model ([`expected_shift_se`]). An
//! eDoF this plan cannot identify (infinite expected SE) gets no axis-by-axis case, so the
//! technician's sheet and the table agree. Each load case measures the TCP, the bracket point
//! `BR` when there is a bracket, the mid-arm points ([`standard_points`], or the user's) and a
//! reflector on the base (`M0`, [`BasePoint`]), like the paper's M1..M3.

mod candidates;
mod options;

use crate::measurements::MeasurementRow;
use crate::stiffness::campaign_cell::require_limits;
pub use crate::stiffness::campaign_cell::{
    BasePoint, Floor, LoadKind, PointSet, TableOption, WorkTable, standard_points,
};
use crate::stiffness::design::{Design, EdofId, edof_label};
use crate::stiffness::uncertainty::unscaled_covariance;
use crate::stiffness::{CalibError, PlanError};
use candidates::{Candidate, candidates};
use deflex_model::{Axis, Data, EdofSite, Robot};
use nalgebra::DMatrix;
pub use options::{
    MAX_BRACKET_M, MAX_CONFIGURATIONS, MAX_DEAD_WEIGHTS, MAX_LOAD_CASES, NOISE_RANGE_M, PlanOptions,
};
use options::{check_options, resolve_setup};

/// Expected precision of one stiffness under a plan.
#[derive(Clone, Debug)]
pub struct ExpectedSe {
    /// The eDoF.
    pub id: EdofId,
    /// Label.
    pub label: String,
    /// Nominal stiffness used (N·m/rad).
    pub nominal_k: f64,
    /// Expected standard error of k (N·m/rad); +∞ when not identifiable.
    pub se_k: f64,
    /// `se_k / nominal_k`.
    pub relative: f64,
}

impl ExpectedSe {
    /// Whether the plan can identify this eDoF (finite expected SE).
    pub fn identifiable(&self) -> bool {
        self.relative.is_finite()
    }
}

/// Expected precision of a centre shift the calibration will fit.
#[derive(Clone, Debug, PartialEq)]
pub struct ExpectedShiftSe {
    /// Joint (1-based).
    pub joint: usize,
    /// Nominal shift (m).
    pub nominal_m: f64,
    /// Expected standard error (m), fitted jointly with the compliances; +∞ when the campaign
    /// cannot see it.
    pub se_m: f64,
}

/// The axis-by-axis choice for one eDoF.
#[derive(Clone, Debug)]
pub struct AxisCase {
    /// The eDoF.
    pub id: EdofId,
    /// Load-case label in the plan.
    pub load_case: String,
    /// That eDoF's share of the summed per-eDoF displacement norms.
    pub share: f64,
    /// Its contribution, in units of the tracker σ.
    pub snr: f64,
}

/// The cell the plan was made for, as resolved from the options and the robot.
#[derive(Clone, Debug, PartialEq)]
pub struct PlanSetup {
    /// Cable tension (N), or the force of the heaviest dead weight.
    pub force_n: f64,
    /// How loads are applied.
    pub load: LoadKind,
    /// Bracket offset in the TCP frame (m), when used.
    pub bracket_m: Option<[f64; 3]>,
    /// Floor height (world z, m), when checked.
    pub floor_z_m: Option<f64>,
    /// The table, when checked.
    pub table: Option<WorkTable>,
    /// The base reflector in R0 (m), when measured.
    pub base_point_r0_m: Option<[f64; 3]>,
    /// Configurations drawn and kept (clear of floor and table).
    pub configurations_drawn: usize,
    /// Configurations kept.
    pub configurations_kept: usize,
}

/// A measurement campaign.
#[derive(Clone, Debug)]
pub struct Plan {
    /// Rows in the plan format (no displacement).
    pub rows: Vec<MeasurementRow>,
    /// Axis-by-axis choices, for the eDoFs the plan can identify.
    pub axis_cases: Vec<AxisCase>,
    /// Expected SE of every planned stiffness.
    pub expected: Vec<ExpectedSe>,
    /// Expected SE of the centre shift of every joint with an x/y eDoF in the model.
    pub expected_shifts: Vec<ExpectedShiftSe>,
    /// `log det` of the final information matrix (relative parameters).
    pub log_det: f64,
    /// The cell as planned for.
    pub setup: PlanSetup,
}

/// Where the base reflector `M0` sat before it became configurable, in R0: 0.3 m forward of
/// and 0.3 m below the origin of R0 (the TX200's base casting). [`default_base_point`](crate::stiffness::campaign_cell::default_base_point) keeps it
/// there when the floor allows.
pub const BASE_POINT_IN_R0_M: [f64; 3] = [0.3, 0.0, -0.3];
/// `log det` of a symmetric positive definite matrix, `None` when it is not (or not finite).
fn log_det(m: &DMatrix<f64>) -> Option<f64> {
    if !crate::stiffness::all_finite(m) {
        return None;
    }
    let ch = m.clone().cholesky()?;
    Some(ch.l().diagonal().iter().map(|v| 2.0 * v.ln()).sum())
}

/// Relative SE of eDoF `e` from the information restricted to `set` (without the ridge).
fn relative_se(info: &DMatrix<f64>, ridge: f64, set: &[usize], e: usize) -> f64 {
    let m = set.len();
    let sub = DMatrix::from_fn(m, m, |i, j| {
        info[(set[i], set[j])] - if i == j { ridge } else { 0.0 }
    });
    let Some(pos) = set.iter().position(|&k| k == e) else {
        return f64::INFINITY;
    };
    let d: Vec<f64> = (0..m).map(|i| sub[(i, i)].max(0.0).sqrt()).collect();
    if d[pos] == 0.0 || !crate::stiffness::all_finite(&sub) {
        return f64::INFINITY;
    }
    let scaled = DMatrix::from_fn(m, m, |i, j| {
        if d[i] > 0.0 && d[j] > 0.0 {
            sub[(i, j)] / (d[i] * d[j])
        } else if i == j {
            1.0
        } else {
            0.0
        }
    });
    let eig_min = scaled
        .clone()
        .symmetric_eigenvalues()
        .iter()
        .copied()
        .fold(f64::INFINITY, f64::min);
    if eig_min < 1e-10 {
        return f64::INFINITY;
    }
    match scaled.cholesky() {
        Some(ch) => ch.inverse()[(pos, pos)].max(0.0).sqrt() / d[pos],
        None => f64::INFINITY,
    }
}

/// Plan a campaign for `robot` (its geometry, eDoFs, stiffnesses and centre shifts are the
/// nominal model).
pub fn plan_experiments(robot: &Robot, options: &PlanOptions) -> Result<Plan, CalibError> {
    check_options(robot, options)?;
    require_limits(robot)?;
    let (obstacles, base_point) = resolve_setup(robot, options)?;
    let (edofs, nominal) = planned_edofs(robot, options.full_family);
    if edofs.is_empty() {
        return Err(PlanError::NoEdof {
            robot: robot.name.clone(),
        }
        .into());
    }
    let shifts: Vec<f64> = robot.joints.iter().map(|j| j.center_shift).collect();
    let (cands, drawn, kept) = candidates(
        robot, options, &obstacles, base_point, &edofs, &nominal, &shifts,
    )?;
    if cands.is_empty() {
        return Err(PlanError::NoClearConfiguration {
            drawn,
            bracket: options.bracket_m.is_some(),
            floor_z_m: obstacles.floor_z_m,
            table: obstacles.table,
        }
        .into());
    }
    let p = edofs.len();
    let picks = axis_picks(&edofs, &cands);
    let (chosen, info) = d_optimal(&picks, &cands, p, options.load_cases);
    let log_det = log_det(&info).unwrap_or(f64::NEG_INFINITY);
    let expected = expected_se(robot, &edofs, &nominal, &info);
    let (axis_cases, rows) = case_rows(picks, chosen, &cands, &expected);
    let expected_shifts = expected_shift_se(robot, &rows, options.noise_sigma_m)?;
    let force_n = match &options.load {
        LoadKind::Cable { .. } => options.max_force_n,
        LoadKind::DeadWeight { masses_kg } => {
            masses_kg.iter().copied().fold(0.0, f64::max) * robot.gravity.norm()
        }
    };
    Ok(Plan {
        rows,
        axis_cases,
        expected,
        expected_shifts,
        log_det,
        setup: PlanSetup {
            force_n,
            load: options.load.clone(),
            bracket_m: options.bracket_m,
            floor_z_m: obstacles.floor_z_m,
            table: obstacles.table,
            base_point_r0_m: base_point,
            configurations_drawn: drawn,
            configurations_kept: kept,
        },
    })
}

/// An axis-by-axis choice: the eDoF, the candidate, its share of the candidate's signal and its
/// signal-to-noise ratio.
type Pick = (EdofId, usize, f64, f64);

/// Ridge added to the information matrix (relative parameters) so that it stays invertible.
const RIDGE: f64 = 1e-9;

/// Axis by axis: for every eDoF the candidate where its share is largest while ≥ 10 σ (or the
/// loudest one, when ≥ 3 σ).
fn axis_picks(edofs: &[EdofId], cands: &[Candidate]) -> Vec<Pick> {
    let mut picks: Vec<(EdofId, usize, f64, f64)> = Vec::new();
    for (e, &id) in edofs.iter().enumerate() {
        let mut best: Option<(f64, f64, usize)> = None;
        let mut loudest: Option<(f64, usize)> = None;
        for (c, cand) in cands.iter().enumerate() {
            let total: f64 = cand.norms.iter().sum();
            if total <= 0.0 {
                continue;
            }
            let share = cand.norms[e] / total;
            if cand.norms[e] >= 10.0 && best.is_none_or(|(s, ..)| share > s) {
                best = Some((share, cand.norms[e], c));
            }
            if loudest.is_none_or(|(s, _)| cand.norms[e] > s) {
                loudest = Some((cand.norms[e], c));
            }
        }
        let pick = best.or_else(|| {
            loudest.filter(|l| l.0 >= 3.0).map(|(snr, c)| {
                let total: f64 = cands[c].norms.iter().sum();
                (snr / total, snr, c)
            })
        });
        if let Some((share, snr, c)) = pick {
            picks.push((id, c, share, snr));
        }
    }
    picks
}

/// The axis-by-axis candidates, completed greedily to `load_cases` by D-optimality (the largest
/// `log det` of the information); returns the candidates in selection order and their
/// information (with [`RIDGE`]).
fn d_optimal(
    picks: &[Pick],
    cands: &[Candidate],
    p: usize,
    load_cases: usize,
) -> (Vec<usize>, DMatrix<f64>) {
    let mut chosen: Vec<usize> = Vec::new();
    for &(_, c, ..) in picks {
        if !chosen.contains(&c) {
            chosen.push(c);
        }
    }
    let axis_count = chosen.len();
    let mut info = DMatrix::<f64>::identity(p, p) * RIDGE;
    for &c in &chosen {
        info += &cands[c].info;
    }
    while chosen.len() < load_cases.max(axis_count) {
        let mut best: Option<(f64, usize)> = None;
        for (c, cand) in cands.iter().enumerate() {
            if chosen.contains(&c) {
                continue;
            }
            let Some(ld) = log_det(&(&info + &cand.info)) else {
                continue;
            };
            if best.is_none_or(|(b, _)| ld > b) {
                best = Some((ld, c));
            }
        }
        let Some((_, c)) = best else { break };
        info += &cands[c].info;
        chosen.push(c);
    }
    (chosen, info)
}

/// Expected standard errors: the model's eDoFs from their joint information; an extra family
/// eDoF (with `full_family`) from the information of the model's eDoFs plus that one, i.e. its
/// precision if the structure search adds it.
fn expected_se(
    robot: &Robot,
    edofs: &[EdofId],
    nominal: &[f64],
    info: &DMatrix<f64>,
) -> Vec<ExpectedSe> {
    let p = edofs.len();
    let own: Vec<usize> = (0..p)
        .filter(|&e| robot.stiffness(edofs[e].0, edofs[e].1).is_some())
        .collect();
    edofs
        .iter()
        .enumerate()
        .map(|(e, &id)| {
            let mut set = own.clone();
            if !set.contains(&e) {
                set.push(e);
            }
            let rel = relative_se(info, RIDGE, &set, e);
            ExpectedSe {
                id,
                label: edof_label(id),
                nominal_k: nominal[e],
                se_k: rel * nominal[e],
                relative: rel,
            }
        })
        .collect()
}

/// The plan's rows and axis-by-axis cases: only identifiable eDoFs keep their axis-by-axis
/// case (a case that serves none of them becomes a D-optimal one); rows keep the selection
/// order, labelled A01, A02, … (cases serving an identifiable eDoF) and D01, … (the others).
fn case_rows(
    picks: Vec<Pick>,
    chosen: Vec<usize>,
    cands: &[Candidate],
    expected: &[ExpectedSe],
) -> (Vec<AxisCase>, Vec<MeasurementRow>) {
    let identifiable = |id: EdofId| expected.iter().any(|x| x.id == id && x.identifiable());
    let picks: Vec<_> = picks
        .into_iter()
        .filter(|(id, ..)| identifiable(*id))
        .collect();
    let order = chosen;
    let mut labels: Vec<String> = Vec::with_capacity(order.len());
    let (mut a, mut d) = (0, 0);
    for &c in &order {
        if picks.iter().any(|p| p.1 == c) {
            a += 1;
            labels.push(format!("A{a:02}"));
        } else {
            d += 1;
            labels.push(format!("D{d:02}"));
        }
    }
    let label_of = |i: usize| labels[i].clone();
    let axis_cases: Vec<AxisCase> = picks
        .iter()
        .map(|&(id, c, share, snr)| AxisCase {
            id,
            load_case: label_of(order.iter().position(|&k| k == c).unwrap_or(0)),
            share,
            snr,
        })
        .collect();
    let mut rows = Vec::new();
    for (i, &c) in order.iter().enumerate() {
        let served: Vec<String> = picks
            .iter()
            .filter(|p| p.1 == c)
            .map(|p| edof_label(p.0))
            .collect();
        let purpose = if served.is_empty() {
            format!("D-optimal; {}", cands[c].loading)
        } else {
            format!("axis-by-axis {}; {}", served.join(" "), cands[c].loading)
        };
        for r in &cands[c].rows {
            rows.push(MeasurementRow {
                load_case: label_of(i),
                purpose: Some(purpose.clone()),
                sigma_m: None,
                ..r.clone()
            });
        }
    }
    (axis_cases, rows)
}

/// Expected standard error of every centre shift the calibration fits (joints with an x or y
/// eDoF in `robot`) if the campaign `rows` is measured with tracker noise `noise_sigma_m`:
/// the square root of the diagonal of `(JᵀWJ)⁻¹` at the nominal model, over the model's
/// compliances and those shifts together — the covariance the calibration reports (eq. 13–15
/// through [`crate::stiffness::design`]), before any measurement.
pub fn expected_shift_se(
    robot: &Robot,
    rows: &[MeasurementRow],
    noise_sigma_m: f64,
) -> Result<Vec<ExpectedShiftSe>, CalibError> {
    let (ids, stiffness) = planned_edofs(robot, false);
    let joints: Vec<usize> = (1..=robot.joint_count())
        .filter(|&j| {
            ids.iter()
                .any(|&(site, axis)| site == EdofSite::Joint(j) && axis != Axis::Z)
        })
        .collect();
    if joints.is_empty() || rows.is_empty() {
        return Ok(Vec::new());
    }
    let rows: Vec<MeasurementRow> = rows
        .iter()
        .map(|r| MeasurementRow {
            sigma_m: Some(noise_sigma_m),
            ..r.clone()
        })
        .collect();
    let design = Design::build(robot, &rows, &ids, false)?;
    let idx: Vec<usize> = (0..ids.len()).collect();
    let compliances: Vec<f64> = stiffness.iter().map(|k| 1.0 / k).collect();
    let shifts: Vec<f64> = robot.joints.iter().map(|j| j.center_shift).collect();
    let covariance = unscaled_covariance(
        &design,
        &idx,
        &compliances,
        &shifts,
        &vec![true; idx.len()],
        joints.clone(),
    );
    Ok(joints
        .into_iter()
        .map(|j| ExpectedShiftSe {
            joint: j,
            nominal_m: shifts[j - 1],
            se_m: covariance
                .labels
                .iter()
                .position(|l| *l == Err(j))
                .map_or(f64::INFINITY, |p| covariance.cov[(p, p)].max(0.0).sqrt()),
        })
        .collect())
}

/// Lowest world height of the joint origins and the TCP (after forward kinematics).
pub fn lowest_point_z(robot: &Robot, data: &Data) -> f64 {
    (1..=robot.joint_count())
        .map(|i| data.link_frame(i).translation.vector.z)
        .fold(data.tcp_position().z, f64::min)
}

/// eDoFs to plan for and their nominal stiffness.
fn planned_edofs(robot: &Robot, full: bool) -> (Vec<EdofId>, Vec<f64>) {
    let own: Vec<(EdofId, f64)> = robot
        .edofs()
        .map(|e| ((e.site, e.axis), e.stiffness))
        .collect();
    if !full {
        return (
            own.iter().map(|e| e.0).collect(),
            own.iter().map(|e| e.1).collect(),
        );
    }
    let mut ks: Vec<f64> = own.iter().map(|e| e.1).collect();
    ks.sort_by(f64::total_cmp);
    let median = ks.get(ks.len() / 2).copied().unwrap_or(1e6);
    let mut ids: Vec<EdofId> = vec![(EdofSite::Base, Axis::X), (EdofSite::Base, Axis::Y)];
    for i in 1..=robot.joint_count() {
        for a in Axis::ALL {
            ids.push((EdofSite::Joint(i), a));
        }
    }
    let nominal = ids
        .iter()
        .map(|id| robot.stiffness(id.0, id.1).unwrap_or(median))
        .collect();
    (ids, nominal)
}
