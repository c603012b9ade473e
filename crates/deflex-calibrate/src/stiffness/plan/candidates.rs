//! Candidate load cases: configurations drawn within the limits and clear of the cell, each
//! loaded by every allowed cable direction or dead weight at every attachment, with the Fisher
//! information it brings.

use super::options::PlanOptions;
use crate::measurements::MeasurementRow;
use crate::stiffness::CalibError;
use crate::stiffness::campaign_cell::{
    LoadKind, Obstacles, PointSet, point_in_world, standard_points, wrap_into_limits,
};
use crate::stiffness::design::{Design, EdofId};
use deflex_model::{Data, Robot};
use nalgebra::{DMatrix, Point3, Vector3};
use rand::SeedableRng;
use rand_chacha::ChaCha8Rng;

/// Round joint values to 0.1° without leaving the limits.
fn round_within_limits(robot: &Robot, q: &mut [f64]) {
    for (value, joint) in q.iter_mut().zip(&robot.joints) {
        let tenths = value.to_degrees() * 10.0;
        let mut rounded = tenths.round().to_radians() / 10.0;
        if let Some([lo, hi]) = joint.limits {
            if rounded < lo {
                rounded = tenths.ceil().to_radians() / 10.0;
            }
            if rounded > hi {
                rounded = tenths.floor().to_radians() / 10.0;
            }
        }
        *value = rounded;
    }
}

/// One candidate load case: its rows and the information it brings.
pub(super) struct Candidate {
    pub(super) rows: Vec<MeasurementRow>,
    /// Purpose words: how it is loaded (`cable`, `dead weight 140 kg`, `at the bracket`).
    pub(super) loading: String,
    /// `U Uᵀ` with U the relative-compliance sensitivities in units of σ (p × p).
    pub(super) info: DMatrix<f64>,
    /// Per eDoF: the norm of its sensitivity row (its displacement in σ).
    pub(super) norms: Vec<f64>,
}

/// The measured points of a configuration: (label, link, world position).
fn measured_points(
    robot: &Robot,
    data: &Data,
    o: &PlanOptions,
    base_point: Option<[f64; 3]>,
) -> Vec<(String, usize, Vector3<f64>)> {
    let n = robot.joint_count();
    let mut points = vec![("TCP".to_string(), n, data.tcp_position())];
    if let Some(b) = o.bracket_m {
        points.push((
            "BR".to_string(),
            n,
            data.tcp.transform_point(&Point3::from(b)).coords,
        ));
    }
    match &o.points {
        PointSet::Standard => points.extend(standard_points(robot, data).into_iter().skip(1)),
        PointSet::Custom(list) => points.extend(list.iter().map(|p| {
            (
                p.name.clone(),
                p.link,
                point_in_world(data, p.link, &p.position_m),
            )
        })),
    }
    if let Some(m0) = base_point {
        points.push(("M0".to_string(), 0, point_in_world(data, 0, &m0)));
    }
    points
}

/// Draw configurations and build the candidate load cases with their information.
#[allow(clippy::too_many_arguments)]
pub(super) fn candidates(
    robot: &Robot,
    o: &PlanOptions,
    obstacles: &Obstacles,
    base_point: Option<[f64; 3]>,
    edofs: &[EdofId],
    nominal: &[f64],
    shifts: &[f64],
) -> Result<(Vec<Candidate>, usize, usize), CalibError> {
    let n = robot.joint_count();
    let mut rng = ChaCha8Rng::seed_from_u64(o.seed);
    let mut data = Data::new();
    let loads: Vec<(Vector3<f64>, bool, String)> = match &o.load {
        LoadKind::Cable { directions } => directions
            .iter()
            .map(|d| {
                let d = Vector3::from(*d);
                (d * o.max_force_n, d.z < -0.7, "cable".to_string())
            })
            .collect(),
        LoadKind::DeadWeight { masses_kg } => masses_kg
            .iter()
            .map(|m| (robot.gravity * *m, true, format!("dead weight {m} kg")))
            .collect(),
    };
    let mut out = Vec::new();
    let (mut kept, mut drawn) = (0, 0);
    while kept < o.configurations && drawn < 20 * o.configurations {
        drawn += 1;
        let mut q: Vec<f64> = crate::stiffness::campaign_cell::random_q(robot, &mut rng);
        round_within_limits(robot, &mut q);
        // The rows carry the joint values wrapped into the limits (what the technician types);
        // the information is computed at the values drawn, the same pose.
        let mut q_wrapped = q.clone();
        wrap_into_limits(robot, &mut q_wrapped);
        robot.forward_kinematics(&mut data, &q)?;
        let points = measured_points(robot, &data, o, base_point);
        let positions: Vec<Vector3<f64>> = points.iter().map(|p| p.2).collect();
        if !obstacles.arm_clear(robot, &data, &positions) {
            continue;
        }
        kept += 1;
        let mut attachments = vec![("TCP", data.tcp_position())];
        if o.bracket_m.is_some() {
            attachments.push(("BR", points[1].2));
        }
        let mut batch: Vec<(Vec<MeasurementRow>, String)> = Vec::new();
        for (attachment, at) in &attachments {
            for (force, hanging, loading) in &loads {
                if *hanging && !obstacles.hanging_clear(at) {
                    continue;
                }
                let rows = points
                    .iter()
                    .map(|(name, link, p)| MeasurementRow {
                        load_case: String::new(),
                        q_rad: q_wrapped.clone(),
                        wrench: [force.x, force.y, force.z, 0.0, 0.0, 0.0],
                        load_link: n,
                        load_point_m: [at.x, at.y, at.z],
                        point: name.clone(),
                        point_link: *link,
                        point_m: [p.x, p.y, p.z],
                        displacement_m: None,
                        sigma_m: Some(o.noise_sigma_m),
                        rotation_rad: None,
                        purpose: None,
                    })
                    .collect();
                let loading = if *attachment == "BR" {
                    format!("{loading} at the bracket")
                } else {
                    loading.clone()
                };
                batch.push((rows, loading));
            }
        }
        if batch.is_empty() {
            continue;
        }
        out.extend(information(robot, batch, &q, edofs, nominal, shifts)?);
    }
    Ok((out, drawn, kept))
}

/// The information of each candidate of a batch (one configuration), from one design built at
/// the joint values drawn (`q_drawn`; the rows carry them wrapped).
fn information(
    robot: &Robot,
    batch: Vec<(Vec<MeasurementRow>, String)>,
    q_drawn: &[f64],
    edofs: &[EdofId],
    nominal: &[f64],
    shifts: &[f64],
) -> Result<Vec<Candidate>, CalibError> {
    let flat: Vec<MeasurementRow> = batch
        .iter()
        .flat_map(|b| b.0.iter())
        .map(|r| MeasurementRow {
            q_rad: q_drawn.to_vec(),
            ..r.clone()
        })
        .collect();
    let design = Design::build(robot, &flat, edofs, false)?;
    let p = edofs.len();
    let mut eq0 = 0;
    let mut out = Vec::with_capacity(batch.len());
    for (rows, loading) in batch {
        let m = 3 * rows.len();
        let mut u = DMatrix::<f64>::zeros(p, m);
        for e in 0..p {
            let s = design.shift_joint(e).map(|j| shifts[j - 1]).unwrap_or(0.0);
            for (b, coef) in design.col(e, s) {
                for k in 0..m {
                    u[(e, k)] += coef * design.x[(eq0 + k, b)] * nominal[e].recip();
                }
            }
        }
        eq0 += m;
        let info = &u * u.transpose();
        let norms: Vec<f64> = (0..p).map(|e| info[(e, e)].max(0.0).sqrt()).collect();
        out.push(Candidate {
            rows,
            loading,
            info,
            norms,
        });
    }
    Ok(out)
}
