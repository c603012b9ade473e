//! Fixed-structure calibration: compliances `c = 1/k` by weighted NNLS (eq. 15 is linear in c),
//! centre shifts by variable projection, with standard errors, 95 % intervals, correlations,
//! condition number and residual statistics (computed in the internal `uncertainty` module).
//! What it produces ([`Calibration`], [`Structure`], [`ResidualStats`], …) is named here.
//!
//! The least-squares problem holds the three position equations of every row and, for rows with
//! a measured rotation, its three rotation equations (weighted by `1/σ_rad`); residual
//! statistics stay position-only in metres, with the rotation RMS reported separately.

use crate::measurements::MeasurementRow;
use crate::stiffness::design::{Design, EdofId, edof_label};
use crate::stiffness::shift::{self, normal_system, scales};
use crate::stiffness::uncertainty::analyse;
use crate::stiffness::{CalibError, StructureError};
use deflex_model::Robot;
use nalgebra::DMatrix;

pub use crate::stiffness::calibration::{
    CHI2_WELL_ABOVE_ONE, Calibration, CorrelatedPair, EdofEstimate, MAX_RELATIVE_SE, ResidualStats,
    STRONG_CORRELATION, ShiftEstimate, Status, Structure, Z95,
};
pub use crate::stiffness::uncertainty::bic;
pub(crate) use crate::stiffness::uncertainty::residual_stats;

/// Calibrate a fixed structure on measurement rows (builds the design for that structure only).
pub fn calibrate_fixed(
    robot: &Robot,
    rows: &[MeasurementRow],
    structure: &Structure,
) -> Result<Calibration, CalibError> {
    if structure.shifts_m.len() != robot.joint_count() {
        return Err(StructureError::ShiftCount {
            shifts: structure.shifts_m.len(),
            joints: robot.joint_count(),
        }
        .into());
    }
    if structure.edofs.is_empty() {
        return Err(StructureError::Empty.into());
    }
    let design = Design::build(robot, rows, &structure.edofs, true)?;
    fit_in_design(&design, structure)
}

/// Calibrate a structure within a prebuilt design (whose candidates include its eDoFs).
/// Unobservable and collinear eDoFs are reported not identifiable and removed, then the rest is
/// refitted.
pub fn fit_in_design(design: &Design, structure: &Structure) -> Result<Calibration, CalibError> {
    // At least one equation more than parameters (χ²/dof needs dof ≥ 1), counting repeated
    // rows once: a repeated reading is not a new equation.
    let parameters = structure.edofs.len() + structure.free_shift_joints().len();
    let rotation_share = (design.rotation_rows * design.distinct_rows)
        .checked_div(design.rows)
        .unwrap_or(0);
    let equations = 3 * design.distinct_rows + 3 * rotation_share;
    if equations <= parameters {
        return Err(crate::stiffness::RowsError::TooFewReadings {
            rows: design.rows,
            distinct: design.distinct_rows,
            equations,
            parameters,
        }
        .into());
    }
    let mut active: Vec<EdofId> = structure.edofs.clone();
    let mut dropped: Vec<(EdofId, String)> = Vec::new();
    let mut shifts = structure.shifts_m.clone();
    let mut warnings = design.warnings.clone();
    for id in &active {
        if design.index_of(*id).is_none() {
            return Err(StructureError::NotInDesign {
                label: edof_label(*id),
            }
            .into());
        }
    }
    loop {
        let idx: Vec<usize> = active
            .iter()
            .map(|id| design.index_of(*id).unwrap_or(0))
            .collect();
        // Unobservable or collinear columns at the current shifts.
        if let Some((k, reason)) = rank_problem(design, &idx, &shifts, &active) {
            dropped.push((active[k], reason));
            active.remove(k);
            if active.is_empty() {
                return Err(StructureError::NothingObservable {
                    dropped: dropped
                        .iter()
                        .map(|(id, r)| (edof_label(*id), r.clone()))
                        .collect(),
                }
                .into());
            }
            continue;
        }
        let free = structure.free_shift_joints();
        let sol = shift::optimize(design, &idx, &mut shifts, &free);
        let cal = analyse(
            design, structure, &active, &idx, &sol, &shifts, &dropped, &free,
        );
        // Refit without eDoFs judged not identifiable after the fit.
        let newly: Vec<(EdofId, String)> = cal
            .edofs
            .iter()
            .filter(|e| active.contains(&e.id))
            .filter_map(|e| match &e.status {
                Status::NotIdentifiable(r) => Some((e.id, r.clone())),
                _ => None,
            })
            .collect();
        if newly.is_empty() || newly.len() == active.len() {
            let mut cal = cal;
            warnings.append(&mut cal.warnings);
            cal.warnings = warnings;
            return Ok(cal);
        }
        for (id, r) in newly {
            active.retain(|a| *a != id);
            dropped.push((id, r));
        }
    }
}

/// First eDoF (position in `idx`) whose column is zero or collinear with others.
fn rank_problem(
    design: &Design,
    idx: &[usize],
    shifts: &[f64],
    active: &[EdofId],
) -> Option<(usize, String)> {
    let cols = shift::columns(design, idx, shifts);
    let (g, _) = normal_system(design, &cols);
    let d = scales(&g);
    if let Some(k) = d.iter().position(|&v| v == 0.0) {
        return Some((
            k,
            "not identifiable: no measured point moves with it under the applied loads".into(),
        ));
    }
    let p = idx.len();
    if p == 0 {
        return None;
    }
    let gs = DMatrix::from_fn(p, p, |i, j| g[(i, j)] * d[i] * d[j]);
    if !crate::stiffness::all_finite(&gs) {
        return Some((
            0,
            "not identifiable: the normal equations are not finite (data magnitudes overflow)"
                .into(),
        ));
    }
    let eig = gs.symmetric_eigen();
    let (imin, &lmin) = eig
        .eigenvalues
        .iter()
        .enumerate()
        .min_by(|a, b| a.1.total_cmp(b.1))?;
    if lmin > 1e-10 {
        return None;
    }
    let v = eig.eigenvectors.column(imin);
    let involved: Vec<usize> = (0..p).filter(|&k| v[k].abs() > 0.1).collect();
    let worst = *involved.iter().max_by(|&&a, &&b| {
        (v[a].abs(), a)
            .partial_cmp(&(v[b].abs(), b))
            .unwrap_or(std::cmp::Ordering::Equal)
    })?;
    let others: Vec<String> = involved
        .iter()
        .filter(|&&k| k != worst)
        .map(|&k| edof_label(active[k]))
        .collect();
    Some((
        worst,
        format!(
            "not identifiable: indistinguishable from {} in this data (only their combination is seen)",
            others.join(", ")
        ),
    ))
}
