//! Reduction to the identifiable parameter set.
//!
//! The identification Jacobian (readings standardised by σ) has one column per candidate
//! parameter. Columns are scaled to unit norm, so only their directions matter, and
//! orthogonalised in a fixed priority order (classical Gram–Schmidt applied twice, which is
//! as accurate as Householder QR): set-up registrations first, then targets, then the
//! geometry from the base to the tip, then compliances, masses and harmonics. A column whose
//! part orthogonal to the columns kept before it is shorter than [`DEFAULT_TOLERANCE`] is
//! *not identifiable*: some combination of kept parameters moves every reading the same way,
//! and the combination is reported (`J1.theta ≡ +1.000·setup[A].rz`). This is QR with the
//! pivot order fixed by physical priority instead of by column norm: a redundancy between the
//! set-up yaw and joint 1's offset is then always resolved by keeping the set-up (which every
//! model needs) and leaving the joint offset at its nominal value. The singular values of the
//! kept, scaled columns give the condition number.

use crate::geometry::campaign::Campaign;
use crate::geometry::params::{EgModel, Param, ParamGroup};
use nalgebra::{DMatrix, DVector};

/// Relative length below which a scaled column counts as a combination of the kept ones.
pub const DEFAULT_TOLERANCE: f64 = 1e-3;
/// Kept parameters whose independent part is below this are flagged as weakly identifiable.
pub const WEAK_THRESHOLD: f64 = 1e-2;

/// A parameter left at its starting value, and why.
#[derive(Clone, Debug)]
pub struct NotIdentifiable {
    /// The parameter.
    pub param: Param,
    /// Length of the part of its scaled column orthogonal to the kept columns (0…1).
    pub independence: f64,
    /// The equivalent combination: changing `param` by δ changes every reading as changing
    /// each listed kept parameter by `coefficient · δ` (physical units).
    pub combination: Vec<(Param, f64)>,
    /// Plain-language reason.
    pub reason: String,
}

/// The identifiable set.
#[derive(Clone, Debug)]
pub struct Reduction {
    /// Kept parameters, in priority order.
    pub kept: Vec<Param>,
    /// Independence (0…1) of each kept parameter, same order.
    pub independence: Vec<f64>,
    /// Parameters left at their starting values.
    pub dropped: Vec<NotIdentifiable>,
    /// Condition number of the kept, scaled Jacobian.
    pub condition_number: f64,
}

/// Reduce `candidates` (in priority order) to an identifiable set on the readings with
/// `multiplicity > 0`.
pub fn reduce(
    model: &EgModel,
    campaign: &Campaign,
    candidates: &[Param],
    multiplicity: &[f64],
    tolerance: f64,
) -> Reduction {
    let p = candidates.len();
    let rows: Vec<usize> = (0..campaign.len())
        .filter(|&i| multiplicity[i] > 0.0)
        .collect();
    let m = 3 * rows.len();
    let mut jacobian = DMatrix::<f64>::zeros(m, p);
    let mut columns = Vec::with_capacity(p);
    for (r, &i) in rows.iter().enumerate() {
        campaign.residual(model, i, candidates, Some(&mut columns));
        let scale = multiplicity[i].sqrt() / campaign.sigma(i);
        for (k, c) in columns.iter().enumerate() {
            for a in 0..3 {
                jacobian[(3 * r + a, k)] = c[a] * scale;
            }
        }
    }
    let norms: Vec<f64> = (0..p).map(|k| jacobian.column(k).norm()).collect();
    let largest = norms.iter().cloned().fold(0.0, f64::max);
    let mut basis: Vec<DVector<f64>> = Vec::new();
    // R of the kept columns (upper triangular, column by column).
    let mut r_columns: Vec<Vec<f64>> = Vec::new();
    let mut kept_index: Vec<usize> = Vec::new();
    let mut independence = Vec::new();
    let mut dropped = Vec::new();
    for k in 0..p {
        let param = candidates[k];
        if norms[k] <= 1e-12 * largest.max(1e-300) {
            dropped.push(NotIdentifiable {
                param,
                independence: 0.0,
                combination: Vec::new(),
                reason: reason(model, param, &[], true),
            });
            continue;
        }
        let column = jacobian.column(k) / norms[k];
        let mut residual = column.clone_owned();
        let mut coefficients = vec![0.0; basis.len()];
        for _ in 0..2 {
            for (j, q) in basis.iter().enumerate() {
                let c = q.dot(&residual);
                coefficients[j] += c;
                residual.axpy(-c, q, 1.0);
            }
        }
        let length = residual.norm();
        if length > tolerance {
            coefficients.push(length);
            r_columns.push(coefficients);
            basis.push(residual / length);
            kept_index.push(k);
            independence.push(length);
        } else {
            // Solve R β = coefficients (back substitution) for the kept scaled columns.
            let r = basis.len();
            let mut beta = vec![0.0; r];
            for i in (0..r).rev() {
                let mut s = coefficients[i];
                for (j, b) in beta.iter().enumerate().skip(i + 1) {
                    s -= r_columns[j][i] * b;
                }
                beta[i] = s / r_columns[i][i];
            }
            let mut combination: Vec<(Param, f64, f64)> = beta
                .iter()
                .enumerate()
                .filter(|(_, b)| b.abs() > 0.05)
                .map(|(j, b)| {
                    let kept = kept_index[j];
                    (candidates[kept], b * norms[k] / norms[kept], b.abs())
                })
                .collect();
            combination.sort_by(|a, b| b.2.total_cmp(&a.2));
            let combination: Vec<(Param, f64)> =
                combination.into_iter().map(|(p, c, _)| (p, c)).collect();
            let others: Vec<Param> = combination.iter().map(|(p, _)| *p).collect();
            let mut why = reason(model, param, &others, false);
            if length > 1e-4 {
                // Not an identity of the rigid model (those leave at most the sag's 10⁻⁵
                // trace): these readings do not separate it.
                why = format!(
                    "nearly so in these configurations (independent part {length:.1e} < {tolerance:.0e}; other configurations could separate it): {why}"
                );
            }
            dropped.push(NotIdentifiable {
                param,
                independence: length,
                reason: why,
                combination,
            });
        }
    }
    let kept: Vec<Param> = kept_index.iter().map(|&k| candidates[k]).collect();
    let condition_number = if kept.is_empty() {
        1.0
    } else {
        let mut scaled = DMatrix::<f64>::zeros(m, kept.len());
        for (c, &k) in kept_index.iter().enumerate() {
            scaled.set_column(c, &(jacobian.column(k) / norms[k]));
        }
        let singular = (scaled.transpose() * &scaled).symmetric_eigenvalues();
        let max = singular.max().max(0.0).sqrt();
        let min = singular.min().max(0.0).sqrt();
        if min > 0.0 { max / min } else { f64::INFINITY }
    };
    Reduction {
        kept,
        independence,
        dropped,
        condition_number,
    }
}

/// A plain-language reason for a non-identifiable parameter, from what it is and what it
/// trades with.
fn reason(model: &EgModel, param: Param, others: &[Param], no_effect: bool) -> String {
    let group = EgModel::group(param);
    if no_effect {
        return match group {
            ParamGroup::Compliance => {
                "no load or gravity torque reaches this eDoF in the measured configurations (e.g. a vertical axis under gravity alone)".into()
            }
            ParamGroup::Mass => {
                "this body's weight loads no eDoF whose compliance is non-zero".into()
            }
            _ => "no reading is sensitive to it".into(),
        };
    }
    let groups: Vec<ParamGroup> = others.iter().map(|p| EgModel::group(*p)).collect();
    let has = |g: ParamGroup| groups.contains(&g);
    let only = |g: ParamGroup| !groups.is_empty() && groups.iter().all(|x| *x == g);
    let last_joint = model.robot.joint_count().saturating_sub(1);
    let after_last_axis = matches!(param, Param::Dh(j, _) if j == last_joint)
        && others.iter().all(|p| match p {
            Param::Target(..) => true,
            Param::Dh(j, _) => *j == last_joint,
            _ => false,
        });
    match group {
        ParamGroup::Geometry if only(ParamGroup::Setup) => {
            "moves every reading like a rigid motion of the whole arm: indistinguishable from where the tracker stands (set-up registration)".into()
        }
        ParamGroup::Geometry if only(ParamGroup::Target) || after_last_axis => {
            "a fixed placement after the last moving axis: the target offset on the flange absorbs it (only positions are measured)".into()
        }
        ParamGroup::Geometry if has(ParamGroup::Setup) && has(ParamGroup::Target) => {
            "a combination that the set-up registration and the target offset together absorb".into()
        }
        ParamGroup::Geometry if has(ParamGroup::Setup) => {
            "with the listed DH parameters, a rigid motion of the arm's base that the set-up registration absorbs".into()
        }
        ParamGroup::Geometry => {
            "parallel or intersecting axes: the common normal can slide along the axes, so another DH parameter of the chain moves every reading the same way".into()
        }
        ParamGroup::Compliance | ParamGroup::Mass => {
            "the sag is compliance × gravity torque: only the products are seen, so one of each compliance–mass pair (or bodies that load the same eDoFs alike) is redundant".into()
        }
        ParamGroup::Harmonic => {
            "this joint-angle harmonic is a combination of constant offsets or other terms over the measured joint range".into()
        }
        ParamGroup::Backlash => {
            "this direction-dependent offset is a combination of constant offsets over the measured approach directions (a joint always approached from the same side)".into()
        }
        ParamGroup::Torsion => {
            "over the measured torque range this torsion curve is a combination of the linear compliance and the other terms".into()
        }
        ParamGroup::Setup | ParamGroup::Target => {
            "a combination of the listed parameters has the same effect on every reading".into()
        }
    }
}
