//! The paper's Figs. 8 and 9 on the twin (SIMULATED): the elastic displacements δp_x and δp_y
//! of points along the arm in the Fig. 7 configuration (q = 0, 90°, 0, 0, 0, 0 on the TX200, a
//! lateral force f_y = 1400 N at the end effector), measured by the twin's laser tracker and
//! predicted by the identified model, the one-eDoF-per-joint model and the robot file's model.
//!
//! The paper does not give where M1–M3 sit on the arm (Fig. 7 shows them along x0); here M1 is
//! on the upper arm 40 % of the way from joint 2 to joint 3, M2 on the forearm 15 cm past the
//! elbow (joint 3), M3 on link 4 a quarter of the forearm before the wrist centre, and the end
//! effector (TCP) carries the load, as in the paper.

use crate::study::DemoError;
use deflex_calibrate::measurements::MeasurementRow;
use deflex_calibrate::stiffness::validation::predict;
use deflex_model::{Data, Robot};
use deflex_sim::CellConfig;
use deflex_sim::twin_campaign::run_campaign;
use nalgebra::Vector3;

/// The Fig. 7 configuration (rad).
pub const FIG7_Q_RAD: [f64; 6] = [0.0, std::f64::consts::FRAC_PI_2, 0.0, 0.0, 0.0, 0.0];
/// The paper's largest lateral force at the end effector (N, +y0).
pub const FIG7_FY_N: f64 = 1400.0;

/// One measured point of the Fig. 7 test.
#[derive(Clone, Debug, serde::Serialize)]
pub struct Fig7Point {
    /// `M1`, `M2`, `M3` or `TCP`.
    pub point: String,
    /// Link carrying it.
    pub link: usize,
    /// Position along x0 in the unloaded pose (mm).
    pub x_mm: f64,
    /// Displacement measured by the twin's tracker, x0 and y0 (mm, SIMULATED).
    pub measured_mm: [f64; 2],
    /// Tracker 1σ of the displacement (mm).
    pub sigma_mm: f64,
    /// Predictions `(model, [δx, δy] mm)` in the order the models were given.
    pub predicted_mm: Vec<(String, [f64; 2])>,
}

/// The plan rows of the test: the four points of one load case (world coordinates of the
/// nominal robot at [`FIG7_Q_RAD`]).
pub fn fig7_rows(nominal: &Robot) -> Result<Vec<MeasurementRow>, DemoError> {
    if nominal.joint_count() != 6 {
        return Err(DemoError::Fig7Joints {
            robot: nominal.name.clone(),
            joints: nominal.joint_count(),
        });
    }
    let mut data = Data::new();
    nominal
        .forward_kinematics(&mut data, &FIG7_Q_RAD)
        .map_err(deflex_model::ModelError::from)?;
    let origin = |link: usize| data.link_frame(link).translation.vector;
    let (j2, j3, wrist) = (origin(2), origin(3), origin(4));
    let forearm = (wrist - j3).normalize();
    let tcp = data.tcp_position();
    let points: [(&str, usize, Vector3<f64>); 4] = [
        ("M1", 2, j2 + 0.4 * (j3 - j2)),
        ("M2", 3, j3 + 0.15 * forearm),
        ("M3", 4, wrist - 0.25 * (wrist - j3)),
        ("TCP", 6, tcp),
    ];
    Ok(points
        .iter()
        .map(|(name, link, p)| MeasurementRow {
            load_case: format!("fig7-fy{FIG7_FY_N:.0}N"),
            q_rad: FIG7_Q_RAD.to_vec(),
            wrench: [0.0, FIG7_FY_N, 0.0, 0.0, 0.0, 0.0],
            load_link: 6,
            load_point_m: [tcp.x, tcp.y, tcp.z],
            point: name.to_string(),
            point_link: *link,
            point_m: [p.x, p.y, p.z],
            displacement_m: None,
            sigma_m: None,
            rotation_rad: None,
            purpose: Some("Fig. 7 configuration, lateral load (Figs. 8-9)".into()),
        })
        .collect())
}

/// Measure the Fig. 7 test on the twin and predict it with each model.
pub fn fig7_study(
    cell: &CellConfig,
    nominal: &Robot,
    models: &[(&str, &Robot)],
    seed: u64,
) -> Result<(Vec<MeasurementRow>, Vec<Fig7Point>), DemoError> {
    let plan = fig7_rows(nominal)?;
    let measured = run_campaign(cell, &plan, seed)?;
    let mut predictions = Vec::new();
    for (name, robot) in models {
        predictions.push((*name, predict(robot, &measured)?));
    }
    let points = measured
        .iter()
        .enumerate()
        .map(|(i, row)| {
            let d = row.displacement_m.unwrap_or([f64::NAN; 3]);
            Fig7Point {
                point: row.point.clone(),
                link: row.point_link,
                x_mm: row.point_m[0] * 1e3,
                measured_mm: [d[0] * 1e3, d[1] * 1e3],
                sigma_mm: row.sigma_m.unwrap_or(f64::NAN) * 1e3,
                predicted_mm: predictions
                    .iter()
                    .map(|(name, p)| (name.to_string(), [p[i][0] * 1e3, p[i][1] * 1e3]))
                    .collect(),
            }
        })
        .collect();
    Ok((measured, points))
}
