//! Analytic Jacobians of the predictions of [`crate::geometry::model`]: one [`ParameterColumn`]
//! (position and orientation of the target) per parameter and reading.
//!
//! Every kinematic parameter is a screw at a known frame of the chain: a rotation δ about unit
//! axis u through point o moves p by `u × (p − o) δ` and turns every frame distal to it by
//! `u δ`; a translation along u moves p by `u δ`. With the model's joint frames R_i:
//!
//! * standard DH (`F_i = R_i·TransX(a_i)·RotX(α_i)·RotY(β_i)`, R_i after `TransZ(d_i)·RotZ`):
//!   θ_i: `z_i × (p − o_i)`; d_i: `z_i`; a_i: `x_i`; α_i: `x_i × (p − o_i − a_i x_i)`;
//!   β_i: `y'_i × (p − o_i − a_i x_i)` with `y'_i = R_i RotX(α_i) e_y`;
//! * modified DH (`R_i = R_{i−1}·RotX(α_i)·RotY(β_i)·TransX(a_i)·TransZ(d_i)·RotZ`):
//!   α_i: `x_{i−1} × (p − o_{i−1})`; β_i: `y'_{i−1} × (p − o_{i−1})` with
//!   `y'_{i−1} = R_{i−1} RotX(α_i) e_y`; a_i: `R_{i−1}RotX(α_i)RotY(β_i) e_x`; d_i: `z_i`;
//!   θ_i: `z_i × (p − o_i)`.
//!
//! Harmonic `cos(n q_j)` and backlash `sign(approach_j)`: the θ_j column times that factor.
//! Target coordinate k: the flange's axis u_k, plus the change of the sag as the target moves
//! (`Σ_e c_e [τ_e (v_e × u_k) + j_e ((v_e × u_k)·f)]`). Target rotation k (`R_t ← exp(φ)R_t`,
//! flange axes): turns the target frame about `R_F e_k`, moves no point. Compliance c_e:
//! `τ_e j_e(p)`, rotation `τ_e v_e`; a torsion term a·g(τ_e): `g(τ_e) j_e(p)`, `g(τ_e) v_e`.
//! Wherever a torque changes, the turn changes by its slope `s_e = c_e + Σ a g'(τ_e)` and
//! wherever a screw moves, by the turn `φ_e = c_e τ_e + Σ a g(τ_e)` (below written with the
//! linear compliance). Lumped mass and first moment of body b:
//! `Σ_e c_e j_e(p) ∂τ_e/∂(m_b, h_b)`, with `∂τ_e/∂m_b = (v_e × (o_b − O_e))·g` and
//! `∂τ_e/∂h_b = R_bᵀ (g × v_e)`. Set-up s (`R_s ← R_s exp(φ)`, `t_s ← t_s + R_s δt`): rotation
//! k: `R_s (e_k × p̂_w)` and `R_s e_k`; translation k: `R_s e_k`. World columns are turned into
//! the tracker frame by `R_s`.
//!
//! **Orientation columns** are the rate ω of the predicted frame `R = R_s exp(θ_sag) R_F R_t`
//! (`dR·Rᵀ = [ω]×`). A rigid turn ω_F of the flange gives `exp(θ_sag) ω_F`; a change dθ of the
//! sag's rotation vector gives `J_l(θ_sag) dθ`, with the left Jacobian of SO(3)
//! `J_l(θ) = I + (1 − cos t)/t² [θ]× + (t − sin t)/t³ [θ]×²`, `t = |θ|`.
//!
//! Each kinematic column also carries the change of the sag: the parameter's small rigid
//! motion ([`ParameterTwist`]) moves the eDoF axes and centres, the bodies, the payload and the
//! target distal to it, which changes both the screws and the gravity torques. The integration
//! tests check every column, position and orientation, against central finite differences of the
//! full prediction.

use crate::geometry::model::Evaluation;
use crate::geometry::params::{DhField, EgModel, Param, approach_sign};
use deflex_model::{DhConvention, MAX_JOINTS};
use nalgebra::{Matrix3, Rotation3, Vector3};

/// The change of a reading's prediction per unit change of one parameter.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct ParameterColumn {
    /// Change of the target's position (m per unit).
    pub position: Vector3<f64>,
    /// Rate of the target frame's rotation, `dR·Rᵀ = [ω]×` (rad per unit).
    pub rotation: Vector3<f64>,
}

/// A kinematic parameter as a small rigid motion of everything distal to where it acts:
/// a rotation about `axis` through `point` (per unit parameter) plus a translation `linear`;
/// joint frames with index ≥ `first_frame` (0-based), their bodies and eDoFs, the flange, the
/// target and the payload move.
#[derive(Clone, Copy, Debug)]
pub struct ParameterTwist {
    /// Rotation axis × rate (zero for a translation).
    pub axis: Vector3<f64>,
    /// A point on the rotation axis.
    pub point: Vector3<f64>,
    /// Translation rate (zero for a rotation).
    pub linear: Vector3<f64>,
    /// First joint frame moved.
    pub first_frame: usize,
}

impl ParameterTwist {
    fn point_rate(&self, x: &Vector3<f64>) -> Vector3<f64> {
        self.axis.cross(&(x - self.point)) + self.linear
    }
}

/// Left Jacobian of SO(3) at rotation vector θ (module documentation).
pub fn left_jacobian(theta: &Vector3<f64>) -> Matrix3<f64> {
    let t = theta.norm();
    let k = theta.cross_matrix();
    if t < 1e-8 {
        return Matrix3::identity() + k * 0.5;
    }
    Matrix3::identity() + k * ((1.0 - t.cos()) / (t * t)) + k * k * ((t - t.sin()) / (t * t * t))
}

impl EgModel {
    /// Orientation column of a change `d_theta` of the sag's rotation vector plus a rigid turn
    /// `omega` of the flange (world axes).
    fn rotation_rate(ev: &Evaluation, d_theta: Vector3<f64>, omega: Vector3<f64>) -> Vector3<f64> {
        left_jacobian(&ev.sag_rotation) * d_theta
            + Rotation3::from_scaled_axis(ev.sag_rotation) * omega
    }

    /// World-frame column of one kinematic, target, compliance, mass, harmonic or backlash
    /// parameter at an evaluation (set-up parameters: see [`EgModel::tracker_column`]).
    pub fn world_column(&self, ev: &Evaluation, param: Param) -> ParameterColumn {
        match param {
            Param::SetupRotation(..) | Param::SetupTranslation(..) => ParameterColumn::default(),
            Param::Target(_, k) => self.target_column(ev, k),
            Param::TargetRotation(_, k) => {
                let axis = ev.data.flange.rotation.matrix().column(k).into_owned();
                ParameterColumn {
                    position: Vector3::zeros(),
                    rotation: Self::rotation_rate(ev, Vector3::zeros(), axis),
                }
            }
            Param::Dh(..) | Param::Harmonic { .. } | Param::Backlash(_) => {
                let twist = self
                    .kinematic_twist(ev, param)
                    .expect("a DH, harmonic or backlash parameter has a twist");
                self.kinematic_column(ev, &twist)
            }
            Param::Compliance(e) => ParameterColumn {
                position: ev.screw_linear[e] * ev.torque[e],
                rotation: Self::rotation_rate(
                    ev,
                    ev.axis_center[e].0 * ev.torque[e],
                    Vector3::zeros(),
                ),
            },
            Param::Torsion { edof, shape } => {
                let (g, _) = shape.value_slope(ev.torque[edof]);
                ParameterColumn {
                    position: ev.screw_linear[edof] * g,
                    rotation: Self::rotation_rate(ev, ev.axis_center[edof].0 * g, Vector3::zeros()),
                }
            }
            Param::Mass(b) | Param::FirstMoment(b, _) => self.mass_column(ev, param, b),
        }
    }

    /// Target coordinate k: the rigid point moves along the flange axis u; the sag's screws
    /// and the external wrench's torques move with it.
    fn target_column(&self, ev: &Evaluation, k: usize) -> ParameterColumn {
        let u = ev.data.flange.rotation.matrix().column(k).into_owned();
        let mut position = u;
        let mut d_theta = Vector3::zeros();
        for e in 0..ev.edof_count {
            let (axis, _) = ev.axis_center[e];
            let d_linear = axis.cross(&u);
            let d_torque = ev.force.map_or(0.0, |f| d_linear.dot(&f));
            position += d_linear * ev.turn[e] + ev.screw_linear[e] * (ev.turn_slope[e] * d_torque);
            d_theta += axis * (ev.turn_slope[e] * d_torque);
        }
        ParameterColumn {
            position,
            rotation: Self::rotation_rate(ev, d_theta, Vector3::zeros()),
        }
    }

    /// Lumped mass or first moment of body b: only the gravity torques change.
    fn mass_column(&self, ev: &Evaluation, param: Param, b: usize) -> ParameterColumn {
        let g = self.robot.gravity;
        let frame = &ev.data.joint_frames[b];
        let mut position = Vector3::zeros();
        let mut d_theta = Vector3::zeros();
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
            position += ev.screw_linear[e] * (ev.turn_slope[e] * dtau);
            d_theta += axis * (ev.turn_slope[e] * dtau);
        }
        ParameterColumn {
            position,
            rotation: Self::rotation_rate(ev, d_theta, Vector3::zeros()),
        }
    }

    /// The small rigid motion a kinematic parameter (DH field, harmonic or backlash) applies (module
    /// documentation); `None` for other parameters.
    pub fn kinematic_twist(&self, ev: &Evaluation, param: Param) -> Option<ParameterTwist> {
        let frames = &ev.data.joint_frames;
        let axis = |rotation: &Rotation3<f64>, k: usize| -> Vector3<f64> {
            rotation.matrix().column(k).into_owned()
        };
        let rotation =
            |axis: Vector3<f64>, point: Vector3<f64>, first_frame: usize| ParameterTwist {
                axis,
                point,
                linear: Vector3::zeros(),
                first_frame,
            };
        let translation = |linear: Vector3<f64>, first_frame: usize| ParameterTwist {
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
            Param::Backlash(joint) => (joint, DhField::Theta, approach_sign(ev.approach[joint])),
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
        Some(ParameterTwist {
            axis: twist.axis * factor,
            linear: twist.linear * factor,
            ..twist
        })
    }

    /// Column of a kinematic parameter: the target's rigid motion plus the change of the sag
    /// (eDoF axes and centres, bodies, payload and target all move with the twist).
    pub fn kinematic_column(&self, ev: &Evaluation, twist: &ParameterTwist) -> ParameterColumn {
        let p = ev.target_world;
        let dp = twist.point_rate(&p);
        let mut column = ParameterColumn {
            position: dp,
            rotation: Vector3::zeros(),
        };
        if !self.is_elastic() {
            column.rotation = twist.axis;
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
        let mut d_theta = Vector3::zeros();
        for e in 0..ev.edof_count {
            let (turn, slope) = (ev.turn[e], ev.turn_slope[e]);
            if turn == 0.0 && slope == 0.0 {
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
            column.position += d_linear * turn + ev.screw_linear[e] * (slope * d_torque);
            d_theta += da * turn + a * (slope * d_torque);
        }
        column.rotation = Self::rotation_rate(ev, d_theta, twist.axis);
        column
    }

    /// Column of `param` for an absolute reading in set-up `setup` (tracker frame).
    pub fn tracker_column(&self, ev: &Evaluation, setup: usize, param: Param) -> ParameterColumn {
        let rotation = self.setups[setup].pose.rotation;
        match param {
            Param::SetupRotation(s, _) | Param::SetupTranslation(s, _) if s != setup => {
                ParameterColumn::default()
            }
            Param::SetupRotation(_, k) => {
                let e = Vector3::ith(k, 1.0);
                ParameterColumn {
                    position: rotation * e.cross(&ev.predicted_world()),
                    rotation: rotation * e,
                }
            }
            Param::SetupTranslation(_, k) => ParameterColumn {
                position: rotation * Vector3::ith(k, 1.0),
                rotation: Vector3::zeros(),
            },
            other => {
                let world = self.world_column(ev, other);
                ParameterColumn {
                    position: rotation * world.position,
                    rotation: rotation * world.rotation,
                }
            }
        }
    }
}
