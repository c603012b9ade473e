//! One configuration of the model (`deflex pose`, `deflect`, `ik`): the TCP pose with the sag
//! under the arm's own weight, the TCP deflection under a wrench (eq. 15), and the joint values
//! reaching a TCP pose; each as text (mm, degrees) and as JSON (SI).

use crate::error::{Error, Result};
use deflex_model::spatial::rpy_from_rotation;
use deflex_model::{Data, Displacement, IkOptions, IkSolution, Pose, Robot, Wrench};
use nalgebra::{Matrix6, Vector3};
use serde_json::json;
use std::fmt::Write as _;

/// Forward kinematics of `q` into `data`.
fn forward(robot: &Robot, data: &mut Data, q: &[f64]) -> Result<()> {
    robot
        .forward_kinematics(data, q)
        .map_err(deflex_model::ModelError::from)?;
    Ok(())
}

/// The rows of a rotation matrix.
fn rotation_rows(rotation: &nalgebra::Rotation3<f64>) -> Vec<[f64; 3]> {
    let m = rotation.matrix();
    (0..3).map(|r| [m[(r, 0)], m[(r, 1)], m[(r, 2)]]).collect()
}

/// The TCP pose of one configuration (`deflex pose`).
#[derive(Clone, Debug)]
pub struct PoseReport {
    /// The TCP pose in the world frame.
    pub pose: Pose,
    /// Sag of the TCP under the arm's own weight and payload `[δp; δφ]` (m, rad), when the
    /// model knows its masses.
    pub sag: Option<Displacement>,
}

impl PoseReport {
    /// The TCP pose of `q` (rad), with the sag when the model knows its masses.
    pub fn at(robot: &Robot, q: &[f64]) -> Result<PoseReport> {
        let mut data = Data::new();
        forward(robot, &mut data, q)?;
        let pose = data.tcp;
        let p = pose.translation.vector;
        // The arm's own weight (and payload) sags the TCP when the model knows its masses.
        let sag = super::knows_masses(robot)
            .then(|| robot.gravity_displacement(&data, &p, robot.joint_count()));
        Ok(PoseReport { pose, sag })
    }

    /// As JSON (SI): position, rotation rows, roll-pitch-yaw and the sag.
    pub fn to_json(&self) -> serde_json::Value {
        let p = self.pose.translation.vector;
        let sag = self.sag;
        json!({
            "tcp_m": [p.x, p.y, p.z],
            "rotation": rotation_rows(&self.pose.rotation),
            "rpy_rad": rpy_from_rotation(&self.pose.rotation),
            "gravity_sag_m": sag.map(|d| [d[0], d[1], d[2]]),
            "gravity_sag_rad": sag.map(|d| [d[3], d[4], d[5]]),
            "tcp_with_gravity_m": sag.map(|d| [p.x + d[0], p.y + d[1], p.z + d[2]]),
        })
    }

    /// As text (mm, degrees), one line per quantity.
    pub fn text(&self) -> String {
        let p = self.pose.translation.vector;
        let rpy = rpy_from_rotation(&self.pose.rotation);
        let mut out = String::new();
        let _ = writeln!(
            out,
            "TCP position (mm): x {:.3}  y {:.3}  z {:.3}",
            p.x * 1e3,
            p.y * 1e3,
            p.z * 1e3
        );
        let _ = writeln!(
            out,
            "TCP orientation (deg, R = Rz·Ry·Rx): roll {:.3}  pitch {:.3}  yaw {:.3}",
            rpy[0].to_degrees(),
            rpy[1].to_degrees(),
            rpy[2].to_degrees()
        );
        let z = self.pose.rotation.matrix().column(2);
        let _ = writeln!(
            out,
            "tool axis z_t: [{:.4}, {:.4}, {:.4}]",
            z[0], z[1], z[2]
        );
        if let Some(d) = self.sag {
            let _ = writeln!(
                out,
                "sag under the arm's own weight (mm): x {:+.4}  y {:+.4}  z {:+.4}  → TCP x {:.3}  y {:.3}  z {:.3}",
                d[0] * 1e3,
                d[1] * 1e3,
                d[2] * 1e3,
                (p.x + d[0]) * 1e3,
                (p.y + d[1]) * 1e3,
                (p.z + d[2]) * 1e3
            );
        }
        out
    }
}

/// The TCP deflection of one configuration under a wrench (`deflex deflect`, eq. 15).
#[derive(Clone, Debug)]
pub struct DeflectionReport {
    /// The TCP position (m, world).
    pub tcp_m: Vector3<f64>,
    /// The wrench at the TCP, world axes: fx, fy, fz (N), mx, my, mz (N·m).
    pub wrench: [f64; 6],
    /// The Cartesian compliance `C = J K_θ⁻¹ Jᵀ` at the TCP.
    pub compliance: Matrix6<f64>,
    /// The deflection `[δp; δφ]` (m, rad).
    pub deflection: Displacement,
}

impl DeflectionReport {
    /// The deflection of `q` (rad) under `wrench`.
    pub fn at(robot: &Robot, q: &[f64], wrench: [f64; 6]) -> Result<DeflectionReport> {
        let mut data = Data::new();
        forward(robot, &mut data, q)?;
        let compliance = robot.compliance_matrix(&data);
        let deflection = robot.tcp_deflection(&data, &Wrench::from_row_slice(&wrench));
        Ok(DeflectionReport {
            tcp_m: data.tcp_position(),
            wrench,
            compliance,
            deflection,
        })
    }

    /// As JSON (SI), with the compliance matrix by rows.
    pub fn to_json(&self) -> serde_json::Value {
        let (p, ds) = (self.tcp_m, &self.deflection);
        let rows: Vec<Vec<f64>> = (0..6)
            .map(|r| (0..6).map(|c| self.compliance[(r, c)]).collect())
            .collect();
        json!({
            "tcp_m": [p.x, p.y, p.z],
            "wrench": self.wrench,
            "dp_m": [ds[0], ds[1], ds[2]],
            "dphi_rad": [ds[3], ds[4], ds[5]],
            "compliance": rows,
        })
    }

    /// As text (mm, mrad).
    pub fn text(&self) -> String {
        let (p, ds) = (self.tcp_m, &self.deflection);
        let mut out = String::new();
        let _ = writeln!(
            out,
            "TCP (mm): x {:.3}  y {:.3}  z {:.3}",
            p.x * 1e3,
            p.y * 1e3,
            p.z * 1e3
        );
        let _ = writeln!(
            out,
            "wrench (N, N·m, world axes at the TCP): {:?}",
            self.wrench
        );
        let _ = writeln!(
            out,
            "deflection δp (mm):   x {:+.4}  y {:+.4}  z {:+.4}   |δp| {:.4}",
            ds[0] * 1e3,
            ds[1] * 1e3,
            ds[2] * 1e3,
            ds.fixed_rows::<3>(0).norm() * 1e3
        );
        let _ = writeln!(
            out,
            "deflection δφ (mrad): x {:+.4}  y {:+.4}  z {:+.4}",
            ds[3] * 1e3,
            ds[4] * 1e3,
            ds[5] * 1e3
        );
        out
    }
}

/// The joint values reaching a TCP pose (`deflex ik`).
#[derive(Clone, Debug)]
pub struct IkReport {
    /// The solution: joint values (rad), iterations and residuals.
    pub solution: IkSolution,
}

impl IkReport {
    /// The joint values reaching `target` (world), from `seed` (rad) and then the model's 36
    /// spread seeds. A target not reached is [`Error::Model`] with the model's reason.
    pub fn solve(robot: &Robot, target: &Pose, seed: &[f64]) -> Result<IkReport> {
        let solution = robot
            .inverse_kinematics_search(target, Some(seed), &IkOptions::default())
            .map_err(Error::Model)?;
        Ok(IkReport { solution })
    }

    /// As JSON: the joint values (rad and degrees), iterations and residuals (m, rad).
    pub fn to_json(&self) -> serde_json::Value {
        let s = &self.solution;
        json!({
            "q_rad": s.q,
            "q_deg": s.q.iter().map(|v| v.to_degrees()).collect::<Vec<_>>(),
            "iterations": s.iterations,
            "position_error_m": s.position_error_m,
            "orientation_error_rad": s.orientation_error_rad,
        })
    }

    /// As text (degrees; residuals in mm and mrad).
    pub fn text(&self) -> String {
        let s = &self.solution;
        let degrees: Vec<String> =
            s.q.iter()
                .map(|v| format!("{:.4}", v.to_degrees()))
                .collect();
        let mut out = String::new();
        let _ = writeln!(out, "q (deg): {}", degrees.join(", "));
        let _ = writeln!(
            out,
            "converged in {} iterations; residual {:.2e} mm, {:.2e} mrad",
            s.iterations,
            s.position_error_m * 1e3,
            s.orientation_error_rad * 1e3
        );
        out
    }
}
