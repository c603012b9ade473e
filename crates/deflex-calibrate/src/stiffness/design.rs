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
//! A row that also measured the rotation of its link (`rotation_rad`) adds three rotation
//! equations. The angular part of the eDoF screw is `v` alone (no dependence on the moved point,
//! hence none on the centre through it), but the torque still depends on the centre through the
//! load point, so the rotation column is linear in the shift:
//!
//! ```text
//! δφ = Σ_e c_e · v · (j_e(A)ᵀ w),   col_e(s) = v τ₀ − s v (u·f)   (a₂ = 0)
//! ```
//!
//! The rotation equations are weighted by `1/σ_rad` and appended after all position
//! equations (3 per row, in row order), so the same basis/Gram machinery covers both.
//!
//! So the design stores the three *basis* vectors of every x/y joint eDoF (one for z and base
//! eDoFs, where `u = 0`) once, together with their Gram matrix. Every fit of every candidate
//! structure, with any centre shifts, then costs O(p²) inner products of precomputed numbers,
//! independent of the number of rows: this is what makes the structure search fast.

use crate::measurements::{DEFAULT_SIGMA_M, MeasurementRow};
use crate::stiffness::{CalibError, RowRef, RowsError, StructureError};
use deflex_model::{Axis, Data, EdofSite, Robot};
use nalgebra::{DMatrix, DVector, Vector3};

/// One eDoF, by site and axis.
pub type EdofId = (EdofSite, Axis);

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
    /// Weighted basis values, one row per equation: 3 per data row (δp x, y, z), then 3 per
    /// row with a measured rotation (δφ x, y, z), from `3 · rows` on.
    pub(crate) x: DMatrix<f64>,
    /// Weighted observations.
    pub(crate) y: DVector<f64>,
    /// Standard deviation of each equation (m for positions, rad for rotations).
    pub(crate) sigma: Vec<f64>,
    /// Gram matrix `XᵀX` of the basis.
    pub(crate) gram: DMatrix<f64>,
    /// `Xᵀy`.
    pub(crate) xty: DVector<f64>,
    /// `yᵀy`.
    pub(crate) yty: f64,
    /// Number of data rows.
    pub rows: usize,
    /// Number of rows with a measured rotation (3 rotation equations each).
    pub rotation_rows: usize,
    /// Number of distinct readings: rows that differ in configuration, load, point or
    /// measured value (a repeated row adds no information about the parameters).
    pub distinct_rows: usize,
    /// Number of joints of the robot.
    pub joint_count: usize,
    /// Observations about the data that do not stop the fit (e.g. unobservable eDoFs).
    pub warnings: Vec<String>,
}

impl Design {
    /// Build the design for `candidates` from measurement rows (`require_displacement`) or plan
    /// rows (observations taken as zero, for information/Fisher computations). Only the robot's
    /// geometry (and base pivot) is used; its stiffnesses and centre shifts are ignored (shifts
    /// are parameters).
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
                return Err(StructureError::NoSuchEdof {
                    joint: i,
                    axis: axis.letter(),
                    joints: n,
                }
                .into());
            }
            let k = match (site, axis) {
                (EdofSite::Joint(_), Axis::X | Axis::Y) => 3,
                _ => 1,
            };
            offset.push(nb);
            nbasis.push(k);
            nb += k;
        }
        let rotation_rows = rows.iter().filter(|r| r.rotation_rad.is_some()).count();
        let neq = 3 * rows.len() + 3 * rotation_rows;
        let mut x = DMatrix::<f64>::zeros(neq, nb);
        let mut y = DVector::<f64>::zeros(neq);
        let mut sigma = vec![DEFAULT_SIGMA_M; neq];
        let mut next_rotation = 3 * rows.len();
        let mut data = Data::new();
        let mut last_q: Option<&[f64]> = None;
        for (r, row) in rows.iter().enumerate() {
            if last_q != Some(row.q_rad.as_slice()) {
                robot.forward_kinematics(&mut data, &row.q_rad)?;
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
            // Rotation equations of this row: (first equation, weight).
            let rotation = row.rotation_rad.map(|m| {
                let e0 = next_rotation;
                next_rotation += 3;
                let sr = m.sigma();
                for ax in 0..3 {
                    sigma[e0 + ax] = sr;
                    y[e0 + ax] = m.value_rad[ax] / sr;
                }
                (e0, 1.0 / sr)
            });
            for (ci, &(site, axis)) in candidates.iter().enumerate() {
                if site.link_index() > reach {
                    continue;
                }
                let frame = data.link_frame(site.link_index());
                let rot = frame.rotation.matrix();
                let v: Vector3<f64> = rot.column(axis.index()).into_owned();
                // A joint's centre shift is a parameter (the basis below); the base tilts about
                // the robot's pivot.
                let o = match site {
                    EdofSite::Base => data.edof_axis_center(robot, site, axis).1,
                    EdofSite::Joint(_) => frame.translation.vector,
                };
                let l0 = v.cross(&(p - o));
                let t0 = v.cross(&(a - o)).dot(&f) + v.dot(&m);
                let a0 = l0 * t0;
                let base = offset[ci];
                for ax in 0..3 {
                    x[(3 * r + ax, base)] = a0[ax] * wgt;
                }
                if let Some((e0, wr)) = rotation {
                    for ax in 0..3 {
                        x[(e0 + ax, base)] = v[ax] * t0 * wr;
                    }
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
                    // Rotation: a₁ = −v (u·f), a₂ = 0.
                    if let Some((e0, wr)) = rotation {
                        for ax in 0..3 {
                            x[(e0 + ax, base + 1)] = -v[ax] * uf * wr;
                        }
                    }
                }
            }
        }
        let gram = x.tr_mul(&x);
        let xty = x.tr_mul(&y);
        let yty = y.norm_squared();
        // Bounded inputs keep these finite; a guard so that no decomposition ever sees NaN.
        if !(yty.is_finite()
            && gram.iter().all(|v| v.is_finite())
            && xty.iter().all(|v| v.is_finite()))
        {
            return Err(RowsError::Overflow.into());
        }
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
            rotation_rows,
            distinct_rows: distinct_rows(rows),
            joint_count: n,
            warnings,
        })
    }

    /// Number of equations (3 per row, plus 3 per row with a measured rotation).
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

/// Rows that differ in configuration, load, point or measured value (bit for bit).
pub fn distinct_rows(rows: &[MeasurementRow]) -> usize {
    let key = |r: &MeasurementRow| -> Vec<u64> {
        let mut k: Vec<u64> = r.q_rad.iter().map(|v| v.to_bits()).collect();
        k.extend(r.wrench.iter().map(|v| v.to_bits()));
        k.push(r.load_link as u64);
        k.extend(r.load_point_m.iter().map(|v| v.to_bits()));
        k.push(r.point_link as u64);
        k.extend(r.point_m.iter().map(|v| v.to_bits()));
        if let Some(d) = r.displacement_m {
            k.extend(d.iter().map(|v| v.to_bits()));
        }
        if let Some(rot) = r.rotation_rad {
            k.extend(rot.value_rad.iter().map(|v| v.to_bits()));
        }
        k
    };
    let mut keys: Vec<Vec<u64>> = rows.iter().map(key).collect();
    keys.sort_unstable();
    keys.dedup();
    keys.len()
}

/// Smallest and largest measurement standard deviation a fit accepts (m and rad alike): below
/// a nanometre the weights overflow, above a metre a reading says nothing about a deflection.
pub const SIGMA_RANGE: (f64, f64) = (1e-9, 1.0);

/// Reject data that cannot be used, with a message a technician can act on.
pub(crate) fn check_rows(
    robot: &Robot,
    rows: &[MeasurementRow],
    require_displacement: bool,
) -> Result<(), RowsError> {
    check_row_set(robot, rows, require_displacement)?;
    if rows.iter().all(|r| r.wrench.iter().all(|v| *v == 0.0)) {
        return Err(RowsError::AllLoadsZero);
    }
    let (lo, hi) = SIGMA_RANGE;
    for (i, r) in rows.iter().enumerate() {
        let sigmas = [
            ("sigma_m", r.sigma_m),
            ("sigma_rad", r.rotation_rad.and_then(|rot| rot.sigma_rad)),
        ];
        for (column, sigma) in sigmas {
            if let Some(got) = sigma
                && !(lo..=hi).contains(&got)
            {
                return Err(RowsError::SigmaOutOfRange {
                    row: RowRef::of(i, r),
                    column,
                    got,
                });
            }
        }
    }
    if require_displacement
        && rows.iter().all(|r| {
            r.displacement_m
                .is_some_and(|d| d.iter().all(|v| *v == 0.0))
        })
    {
        return Err(RowsError::AllDisplacementsZero);
    }
    Ok(())
}

/// Rows the model can predict: at least one, one joint value per joint, links within the arm,
/// every value within the bounds of the file format (rows built in code are checked as a file's
/// are at parse time), and with `require_displacement` a measured displacement on every row.
pub(crate) fn check_row_set(
    robot: &Robot,
    rows: &[MeasurementRow],
    require_displacement: bool,
) -> Result<(), RowsError> {
    if rows.is_empty() {
        return Err(RowsError::NoRows);
    }
    for (i, row) in rows.iter().enumerate() {
        check_row_fits(robot, i, row)?;
        if let Err(source) = crate::measurements::check_row_values(row) {
            return Err(RowsError::Value {
                row: RowRef::of(i, row),
                source,
            });
        }
        if require_displacement && row.displacement_m.is_none() {
            return Err(RowsError::NoDisplacement {
                row: RowRef::of(i, row),
            });
        }
    }
    Ok(())
}

/// A row the robot can predict: one joint value per joint, links within the arm (what a file's
/// parser cannot know: it does not know the robot).
pub(crate) fn check_row_fits(
    robot: &Robot,
    index: usize,
    row: &MeasurementRow,
) -> Result<(), RowsError> {
    let n = robot.joint_count();
    if row.q_rad.len() != n {
        return Err(RowsError::JointCount {
            found: row.q_rad.len(),
            robot: robot.name.clone(),
            joints: n,
        });
    }
    if row.point_link > n || row.load_link > n {
        return Err(RowsError::LinkOutOfRange {
            row: RowRef::of(index, row),
            joints: n,
        });
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
