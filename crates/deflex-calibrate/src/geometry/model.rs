//! Prediction of absolute and loaded readings (their Jacobians: [`crate::geometry::jacobian`]).
//!
//! **Absolute reading** of target t in set-up s at joint values q:
//!
//! `p_tracker = R_s · (p_w + δp_w) + t_s`, with `p_w = F(q')·t` the target on the flange of the
//! rigid model (`q' = q + Δθ(q, approach)`: the joint-angle harmonics and the
//! direction-dependent offsets) and `δp_w = Σ_e c_e · τ_e · (v_e × (p_w − O_e))` the elastic
//! sag: eDoF e (axis v_e, centre O_e, compliance c_e) turns by `c_e τ_e` under the torque
//! `τ_e = Σ_{b ≥ site(e)} (v_e × (m_b (o_b − O_e) + R_b h_b)) · g + (v_e × (p_w − O_e)) · f + v_e · μ`
//! of gravity on the bodies it carries (mass m_b, first moment h_b = m_b c_b in joint frame b
//! of origin o_b, rotation R_b; payload folded into the last body) and of an external wrench
//! (f, μ) at the target. First order in the deflection, like eq. 15 of the paper. With
//! nonlinear torsion terms ([`crate::geometry::params::TorsionShape`]) the turn `c_e τ_e` becomes
//! `c_e τ_e + Σ a g(τ_e)` (the loaded readings below keep the linear compliance).
//!
//! With a residual model ([`crate::geometry::residual_model`]) its correction `R_1(q) Δ(q)` (learnt in
//! joint 1's frame R_1) is added to `p_w + δp_w`.
//!
//! **Measured orientation** of the same target (a 6-DoF probe):
//! `R_tracker = R_s · exp(θ_sag) · R_F(q') · R_t`, with `θ_sag = Σ_e c_e τ_e v_e` the sag's
//! rotation (world axes) and `R_t` the target frame on the flange.
//!
//! **Loaded reading** (the stiffness campaign's rows): displacement loaded − unloaded of point P
//! on link k under wrench w at A on link l, `Σ_{e: site ≤ min(k,l)} c_e j_e(P) j_e(A)ᵀ w`.

use crate::geometry::params::EgModel;
use crate::measurements::MeasurementRow;
use deflex_model::{Data, MAX_EDOFS, MAX_JOINTS};
use nalgebra::{Rotation3, Vector3};

/// Which joint frame quantities a column needs, precomputed per configuration.
pub struct Evaluation {
    /// Forward kinematics of the rigid model at q'.
    pub data: Data,
    /// Joint values as measured (before the harmonic offsets).
    pub q_raw: [f64; MAX_JOINTS],
    /// Approach motion of each joint (rad; 0 = unknown), see [`Conditions::approach_rad`].
    pub approach: [f64; MAX_JOINTS],
    /// Target on the flange, world, rigid (m).
    pub target_world: Vector3<f64>,
    /// Target frame's rotation, world, rigid: `R_F R_t`.
    pub target_rotation: Rotation3<f64>,
    /// Elastic sag of the target, world (m).
    pub sag_world: Vector3<f64>,
    /// Correction of the residual model at q, world (m; zero without one).
    pub correction_world: Vector3<f64>,
    /// Elastic rotation of the flange, world rotation vector `Σ c_e τ_e v_e` (rad).
    pub sag_rotation: Vector3<f64>,
    /// Torque on each eDoF (N·m), [`deflex_model::Robot::edofs`] order.
    pub torque: [f64; MAX_EDOFS],
    /// Turn of each eDoF under its torque, `c τ + Σ a g(τ)` (rad).
    pub turn: [f64; MAX_EDOFS],
    /// Slope of each eDoF's turn, `c + Σ a g'(τ)` (rad/(N·m)).
    pub turn_slope: [f64; MAX_EDOFS],
    /// Linear part of each eDoF's screw at the target: `v_e × (p − O_e)`.
    pub screw_linear: [Vector3<f64>; MAX_EDOFS],
    /// Axis and centre of each eDoF.
    pub axis_center: [(Vector3<f64>, Vector3<f64>); MAX_EDOFS],
    /// Site (0 = base, i = joint i) of each eDoF.
    pub site: [usize; MAX_EDOFS],
    /// Number of eDoFs.
    pub edof_count: usize,
    /// External force at the target, world (N), if any.
    pub force: Option<Vector3<f64>>,
    /// External moment, world (N·m), if any.
    pub moment: Option<Vector3<f64>>,
    /// Mass of each body (kg), payload excluded.
    pub body_mass: [f64; MAX_JOINTS],
    /// World first moment m·c of each body (kg·m), payload excluded.
    pub body_moment: [Vector3<f64>; MAX_JOINTS],
    /// Payload mass (kg) and world first moment (kg·m); it rides on the flange.
    pub payload: (f64, Vector3<f64>),
}

impl Evaluation {
    /// Predicted target position, world: rigid + sag + residual model (m).
    pub fn predicted_world(&self) -> Vector3<f64> {
        self.target_world + self.sag_world + self.correction_world
    }
}

/// What acts on one reading besides its joint values: a payload, an external wrench, and the
/// direction each joint approached from.
#[derive(Clone, Copy, Debug, Default)]
pub struct Conditions {
    /// Payload mass (kg) and centre of mass in the flange frame (m).
    pub payload: Option<(f64, Vector3<f64>)>,
    /// External wrench at the target, world axes, moment about the target.
    pub wrench: Option<[f64; 6]>,
    /// Joint motion that brought the robot here (rad; its sign is the approach direction, 0 =
    /// unknown).
    pub approach_rad: [f64; MAX_JOINTS],
}

impl EgModel {
    /// Evaluate the rigid pose, torques and sag of target `target` at joint values `q`.
    pub fn evaluate(&self, q: &[f64], target: usize, conditions: &Conditions) -> Evaluation {
        let robot = &self.robot;
        let n = robot.joint_count();
        let mut q_effective = [0.0; MAX_JOINTS];
        self.effective_q(q, &conditions.approach_rad[..n], &mut q_effective);
        let mut data = Data::new();
        robot
            .forward_kinematics(&mut data, &q_effective[..n])
            .expect("joint count checked when the data was read");
        let target_world = data
            .flange
            .transform_point(&self.targets[target].position.into())
            .coords;
        let target_rotation = data.flange.rotation * self.target_rotation(target);
        let mut q_raw = [0.0; MAX_JOINTS];
        q_raw[..n].copy_from_slice(q);
        let mut out = Evaluation {
            data,
            q_raw,
            approach: conditions.approach_rad,
            target_world,
            target_rotation,
            sag_world: Vector3::zeros(),
            correction_world: Vector3::zeros(),
            sag_rotation: Vector3::zeros(),
            torque: [0.0; MAX_EDOFS],
            turn: [0.0; MAX_EDOFS],
            turn_slope: [0.0; MAX_EDOFS],
            screw_linear: [Vector3::zeros(); MAX_EDOFS],
            axis_center: [(Vector3::zeros(), Vector3::zeros()); MAX_EDOFS],
            site: [0; MAX_EDOFS],
            edof_count: 0,
            force: conditions.wrench.map(|w| Vector3::new(w[0], w[1], w[2])),
            moment: conditions.wrench.map(|w| Vector3::new(w[3], w[4], w[5])),
            body_mass: [0.0; MAX_JOINTS],
            body_moment: [Vector3::zeros(); MAX_JOINTS],
            payload: (0.0, Vector3::zeros()),
        };
        if let Some(r) = &self.residual {
            out.correction_world = out.data.joint_frames[0].rotation * r.predict(&q[..n]);
        }
        let (mass, moment) = self.body_weights(&mut out, conditions);
        for (e, edof) in robot.edofs().enumerate() {
            let (axis, center) = out.data.edof_axis_center(robot, edof.site, edof.axis);
            let site = edof.site.link_index();
            let first_body = site.max(1) - 1;
            let mut torque = 0.0;
            for b in first_body..n {
                // Σ (v × (m c − m O)) · g
                torque += axis
                    .cross(&(moment[b] - center * mass[b]))
                    .dot(&robot.gravity);
            }
            let linear = axis.cross(&(target_world - center));
            if let Some(w) = conditions.wrench {
                torque += linear.dot(&Vector3::new(w[0], w[1], w[2]))
                    + axis.dot(&Vector3::new(w[3], w[4], w[5]));
            }
            let (turn, slope) = self.edof_turn(e, torque);
            out.torque[e] = torque;
            out.turn[e] = turn;
            out.turn_slope[e] = slope;
            out.screw_linear[e] = linear;
            out.axis_center[e] = (axis, center);
            out.site[e] = site;
            out.sag_world += linear * turn;
            out.sag_rotation += axis * turn;
            out.edof_count = e + 1;
        }
        out
    }

    /// Fill the bodies' masses and world first moments (payload excluded) into `ev`; return
    /// them with the payload folded into the last body.
    fn body_weights(
        &self,
        ev: &mut Evaluation,
        conditions: &Conditions,
    ) -> ([f64; MAX_JOINTS], [Vector3<f64>; MAX_JOINTS]) {
        let n = self.robot.joint_count();
        let mut mass = [0.0; MAX_JOINTS];
        let mut moment = [Vector3::zeros(); MAX_JOINTS];
        for (b, lumped) in self.lumped.iter().enumerate().take(n) {
            let frame = &ev.data.joint_frames[b];
            mass[b] = lumped[0];
            moment[b] = frame.translation.vector * lumped[0]
                + frame.rotation * Vector3::new(lumped[1], lumped[2], lumped[3]);
        }
        ev.body_mass = mass;
        ev.body_moment = moment;
        if let Some((m, com)) = conditions.payload {
            let com_world = ev.data.flange.transform_point(&com.into()).coords;
            ev.payload = (m, com_world * m);
            mass[n - 1] += m;
            moment[n - 1] += com_world * m;
        }
        (mass, moment)
    }

    /// Predicted target position in set-up `setup`'s tracker frame.
    pub fn predict_tracker(
        &self,
        q: &[f64],
        setup: usize,
        target: usize,
        conditions: &Conditions,
    ) -> Vector3<f64> {
        let ev = self.evaluate(q, target, conditions);
        self.tracker_position(&ev, setup)
    }

    /// Target position of an evaluation in set-up `setup`'s tracker frame.
    pub fn tracker_position(&self, ev: &Evaluation, setup: usize) -> Vector3<f64> {
        self.setups[setup]
            .pose
            .transform_point(&ev.predicted_world().into())
            .coords
    }

    /// Target frame's orientation of an evaluation in set-up `setup`'s tracker frame:
    /// `R_s · exp(θ_sag) · R_F · R_t`.
    pub fn tracker_orientation(&self, ev: &Evaluation, setup: usize) -> Rotation3<f64> {
        self.setups[setup].pose.rotation
            * Rotation3::from_scaled_axis(ev.sag_rotation)
            * ev.target_rotation
    }

    /// Predicted target orientation in set-up `setup`'s tracker frame.
    pub fn predict_orientation(
        &self,
        q: &[f64],
        setup: usize,
        target: usize,
        conditions: &Conditions,
    ) -> Rotation3<f64> {
        let ev = self.evaluate(q, target, conditions);
        self.tracker_orientation(&ev, setup)
    }

    /// Predicted displacement (loaded − unloaded) of a loaded reading (the stiffness
    /// campaign's row: point, load point, links and wrench, world axes), and the column of each
    /// compliance in `columns` (others zero).
    pub fn loaded_displacement(
        &self,
        row: &MeasurementRow,
        columns: &mut [Vector3<f64>; MAX_EDOFS],
    ) -> Vector3<f64> {
        let (q, point, point_link) = (&row.q_rad, Vector3::from(row.point_m), row.point_link);
        let (load_point, load_link, wrench) =
            (Vector3::from(row.load_point_m), row.load_link, &row.wrench);
        let n = self.robot.joint_count();
        let mut q_effective = [0.0; MAX_JOINTS];
        self.effective_q(q, &[], &mut q_effective);
        let mut data = Data::new();
        self.robot
            .forward_kinematics(&mut data, &q_effective[..n])
            .expect("joint count checked when the data was read");
        let reach = point_link.min(load_link);
        let force = Vector3::new(wrench[0], wrench[1], wrench[2]);
        let moment = Vector3::new(wrench[3], wrench[4], wrench[5]);
        let mut total = Vector3::zeros();
        for (e, edof) in self.robot.edofs().enumerate() {
            columns[e] = Vector3::zeros();
            if edof.site.link_index() > reach {
                continue;
            }
            let (axis, center) = data.edof_axis_center(&self.robot, edof.site, edof.axis);
            let torque = axis.cross(&(load_point - center)).dot(&force) + axis.dot(&moment);
            columns[e] = axis.cross(&(point - center)) * torque;
            total += columns[e] * self.compliance[e];
        }
        total
    }
}
