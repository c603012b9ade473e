//! Synthetic measurements from a known model: the displacement of each planned point under its
//! load case by the VJM transfer (eq. 15 generalised to any point/load link), optionally plus a
//! coupling term the diagonal-K_θ family cannot represent, plus Gaussian tracker noise;
//! optionally also the small rotation of the measured point's link (a 6-DoF probe), with its
//! own noise.
//! Used by the recovery tests, the benches and demos.

use crate::measurements::{MeasuredRotation, MeasurementRow};
use crate::stiffness::CalibError;
use crate::stiffness::campaign_cell::{random_q, standard_points};
use crate::stiffness::design::EdofId;
use deflex_model::{Data, Robot, Wrench};
use nalgebra::{Vector3, Vector6};
use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;
use rand_distr::{Distribution, Normal, UnitSphere};

/// An off-diagonal compliance between two eDoFs (K_θ⁻¹ no longer diagonal, eq. 11 violated):
/// `δ += c_ab (j_a(P) j_b(A)ᵀ + j_b(P) j_a(A)ᵀ) w`.
#[derive(Clone, Copy, Debug)]
pub struct Coupling {
    /// First eDoF.
    pub a: EdofId,
    /// Second eDoF.
    pub b: EdofId,
    /// Cross compliance (rad/(N·m)).
    pub compliance: f64,
}

/// Options of [`measure`].
#[derive(Clone, Debug)]
pub struct SyntheticOptions {
    /// Tracker noise standard deviation per axis (m).
    pub noise_sigma_m: f64,
    /// Random seed.
    pub seed: u64,
    /// Coupling terms added to the truth.
    pub coupling: Vec<Coupling>,
    /// Write `sigma_m` (and `sigma_rad` in [`measure_with_rotations`]) into the rows.
    pub record_sigma: bool,
}

impl Default for SyntheticOptions {
    fn default() -> Self {
        SyntheticOptions {
            noise_sigma_m: 15e-6,
            seed: 1,
            coupling: Vec::new(),
            record_sigma: true,
        }
    }
}

/// Fill the displacement of every plan row from the `truth` model (plus coupling and noise).
pub fn measure(
    truth: &Robot,
    plan: &[MeasurementRow],
    options: &SyntheticOptions,
) -> Result<Vec<MeasurementRow>, CalibError> {
    measure_rows(truth, plan, options, None)
}

/// [`measure`], and also the small rotation of each measured point's link (`rotation_rad`, as
/// a 6-DoF probe sees it) plus Gaussian noise of `rotation_noise_sigma_rad` per axis (rad),
/// with `sigma_rad` recorded when [`SyntheticOptions::record_sigma`]. The rotation noise has
/// its own random stream: the displacements are exactly those of [`measure`].
pub fn measure_with_rotations(
    truth: &Robot,
    plan: &[MeasurementRow],
    options: &SyntheticOptions,
    rotation_noise_sigma_rad: f64,
) -> Result<Vec<MeasurementRow>, CalibError> {
    measure_rows(truth, plan, options, Some(rotation_noise_sigma_rad))
}

fn measure_rows(
    truth: &Robot,
    plan: &[MeasurementRow],
    options: &SyntheticOptions,
    rotation_noise_sigma_rad: Option<f64>,
) -> Result<Vec<MeasurementRow>, CalibError> {
    // Salted so that the noise stream never equals a campaign generated with the same seed
    // (which would correlate the noise with the design and bias the fit).
    let mut rng = ChaCha8Rng::seed_from_u64(options.seed ^ 0x9E37_79B9_7F4A_7C15);
    let noise =
        Normal::new(0.0, options.noise_sigma_m.max(0.0)).map_err(|source| CalibError::Noise {
            what: "noise",
            source,
        })?;
    let mut rotation_rng = ChaCha8Rng::seed_from_u64(options.seed ^ 0x6A09_E667_F3BC_C908);
    let rotation_noise = rotation_noise_sigma_rad
        .map(|s| Normal::new(0.0, s.max(0.0)))
        .transpose()
        .map_err(|source| CalibError::Noise {
            what: "rotation noise",
            source,
        })?;
    let mut data = Data::new();
    let mut out = Vec::with_capacity(plan.len());
    let mut last_q: Option<Vec<f64>> = None;
    for row in plan {
        if last_q.as_deref() != Some(row.q_rad.as_slice()) {
            truth.forward_kinematics(&mut data, &row.q_rad)?;
            last_q = Some(row.q_rad.clone());
        }
        let p = Vector3::from(row.point_m);
        let a = Vector3::from(row.load_point_m);
        let w = Wrench::from_row_slice(&row.wrench);
        let mut d = truth.point_displacement(&data, &p, row.point_link, &a, row.load_link, &w);
        for c in &options.coupling {
            let screw = |id: EdofId, x: &Vector3<f64>| -> Vector6<f64> {
                let (v, o) = data.edof_axis_center(truth, id.0, id.1);
                deflex_model::edof_screw(&v, &o, x)
            };
            // In joint space: the load puts a torque on each eDoF that lies between the base
            // and its link; the coupling turns each end by c times the other end's torque; a
            // turn moves the point when the eDoF lies between the base and the point's link.
            let torque = |id: EdofId| {
                if id.0.link_index() <= row.load_link {
                    screw(id, &a).dot(&w)
                } else {
                    0.0
                }
            };
            let turns = [
                (c.a, c.compliance * torque(c.b)),
                (c.b, c.compliance * torque(c.a)),
            ];
            for (id, theta) in turns {
                if id.0.link_index() <= row.point_link {
                    d += screw(id, &p) * theta;
                }
            }
        }
        let mut r = row.clone();
        r.displacement_m = Some([
            d.x + noise.sample(&mut rng),
            d.y + noise.sample(&mut rng),
            d.z + noise.sample(&mut rng),
        ]);
        if options.record_sigma {
            r.sigma_m = Some(options.noise_sigma_m);
        }
        if let Some(noise) = rotation_noise {
            r.rotation_rad = Some(MeasuredRotation {
                value_rad: [
                    d[3] + noise.sample(&mut rotation_rng),
                    d[4] + noise.sample(&mut rotation_rng),
                    d[5] + noise.sample(&mut rotation_rng),
                ],
                sigma_rad: options
                    .record_sigma
                    .then_some(rotation_noise_sigma_rad)
                    .flatten(),
            });
        }
        out.push(r);
    }
    Ok(out)
}

/// A random campaign: `load_cases` configurations uniform within the joint limits (±π without
/// limits), each loaded at the TCP by a force of random direction and magnitude in
/// `force_range_n`, measuring the TCP and the standard mid-arm points ([`standard_points`]).
/// Plan rows (no displacement).
pub fn random_campaign(
    robot: &Robot,
    load_cases: usize,
    force_range_n: (f64, f64),
    seed: u64,
) -> Vec<MeasurementRow> {
    let mut rng = ChaCha8Rng::seed_from_u64(seed);
    let mut data = Data::new();
    let mut rows = Vec::new();
    for case in 0..load_cases {
        let q = random_q(robot, &mut rng);
        let dir: [f64; 3] = UnitSphere.sample(&mut rng);
        let magnitude = if force_range_n.1 > force_range_n.0 {
            rng.gen_range(force_range_n.0..=force_range_n.1)
        } else {
            force_range_n.0
        };
        let force = Vector3::from(dir) * magnitude;
        if robot.forward_kinematics(&mut data, &q).is_err() {
            continue;
        }
        rows.extend(case_rows(
            robot,
            &data,
            &q,
            &force,
            &format!("R{:04}", case + 1),
            None,
        ));
    }
    rows
}

/// The rows of one load case: force at the TCP (link N), measuring the standard points.
pub fn case_rows(
    robot: &Robot,
    data: &Data,
    q: &[f64],
    force: &Vector3<f64>,
    label: &str,
    purpose: Option<&str>,
) -> Vec<MeasurementRow> {
    let tcp = data.tcp_position();
    standard_points(robot, data)
        .into_iter()
        .map(|(name, link, p)| MeasurementRow {
            load_case: label.to_string(),
            q_rad: q.to_vec(),
            wrench: [force.x, force.y, force.z, 0.0, 0.0, 0.0],
            load_link: robot.joint_count(),
            load_point_m: [tcp.x, tcp.y, tcp.z],
            point: name,
            point_link: link,
            point_m: [p.x, p.y, p.z],
            displacement_m: None,
            sigma_m: None,
            rotation_rad: None,
            purpose: purpose.map(str::to_string),
        })
        .collect()
}

/// The paper's validation set-up (Section 3.2, Figs. 10–13): TCP on a horizontal square grid
/// (`side_m`, `per_side` points per side, centred at `center_m`), tool pointing down, a vertical
/// load `force_z_n` (negative = deadweight). Points the IK cannot reach are skipped. Measures
/// the TCP only. `seed_q` seeds the IK (the forming configuration of the paper for the TX200).
pub fn grid_campaign(
    robot: &Robot,
    center_m: [f64; 3],
    side_m: f64,
    per_side: usize,
    force_z_n: f64,
    seed_q: &[f64],
) -> Vec<MeasurementRow> {
    use deflex_model::spatial::pose_from_xyz_rpy;
    let mut rows = Vec::new();
    let mut data = Data::new();
    let mut seed = seed_q.to_vec();
    let n = per_side.max(1);
    for j in 0..n {
        for i in 0..n {
            let t = |k: usize| {
                if n == 1 {
                    0.0
                } else {
                    k as f64 / (n - 1) as f64 - 0.5
                }
            };
            let x = center_m[0] + side_m * t(i);
            let y = center_m[1] + side_m * t(j);
            let target = pose_from_xyz_rpy([x, y, center_m[2]], [std::f64::consts::PI, 0.0, 0.0]);
            let Ok(sol) =
                robot.inverse_kinematics(&target, &seed, &deflex_model::IkOptions::default())
            else {
                continue;
            };
            seed = sol.q.clone();
            if robot.forward_kinematics(&mut data, &sol.q).is_err() {
                continue;
            }
            let tcp = data.tcp_position();
            rows.push(MeasurementRow {
                load_case: format!("G{:03}", j * n + i + 1),
                q_rad: sol.q,
                wrench: [0.0, 0.0, force_z_n, 0.0, 0.0, 0.0],
                load_link: robot.joint_count(),
                load_point_m: [tcp.x, tcp.y, tcp.z],
                point: "TCP".into(),
                point_link: robot.joint_count(),
                point_m: [tcp.x, tcp.y, tcp.z],
                displacement_m: None,
                sigma_m: None,
                rotation_rad: None,
                purpose: Some("validation grid".into()),
            });
        }
    }
    rows
}
