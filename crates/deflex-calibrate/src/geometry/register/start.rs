//! Starting values for set-up registrations and target offsets: closed-form point-set
//! registration (Kabsch/Horn, by SVD) alternated with a linear least-squares fit of the target
//! on the flange, so the LM loop starts within millimetres wherever the tracker stood; and the
//! target frame's rotation as the chordal mean of what each measured orientation implies.

use crate::geometry::campaign::Campaign;
use crate::geometry::params::EgModel;
use nalgebra::{Matrix3, Rotation3, Vector3};

/// Best rigid `(R, t)` with `b ≈ R a + t` (least squares, proper rotation).
pub fn kabsch(a: &[Vector3<f64>], b: &[Vector3<f64>]) -> Option<(Rotation3<f64>, Vector3<f64>)> {
    if a.len() < 3 || a.len() != b.len() {
        return None;
    }
    let n = a.len() as f64;
    let ca = a.iter().sum::<Vector3<f64>>() / n;
    let cb = b.iter().sum::<Vector3<f64>>() / n;
    let mut h = Matrix3::zeros();
    for (x, y) in a.iter().zip(b) {
        h += (x - ca) * (y - cb).transpose();
    }
    let svd = h.svd(true, true);
    let (u, v_t) = (svd.u?, svd.v_t?);
    let mut d = Matrix3::identity();
    if (v_t.transpose() * u.transpose()).determinant() < 0.0 {
        d[(2, 2)] = -1.0;
    }
    let r = v_t.transpose() * d * u.transpose();
    let rotation = Rotation3::from_matrix_unchecked(r);
    Some((rotation, cb - rotation * ca))
}

/// Initialise the registrations of `setups` and the offsets of `targets` (indices into the
/// model) from the readings with `multiplicity > 0`, by alternating Kabsch and the target
/// least squares (`rounds` times). Set-ups with fewer than 3 readings are left as they are.
pub fn initialise(
    model: &mut EgModel,
    campaign: &Campaign,
    setups: &[usize],
    targets: &[usize],
    multiplicity: &[f64],
    rounds: usize,
) {
    let rows: Vec<usize> = (0..campaign.absolute.len())
        .filter(|&i| multiplicity[i] > 0.0)
        .collect();
    for _ in 0..rounds.max(1) {
        for &s in setups {
            let mut world = Vec::new();
            let mut tracker = Vec::new();
            for &i in rows.iter().filter(|&&i| campaign.setup_of[i] == s) {
                let loads = campaign.conditions(model, i);
                let ev = model.evaluate(&campaign.absolute[i].q_rad, campaign.target_of[i], &loads);
                world.push(ev.predicted_world());
                tracker.push(Vector3::from(campaign.absolute[i].position_m));
            }
            if let Some((r, t)) = kabsch(&world, &tracker) {
                model.setups[s].pose = deflex_model::Pose::from_parts(t.into(), r);
            }
        }
        if targets.is_empty() {
            continue;
        }
        for &t in targets {
            // R_s F_rot x = p − R_s (F_pos + sag) − t_s, stacked over the target's readings.
            let mut normal = Matrix3::zeros();
            let mut rhs = Vector3::zeros();
            for &i in rows.iter().filter(|&&i| campaign.target_of[i] == t) {
                let s = campaign.setup_of[i];
                let loads = campaign.conditions(model, i);
                let row = &campaign.absolute[i];
                let ev = model.evaluate(&row.q_rad, t, &loads);
                let setup = &model.setups[s].pose;
                let a = (setup.rotation * ev.data.flange.rotation).into_inner();
                let flange_origin = ev.data.flange.translation.vector;
                let b = Vector3::from(row.position_m)
                    - setup
                        .transform_point(
                            &(flange_origin + ev.sag_world + ev.correction_world).into(),
                        )
                        .coords;
                normal += a.transpose() * a;
                rhs += a.transpose() * b;
            }
            if let Some(x) = normal.try_inverse().map(|inv| inv * rhs) {
                model.targets[t].position = x;
            }
        }
    }
}

/// The rotation nearest (Frobenius) to a 3×3 matrix: `U·diag(1, 1, det(U Vᵀ))·Vᵀ`.
fn nearest_rotation(m: &Matrix3<f64>) -> Option<Rotation3<f64>> {
    let svd = m.svd(true, true);
    let (u, v_t) = (svd.u?, svd.v_t?);
    let mut d = Matrix3::identity();
    if (u * v_t).determinant() < 0.0 {
        d[(2, 2)] = -1.0;
    }
    Some(Rotation3::from_matrix_unchecked(u * d * v_t))
}

/// Initialise the frame rotation of `targets` from the measured orientations of the readings
/// with `multiplicity > 0`: each implies `R_t = (R_s exp(θ_sag) R_F)ᵀ R_measured`; their
/// chordal mean (the rotation nearest to the sum). Targets without such readings are left as
/// they are.
pub fn initialise_target_rotations(
    model: &mut EgModel,
    campaign: &Campaign,
    targets: &[usize],
    multiplicity: &[f64],
) {
    for &t in targets {
        let mut sum = Matrix3::zeros();
        let mut count = 0;
        for i in (0..campaign.absolute.len()).filter(|&i| multiplicity[i] > 0.0) {
            if campaign.target_of[i] != t {
                continue;
            }
            let Some(measured) = campaign.measured_orientation(i) else {
                continue;
            };
            let row = &campaign.absolute[i];
            let ev = model.evaluate(&row.q_rad, t, &campaign.conditions(model, i));
            let flange = model.setups[campaign.setup_of[i]].pose.rotation
                * Rotation3::from_scaled_axis(ev.sag_rotation)
                * ev.data.flange.rotation;
            sum += (flange.inverse() * measured).into_inner();
            count += 1;
        }
        if count > 0
            && let Some(r) = nearest_rotation(&sum)
        {
            model.targets[t].rotation = Some(r);
        }
    }
}
