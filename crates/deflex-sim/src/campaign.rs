//! Calibration and validation campaigns on the twin (SIMULATED), written in the measurement
//! format of `deflex_calib::data`.
//!
//! * [`run_campaign`]: a plan (load cases: configuration, load by cable tension or dead weight,
//!   points to measure) → for each load case the tracker reads every point unloaded, the load is
//!   applied **to the plant**, the tracker reads the points again; the row's displacement is the
//!   difference of the two (averaged) readings, its `sigma_m` the tracker's 1σ for it, and the
//!   reported wrench is what the load cell measured (nominal load plus sensor noise). The plant's
//!   hysteresis state carries over from one load case to the next, as on the real robot.
//! * [`validation_grid`]: the paper's 200 poses on a 0.6 × 0.6 m plane at z = 0.1 m centred on
//!   the work area, 600 N and 1100 N dead weights (Section 3.2, Figs. 10–13), as a plan.
//! * [`spiral`]: the spiral of Fig. 14 (0.25 m initial radius, 2.7 m long, z = 0.3 m, 600 N
//!   dead weight, 10 mm/s) tracked at the tracker rate; displacement = tracked loaded position −
//!   commanded position.

use crate::config::CellConfig;
use crate::error::SimError;
use crate::plant::Plant;
use crate::tracker::LaserTracker;
use deflex_calib::MeasurementRow;
use deflex_model::{IkOptions, Pose, Robot, Wrench};
use nalgebra::{Point3, Rotation3, Vector3};
use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;
use rand_distr::StandardNormal;

/// Run a measurement campaign on the plant for the plan rows (rows of one load case must share
/// the configuration and the load). Output rows keep the plan's order.
pub fn run_campaign(
    config: &CellConfig,
    plan: &[MeasurementRow],
    seed: u64,
) -> Result<Vec<MeasurementRow>, SimError> {
    config.validate()?;
    let nominal = config.nominal_robot()?;
    let mut plant = Plant::new(&config.plant, &nominal)?;
    let (mut tracker, mut rng) = instruments(config, seed);
    let sigma = config.sensor.noise_sigma;
    let mut out = Vec::with_capacity(plan.len());
    let mut start = 0;
    while start < plan.len() {
        let case = &plan[start].load_case;
        let end = start
            + plan[start..]
                .iter()
                .take_while(|r| &r.load_case == case)
                .count();
        let rows = &plan[start..end];
        let first = &rows[0];
        if first.q_rad.len() != 6 {
            return Err(SimError::Path(format!(
                "load case {case}: the twin's robot has 6 joints, the plan gives {}",
                first.q_rad.len()
            )));
        }
        for r in rows {
            if r.q_rad != first.q_rad || r.wrench != first.wrench {
                return Err(SimError::Path(format!(
                    "load case {case}: all its rows must share the configuration and the load"
                )));
            }
        }
        let mut q = [0.0; 6];
        q.copy_from_slice(&first.q_rad);
        plant.set_configuration(&q);
        let wrench = Wrench::from_row_slice(&first.wrench);
        // Unloaded readings (the hysteresis of earlier cases may leave a small offset).
        let mut unloaded = Vec::with_capacity(rows.len());
        for r in rows {
            let p = Vector3::from(r.point_m);
            let a = Vector3::from(r.load_point_m);
            let d = plant.point_displacement(&p, r.point_link, &a, r.load_link, &Wrench::zeros());
            unloaded.push(tracker.measure_static(&(p + d.fixed_rows::<3>(0))));
        }
        // The load cell's reading of the applied load.
        let mut measured_wrench = first.wrench;
        for (w, s) in measured_wrench.iter_mut().zip(sigma) {
            *w += s * rng.sample::<f64, _>(StandardNormal);
        }
        for (r, (u, su)) in rows.iter().zip(unloaded) {
            let p = Vector3::from(r.point_m);
            let a = Vector3::from(r.load_point_m);
            let d = plant.point_displacement(&p, r.point_link, &a, r.load_link, &wrench);
            let (l, sl) = tracker.measure_static(&(p + d.fixed_rows::<3>(0)));
            let disp = l - u;
            out.push(MeasurementRow {
                wrench: measured_wrench,
                point_m: [u.x, u.y, u.z],
                displacement_m: Some([disp.x, disp.y, disp.z]),
                sigma_m: Some((su * su + sl * sl).sqrt()),
                rotation_rad: None,
                ..r.clone()
            });
        }
        // Unload: the wrist reducers keep part of the lost motion.
        for r in rows {
            let p = Vector3::from(r.point_m);
            let a = Vector3::from(r.load_point_m);
            plant.point_displacement(&p, r.point_link, &a, r.load_link, &Wrench::zeros());
        }
        start = end;
    }
    Ok(out)
}

fn instruments(config: &CellConfig, seed: u64) -> (LaserTracker, ChaCha8Rng) {
    let mut tracker_rng = ChaCha8Rng::seed_from_u64(seed);
    tracker_rng.set_stream(3);
    let mut load_rng = ChaCha8Rng::seed_from_u64(seed);
    load_rng.set_stream(4);
    (LaserTracker::new(&config.tracker, tracker_rng), load_rng)
}

fn ik_down(
    robot: &Robot,
    rotation: &Rotation3<f64>,
    p: &Vector3<f64>,
    seed: &mut [f64],
    what: &str,
) -> Result<[f64; 6], SimError> {
    let target = Pose::from_parts((*p).into(), *rotation);
    let options = IkOptions {
        position_tolerance_m: 1e-10,
        orientation_tolerance_rad: 1e-10,
        ..IkOptions::default()
    };
    let solution = robot
        .inverse_kinematics(&target, seed, &options)
        .map_err(|source| SimError::Unreachable {
            what: what.to_string(),
            source,
        })?;
    seed.copy_from_slice(&solution.q);
    let mut q = [0.0; 6];
    q.copy_from_slice(&solution.q);
    Ok(q)
}

/// The paper's validation grid as a plan: 20 × 10 = 200 TCP positions regularly spaced over a
/// 0.6 × 0.6 m square at z = 0.1 m centred on (x, y) = (1.5, 0) m (the ISF work area), tool
/// pointing down, each loaded by a 600 N and by a 1100 N dead weight (force along −z at the TCP).
pub fn validation_grid(config: &CellConfig) -> Result<Vec<MeasurementRow>, SimError> {
    let robot = config.nominal_robot()?;
    let seed_q = config.seed_q_rad();
    let rotation = robot
        .tcp_pose(&seed_q)
        .map_err(|e| SimError::config("part.seed_q_deg", e.to_string()))?
        .rotation;
    let mut seed = seed_q.to_vec();
    let (nx, ny) = (10, 20);
    let mut rows = Vec::with_capacity(2 * nx * ny);
    let mut index = 0;
    for iy in 0..ny {
        for k in 0..nx {
            // Serpentine order keeps IK seeds close.
            let ix = if iy % 2 == 0 { k } else { nx - 1 - k };
            let x = 1.5 - 0.3 + 0.6 * ix as f64 / (nx - 1) as f64;
            let y = -0.3 + 0.6 * iy as f64 / (ny - 1) as f64;
            let p = Vector3::new(x, y, 0.1);
            let q = ik_down(
                &robot,
                &rotation,
                &p,
                &mut seed,
                &format!("grid pose ({x:.3}, {y:.3}, 0.1) m"),
            )?;
            index += 1;
            for load in [600.0, 1100.0] {
                rows.push(MeasurementRow {
                    load_case: format!("grid{load:.0}N-{index:03}"),
                    q_rad: q.to_vec(),
                    wrench: [0.0, 0.0, -load, 0.0, 0.0, 0.0],
                    load_link: 6,
                    load_point_m: [p.x, p.y, p.z],
                    point: "TCP".into(),
                    point_link: 6,
                    point_m: [p.x, p.y, p.z],
                    displacement_m: None,
                    sigma_m: None,
                    rotation_rad: None,
                    purpose: Some(format!(
                        "validation grid {load:.0} N dead weight (Figs. 10-13)"
                    )),
                });
            }
        }
    }
    Ok(rows)
}

/// Spiral settings (Fig. 14).
#[derive(Clone, Debug, PartialEq)]
pub struct SpiralParams {
    /// Centre (m, world).
    pub center_m: [f64; 3],
    /// Initial radius (m).
    pub initial_radius_m: f64,
    /// Radius lost per turn (m).
    pub pitch_m: f64,
    /// Length (m).
    pub length_m: f64,
    /// Speed (m/s).
    pub speed_m_s: f64,
    /// Dead weight (N, along −z).
    pub load_n: f64,
}

impl Default for SpiralParams {
    /// The paper's spiral: 0.25 m initial radius, 2.7 m long, 0.2 m above the ISF work area
    /// (z = 0.3 m), 600 N, 10 mm/s. The pitch is not published; 50 mm per turn.
    fn default() -> Self {
        SpiralParams {
            center_m: [1.5, 0.0, 0.3],
            initial_radius_m: 0.25,
            pitch_m: 0.05,
            length_m: 2.7,
            speed_m_s: 0.010,
            load_n: 600.0,
        }
    }
}

/// Track the spiral with the dead weight hanging at the TCP: one measurement row per tracker
/// sample (50 Hz: 13 500 rows for the paper's spiral).
pub fn spiral(
    config: &CellConfig,
    params: &SpiralParams,
    seed: u64,
) -> Result<Vec<MeasurementRow>, SimError> {
    config.validate()?;
    let robot = config.nominal_robot()?;
    let mut plant = Plant::new(&config.plant, &robot)?;
    let (mut tracker, mut rng) = instruments(config, seed);
    let seed_q = config.seed_q_rad();
    let rotation = robot
        .tcp_pose(&seed_q)
        .map_err(|e| SimError::config("part.seed_q_deg", e.to_string()))?
        .rotation;
    let mut ik_seed = seed_q.to_vec();
    let dt = tracker.period_s();
    let samples = (params.length_m / params.speed_m_s / dt).floor() as usize + 1;
    let b = params.pitch_m / (2.0 * std::f64::consts::PI);
    let wrench = Wrench::new(0.0, 0.0, -params.load_n, 0.0, 0.0, 0.0);
    let center = Vector3::from(params.center_m);
    let (mut theta, mut travelled) = (0.0f64, 0.0f64);
    let mut rows = Vec::with_capacity(samples);
    for k in 0..samples {
        let target_length = k as f64 * dt * params.speed_m_s;
        // Advance θ along the arc length (small steps, exact enough at 0.2 mm per sample).
        while travelled < target_length {
            let r = params.initial_radius_m - b * theta;
            if r <= 0.0 {
                return Err(SimError::Path(
                    "spiral reaches its centre: shorten it".into(),
                ));
            }
            let dtheta = 1e-4 / r;
            travelled += (r * r + b * b).sqrt() * dtheta;
            theta += dtheta;
        }
        let r = params.initial_radius_m - b * theta;
        let p = center + Vector3::new(r * theta.cos(), r * theta.sin(), 0.0);
        let q = ik_down(
            &robot,
            &rotation,
            &p,
            &mut ik_seed,
            &format!("spiral sample {k}"),
        )?;
        plant.set_configuration(&q);
        let tcp = plant.tcp_pose().translation.vector;
        let d = plant.point_displacement(&tcp, 6, &tcp, 6, &wrench);
        let reading = tracker.measure(&(tcp + d.fixed_rows::<3>(0)));
        let disp = reading - tcp;
        let mut measured = [0.0, 0.0, -params.load_n, 0.0, 0.0, 0.0];
        for (w, s) in measured.iter_mut().zip(config.sensor.noise_sigma) {
            *w += s * rng.sample::<f64, _>(StandardNormal);
        }
        let p: Point3<f64> = tcp.into();
        rows.push(MeasurementRow {
            load_case: format!("spiral-{k:05}"),
            q_rad: q.to_vec(),
            wrench: measured,
            load_link: 6,
            load_point_m: [p.x, p.y, p.z],
            point: "TCP".into(),
            point_link: 6,
            point_m: [p.x, p.y, p.z],
            displacement_m: Some([disp.x, disp.y, disp.z]),
            sigma_m: Some(tracker.sigma_at(&tcp)),
            rotation_rad: None,
            purpose: Some(format!("spiral (Fig. 14), t = {:.2} s", k as f64 * dt)),
        });
    }
    Ok(rows)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn grid_has_200_poses_on_the_paper_plane() {
        let config = CellConfig::default();
        let plan = validation_grid(&config).unwrap();
        assert_eq!(plan.len(), 400);
        let robot = config.nominal_robot().unwrap();
        for row in plan.iter().step_by(37) {
            let p = robot.tcp_pose(&row.q_rad).unwrap().translation.vector;
            assert!((p - Vector3::from(row.point_m)).norm() < 1e-8);
            assert!(
                (p.z - 0.1).abs() < 1e-8
                    && (p.x - 1.5).abs() <= 0.3 + 1e-9
                    && p.y.abs() <= 0.3 + 1e-9
            );
        }
    }

    #[test]
    fn campaign_measures_the_plant_not_the_model() {
        let config = CellConfig::default();
        let plan: Vec<_> = validation_grid(&config)
            .unwrap()
            .into_iter()
            .take(20)
            .collect();
        let meas = run_campaign(&config, &plan, 5).unwrap();
        assert_eq!(meas.len(), plan.len());
        let nominal = config.nominal_robot().unwrap();
        let mut plant = Plant::new(&config.plant, &nominal).unwrap();
        for (m, p) in meas.iter().zip(&plan) {
            let d = m.displacement_m.unwrap();
            // Downward load: the TCP goes down by about a millimetre.
            assert!(d[2] < -0.5e-3 && d[2] > -5e-3, "{d:?}");
            let mut q = [0.0; 6];
            q.copy_from_slice(&p.q_rad);
            plant.set_configuration(&q);
            let tcp = Vector3::from(p.point_m);
            let truth =
                plant.point_displacement(&tcp, 6, &tcp, 6, &Wrench::from_row_slice(&p.wrench));
            let s = m.sigma_m.unwrap();
            assert!(
                (d[2] - truth[2]).abs() < 6.0 * s + 2e-6,
                "{} vs {}",
                d[2],
                truth[2]
            );
        }
        // Deterministic under the seed.
        assert_eq!(run_campaign(&config, &plan, 5).unwrap(), meas);
        assert_ne!(run_campaign(&config, &plan, 6).unwrap(), meas);
    }

    #[test]
    fn spiral_is_2_7_m_at_50_hz() {
        let config = CellConfig::default();
        let short = SpiralParams {
            length_m: 0.05,
            ..SpiralParams::default()
        };
        let rows = spiral(&config, &short, 1).unwrap();
        assert_eq!(rows.len(), 251);
        let a = Vector3::from(rows[0].point_m);
        let b = Vector3::from(rows[250].point_m);
        assert!(((a - b).norm() - 0.05).abs() < 1e-3);
        assert!((a.z - 0.3).abs() < 1e-8 && (a.x - 1.75).abs() < 1e-8);
        let full = SpiralParams::default();
        assert_eq!((full.length_m / full.speed_m_s * 50.0) as usize, 13_500);
    }
}
