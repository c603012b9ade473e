//! Joint-angle error maps: what each joint's angle is off by, as a smooth function of that
//! joint's own angle, learnt from what the parametric model leaves.
//!
//! **Why.** A joint's measured angle is not its true angle to within a constant (the θ offset)
//! or a low harmonic (encoder eccentricity): an output encoder's scale has its own graduation
//! error, and a strain-wave gear's transmission error and the encoder's interpolation error
//! repeat over a few degrees. What they share is that they depend on that joint's angle alone
//! and repeat from one session to the next: on the real UR10 data such errors on joints 1–4
//! are most of the 0.42 mm the parametric model leaves, and a map learnt on one series and
//! session transfers to others (README, UR10 section).
//!
//! **Model.** Joint j turns by `q_j + Δθ_j(q_j)`, with `Δθ_j` a uniform cubic B-spline of knot
//! spacing h (`Δθ_j(q) = Σ_k c_{j,k} B_k((q − q₀)/h)`, zero outside its knots), added to the
//! joint values before the forward kinematics like the harmonics (so positions, orientations
//! and the sag all follow it).
//!
//! **Training** (a linear, penalised least squares on the fitted model's residuals). Each
//! reading i of a training row gives the residual `r_i` (position, tracker frame; and, when
//! orientations are fitted, the rotation vector) and the column `J_ij` of a change of joint j's
//! angle at that reading (the θ_j column of [`crate::geometry::jacobian`], the sag's change included), so
//! that `r_i ≈ Σ_j J_ij Σ_k c_{j,k} B_k(q_ij) + (registration increments)`. The set-ups' six
//! registration increments are unknowns too (unpenalised), so that nothing rigid is learnt as a
//! map; they are applied to the set-ups. The coefficients have a Gaussian prior: each
//! `c_{j,k} ~ N(0, σ_v²)` (a map returns to zero where no reading constrains it) and each
//! second difference `c_{j,k−1} − 2c_{j,k} + c_{j,k+1} ~ N(0, σ_c²)` (smooth between knots);
//! the readings are weighted by the training residual's own scatter per component (position
//! and orientation separately), so σ_v and σ_c are in radians whatever the tracker's noise. The
//! normal matrix is accumulated sparsely (a reading touches four coefficients per mapped joint
//! and six registration increments) and solved by Cholesky.
//!
//! **Hyper-parameters** (which joints, h, σ_v, σ_c) are not fitted to the training rows: the
//! caller picks them from [`MAPS_GRID`] by the held-out protocol across sessions or series
//! ([`crate::geometry::fit`]), like the residual model's.

use crate::geometry::campaign::{Campaign, ReadingKind};
use crate::geometry::params::{DhField, EgModel, Param};
use nalgebra::{DMatrix, DVector, Vector3};

/// Largest number of coefficients of one joint's map.
pub const MAX_MAP_COEFFICIENTS: usize = 4096;
/// Smallest knot spacing (rad).
pub const MIN_SPACING_RAD: f64 = 1e-3;
/// Knots beyond the trained joint range on each side (in knot spacings): the map is pulled back
/// to zero there by its prior.
const MARGIN_KNOTS: f64 = 3.0;

/// The map hyper-parameters.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct JointMapsHyper {
    /// Joints mapped (bit j = joint j + 1).
    pub joints: u16,
    /// Knot spacing h (rad).
    pub spacing_rad: f64,
    /// Prior standard deviation of a coefficient σ_v (rad).
    pub value_sigma_rad: f64,
    /// Prior standard deviation of a second difference of the coefficients σ_c (rad).
    pub curvature_sigma_rad: f64,
}

impl JointMapsHyper {
    /// Joints mapped (0-based), below `joint_count`.
    pub fn mapped_joints(&self, joint_count: usize) -> Vec<usize> {
        (0..joint_count.min(16))
            .filter(|j| self.joints & (1 << j) != 0)
            .collect()
    }

    /// One-line description (`J1–J4, h 1.15°, σ_v 0.75 mrad, σ_c 0.25 mrad`).
    pub fn describe(&self) -> String {
        let joints: Vec<String> = (0..16)
            .filter(|j| self.joints & (1 << j) != 0)
            .map(|j| format!("J{}", j + 1))
            .collect();
        format!(
            "{}, knots every {:.2}°, σ_v {:.2} mrad, σ_c {:.2} mrad",
            joints.join(" "),
            self.spacing_rad.to_degrees(),
            self.value_sigma_rad * 1e3,
            self.curvature_sigma_rad * 1e3
        )
    }
}

/// Joints 1–3 (the arm).
pub const JOINTS_1_TO_3: u16 = 0b111;
/// Joints 1–4.
pub const JOINTS_1_TO_4: u16 = 0b1111;
/// Every joint of a six-axis arm.
pub const JOINTS_1_TO_6: u16 = 0b11_1111;

/// The candidates the held-out protocol chooses from: the arm's joints (1–3), joints 1–4 or all
/// six; knots every 0.02 rad (1.15°) or 0.05 rad (2.9°); a loose or a tight prior.
pub const MAPS_GRID: [JointMapsHyper; 6] = {
    const fn h(joints: u16, spacing_rad: f64, value: f64, curvature: f64) -> JointMapsHyper {
        JointMapsHyper {
            joints,
            spacing_rad,
            value_sigma_rad: value,
            curvature_sigma_rad: curvature,
        }
    }
    [
        h(JOINTS_1_TO_3, 0.02, 0.75e-3, 0.25e-3),
        h(JOINTS_1_TO_4, 0.02, 0.75e-3, 0.25e-3),
        h(JOINTS_1_TO_6, 0.02, 0.75e-3, 0.25e-3),
        h(JOINTS_1_TO_4, 0.05, 0.75e-3, 0.25e-3),
        h(JOINTS_1_TO_4, 0.02, 0.35e-3, 0.1e-3),
        h(JOINTS_1_TO_4, 0.02, 1.5e-3, 0.5e-3),
    ]
};

/// One joint's map `Δθ(q) = Σ_k c_k B_k((q − q₀)/h)`: B_k the uniform cubic B-spline on knots
/// `q₀ + k h … q₀ + (k+4) h`.
#[derive(Clone, Debug, PartialEq)]
pub struct JointMap {
    /// Joint (0-based).
    pub joint: usize,
    /// First knot q₀ (rad).
    pub start_rad: f64,
    /// Knot spacing h (rad).
    pub spacing_rad: f64,
    /// Coefficients c_k (rad).
    pub coefficients: Vec<f64>,
}

impl JointMap {
    /// The coefficients that are non-zero at `q` (index of the first, four weights; weights of
    /// indices outside the map are to be ignored), `None` outside the knots.
    pub fn basis(
        start_rad: f64,
        spacing_rad: f64,
        count: usize,
        q: f64,
    ) -> Option<(isize, [f64; 4])> {
        let u = (q - start_rad) / spacing_rad;
        if !u.is_finite() || u < 0.0 || u >= (count + 3) as f64 {
            return None;
        }
        let i = u.floor();
        let t = u - i;
        let t2 = t * t;
        let t3 = t2 * t;
        let s = 1.0 - t;
        Some((
            i as isize - 3,
            [
                s * s * s / 6.0,
                (3.0 * t3 - 6.0 * t2 + 4.0) / 6.0,
                (-3.0 * t3 + 3.0 * t2 + 3.0 * t + 1.0) / 6.0,
                t3 / 6.0,
            ],
        ))
    }

    /// `Δθ(q)` (rad); zero outside the knots.
    pub fn value(&self, q: f64) -> f64 {
        let n = self.coefficients.len();
        let Some((first, w)) = Self::basis(self.start_rad, self.spacing_rad, n, q) else {
            return 0.0;
        };
        (0..4)
            .filter_map(|k| {
                let index = first + k as isize;
                (index >= 0 && (index as usize) < n)
                    .then(|| w[k] * self.coefficients[index as usize])
            })
            .sum()
    }

    /// The angle range where the map may be non-zero (rad).
    pub fn range_rad(&self) -> (f64, f64) {
        (
            self.start_rad,
            self.start_rad + (self.coefficients.len() + 3) as f64 * self.spacing_rad,
        )
    }
}

/// The trained maps.
#[derive(Clone, Debug, PartialEq)]
pub struct JointMaps {
    /// The hyper-parameters they were trained with.
    pub hyper: JointMapsHyper,
    /// One map per mapped joint.
    pub maps: Vec<JointMap>,
}

impl JointMaps {
    /// Add each map's `Δθ_j(q_j)` to `out[j]` (`q` as measured).
    pub fn add_offsets(&self, q: &[f64], out: &mut [f64]) {
        for map in &self.maps {
            if let (Some(&qj), Some(slot)) = (q.get(map.joint), out.get_mut(map.joint)) {
                *slot += map.value(qj);
            }
        }
    }
}

/// Why maps could not be trained.
#[derive(Clone, Debug, PartialEq, thiserror::Error)]
pub enum MapsError {
    /// No training reading.
    #[error("no fitted absolute reading to learn joint maps from")]
    NoReadings,
    /// The grid point asks for nothing, or for a knot spacing below [`MIN_SPACING_RAD`].
    #[error(
        "joint maps need at least one joint and knots at least {MIN_SPACING_RAD} rad apart (got joints {joints:#b}, {spacing_rad} rad)"
    )]
    Hyper {
        /// Joint mask.
        joints: u16,
        /// Spacing.
        spacing_rad: f64,
    },
    /// A joint's range needs more coefficients than [`MAX_MAP_COEFFICIENTS`].
    #[error(
        "joint {joint}: {count} map coefficients over its range, at most {MAX_MAP_COEFFICIENTS}"
    )]
    TooManyCoefficients {
        /// Joint (1-based).
        joint: usize,
        /// Coefficients needed.
        count: usize,
    },
    /// The penalised normal matrix is not positive definite (non-finite readings).
    #[error(
        "the joint maps' normal equations could not be solved (non-finite residuals or columns)"
    )]
    Singular,
}

/// Train joint maps on the rows with `mult > 0` of `campaign` (and their orientation readings,
/// when the campaign has them) against `model`'s residuals, then put them into `model` with the
/// fitted set-ups' registration increments applied (module documentation).
pub fn train_into(
    model: &mut EgModel,
    campaign: &Campaign,
    mult: &[f64],
    hyper: JointMapsHyper,
) -> Result<(), MapsError> {
    let joint_count = model.robot.joint_count();
    let joints = hyper.mapped_joints(joint_count);
    if joints.is_empty() || hyper.spacing_rad.is_nan() || hyper.spacing_rad < MIN_SPACING_RAD {
        return Err(MapsError::Hyper {
            joints: hyper.joints,
            spacing_rad: hyper.spacing_rad,
        });
    }
    model.joint_maps = None;
    let readings: Vec<usize> = (0..campaign.len())
        .filter(|&i| campaign.kind(i) != ReadingKind::Loaded && mult[i] > 0.0)
        .collect();
    if readings.is_empty() {
        return Err(MapsError::NoReadings);
    }
    // Layout: each mapped joint's coefficients, then six increments per set-up seen.
    let h = hyper.spacing_rad;
    let mut layout: Vec<(usize, f64, usize, usize)> = Vec::new(); // joint, start, count, offset
    let mut offset = 0;
    for &j in &joints {
        let (lo, hi) = readings
            .iter()
            .filter_map(|&i| campaign.absolute_row(i))
            .map(|r| campaign.absolute[r].q_rad[j])
            .fold((f64::INFINITY, f64::NEG_INFINITY), |(lo, hi), v| {
                (lo.min(v), hi.max(v))
            });
        let start = lo - (MARGIN_KNOTS + 3.0) * h;
        let count = ((hi - lo + 2.0 * MARGIN_KNOTS * h) / h).ceil() as usize + 4;
        if count > MAX_MAP_COEFFICIENTS || !start.is_finite() {
            return Err(MapsError::TooManyCoefficients {
                joint: j + 1,
                count,
            });
        }
        layout.push((j, start, count, offset));
        offset += count;
    }
    let map_unknowns = offset;
    let mut setups: Vec<usize> = readings
        .iter()
        .filter_map(|&i| campaign.absolute_row(i))
        .map(|r| campaign.setup_of[r])
        .collect();
    setups.sort_unstable();
    setups.dedup();
    let unknowns = map_unknowns + 6 * setups.len();
    let setup_params: Vec<Param> = setups.iter().flat_map(|&s| Param::setup_pose(s)).collect();

    // Residual scatter per kind (whitening).
    let mut residuals = Vec::with_capacity(readings.len());
    let (mut sum, mut count) = ([0.0f64; 2], [0.0f64; 2]);
    for &i in &readings {
        let r = campaign.residual(model, i, &[], None);
        let kind = usize::from(campaign.kind(i) == ReadingKind::Orientation);
        sum[kind] += mult[i] * r.norm_squared();
        count[kind] += mult[i] * 3.0;
        residuals.push(r);
    }
    let scatter = [0, 1].map(|k| {
        if count[k] > 0.0 {
            (sum[k] / count[k]).sqrt().max(1e-12)
        } else {
            1.0
        }
    });

    let mut normal = DMatrix::<f64>::zeros(unknowns, unknowns);
    let mut rhs = DVector::<f64>::zeros(unknowns);
    let mut index: Vec<usize> = Vec::with_capacity(4 * layout.len() + 6);
    let mut column: Vec<Vector3<f64>> = Vec::with_capacity(4 * layout.len() + 6);
    for (&i, r) in readings.iter().zip(&residuals) {
        let row = campaign.absolute_row(i).unwrap_or(i);
        let s = campaign.setup_of[row];
        let absolute = &campaign.absolute[row];
        let ev = model.evaluate(
            &absolute.q_rad,
            campaign.target_of[row],
            &campaign.conditions(model, row),
        );
        let orientation = campaign.kind(i) == ReadingKind::Orientation;
        let pick = |c: crate::geometry::jacobian::ParameterColumn| {
            if orientation { c.rotation } else { c.position }
        };
        index.clear();
        column.clear();
        for &(j, start, count, first) in &layout {
            let Some((k0, w)) = JointMap::basis(start, h, count, absolute.q_rad[j]) else {
                continue;
            };
            let theta = pick(model.tracker_column(&ev, s, Param::Dh(j, DhField::Theta)));
            for (k, wk) in w.iter().enumerate() {
                let c = k0 + k as isize;
                if c >= 0 && (c as usize) < count {
                    index.push(first + c as usize);
                    column.push(theta * *wk);
                }
            }
        }
        let setup_slot = setups.iter().position(|&x| x == s).unwrap_or(0);
        for (k, &p) in setup_params[6 * setup_slot..6 * setup_slot + 6]
            .iter()
            .enumerate()
        {
            index.push(map_unknowns + 6 * setup_slot + k);
            column.push(pick(model.tracker_column(&ev, s, p)));
        }
        let weight = mult[i] / scatter[usize::from(orientation)].powi(2);
        for (a, ca) in index.iter().zip(&column) {
            rhs[*a] += weight * ca.dot(r);
            for (b, cb) in index.iter().zip(&column) {
                normal[(*a, *b)] += weight * ca.dot(cb);
            }
        }
    }
    // Priors on the map coefficients; a vanishing one keeps the registration block definite.
    let value = 1.0 / hyper.value_sigma_rad.powi(2);
    let curvature = 1.0 / hyper.curvature_sigma_rad.powi(2);
    for &(_, _, count, first) in &layout {
        for k in 0..count {
            normal[(first + k, first + k)] += value;
        }
        for k in 1..count.saturating_sub(1) {
            let d = [first + k - 1, first + k, first + k + 1];
            let coefficient = [1.0, -2.0, 1.0];
            for (a, ca) in d.iter().zip(coefficient) {
                for (b, cb) in d.iter().zip(coefficient) {
                    normal[(*a, *b)] += curvature * ca * cb;
                }
            }
        }
    }
    let trace = normal.diagonal().iter().map(|v| v.abs()).sum::<f64>() / unknowns as f64;
    for k in map_unknowns..unknowns {
        normal[(k, k)] += 1e-12 * trace.max(1.0);
    }
    let solution = normal.cholesky().ok_or(MapsError::Singular)?.solve(&rhs);
    if solution.iter().any(|v| !v.is_finite()) {
        return Err(MapsError::Singular);
    }
    let maps = layout
        .iter()
        .map(|&(joint, start, count, first)| JointMap {
            joint,
            start_rad: start,
            spacing_rad: h,
            coefficients: solution.as_slice()[first..first + count].to_vec(),
        })
        .collect();
    model.apply(&setup_params, &solution.as_slice()[map_unknowns..]);
    model.joint_maps = Some(JointMaps { hyper, maps });
    Ok(())
}

/// Summary of a map for reports: its RMS and largest |Δθ| over its range (rad), sampled at a
/// tenth of the knot spacing.
pub fn map_size(map: &JointMap) -> (f64, f64) {
    let (lo, hi) = map.range_rad();
    let step = map.spacing_rad / 10.0;
    let samples = ((hi - lo) / step).ceil().max(1.0) as usize;
    let (mut sum, mut max) = (0.0, 0.0f64);
    for k in 0..samples {
        let v = map.value(lo + (k as f64 + 0.5) * step);
        sum += v * v;
        max = max.max(v.abs());
    }
    ((sum / samples as f64).sqrt(), max)
}
