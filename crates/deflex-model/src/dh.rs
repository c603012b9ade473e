//! Denavit–Hartenberg tables → the model's joint placements.
//!
//! Every joint of a [`Robot`] is a fixed placement followed by `RotZ(q_i + θ_i)`; the joint frame
//! R_i sits on joint i's axis with x_i along the common normal towards joint i+1's axis. Both DH
//! conventions describe exactly these frames, only the bookkeeping differs:
//!
//! * **Modified (Craig):** `T(i-1,i) = RotX(α_i)·RotY(β_i)·TransX(a_i)·TransZ(d_i)·RotZ(q_i+θ_i)`,
//!   so `placement_i = RotX(α_i)·RotY(β_i)·TransX(a_i)·TransZ(d_i)` and the flange is R_N.
//! * **Standard:** `F_i = F_{i-1}·RotZ(q_i+θ_i)·TransZ(d_i)·L_i` with
//!   `L_i = TransX(a_i)·RotX(α_i)·RotY(β_i)`. `TransZ(d_i)` commutes with `RotZ`, so with
//!   `R_i = F_{i-1}·TransZ(d_i)·RotZ(q_i+θ_i)` we get `F_i = R_i·L_i`,
//!   `placement_i = L_{i-1}·TransZ(d_i)` (with `L_0 = I`) and `flange = L_N`. A standard table
//!   therefore equals the modified one with `(α, a)` moved one row down and `L_N` as flange;
//!   `tests/standard_dh.rs` checks that on the UR10.
//!
//! β is Hayati's tilt about y for (nearly) parallel consecutive axes, where a small tilt about y
//! would otherwise make `d` jump by metres; it is 0 in nominal tables.

use crate::robot::{DhConvention, DhParams, Robot};
use crate::spatial::Pose;
use nalgebra::{Rotation3, Translation3, Vector3};

fn rot_x(angle: f64) -> Pose {
    Pose::from_parts(
        Translation3::identity(),
        Rotation3::from_axis_angle(&Vector3::x_axis(), angle),
    )
}

fn rot_y(angle: f64) -> Pose {
    Pose::from_parts(
        Translation3::identity(),
        Rotation3::from_axis_angle(&Vector3::y_axis(), angle),
    )
}

fn trans(x: f64, y: f64, z: f64) -> Pose {
    Pose::from_parts(Translation3::new(x, y, z), Rotation3::identity())
}

/// Modified DH placement of joint i: `RotX(α)·RotY(β)·TransX(a)·TransZ(d)`.
pub fn modified_dh_placement(row: &DhParams) -> Pose {
    rot_x(row.alpha) * rot_y(row.beta) * trans(row.a, 0.0, row.d)
}

/// The fixed part `L_i = TransX(a_i)·RotX(α_i)·RotY(β_i)` of a standard DH row: from the joint
/// frame R_i (after `TransZ(d_i)·RotZ`) to the standard DH frame F_i at the end of link i.
pub fn standard_dh_link(row: &DhParams) -> Pose {
    trans(row.a, 0.0, 0.0) * rot_x(row.alpha) * rot_y(row.beta)
}

/// Joint placements and the flange placement of a DH table in `convention`.
pub fn dh_placements(convention: DhConvention, rows: &[DhParams]) -> (Vec<Pose>, Pose) {
    match convention {
        DhConvention::Modified => (
            rows.iter().map(modified_dh_placement).collect(),
            Pose::identity(),
        ),
        DhConvention::Standard => {
            let mut previous_link = Pose::identity();
            let placements = rows
                .iter()
                .map(|row| {
                    let placement = previous_link * trans(0.0, 0.0, row.d);
                    previous_link = standard_dh_link(row);
                    placement
                })
                .collect();
            (placements, previous_link)
        }
    }
}

impl Robot {
    /// Rebuild the joint placements and the flange from the joints' DH rows (after a geometric
    /// calibration changed them), and the link frames in which centres of mass are written.
    /// Does nothing for a robot whose geometry is not a DH table.
    pub fn rebuild_dh_geometry(&mut self) {
        let Some(convention) = self.dh_convention else {
            return;
        };
        let rows: Vec<DhParams> = self
            .joints
            .iter()
            .map(|j| j.dh.unwrap_or_default())
            .collect();
        let (placements, flange) = dh_placements(convention, &rows);
        for ((joint, placement), row) in self.joints.iter_mut().zip(placements).zip(&rows) {
            joint.placement = placement;
            // Centres of mass stay put in R_i; the frame the file writes them in follows the row.
            joint.link_frame = match convention {
                DhConvention::Modified => Pose::identity(),
                DhConvention::Standard => standard_dh_link(row),
            };
        }
        self.flange = flange * self.flange_offset;
    }
}
