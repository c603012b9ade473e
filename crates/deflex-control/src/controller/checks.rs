//! The controller's per-cycle checks and estimates: input supervision (each fault names its
//! check, joint or channel, value and limit), the wrench path and the deflection estimate
//! (eq. 2; eq. 15 is [`crate::estimate`]), the force/torque limits, the runaway guard's update,
//! and the frames the robot links need (TCP orientation, the joint-space map of a correction).
//! All allocation-free.

use super::{Controller, CycleInput, CycleOutput, JointCorrectionMap};
use crate::estimate::tcp_deflection_in_base;
use crate::model_check::pose_mismatch;
use crate::runaway::RunawayAction;
use crate::safety::{Channel, Fault};
use deflex_model::{MAX_JOINTS, Pose, Wrench};
use deflex_telemetry::Phase;
use deflex_telemetry::{FaultKind, Flags};
use nalgebra::{Rotation3, Vector3, Vector6};

/// Damping λ of the least-squares map from a Cartesian correction to joint corrections
/// ([`Controller::joint_correction_map`]): Δq = Jᵀ (J Jᵀ + λ² I)⁻¹ ξ. With J in metres per radian
/// (position rows) and 1 (rotation rows), λ = 10⁻³ leaves a well-conditioned arm untouched
/// (its smallest singular value is ≥ 0.1) and bounds Δq near a singularity to |ξ|/(2λ).
pub const JOINT_MAP_DAMPING: f64 = 1e-3;

impl Controller {
    /// Input checks; trips and returns the first fault kind detected this cycle.
    pub(super) fn check_inputs(&mut self, input: &CycleInput, now: f64) -> Option<FaultKind> {
        let cfg = self.config.safety;
        let n = self.robot.joint_count();
        let fault = |kind, value, limit, channel| Fault::new(kind, now, value, limit).on(channel);
        let mut found: Option<Fault> = None;
        if !input.now_s.is_finite() {
            found = Some(fault(FaultKind::NonFinite, f64::NAN, 0.0, Channel::Time));
        } else if let Some(i) = input.q_rad.iter().position(|v| !v.is_finite()) {
            found = Some(fault(
                FaultKind::NonFinite,
                f64::NAN,
                0.0,
                Channel::Joint(i as u8),
            ));
        } else if let Some(i) = input.wrench_sensor.iter().position(|v| !v.is_finite()) {
            found = Some(fault(
                FaultKind::NonFinite,
                f64::NAN,
                0.0,
                Channel::Sensor(i as u8),
            ));
        } else if input.q_rad.len() != n {
            found = Some(fault(
                FaultKind::JointCountMismatch,
                input.q_rad.len() as f64,
                n as f64,
                Channel::Whole,
            ));
        } else if let Some(i) =
            (0..6).find(|&i| input.wrench_sensor[i].abs() >= cfg.sensor_range[i])
        {
            found = Some(fault(
                FaultKind::SensorOverRange,
                input.wrench_sensor[i],
                cfg.sensor_range[i].copysign(input.wrench_sensor[i]),
                Channel::Sensor(i as u8),
            ));
        } else {
            for i in 0..n {
                let qi = input.q_rad[i];
                if let Some([lo, hi]) = self.robot.joints[i].limits {
                    let m = cfg.joint_limit_margin_rad;
                    if qi < lo - m || qi > hi + m {
                        let limit = if qi < lo { lo - m } else { hi + m };
                        found = Some(fault(
                            FaultKind::JointOutOfLimits,
                            qi,
                            limit,
                            Channel::Joint(i as u8),
                        ));
                        break;
                    }
                }
                if self.q_prev_valid && (qi - self.q_prev[i]).abs() > cfg.max_joint_step_rad {
                    found = Some(fault(
                        FaultKind::JointJump,
                        qi - self.q_prev[i],
                        cfg.max_joint_step_rad.copysign(qi - self.q_prev[i]),
                        Channel::Joint(i as u8),
                    ));
                    break;
                }
            }
        }
        if found.is_none() && (input.q_age_s.is_nan() || input.q_age_s > cfg.robot_timeout_s) {
            found = Some(fault(
                FaultKind::RobotLinkLost,
                input.q_age_s,
                cfg.robot_timeout_s,
                Channel::Whole,
            ));
        }
        if found.is_none() && input.sensor_status != 0 {
            found = Some(fault(
                FaultKind::SensorStatus,
                f64::from(input.sensor_status),
                0.0,
                Channel::Whole,
            ));
        }
        if found.is_none()
            && (input.wrench_age_s.is_nan() || input.wrench_age_s > cfg.sensor_timeout_s)
        {
            found = Some(fault(
                FaultKind::SensorTimeout,
                input.wrench_age_s,
                cfg.sensor_timeout_s,
                Channel::Whole,
            ));
        }
        let fault = found?;
        self.trip(fault);
        Some(fault.kind)
    }

    /// The robot's reported TCP pose against the model's at the same joints (forward
    /// kinematics done): keeps the session's largest difference and latches
    /// [`FaultKind::ModelMismatch`] above the tolerance ([`crate::model_check`]).
    pub(super) fn check_model(&mut self, reported: &Pose, now: f64, flags: &mut Flags) {
        let cfg = self.config.model_check;
        if !cfg.enabled {
            return;
        }
        let mismatch = pose_mismatch(&self.robot, &self.data, reported);
        self.pose_mismatch_max = Some(
            self.pose_mismatch_max
                .map_or(mismatch, |m| m.max(&mismatch)),
        );
        if !mismatch.exceeds(&cfg) {
            return;
        }
        let (value, limit, channel) =
            if mismatch.position_m > cfg.position_tolerance_m || !mismatch.position_m.is_finite() {
                (
                    mismatch.position_m,
                    cfg.position_tolerance_m,
                    Channel::TcpPosition,
                )
            } else {
                (
                    mismatch.orientation_rad,
                    cfg.orientation_tolerance_rad,
                    Channel::TcpOrientation,
                )
            };
        let fault = Fault::new(FaultKind::ModelMismatch, now, value, limit).on(channel);
        flags.set(FaultKind::ModelMismatch.flag());
        self.trip(fault);
    }

    /// Wrench path (eq. 2) and deflection estimate (eq. 15, [`tcp_deflection_in_base`]) into
    /// `out`, in base axes.
    #[inline]
    pub(super) fn estimate(&mut self, raw: &Wrench, h: f64, out: &mut CycleOutput) {
        let processed = self.wrench.process(raw, &self.data, h);
        let estimate = tcp_deflection_in_base(&self.robot, &self.data, &processed.tcp_world);
        out.wrench_sensor = processed.sensor.into();
        out.wrench_tcp = estimate.wrench_tcp.into();
        out.delta_s_hat = estimate.deflection.into();
    }

    /// Checks the estimate; returns false when it is not finite.
    pub(super) fn check_estimate(
        &mut self,
        out: &CycleOutput,
        now: f64,
        flags: &mut Flags,
    ) -> bool {
        let cfg = self.config.safety;
        let w = &out.wrench_tcp;
        let force = (w[0] * w[0] + w[1] * w[1] + w[2] * w[2]).sqrt();
        let torque = (w[3] * w[3] + w[4] * w[4] + w[5] * w[5]).sqrt();
        let finite = out.delta_s_hat.iter().all(|v| v.is_finite())
            && force.is_finite()
            && torque.is_finite();
        if self.phase == Phase::Taring {
            return finite;
        }
        let fault = if !finite {
            Some(Fault::new(FaultKind::NonFinite, now, f64::NAN, 0.0))
        } else if force > cfg.max_force_n {
            Some(Fault::new(
                FaultKind::ForceOverLimit,
                now,
                force,
                cfg.max_force_n,
            ))
        } else if torque > cfg.max_torque_nm {
            Some(Fault::new(
                FaultKind::TorqueOverLimit,
                now,
                torque,
                cfg.max_torque_nm,
            ))
        } else {
            None
        };
        if let Some(fault) = fault {
            flags.set(fault.kind.flag());
            self.trip(fault);
        }
        finite
    }

    /// The TCP position in the robot base frame (m), from the last forward kinematics of the
    /// reported joints: the corrected TCP the robot realises (the program's is this minus ξ).
    pub fn tcp_position_in_base(&self) -> Vector3<f64> {
        let base = &self.robot.base;
        base.rotation.inverse() * (self.data.tcp_position() - base.translation.vector)
    }

    /// Updates the runaway guard with this cycle's position, force and applied correction, and
    /// acts on a detection (hold: record and flag; fault: latch `contact_runaway`).
    pub(super) fn watch_runaway(
        &mut self,
        out: &mut CycleOutput,
        now: f64,
        h: f64,
        flags: &mut Flags,
    ) {
        if !self.guard.config().enabled {
            return;
        }
        // The feedback part of the applied correction (without the feed-forward).
        let output = self.limiter.output();
        let applied: [f64; 6] = std::array::from_fn(|i| output[i] - self.feedforward_sent[i]);
        let xi_p = [applied[0], applied[1], applied[2]];
        let u = self.guard.direction(&xi_p);
        // The model's compliance along the watched direction (a hold's own while one is
        // active): deflection along u under a unit force along u.
        let watched = self.guard.hold().map(|hold| hold.u).or(u);
        let compliance_u = watched.map_or(f64::NAN, |u| {
            let r = self.robot.base.rotation;
            let uw = r * Vector3::new(u[0], u[1], u[2]);
            let ds = self
                .robot
                .tcp_deflection(&self.data, &Wrench::from([uw.x, uw.y, uw.z, 0.0, 0.0, 0.0]));
            ds[0] * uw.x + ds[1] * uw.y + ds[2] * uw.z
        });
        let p = self.tcp_position_in_base();
        let x = [p.x, p.y, p.z];
        let force = [out.wrench_tcp[0], out.wrench_tcp[1], out.wrench_tcp[2]];
        let update = self.guard.update(&x, &force, &xi_p, u, compliance_u, h);
        out.loop_gain = update.gain;
        if update.tripped {
            self.runaway_events += 1;
            flags.set(Flags::CONTACT_RUNAWAY);
            let limit = self.guard.config().gain_limit;
            let fault = Fault::new(FaultKind::ContactRunaway, now, update.gain, limit);
            if self.first_runaway.is_none() {
                self.first_runaway = Some(fault);
            }
            if self.guard.config().action == RunawayAction::Fault {
                self.trip(fault);
            }
        }
    }

    /// Orientation of the TCP in the robot base frame, from the last forward kinematics: what a
    /// link whose correction frame follows the tool needs (ABB EGM).
    pub fn tcp_rotation_in_base(&self) -> Rotation3<f64> {
        self.robot.base.rotation.inverse() * self.data.tcp.rotation
    }

    /// The least-squares map `P` (row i: joint i) from a correction ξ (base axes, [δp; δφ]) to
    /// joint corrections Δq = P ξ at the last reported joints: Δq = Jᵀ (J Jᵀ + λ² I)⁻¹ ξ with J
    /// the geometric Jacobian at the TCP in base axes and λ = [`JOINT_MAP_DAMPING`], so that
    /// J Δq ≈ ξ (the robot moves its TCP by the correction). Rows past the joint count are
    /// zero; a failed solve gives an all-zero map.
    pub fn joint_correction_map(&self) -> JointCorrectionMap {
        let mut map = JointCorrectionMap::zeros();
        let n = self.robot.joint_count();
        let tcp = self.data.tcp_position();
        let columns = self.robot.geometric_jacobian_columns(&self.data, &tcp);
        let r_t = self.robot.base.rotation.inverse();
        let mut base_columns = [Vector6::zeros(); MAX_JOINTS];
        for (b, c) in base_columns.iter_mut().zip(&columns).take(n) {
            let lin = r_t * Vector3::new(c[0], c[1], c[2]);
            let ang = r_t * Vector3::new(c[3], c[4], c[5]);
            *b = Vector6::new(lin.x, lin.y, lin.z, ang.x, ang.y, ang.z);
        }
        let Some(inverse) =
            deflex_model::damped_gram(&base_columns[..n], JOINT_MAP_DAMPING).map(|ch| ch.inverse())
        else {
            return map;
        };
        for (i, c) in base_columns.iter().enumerate().take(n) {
            let r = inverse * c; // (J Jᵀ + λ²I)⁻¹ is symmetric: row i of P is (inverse · j_i)ᵀ.
            if r.iter().all(|v| v.is_finite()) {
                map.set_row(i, &r.transpose());
            }
        }
        map
    }
}
