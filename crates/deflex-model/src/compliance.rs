//! VJM compliance and deflection: the eDoF Jacobian (eq. 13), the Cartesian compliance
//! `C = J K_θ⁻¹ Jᵀ` and the deflection `δs = J K_θ⁻¹ Jᵀ w` (eq. 15), and the general
//! point-to-point form that a laser tracker sees.

use crate::kinematics::Data;
use crate::robot::{Axis, ComplianceCoupling, Edof, EdofSite, Robot};
use crate::spatial::{Displacement, Wrench, edof_screw};
use crate::{MAX_EDOFS, MAX_JOINTS};
use nalgebra::{DMatrix, Matrix6, Vector3, Vector6};

/// The eDoF Jacobian at one point as fixed-size storage (eq. 13): `columns[..count]` are the
/// columns in [`Robot::edofs`] order. No heap.
#[derive(Clone, Debug)]
pub struct EdofColumns {
    /// Jacobian columns `[v × (p − O); v]`.
    pub columns: [Vector6<f64>; MAX_EDOFS],
    /// The eDoF each column belongs to.
    pub edofs: [Option<Edof>; MAX_EDOFS],
    /// Number of columns filled.
    pub count: usize,
}

impl Robot {
    /// eDoF Jacobian (eq. 13) at a world `point` rigidly attached to link `link` (0 = base,
    /// N = last link): eDoFs of joints with index > `link` do not move the point, so their
    /// columns are zero. Allocation-free.
    pub fn edof_columns(&self, data: &Data, point: &Vector3<f64>, link: usize) -> EdofColumns {
        let mut out = EdofColumns {
            columns: [Vector6::zeros(); MAX_EDOFS],
            edofs: [None; MAX_EDOFS],
            count: 0,
        };
        for edof in self.edofs() {
            let column = if edof.site.link_index() <= link {
                let (axis, center) = data.edof_axis_center(self, edof.site, edof.axis);
                edof_screw(&axis, &center, point)
            } else {
                Vector6::zeros()
            };
            out.columns[out.count] = column;
            out.edofs[out.count] = Some(edof);
            out.count += 1;
        }
        out
    }

    /// The eDoF Jacobian of eq. 13 at the TCP as a 6×n matrix (allocates; for analysis, not for
    /// the control cycle).
    pub fn edof_jacobian(&self, data: &Data) -> DMatrix<f64> {
        let columns = self.edof_columns(data, &data.tcp_position(), self.joint_count());
        DMatrix::from_fn(6, columns.count, |r, c| columns.columns[c][r])
    }

    /// Diagonal articular stiffness matrix K_θ (eq. 11) in [`Robot::edofs`] order.
    pub fn stiffness_matrix(&self) -> DMatrix<f64> {
        let k: Vec<f64> = self.edofs().map(|e| e.stiffness).collect();
        DMatrix::from_diagonal(&nalgebra::DVector::from_vec(k))
    }

    /// Cartesian compliance at the TCP, `C = J K_θ⁻¹ Jᵀ` (eq. 15), 6×6 in world axes, mapping a
    /// wrench at the TCP (moment about the TCP) to `δs = [δp; δφ]`. Symmetric positive
    /// semi-definite. Allocation-free.
    pub fn compliance_matrix(&self, data: &Data) -> Matrix6<f64> {
        let tcp = data.tcp_position();
        let mut compliance = Matrix6::zeros();
        self.for_each_edof_screw(data, |edof, axis, center| {
            let j = edof_screw(axis, center, &tcp);
            compliance += (j * j.transpose()) / edof.stiffness;
        });
        // Off-diagonal joint compliances: `c (j_a j_bᵀ + j_b j_aᵀ)`.
        for coupling in &self.couplings {
            let (ja, jb) = self.coupling_screws(data, coupling, &tcp);
            compliance += (ja * jb.transpose() + jb * ja.transpose()) * coupling.compliance;
        }
        compliance
    }

    /// The screws `(j_a(point), j_b(point))` of a coupling's two eDoFs (eq. 13's columns). The
    /// coupling moves a point P under a wrench w at A by `c (j_a(P) j_b(A)ᵀ + j_b(P) j_a(A)ᵀ) w`.
    #[inline]
    fn coupling_screws(
        &self,
        data: &Data,
        coupling: &ComplianceCoupling,
        point: &Vector3<f64>,
    ) -> (Vector6<f64>, Vector6<f64>) {
        let screw = |(site, axis): (EdofSite, Axis)| {
            let (v, o) = data.edof_axis_center(self, site, axis);
            edof_screw(&v, &o, point)
        };
        (screw(coupling.a), screw(coupling.b))
    }

    /// TCP deflection `δs = J K_θ⁻¹ Jᵀ w` (eq. 15) for a wrench `w` applied at the TCP (world
    /// axes, moment about the TCP). Computed as `Σ_e j_e (j_eᵀ w) / k_e` without forming C:
    /// allocation-free and O(number of eDoFs).
    pub fn tcp_deflection(&self, data: &Data, wrench: &Wrench) -> Displacement {
        let tcp = data.tcp_position();
        let mut deflection = Displacement::zeros();
        self.for_each_edof_screw(data, |edof, axis, center| {
            let j = edof_screw(axis, center, &tcp);
            deflection += j * (j.dot(wrench) / edof.stiffness);
        });
        for coupling in &self.couplings {
            let (ja, jb) = self.coupling_screws(data, coupling, &tcp);
            deflection += (ja * jb.dot(wrench) + jb * ja.dot(wrench)) * coupling.compliance;
        }
        deflection
    }

    /// General VJM transfer: small displacement `[δp; δφ]` of a world point `point` on link
    /// `point_link` caused by a wrench applied at world point `load_point` on link `load_link`
    /// (world axes, moment about `load_point`). An eDoF contributes when it lies between the base
    /// and both links: `δ = Σ_{e: site ≤ min(k, l)} j_e(P) j_e(A)ᵀ w / k_e`; a coupling's
    /// `c j_a(P) j_b(A)ᵀ w` when `a ≤ k` and `b ≤ l` (and the same with a and b swapped). This is what a laser
    /// tracker sees at the paper's points M1..M3; with both points at the TCP on link N it
    /// reduces to eq. 15. Satisfies Maxwell–Betti reciprocity.
    pub fn point_displacement(
        &self,
        data: &Data,
        point: &Vector3<f64>,
        point_link: usize,
        load_point: &Vector3<f64>,
        load_link: usize,
        wrench: &Wrench,
    ) -> Displacement {
        let reach = point_link.min(load_link);
        let mut displacement = Displacement::zeros();
        self.for_each_edof_screw(data, |edof, axis, center| {
            if edof.site.link_index() <= reach {
                let torque = edof_screw(axis, center, load_point).dot(wrench);
                displacement += edof_screw(axis, center, point) * (torque / edof.stiffness);
            }
        });
        // θ_a += c τ_b and θ_b += c τ_a: the torque on b exists when b lies between the base
        // and the load's link, and the rotation of a moves the point when a lies between the
        // base and the point's link (a marker on the upper arm turns with J2 under a torque that
        // only J3 carries). Each term has its own condition; swapping point and load swaps the
        // terms (Maxwell–Betti).
        for coupling in &self.couplings {
            let (ia, ib) = (coupling.a.0.link_index(), coupling.b.0.link_index());
            let (pa, pb) = self.coupling_screws(data, coupling, point);
            let (aa, ab) = self.coupling_screws(data, coupling, load_point);
            if ia <= point_link && ib <= load_link {
                displacement += pa * (ab.dot(wrench) * coupling.compliance);
            }
            if ib <= point_link && ia <= load_link {
                displacement += pb * (aa.dot(wrench) * coupling.compliance);
            }
        }
        displacement
    }

    /// Calls `f(edof, axis, center)` for every eDoF with its world axis and centre.
    #[inline]
    pub(crate) fn for_each_edof_screw(
        &self,
        data: &Data,
        mut f: impl FnMut(&Edof, &Vector3<f64>, &Vector3<f64>),
    ) {
        let base_rotation = data.base_frame.rotation.matrix();
        let base_origin = crate::kinematics::base_pivot_world(&data.base_frame, self);
        for axis in Axis::ALL {
            if let Some(stiffness) = self.base_stiffness.get(axis) {
                let edof = Edof {
                    site: EdofSite::Base,
                    axis,
                    stiffness,
                };
                let v = base_rotation.column(axis.index()).into_owned();
                f(&edof, &v, &base_origin);
            }
        }
        for (i, joint) in self.joints.iter().enumerate().take(MAX_JOINTS) {
            if joint.stiffness.count() == 0 {
                continue;
            }
            let frame = &data.joint_frames[i];
            let rotation = frame.rotation.matrix();
            let center = crate::kinematics::edof_center(frame, joint.center_shift);
            for axis in Axis::ALL {
                if let Some(stiffness) = joint.stiffness.get(axis) {
                    let edof = Edof {
                        site: EdofSite::Joint(i + 1),
                        axis,
                        stiffness,
                    };
                    let v = rotation.column(axis.index()).into_owned();
                    f(&edof, &v, &center);
                }
            }
        }
    }
}
