//! Experiment planning: which configurations, loads and points to measure.
//!
//! 1. **Axis by axis** (the paper's Fig. 7 and Tables A1/A2, generalised): for every eDoF, among
//!    many reachable configurations (joint limits respected, angles rounded to 0.1°) and
//!    world-axis load directions (±x, ±y, ±z at the TCP, like a cable or a deadweight), the load
//!    case where that eDoF's share of the predicted displacement (eq. 15, all measured points) is
//!    largest while being clearly visible (≥ 10 σ).
//! 2. **D-optimal completion**: greedily add, from the same candidates, the load case that
//!    maximises `log det F` of the Fisher information `F = Σ JᵀJ/σ²` of the relative compliances
//!    `c_e / c_e,nominal`, up to the requested number of load cases.
//!
//! The expected standard error of every stiffness follows from `F⁻¹` (relative SE of k equals
//! relative SE of c to first order); that of every centre shift the calibration fits from the
//! calibration's own covariance `(JᵀWJ)⁻¹` at the nominal model ([`expected_shift_se`]). Each
//! load case measures the TCP, two mid-arm points ([`standard_points`]) and a reflector on the
//! base casting (`M0`, [`PlanOptions::base_point`]), like the paper's M1..M3.

use crate::CalibError;
use crate::data::MeasurementRow;
use crate::design::{Design, EdofId, edof_label};
use crate::synthetic::{case_rows, random_q};
use crate::uncertainty::unscaled_covariance;
use deflex_model::{Axis, Data, EdofSite, Robot};
use nalgebra::{DMatrix, Vector3};
use rand::SeedableRng;
use rand_chacha::ChaCha8Rng;

/// Settings of [`plan_experiments`].
#[derive(Clone, Debug)]
pub struct PlanOptions {
    /// Load magnitude (N).
    pub max_force_n: f64,
    /// Total number of load cases (axis-by-axis ones included).
    pub load_cases: usize,
    /// Random configurations tried (each with 6 load directions).
    pub configurations: usize,
    /// Tracker noise (m) for the expected standard errors.
    pub noise_sigma_m: f64,
    /// Random seed.
    pub seed: u64,
    /// Plan for every eDoF of the model family (x, y, z per joint, base x/y tilt), not only the
    /// model's: what the structure search needs. Absent eDoFs get the median stiffness.
    pub full_family: bool,
    /// Also measure a reflector `M0` on the base casting in every load case: only base eDoFs
    /// move it, which separates a baseplate tilt from the x/y eDoFs of joint 1 (the paper's M1
    /// saw the tilt, Section 3.1).
    pub base_point: bool,
    /// Keep every joint origin and the TCP at or above this world height (m): the floor, the
    /// table or the fixture under the robot. World = the robot file's frame (R0 at the
    /// shoulder for the built-in TX200, so its floor is negative). `None`: joint limits only.
    pub floor_z_m: Option<f64>,
}

impl Default for PlanOptions {
    fn default() -> Self {
        PlanOptions {
            max_force_n: 1500.0,
            load_cases: 24,
            configurations: 600,
            noise_sigma_m: 15e-6,
            seed: 1,
            full_family: false,
            base_point: true,
            floor_z_m: None,
        }
    }
}

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

/// A measurement campaign.
#[derive(Clone, Debug)]
pub struct Plan {
    /// Rows in the plan format (no displacement).
    pub rows: Vec<MeasurementRow>,
    /// Axis-by-axis choices.
    pub axis_cases: Vec<AxisCase>,
    /// Expected SE of every planned stiffness.
    pub expected: Vec<ExpectedSe>,
    /// Expected SE of the centre shift of every joint with an x/y eDoF in the model.
    pub expected_shifts: Vec<ExpectedShiftSe>,
    /// `log det` of the final information matrix (relative parameters).
    pub log_det: f64,
}

/// Measured points of a load case: the TCP (last link) and the middle of the two links at the
/// middle of the arm (links ⌈N/2⌉ and ⌈N/2⌉ − 1), named `M<link>`. A point too close to its
/// joint axis is moved 0.1 m along x_k so that it sees the joint's z-eDoF.
pub fn standard_points(robot: &Robot, data: &Data) -> Vec<(String, usize, Vector3<f64>)> {
    let n = robot.joint_count();
    let mut out = vec![("TCP".to_string(), n, data.tcp_position())];
    let m = n.div_ceil(2);
    for link in [m, m.saturating_sub(1)] {
        if link == 0 || link >= n {
            continue;
        }
        let frame = data.link_frame(link);
        let o = frame.translation.vector;
        let next = data.link_frame(link + 1).translation.vector;
        let mut p = 0.5 * (o + next);
        let z: Vector3<f64> = frame.rotation.matrix().column(2).into_owned();
        let radial = (p - o) - z * z.dot(&(p - o));
        if radial.norm() < 0.05 {
            p += frame.rotation.matrix().column(0) * 0.1;
        }
        out.push((format!("M{link}"), link, p));
    }
    out
}

/// Where the base reflector `M0` sits in R0: 0.3 m forward of and 0.3 m below the origin of R0,
/// on the base casting under the shoulder.
pub const BASE_POINT_IN_R0_M: [f64; 3] = [0.3, 0.0, -0.3];

/// The `M0` row of a load case (same configuration and load as `template`).
fn base_point_row(template: &MeasurementRow, data: &Data) -> MeasurementRow {
    let [x, y, z] = BASE_POINT_IN_R0_M;
    let p = data
        .link_frame(0)
        .transform_point(&nalgebra::Point3::new(x, y, z));
    MeasurementRow {
        point: "M0".to_string(),
        point_link: 0,
        point_m: [p.x, p.y, p.z],
        ..template.clone()
    }
}

/// Plan a campaign for `robot` (its geometry, eDoFs, stiffnesses and centre shifts are the
/// nominal model).
pub fn plan_experiments(robot: &Robot, options: &PlanOptions) -> Result<Plan, CalibError> {
    if !(options.max_force_n.is_finite() && options.max_force_n > 0.0) {
        return Err(CalibError::Invalid(
            "--max-force-N must be a positive number".into(),
        ));
    }
    if !(options.noise_sigma_m.is_finite() && options.noise_sigma_m > 0.0) {
        return Err(CalibError::Invalid("tracker noise must be positive".into()));
    }
    if options.floor_z_m.is_some_and(|z| !z.is_finite()) {
        return Err(CalibError::Invalid(
            "the floor height must be a number".into(),
        ));
    }
    let (edofs, nominal) = planned_edofs(robot, options.full_family);
    if edofs.is_empty() {
        return Err(CalibError::Invalid(format!(
            "robot \"{}\" has no eDoF to plan for (use the full model family)",
            robot.name
        )));
    }
    let shifts: Vec<f64> = robot.joints.iter().map(|j| j.center_shift).collect();
    let mut rng = ChaCha8Rng::seed_from_u64(options.seed);
    let mut data = Data::new();
    // Candidates: configurations × 6 world-axis load directions.
    let mut cand_rows: Vec<Vec<MeasurementRow>> = Vec::new();
    let wanted = options.configurations.max(1);
    let (mut accepted, mut drawn) = (0, 0);
    while accepted < wanted && drawn < 20 * wanted {
        drawn += 1;
        let q: Vec<f64> = random_q(robot, &mut rng)
            .into_iter()
            .map(|v| (v.to_degrees() * 10.0).round().to_radians() / 10.0)
            .collect();
        robot
            .forward_kinematics(&mut data, &q)
            .map_err(|e| CalibError::Invalid(e.to_string()))?;
        if let Some(floor) = options.floor_z_m
            && lowest_point_z(robot, &data) < floor
        {
            continue;
        }
        accepted += 1;
        for dir in 0..6 {
            let mut f = Vector3::zeros();
            f[dir / 2] = if dir % 2 == 0 { 1.0 } else { -1.0 } * options.max_force_n;
            let mut rows = case_rows(robot, &data, &q, &f, "", None);
            if options.base_point {
                rows.push(base_point_row(&rows[0], &data));
            }
            cand_rows.push(rows);
        }
    }
    if cand_rows.is_empty() {
        return Err(CalibError::Invalid(format!(
            "no configuration out of {drawn} drawn keeps the arm above the floor at z = {:.3} m",
            options.floor_z_m.unwrap_or(f64::NAN)
        )));
    }
    let flat: Vec<MeasurementRow> = cand_rows
        .iter()
        .flatten()
        .cloned()
        .map(|mut r| {
            r.sigma_m = Some(options.noise_sigma_m);
            r
        })
        .collect();
    let design = Design::build(robot, &flat, &edofs, false)?;
    let p = edofs.len();
    // U_c: p × (equations of the case), relative-compliance sensitivities in units of σ.
    let mut sens: Vec<DMatrix<f64>> = Vec::with_capacity(cand_rows.len());
    let mut eq0 = 0;
    for case in &cand_rows {
        let m = 3 * case.len();
        let mut u = DMatrix::zeros(p, m);
        for e in 0..p {
            let s = design.shift_joint(e).map(|j| shifts[j - 1]).unwrap_or(0.0);
            for (b, coef) in design.col(e, s) {
                for k in 0..m {
                    u[(e, k)] += coef * design.x[(eq0 + k, b)] * nominal[e].recip();
                }
            }
        }
        eq0 += m;
        sens.push(u);
    }
    let mut chosen: Vec<(usize, String)> = Vec::new();
    let mut axis_cases = Vec::new();
    for (e, &id) in edofs.iter().enumerate() {
        let mut best: Option<(f64, f64, usize)> = None;
        let mut loudest: Option<(f64, usize)> = None;
        for (c, u) in sens.iter().enumerate() {
            let norms: Vec<f64> = (0..p).map(|f| u.row(f).norm()).collect();
            let total: f64 = norms.iter().sum();
            if total <= 0.0 {
                continue;
            }
            let share = norms[e] / total;
            if norms[e] >= 10.0 && best.is_none_or(|(s, ..)| share > s) {
                best = Some((share, norms[e], c));
            }
            if loudest.is_none_or(|(s, _)| norms[e] > s) {
                loudest = Some((norms[e], c));
            }
        }
        let pick = best.or_else(|| {
            loudest.filter(|l| l.0 >= 3.0).map(|(snr, c)| {
                let u = &sens[c];
                let total: f64 = (0..p).map(|f| u.row(f).norm()).sum();
                (snr / total, snr, c)
            })
        });
        if let Some((share, snr, c)) = pick {
            let label = format!("A{:02}", axis_cases.len() + 1);
            if !chosen.iter().any(|(k, _)| *k == c) {
                chosen.push((c, format!("axis-by-axis {}", edof_label(id))));
            }
            let load_case = chosen
                .iter()
                .position(|(k, _)| *k == c)
                .map(|i| format!("A{:02}", i + 1))
                .unwrap_or(label);
            axis_cases.push(AxisCase {
                id,
                load_case,
                share,
                snr,
            });
        }
    }
    let axis_count = chosen.len();
    // Greedy D-optimal completion.
    let ridge = 1e-9;
    let mut info = DMatrix::<f64>::identity(p, p) * ridge;
    for (c, _) in &chosen {
        info += &sens[*c] * sens[*c].transpose();
    }
    while chosen.len() < options.load_cases.max(axis_count) {
        let mut best: Option<(f64, usize)> = None;
        for (c, u) in sens.iter().enumerate() {
            if chosen.iter().any(|(k, _)| *k == c) {
                continue;
            }
            let trial = &info + u * u.transpose();
            let Some(ch) = trial.cholesky() else { continue };
            let ld: f64 = ch.l().diagonal().iter().map(|v| 2.0 * v.ln()).sum();
            if best.is_none_or(|(b, _)| ld > b) {
                best = Some((ld, c));
            }
        }
        let Some((_, c)) = best else { break };
        info += &sens[c] * sens[c].transpose();
        chosen.push((c, "D-optimal".into()));
    }
    let log_det = info
        .clone()
        .cholesky()
        .map(|ch| ch.l().diagonal().iter().map(|v| 2.0 * v.ln()).sum())
        .unwrap_or(f64::NEG_INFINITY);
    // Expected SE: the model's eDoFs from their joint information; an extra family eDoF (with
    // `full_family`) from the information of the model's eDoFs plus that one, i.e. its precision
    // if the structure search adds it.
    let own: Vec<usize> = (0..p)
        .filter(|&e| robot.stiffness(edofs[e].0, edofs[e].1).is_some())
        .collect();
    let relative_se = |set: &[usize], e: usize| -> f64 {
        let m = set.len();
        let sub = DMatrix::from_fn(m, m, |i, j| {
            info[(set[i], set[j])] - if i == j { ridge } else { 0.0 }
        });
        let Some(pos) = set.iter().position(|&k| k == e) else {
            return f64::INFINITY;
        };
        let d: Vec<f64> = (0..m).map(|i| sub[(i, i)].max(0.0).sqrt()).collect();
        if d[pos] == 0.0 {
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
    };
    let expected = edofs
        .iter()
        .enumerate()
        .map(|(e, &id)| {
            let mut set = own.clone();
            if !set.contains(&e) {
                set.push(e);
            }
            let rel = relative_se(&set, e);
            ExpectedSe {
                id,
                label: edof_label(id),
                nominal_k: nominal[e],
                se_k: rel * nominal[e],
                relative: rel,
            }
        })
        .collect();
    let mut rows = Vec::new();
    for (i, (c, purpose)) in chosen.iter().enumerate() {
        let label = if i < axis_count {
            format!("A{:02}", i + 1)
        } else {
            format!("D{:02}", i + 1 - axis_count)
        };
        for r in &cand_rows[*c] {
            let mut r = r.clone();
            r.load_case = label.clone();
            r.purpose = Some(purpose.clone());
            rows.push(r);
        }
    }
    let expected_shifts = expected_shift_se(robot, &rows, options.noise_sigma_m)?;
    Ok(Plan {
        rows,
        axis_cases,
        expected,
        expected_shifts,
        log_det,
    })
}

/// Expected standard error of every centre shift the calibration fits (joints with an x or y
/// eDoF in `robot`) if the campaign `rows` is measured with tracker noise `noise_sigma_m`:
/// the square root of the diagonal of `(JᵀWJ)⁻¹` at the nominal model, over the model's
/// compliances and those shifts together — the covariance the calibration reports (eq. 13–15
/// through [`crate::design`]), before any measurement.
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
