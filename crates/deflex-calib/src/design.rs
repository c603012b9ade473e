//! The design matrix of the identification problem (eqs. 13–15).
//!
//! For a measured point P on link k, a wrench w applied at A on link l, and an eDoF e (axis v,
//! centre c) with site ≤ min(k, l), the VJM displacement of P is linear in the compliance
//! `c_e = 1/k_e`:
//!
//! ```text
//! δp(P) = Σ_e c_e · lin(j_e(P)) · (j_e(A)ᵀ w),   j_e(X) = [v × (X − c); v]   (eqs. 13–15)
//! ```
//!
//! The centre of a joint eDoF is `c = O_i + s·z_i`, with `s` the paper's centre shift δr_i. With
//! `u = v × z_i`, `L₀ = v × (P − O_i)` and `τ₀ = (v × (A − O_i))·f + v·m` the column is a
//! quadratic polynomial in the shift:
//!
//! ```text
//! col_e(s) = L₀τ₀ − s (u τ₀ + L₀ (u·f)) + s² u (u·f)  =  a₀ + a₁ s + a₂ s²
//! ```
//!
//! so the design stores the three *basis* vectors of every x/y joint eDoF (one for z and base
//! eDoFs, where `u = 0`) once, together with their Gram matrix. Every fit of every candidate
//! structure, with any centre shifts, then costs O(p²) inner products of precomputed numbers,
//! independent of the number of rows: this is what makes the structure search fast.

use crate::CalibError;
use crate::data::MeasurementRow;
use deflex_model::{Axis, Data, EdofSite, Robot};
use nalgebra::{DMatrix, DVector, Vector3};

/// One eDoF, by site and axis.
pub type EdofId = (EdofSite, Axis);

/// Default tracker standard deviation when a row has no `sigma_m` (15 µm).
pub const DEFAULT_SIGMA_M: f64 = 15e-6;

/// Label of an eDoF as in the paper's Table 1: `J3.x`, `base.y`.
pub fn edof_label(id: EdofId) -> String {
    format!("{}.{}", id.0, id.1.letter())
}

/// Every eDoF the model family allows for a robot with `joint_count` joints, in the robot's
/// column order (base x, y, z, then joint 1 x, y, z, …).
pub fn all_edofs(joint_count: usize) -> Vec<EdofId> {
    let mut out: Vec<EdofId> = Axis::ALL.iter().map(|&a| (EdofSite::Base, a)).collect();
    for i in 1..=joint_count {
        out.extend(Axis::ALL.iter().map(|&a| (EdofSite::Joint(i), a)));
    }
    out
}

/// Sort key matching [`Robot::edofs`] order.
pub fn edof_order(id: &EdofId) -> (usize, usize) {
    (id.0.link_index(), id.1.index())
}

/// A sparse combination of basis vectors: `(basis index, coefficient)`.
pub(crate) type Combo = Vec<(usize, f64)>;

/// Weighted design of a data set for a set of candidate eDoFs: basis vectors, their Gram
/// matrix, and the weighted observations.
#[derive(Clone, Debug)]
pub struct Design {
    /// Candidate eDoFs, one per column block.
    pub candidates: Vec<EdofId>,
    /// First basis index of each candidate.
    pub(crate) offset: Vec<usize>,
    /// Number of basis vectors of each candidate (3 for joint x/y, 1 otherwise).
    pub(crate) nbasis: Vec<usize>,
    /// Weighted basis values, one row per equation (3 per data row: x, y, z).
    pub(crate) x: DMatrix<f64>,
    /// Weighted observations.
    pub(crate) y: DVector<f64>,
    /// Standard deviation of each equation (m).
    pub(crate) sigma: Vec<f64>,
    /// Gram matrix `XᵀX` of the basis.
    pub(crate) gram: DMatrix<f64>,
    /// `Xᵀy`.
    pub(crate) xty: DVector<f64>,
    /// `yᵀy`.
    pub(crate) yty: f64,
    /// Number of data rows.
    pub rows: usize,
    /// Number of joints of the robot.
    pub joint_count: usize,
    /// Observations about the data that do not stop the fit (e.g. unobservable eDoFs).
    pub warnings: Vec<String>,
}

impl Design {
    /// Build the design for `candidates` from measurement rows (`require_displacement`) or plan
    /// rows (observations taken as zero, for information/Fisher computations). Only the robot's
    /// geometry is used; its stiffnesses and centre shifts are ignored (shifts are parameters).
    /// FK is computed once per distinct joint configuration.
    pub fn build(
        robot: &Robot,
        rows: &[MeasurementRow],
        candidates: &[EdofId],
        require_displacement: bool,
    ) -> Result<Design, CalibError> {
        check_rows(robot, rows, require_displacement)?;
        let n = robot.joint_count();
        let mut offset = Vec::with_capacity(candidates.len());
        let mut nbasis = Vec::with_capacity(candidates.len());
        let mut nb = 0;
        for &(site, axis) in candidates {
            if let EdofSite::Joint(i) = site
                && (i == 0 || i > n)
            {
                return Err(CalibError::Invalid(format!(
                    "eDoF J{i}.{} does not exist: the robot has {n} joints",
                    axis.letter()
                )));
            }
            let k = match (site, axis) {
                (EdofSite::Joint(_), Axis::X | Axis::Y) => 3,
                _ => 1,
            };
            offset.push(nb);
            nbasis.push(k);
            nb += k;
        }
        let neq = 3 * rows.len();
        let mut x = DMatrix::<f64>::zeros(neq, nb);
        let mut y = DVector::<f64>::zeros(neq);
        let mut sigma = vec![DEFAULT_SIGMA_M; neq];
        let mut data = Data::new();
        let mut last_q: Option<&[f64]> = None;
        for (r, row) in rows.iter().enumerate() {
            if last_q != Some(row.q_rad.as_slice()) {
                robot
                    .forward_kinematics(&mut data, &row.q_rad)
                    .map_err(|e| CalibError::Invalid(e.to_string()))?;
                last_q = Some(row.q_rad.as_slice());
            }
            let s = row.sigma_m.unwrap_or(DEFAULT_SIGMA_M);
            let wgt = 1.0 / s;
            let p = Vector3::from(row.point_m);
            let a = Vector3::from(row.load_point_m);
            let f = Vector3::new(row.wrench[0], row.wrench[1], row.wrench[2]);
            let m = Vector3::new(row.wrench[3], row.wrench[4], row.wrench[5]);
            let reach = row.point_link.min(row.load_link);
            for ax in 0..3 {
                sigma[3 * r + ax] = s;
                if let Some(d) = row.displacement_m {
                    y[3 * r + ax] = d[ax] * wgt;
                }
            }
            for (ci, &(site, axis)) in candidates.iter().enumerate() {
                if site.link_index() > reach {
                    continue;
                }
                let frame = data.link_frame(site.link_index());
                let rot = frame.rotation.matrix();
                let v: Vector3<f64> = rot.column(axis.index()).into_owned();
                let o = frame.translation.vector;
                let l0 = v.cross(&(p - o));
                let t0 = v.cross(&(a - o)).dot(&f) + v.dot(&m);
                let a0 = l0 * t0;
                let base = offset[ci];
                for ax in 0..3 {
                    x[(3 * r + ax, base)] = a0[ax] * wgt;
                }
                if nbasis[ci] == 3 {
                    let z: Vector3<f64> = rot.column(2).into_owned();
                    let u = v.cross(&z);
                    let uf = u.dot(&f);
                    let a1 = -(u * t0 + l0 * uf);
                    let a2 = u * uf;
                    for ax in 0..3 {
                        x[(3 * r + ax, base + 1)] = a1[ax] * wgt;
                        x[(3 * r + ax, base + 2)] = a2[ax] * wgt;
                    }
                }
            }
        }
        let gram = x.tr_mul(&x);
        let xty = x.tr_mul(&y);
        let yty = y.norm_squared();
        let warnings = observability_warnings(rows, candidates, n);
        Ok(Design {
            candidates: candidates.to_vec(),
            offset,
            nbasis,
            x,
            y,
            sigma,
            gram,
            xty,
            yty,
            rows: rows.len(),
            joint_count: n,
            warnings,
        })
    }

    /// Number of equations (3 per row).
    pub fn equations(&self) -> usize {
        self.y.len()
    }

    /// Index of an eDoF among the candidates.
    pub fn index_of(&self, id: EdofId) -> Option<usize> {
        self.candidates.iter().position(|&c| c == id)
    }

    /// Column of candidate `ci` at centre shift `s`, as a basis combination.
    pub(crate) fn col(&self, ci: usize, s: f64) -> Combo {
        let o = self.offset[ci];
        if self.nbasis[ci] == 3 {
            vec![(o, 1.0), (o + 1, s), (o + 2, s * s)]
        } else {
            vec![(o, 1.0)]
        }
    }

    /// Derivative of the column of candidate `ci` with respect to its joint's centre shift.
    pub(crate) fn dcol(&self, ci: usize, s: f64) -> Combo {
        let o = self.offset[ci];
        if self.nbasis[ci] == 3 {
            vec![(o + 1, 1.0), (o + 2, 2.0 * s)]
        } else {
            Vec::new()
        }
    }

    /// Inner product of two basis combinations (weighted).
    pub(crate) fn ip(&self, u: &[(usize, f64)], v: &[(usize, f64)]) -> f64 {
        let mut sum = 0.0;
        for &(a, ca) in u {
            for &(b, cb) in v {
                sum += ca * cb * self.gram[(a, b)];
            }
        }
        sum
    }

    /// Inner product of a basis combination with the weighted observations.
    pub(crate) fn iy(&self, u: &[(usize, f64)]) -> f64 {
        u.iter().map(|&(a, c)| c * self.xty[a]).sum()
    }

    /// Weighted prediction `Σ coef · basis` for every equation.
    pub(crate) fn predict(&self, beta: &DVector<f64>) -> DVector<f64> {
        &self.x * beta
    }

    /// Which joint centre shift a candidate depends on (`Some(joint index 1-based)` for joint x/y).
    pub(crate) fn shift_joint(&self, ci: usize) -> Option<usize> {
        match self.candidates[ci] {
            (EdofSite::Joint(i), Axis::X | Axis::Y) => Some(i),
            _ => None,
        }
    }
}

/// Reject data that cannot be used, with a message a technician can act on.
fn check_rows(
    robot: &Robot,
    rows: &[MeasurementRow],
    require_displacement: bool,
) -> Result<(), CalibError> {
    let n = robot.joint_count();
    if rows.is_empty() {
        return Err(CalibError::Invalid("no data rows".into()));
    }
    for (i, row) in rows.iter().enumerate() {
        let at = || {
            format!(
                "row {} (load case {}, point {})",
                i + 1,
                row.load_case,
                row.point
            )
        };
        if row.q_rad.len() != n {
            return Err(CalibError::Invalid(format!(
                "the data has {} joint columns (q1_rad…q{}_rad) but robot \"{}\" has {n} joints",
                row.q_rad.len(),
                row.q_rad.len(),
                robot.name
            )));
        }
        if row.point_link > n || row.load_link > n {
            return Err(CalibError::Invalid(format!(
                "{}: link index out of range (0 = base … {n} = last link)",
                at()
            )));
        }
        let finite = row.q_rad.iter().all(|v| v.is_finite())
            && row.wrench.iter().all(|v| v.is_finite())
            && row.load_point_m.iter().all(|v| v.is_finite())
            && row.point_m.iter().all(|v| v.is_finite())
            && row
                .displacement_m
                .is_none_or(|d| d.iter().all(|v| v.is_finite()))
            && row.sigma_m.is_none_or(|s| s.is_finite() && s > 0.0);
        if !finite {
            return Err(CalibError::Invalid(format!(
                "{}: a value is NaN or infinite (or sigma_m ≤ 0)",
                at()
            )));
        }
        if require_displacement && row.displacement_m.is_none() {
            return Err(CalibError::Invalid(format!(
                "{}: no measured displacement (dx_m, dy_m, dz_m)",
                at()
            )));
        }
    }
    if rows.iter().all(|r| r.wrench.iter().all(|v| *v == 0.0)) {
        return Err(CalibError::Invalid(
            "every load is zero: nothing to identify".into(),
        ));
    }
    Ok(())
}

/// Warn about candidates that no row can see (site beyond every measured/loaded link).
fn observability_warnings(
    rows: &[MeasurementRow],
    candidates: &[EdofId],
    joint_count: usize,
) -> Vec<String> {
    let reach = rows
        .iter()
        .filter(|r| r.wrench.iter().any(|v| *v != 0.0))
        .map(|r| r.point_link.min(r.load_link))
        .max()
        .unwrap_or(0);
    let blind: Vec<String> = candidates
        .iter()
        .filter(|c| c.0.link_index() > reach)
        .map(|&c| edof_label(c))
        .collect();
    if blind.is_empty() {
        return Vec::new();
    }
    let links: std::collections::BTreeSet<usize> = rows.iter().map(|r| r.point_link).collect();
    let where_ = if links.len() == 1 {
        format!("all measured points are on link {}", reach)
    } else {
        format!(
            "no loaded, measured point lies beyond link {reach} (measured links: {})",
            links
                .iter()
                .map(|l| l.to_string())
                .collect::<Vec<_>>()
                .join(", ")
        )
    };
    let _ = joint_count;
    vec![format!(
        "{where_}: eDoF(s) {} cannot be observed (they only move links beyond {reach}); measure a point on a later link",
        blind.join(", ")
    )]
}
