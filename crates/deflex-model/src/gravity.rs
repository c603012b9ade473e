//! Gravity-induced deflection through the same eDoFs as the load model.
//!
//! Body i (the link moved by joint i and everything rigidly attached up to joint i+1) has mass
//! m_i and centre of mass c_i (world, at the current configuration); the payload hangs on the
//! flange. Gravity is a force `m_i g` at c_i, so by eq. 14 the torque on an eDoF e (axis v_e,
//! centre O_e, site s_e) is the sum over the bodies it carries:
//!
//! `τ_e = Σ_{i ≥ s_e} j_e(c_i)ᵀ [m_i g; 0] = Σ_{i ≥ s_e} (v_e × (c_i − O_e)) · m_i g`
//!
//! and, as for an external load, the spring turns by `δθ_e = τ_e / k_e` and a point P on link k
//! moves by `Σ_{e: s_e ≤ k} j_e(P) δθ_e`. Torques are evaluated on the undeflected pose (first
//! order, like eq. 15). The base eDoFs carry every body. Bodies without a known inertia weigh
//! nothing. Allocation-free.

use crate::kinematics::Data;
use crate::robot::Robot;
use crate::spatial::Displacement;
use crate::spatial::edof_screw;
use crate::{MAX_EDOFS, MAX_JOINTS};
use nalgebra::Vector3;

/// Gravity forces of the bodies at one configuration: world centre of mass and weight (N) of
/// body i at index i−1; the payload is folded into the last body.
#[derive(Clone, Copy, Debug)]
struct BodyWeights {
    com: [Vector3<f64>; MAX_JOINTS],
    weight: [Vector3<f64>; MAX_JOINTS],
    count: usize,
}

impl Robot {
    fn body_weights(&self, data: &Data) -> BodyWeights {
        let mut out = BodyWeights {
            com: [Vector3::zeros(); MAX_JOINTS],
            weight: [Vector3::zeros(); MAX_JOINTS],
            count: self.joints.len(),
        };
        for (i, joint) in self.joints.iter().enumerate() {
            if let Some(inertia) = &joint.inertia {
                out.com[i] = data.joint_frames[i]
                    .transform_point(&inertia.com.into())
                    .coords;
                out.weight[i] = self.gravity * inertia.mass_kg;
            }
        }
        if let Some(payload) = &self.payload
            && payload.mass_kg > 0.0
        {
            let last = self.joints.len() - 1;
            let payload_com = data.flange.transform_point(&payload.com.into()).coords;
            let total = out.weight[last] + self.gravity * payload.mass_kg;
            let body_mass = self.joints[last].inertia.map_or(0.0, |i| i.mass_kg);
            let mass = body_mass + payload.mass_kg;
            // Combined centre of mass of the last body and the payload.
            out.com[last] = (out.com[last] * body_mass + payload_com * payload.mass_kg) / mass;
            out.weight[last] = total;
        }
        out
    }

    /// Gravity torque on every eDoF (N·m), in [`Robot::edofs`] order: `τ_e` of the module
    /// documentation. The first [`Robot::edof_count`] entries are filled.
    pub fn gravity_edof_torques(&self, data: &Data) -> [f64; MAX_EDOFS] {
        let bodies = self.body_weights(data);
        let mut torques = [0.0; MAX_EDOFS];
        let mut index = 0;
        self.for_each_edof_screw(data, |edof, axis, center| {
            let first_body = edof.site.link_index().max(1) - 1;
            let mut torque = 0.0;
            for body in first_body..bodies.count {
                let screw = edof_screw(axis, center, &bodies.com[body]);
                torque += screw.fixed_rows::<3>(0).dot(&bodies.weight[body]);
            }
            torques[index] = torque;
            index += 1;
        });
        torques
    }

    /// Small displacement `[δp; δφ]` of a world point on link `point_link` caused by the
    /// robot's own weight and its payload: `Σ_{e: s_e ≤ k} j_e(P) τ_e / k_e` (module
    /// documentation). Zero for a robot without masses.
    pub fn gravity_displacement(
        &self,
        data: &Data,
        point: &Vector3<f64>,
        point_link: usize,
    ) -> Displacement {
        let torques = self.gravity_edof_torques(data);
        let mut displacement = Displacement::zeros();
        let mut index = 0;
        self.for_each_edof_screw(data, |edof, axis, center| {
            if edof.site.link_index() <= point_link {
                displacement += edof_screw(axis, center, point) * (torques[index] / edof.stiffness);
            }
            index += 1;
        });
        // Off-diagonal compliances: θ_a += c τ_b, θ_b += c τ_a.
        for coupling in &self.couplings {
            if coupling.a.0.link_index() > point_link || coupling.b.0.link_index() > point_link {
                continue;
            }
            let index_of = |(site, axis): (crate::EdofSite, crate::Axis)| {
                self.edofs().position(|e| e.site == site && e.axis == axis)
            };
            if let (Some(ia), Some(ib)) = (index_of(coupling.a), index_of(coupling.b)) {
                let screw = |(site, axis)| {
                    let (v, o) = data.edof_axis_center(self, site, axis);
                    edof_screw(&v, &o, point)
                };
                displacement += (screw(coupling.a) * torques[ib] + screw(coupling.b) * torques[ia])
                    * coupling.compliance;
            }
        }
        displacement
    }
}
