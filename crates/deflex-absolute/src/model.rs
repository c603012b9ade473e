//! Prediction of absolute and loaded readings, and their analytic Jacobians.
//!
//! **Absolute reading** of target t in set-up s at joint values q:
//!
//! `p_tracker = R_s · (p_w + δp_w) + t_s`, with `p_w = F(q')·t` the target on the flange of the
//! rigid model (`q' = q + Δθ(q)`, the joint-angle harmonics) and
//! `δp_w = Σ_e c_e · τ_e · (v_e × (p_w − O_e))` the elastic sag: eDoF e (axis v_e, centre O_e,
//! compliance c_e) turns by `c_e τ_e` under the torque
//! `τ_e = Σ_{b ≥ site(e)} (v_e × (m_b (o_b − O_e) + R_b h_b)) · g + (v_e × (p_w − O_e)) · f + v_e · μ`
//! of gravity on the bodies it carries (mass m_b, first moment h_b = m_b c_b in joint frame b
//! of origin o_b, rotation R_b; payload folded into the last body) and of an external wrench
//! (f, μ) at the target. First order in the deflection, like eq. 15 of the paper.
//!
//! **Loaded reading** (the stiffness campaign's rows): displacement loaded − unloaded of point P
//! on link k under wrench w at A on link l, `Σ_{e: site ≤ min(k,l)} c_e j_e(P) j_e(A)ᵀ w`.
//!
//! **Jacobian.** Every kinematic parameter is a screw at a known frame of the chain:
//! a rotation δ about unit axis u through point o moves p by `u × (p − o) δ`, a translation
//! along u by `u δ`. With the model's joint frames R_i:
//!
//! * standard DH (`F_i = R_i·TransX(a_i)·RotX(α_i)·RotY(β_i)`, R_i after `TransZ(d_i)·RotZ`):
//!   θ_i: `z_i × (p − o_i)`; d_i: `z_i`; a_i: `x_i`; α_i: `x_i × (p − o_i − a_i x_i)`;
//!   β_i: `y'_i × (p − o_i − a_i x_i)` with `y'_i = R_i RotX(α_i) e_y`;
//! * modified DH (`R_i = R_{i−1}·RotX(α_i)·RotY(β_i)·TransX(a_i)·TransZ(d_i)·RotZ`):
//!   α_i: `x_{i−1} × (p − o_{i−1})`; β_i: `y'_{i−1} × (p − o_{i−1})` with
//!   `y'_{i−1} = R_{i−1} RotX(α_i) e_y`; a_i: `R_{i−1}RotX(α_i)RotY(β_i) e_x`; d_i: `z_i`;
//!   θ_i: `z_i × (p − o_i)`.
//!
//! Target coordinate k: the flange's axis u_k, plus the change of the sag as the target moves
//! (`Σ_e c_e [τ_e (v_e × u_k) + j_e ((v_e × u_k)·f)]`). Compliance c_e: `τ_e j_e(p)`. Lumped mass and
//! first moment of body b: `Σ_e c_e j_e(p) ∂τ_e/∂(m_b, h_b)`, with `∂τ_e/∂m_b = (v_e × (o_b −
//! O_e))·g` and `∂τ_e/∂h_b = R_bᵀ (g × v_e)`. Harmonic `cos(n q_j)`: the θ_j column times
//! `cos(n q_j)`. Set-up s (increments in robot-world axes, `R_s ← R_s exp(φ)`,
//! `t_s ← t_s + R_s δt`): rotation k: `R_s (e_k × p̂_w)`; translation k: `R_s e_k`. World columns
//! are turned into the tracker frame by `R_s`.
//!
//! Each kinematic column also carries the change of the sag: the parameter's small rigid
//! motion ([`Twist`]) moves the eDoF axes and centres, the bodies, the payload and the target
//! distal to it, which changes both the screws and the gravity torques. `tests/jacobian.rs`
//! checks every column against central finite differences of the full prediction.

use crate::params::{DhField, EgModel, Param};
use deflex_model::{Data, DhConvention, MAX_EDOFS, MAX_JOINTS};
use nalgebra::{Rotation3, Vector3};

/// Which joint frame quantities a kinematic column needs, precomputed per configuration.
pub struct Evaluation {
    /// Forward kinematics of the rigid model at q'.
    pub data: Data,
    /// Joint values as measured (before the harmonic offsets).
    pub q_raw: [f64; MAX_JOINTS],
    /// Target on the flange, world, rigid (m).
    pub target_world: Vector3<f64>,
    /// Elastic sag of the target, world (m).
    pub sag_world: Vector3<f64>,
    /// Torque on each eDoF (N·m), [`deflex_model::Robot::edofs`] order.
    pub torque: [f64; MAX_EDOFS],
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

/// A kinematic parameter as a small rigid motion of everything distal to where it acts:
/// a rotation about `axis` through `point` (per unit parameter) plus a translation `linear`;
/// joint frames with index ≥ `first_frame` (0-based), their bodies and eDoFs, the flange, the
/// target and the payload move.
#[derive(Clone, Copy, Debug)]
pub struct Twist {
    /// Rotation axis × rate (zero for a translation).
    pub axis: Vector3<f64>,
    /// A point on the rotation axis.
    pub point: Vector3<f64>,
    /// Translation rate (zero for a rotation).
    pub linear: Vector3<f64>,
    /// First joint frame moved.
    pub first_frame: usize,
}

impl Twist {
    fn point_rate(&self, x: &Vector3<f64>) -> Vector3<f64> {
        self.axis.cross(&(x - self.point)) + self.linear
    }
}

/// A payload and an external wrench for one evaluation.
#[derive(Clone, Copy, Debug, Default)]
pub struct Loads {
    /// Payload mass (kg) and centre of mass in the flange frame (m).
    pub payload: Option<(f64, Vector3<f64>)>,
    /// External wrench at the target, world axes, moment about the target.
    pub wrench: Option<[f64; 6]>,
}

impl EgModel {
    /// Evaluate the rigid pose, torques and sag of target `target` at joint values `q`.
    pub fn evaluate(&self, q: &[f64], target: usize, loads: &Loads) -> Evaluation {
        let robot = &self.robot;
        let n = robot.joint_count();
        let mut q_effective = [0.0; MAX_JOINTS];
        self.effective_q(q, &mut q_effective);
        let mut data = Data::new();
        robot
            .forward_kinematics(&mut data, &q_effective[..n])
            .expect("joint count checked when the data was read");
        let target_world = data
            .flange
            .transform_point(&self.targets[target].position.into())
            .coords;
        let mut q_raw = [0.0; MAX_JOINTS];
        q_raw[..n].copy_from_slice(q);
        let mut out = Evaluation {
            data,
            q_raw,
            target_world,
            sag_world: Vector3::zeros(),
            torque: [0.0; MAX_EDOFS],
            screw_linear: [Vector3::zeros(); MAX_EDOFS],
            axis_center: [(Vector3::zeros(), Vector3::zeros()); MAX_EDOFS],
            site: [0; MAX_EDOFS],
            edof_count: 0,
            force: loads.wrench.map(|w| Vector3::new(w[0], w[1], w[2])),
            moment: loads.wrench.map(|w| Vector3::new(w[3], w[4], w[5])),
            body_mass: [0.0; MAX_JOINTS],
            body_moment: [Vector3::zeros(); MAX_JOINTS],
            payload: (0.0, Vector3::zeros()),
        };
        // Body weights: m_b and the world first moment m_b c_b (payload folded into the last).
        let g = robot.gravity;
        let mut mass = [0.0; MAX_JOINTS];
        let mut moment = [Vector3::zeros(); MAX_JOINTS];
        for (b, lumped) in self.lumped.iter().enumerate().take(n) {
            let frame = &out.data.joint_frames[b];
            mass[b] = lumped[0];
            moment[b] = frame.translation.vector * lumped[0]
                + frame.rotation * Vector3::new(lumped[1], lumped[2], lumped[3]);
        }
        out.body_mass = mass;
        out.body_moment = moment;
        if let Some((m, com)) = loads.payload {
            let com_world = out.data.flange.transform_point(&com.into()).coords;
            out.payload = (m, com_world * m);
            mass[n - 1] += m;
            moment[n - 1] += com_world * m;
        }
        for (e, edof) in robot.edofs().enumerate() {
            let (axis, center) = out.data.edof_axis_center(robot, edof.site, edof.axis);
            let site = edof.site.link_index();
            let first_body = site.max(1) - 1;
            let mut torque = 0.0;
            for b in first_body..n {
                // Σ (v × (m c − m O)) · g
                torque += axis.cross(&(moment[b] - center * mass[b])).dot(&g);
            }
            let linear = axis.cross(&(target_world - center));
            if let Some(w) = loads.wrench {
                torque += linear.dot(&Vector3::new(w[0], w[1], w[2]))
                    + axis.dot(&Vector3::new(w[3], w[4], w[5]));
            }
            out.torque[e] = torque;
            out.screw_linear[e] = linear;
            out.axis_center[e] = (axis, center);
            out.site[e] = site;
            out.sag_world += linear * (self.compliance[e] * torque);
            out.edof_count = e + 1;
        }
        out
    }

    /// Predicted target position in set-up `setup`'s tracker frame.
    pub fn predict_tracker(
        &self,
        q: &[f64],
        setup: usize,
        target: usize,
        loads: &Loads,
    ) -> Vector3<f64> {
        let ev = self.evaluate(q, target, loads);
        self.setups[setup]
            .pose
            .transform_point(&(ev.target_world + ev.sag_world).into())
            .coords
    }

    /// World-frame column of one kinematic, target, compliance, mass or harmonic parameter at
    /// an evaluation (set-up parameters: see [`EgModel::tracker_column`]).
    pub fn world_column(&self, ev: &Evaluation, param: Param) -> Vector3<f64> {
        let frames = &ev.data.joint_frames;
        let frame_axis = |pose: &deflex_model::Pose, k: usize| -> Vector3<f64> {
            pose.rotation.matrix().column(k).into_owned()
        };
        match param {
            Param::SetupRotation(..) | Param::SetupTranslation(..) => Vector3::zeros(),
            Param::Target(_, k) => {
                // The rigid point moves along the flange axis u; the sag's screws and the
                // external wrench's torques move with it.
                let u = frame_axis(&ev.data.flange, k);
                let mut column = u;
                for e in 0..ev.edof_count {
                    let (axis, _) = ev.axis_center[e];
                    let d_linear = axis.cross(&u);
                    let d_torque = ev.force.map_or(0.0, |f| d_linear.dot(&f));
                    column += (d_linear * ev.torque[e] + ev.screw_linear[e] * d_torque)
                        * self.compliance[e];
                }
                column
            }
            Param::Dh(..) | Param::Harmonic { .. } => {
                let twist = self
                    .kinematic_twist(ev, param)
                    .expect("a DH or harmonic parameter has a twist");
                self.kinematic_column(ev, &twist)
            }
            Param::Compliance(e) => ev.screw_linear[e] * ev.torque[e],
            Param::Mass(b) | Param::FirstMoment(b, _) => {
                let g = self.robot.gravity;
                let frame = &frames[b];
                let mut column = Vector3::zeros();
                for e in 0..ev.edof_count {
                    if ev.site[e].max(1) - 1 > b {
                        continue;
                    }
                    let (axis, center) = ev.axis_center[e];
                    let dtau = match param {
                        Param::Mass(_) => axis.cross(&(frame.translation.vector - center)).dot(&g),
                        Param::FirstMoment(_, k) => (frame.rotation.inverse() * g.cross(&axis))[k],
                        _ => 0.0,
                    };
                    column += ev.screw_linear[e] * (self.compliance[e] * dtau);
                }
                column
            }
        }
    }

    /// The small rigid motion a kinematic parameter (DH field or harmonic) applies (module
    /// documentation); `None` for other parameters.
    pub fn kinematic_twist(&self, ev: &Evaluation, param: Param) -> Option<Twist> {
        let frames = &ev.data.joint_frames;
        let axis = |rotation: &Rotation3<f64>, k: usize| -> Vector3<f64> {
            rotation.matrix().column(k).into_owned()
        };
        let rotation = |axis: Vector3<f64>, point: Vector3<f64>, first_frame: usize| Twist {
            axis,
            point,
            linear: Vector3::zeros(),
            first_frame,
        };
        let translation = |linear: Vector3<f64>, first_frame: usize| Twist {
            axis: Vector3::zeros(),
            point: Vector3::zeros(),
            linear,
            first_frame,
        };
        let (j, field, factor) = match param {
            Param::Dh(j, field) => (j, field, 1.0),
            Param::Harmonic { joint, order, sine } => {
                let x = f64::from(order) * ev.q_raw[joint];
                (joint, DhField::Theta, if sine { x.sin() } else { x.cos() })
            }
            _ => return None,
        };
        let joint = &self.robot.joints[j];
        let dh = joint.dh.unwrap_or_default();
        let frame = &frames[j];
        let z = axis(&frame.rotation, 2);
        let origin = frame.translation.vector;
        let twist = match self.robot.dh_convention.unwrap_or_default() {
            DhConvention::Standard => {
                let x = axis(&frame.rotation, 0);
                let link_origin = origin + x * dh.a;
                match field {
                    DhField::Theta => rotation(z, origin, j),
                    DhField::D => translation(z, j),
                    DhField::A => translation(x, j + 1),
                    DhField::Alpha => rotation(x, link_origin, j + 1),
                    DhField::Beta => {
                        let y = frame.rotation
                            * Rotation3::from_axis_angle(&Vector3::x_axis(), dh.alpha)
                            * Vector3::y();
                        rotation(y, link_origin, j + 1)
                    }
                }
            }
            DhConvention::Modified => {
                let previous = if j == 0 {
                    ev.data.base_frame
                } else {
                    frames[j - 1]
                };
                let prev_origin = previous.translation.vector;
                let after_alpha =
                    previous.rotation * Rotation3::from_axis_angle(&Vector3::x_axis(), dh.alpha);
                match field {
                    DhField::Alpha => rotation(axis(&previous.rotation, 0), prev_origin, j),
                    DhField::Beta => rotation(axis(&after_alpha, 1), prev_origin, j),
                    DhField::A => {
                        let after_beta =
                            after_alpha * Rotation3::from_axis_angle(&Vector3::y_axis(), dh.beta);
                        translation(axis(&after_beta, 0), j)
                    }
                    DhField::D => translation(z, j),
                    DhField::Theta => rotation(z, origin, j),
                }
            }
        };
        Some(Twist {
            axis: twist.axis * factor,
            linear: twist.linear * factor,
            ..twist
        })
    }

    /// World column of a kinematic parameter: the target's rigid motion plus the change of
    /// the sag (eDoF axes and centres, bodies, payload and target all move with the twist).
    pub fn kinematic_column(&self, ev: &Evaluation, twist: &Twist) -> Vector3<f64> {
        let p = ev.target_world;
        let dp = twist.point_rate(&p);
        let mut column = dp;
        if self.compliance.iter().all(|c| *c == 0.0) {
            return column;
        }
        let n = self.robot.joint_count();
        let g = self.robot.gravity;
        // Rates of the bodies' first moments (payload on the last body).
        let mut d_moment = [Vector3::zeros(); MAX_JOINTS];
        for (b, rate) in d_moment
            .iter_mut()
            .enumerate()
            .take(n)
            .skip(twist.first_frame)
        {
            *rate = twist
                .axis
                .cross(&(ev.body_moment[b] - twist.point * ev.body_mass[b]))
                + twist.linear * ev.body_mass[b];
        }
        let (payload_mass, payload_moment) = ev.payload;
        d_moment[n - 1] += twist
            .axis
            .cross(&(payload_moment - twist.point * payload_mass))
            + twist.linear * payload_mass;
        let mut mass = ev.body_mass;
        let mut moment = ev.body_moment;
        mass[n - 1] += payload_mass;
        moment[n - 1] += payload_moment;
        for e in 0..ev.edof_count {
            let c = self.compliance[e];
            if c == 0.0 {
                continue;
            }
            let (a, center) = ev.axis_center[e];
            let site = ev.site[e];
            let moved = site > twist.first_frame;
            let (da, dcenter) = if moved {
                (twist.axis.cross(&a), twist.point_rate(&center))
            } else {
                (Vector3::zeros(), Vector3::zeros())
            };
            let d_linear = da.cross(&(p - center)) + a.cross(&(dp - dcenter));
            let mut d_torque = 0.0;
            for b in (site.max(1) - 1)..n {
                let arm = moment[b] - center * mass[b];
                let d_arm = d_moment[b] - dcenter * mass[b];
                d_torque += (da.cross(&arm) + a.cross(&d_arm)).dot(&g);
            }
            if let Some(f) = ev.force {
                d_torque += d_linear.dot(&f);
            }
            if let Some(mu) = ev.moment {
                d_torque += da.dot(&mu);
            }
            column += (d_linear * ev.torque[e] + ev.screw_linear[e] * d_torque) * c;
        }
        column
    }

    /// Column of `param` for an absolute reading in set-up `setup` (tracker frame).
    pub fn tracker_column(&self, ev: &Evaluation, setup: usize, param: Param) -> Vector3<f64> {
        let rotation = self.setups[setup].pose.rotation;
        match param {
            Param::SetupRotation(s, k) | Param::SetupTranslation(s, k) if s != setup => {
                let _ = k;
                Vector3::zeros()
            }
            Param::SetupRotation(_, k) => {
                rotation * Vector3::ith(k, 1.0).cross(&(ev.target_world + ev.sag_world))
            }
            Param::SetupTranslation(_, k) => rotation * Vector3::ith(k, 1.0),
            other => rotation * self.world_column(ev, other),
        }
    }

    /// Predicted displacement (loaded − unloaded) of a loaded reading (the stiffness
    /// campaign's row: point, load point, links and wrench, world axes), and the column of each
    /// compliance in `columns` (others zero).
    pub fn loaded_displacement(
        &self,
        row: &deflex_stiffness::MeasurementRow,
        columns: &mut [Vector3<f64>; MAX_EDOFS],
    ) -> Vector3<f64> {
        let (q, point, point_link) = (&row.q_rad, Vector3::from(row.point_m), row.point_link);
        let (load_point, load_link, wrench) =
            (Vector3::from(row.load_point_m), row.load_link, &row.wrench);
        let n = self.robot.joint_count();
        let mut q_effective = [0.0; MAX_JOINTS];
        self.effective_q(q, &mut q_effective);
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
