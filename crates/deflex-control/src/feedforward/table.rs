//! The compensated-path table as the controller reads it: loaded from `compensated_path.csv`
//! rows, checked, rotated into the robot's base axes, interpolated by arc length or time.

use super::{
    FeedForwardColumn, FeedForwardError, MAX_TABLE_COORDINATE_M, MAX_TABLE_POSITION_M,
    MAX_TABLE_ROTATION_RAD,
};
use deflex_model::{Displacement, Robot};
use nalgebra::Vector3;

/// One point of an offline compensation, as data: what `deflex compensate` wrote for it in
/// `compensated_path.csv` (the runtime reads the file and hands the points over), world frame of
/// the model.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct FeedForwardPoint {
    /// Arc length along the desired path (m).
    pub arc_length_m: f64,
    /// Time at the programmed feeds (s).
    pub time_s: f64,
    /// Desired TCP position, world (m).
    pub desired_m: Vector3<f64>,
    /// Predicted deflection at the compensated configuration, world axes [m; rad].
    pub deflection: Displacement,
    /// Compensation the program applies, world axes [m; rad]: commanded = desired ⊕ compensation.
    pub compensation: Displacement,
}

/// The compensated path as the controller uses it: arc length, time, the commanded position
/// (world) and, in the robot's **base axes** (those of ξ), the predicted deflection and the
/// compensation.
#[derive(Clone, Debug, PartialEq)]
pub struct FeedForwardTable {
    pub(super) s_m: Vec<f64>,
    pub(super) t_s: Vec<f64>,
    pub(super) desired: Vec<Vector3<f64>>,
    pub(super) commanded: Vec<Vector3<f64>>,
    pub(super) deflection: Vec<[f64; 6]>,
    pub(super) compensation: Vec<[f64; 6]>,
}

fn rotate6(r: &nalgebra::Rotation3<f64>, v: &[f64]) -> [f64; 6] {
    let a = r * Vector3::new(v[0], v[1], v[2]);
    let b = r * Vector3::new(v[3], v[4], v[5]);
    [a.x, a.y, a.z, b.x, b.y, b.z]
}

/// `value` within ±`limit`, else the error naming the point and the quantity.
fn bounded(
    point: usize,
    column: FeedForwardColumn,
    value: f64,
    limit: f64,
) -> Result<(), FeedForwardError> {
    if value.abs() <= limit {
        Ok(())
    } else {
        Err(FeedForwardError::OutOfBounds {
            point,
            column,
            value,
            limit,
        })
    }
}

/// Checks one point against the previous one and the bounds; returns its commanded position.
fn check_point(
    i: usize,
    p: &FeedForwardPoint,
    previous: Option<&FeedForwardPoint>,
) -> Result<Vector3<f64>, FeedForwardError> {
    if let Some(prev) = previous {
        for (column, value, previous) in [
            (
                FeedForwardColumn::ArcLength,
                p.arc_length_m,
                prev.arc_length_m,
            ),
            (FeedForwardColumn::Time, p.time_s, prev.time_s),
        ] {
            if value < previous {
                return Err(FeedForwardError::NotMonotone {
                    point: i,
                    column,
                    value,
                    previous,
                });
            }
        }
    }
    for k in 0..6 {
        let limit = if k < 3 {
            MAX_TABLE_POSITION_M
        } else {
            MAX_TABLE_ROTATION_RAD
        };
        bounded(i, FeedForwardColumn::Deflection(k), p.deflection[k], limit)?;
        bounded(
            i,
            FeedForwardColumn::Compensation(k),
            p.compensation[k],
            limit,
        )?;
    }
    let commanded =
        p.desired_m + Vector3::new(p.compensation[0], p.compensation[1], p.compensation[2]);
    for k in 0..3 {
        bounded(
            i,
            FeedForwardColumn::CommandedPosition(k),
            commanded[k],
            MAX_TABLE_COORDINATE_M,
        )?;
    }
    Ok(commanded)
}

impl FeedForwardTable {
    /// From the points of an offline compensation (world frame of `robot`), checked: arc length
    /// and time non-decreasing, deflections and compensations within [`MAX_TABLE_POSITION_M`] /
    /// [`MAX_TABLE_ROTATION_RAD`], commanded positions within [`MAX_TABLE_COORDINATE_M`].
    pub fn from_points(
        points: &[FeedForwardPoint],
        robot: &Robot,
    ) -> Result<FeedForwardTable, FeedForwardError> {
        let length_m = points.last().map_or(0.0, |p| p.arc_length_m);
        if points.len() < 2 || length_m.partial_cmp(&0.0) != Some(std::cmp::Ordering::Greater) {
            return Err(FeedForwardError::TooShort {
                points: points.len(),
                length_m,
            });
        }
        let to_base = robot.base.rotation.inverse();
        let n = points.len();
        let mut table = FeedForwardTable {
            s_m: Vec::with_capacity(n),
            t_s: Vec::with_capacity(n),
            desired: Vec::with_capacity(n),
            commanded: Vec::with_capacity(n),
            deflection: Vec::with_capacity(n),
            compensation: Vec::with_capacity(n),
        };
        for (i, p) in points.iter().enumerate() {
            let commanded = check_point(i, p, i.checked_sub(1).map(|j| &points[j]))?;
            table.s_m.push(p.arc_length_m);
            table.t_s.push(p.time_s);
            table.desired.push(p.desired_m);
            table.commanded.push(commanded);
            table
                .deflection
                .push(rotate6(&to_base, p.deflection.as_slice()));
            table
                .compensation
                .push(rotate6(&to_base, p.compensation.as_slice()));
        }
        Ok(table)
    }

    /// Points.
    pub fn len(&self) -> usize {
        self.s_m.len()
    }

    /// Never empty (at least two points).
    pub fn is_empty(&self) -> bool {
        self.s_m.is_empty()
    }

    /// Path length (m).
    pub fn length_m(&self) -> f64 {
        self.s_m[self.s_m.len() - 1]
    }

    /// Path duration at the programmed feeds (s).
    pub fn duration_s(&self) -> f64 {
        self.t_s[self.t_s.len() - 1]
    }

    /// Time of each point at the programmed feeds (s), non-decreasing.
    pub fn times_s(&self) -> &[f64] {
        &self.t_s
    }

    /// Predicted deflection at each point, in the robot's base axes [m; rad] (the points'
    /// world-frame deflections rotated by the inverse of the base rotation).
    pub fn deflections(&self) -> &[[f64; 6]] {
        &self.deflection
    }

    /// Linear interpolation of a per-point quantity on segment `k` at fraction `u`.
    pub(super) fn lerp6(values: &[[f64; 6]], k: usize, u: f64) -> [f64; 6] {
        let (a, b) = (&values[k], &values[(k + 1).min(values.len() - 1)]);
        std::array::from_fn(|i| a[i] + u * (b[i] - a[i]))
    }

    /// Segment `k` and fraction `u` ∈ [0, 1] at time `t_s` (clamped to the path; a NaN time
    /// gives `(0, 0.0)`): `t_s` lies between the times of points `k` and `k + 1`, `u` of the way.
    /// Searched from segment `hint` (any value; beyond the table it is clamped): galloping
    /// forward from it when `t_s` lies ahead (the usual case: a lead, or the next cycle's time),
    /// so the search touches the table near the robot's place, not all of it. Allocation-free.
    pub fn locate_time(&self, t_s: f64, hint: usize) -> (usize, f64) {
        let last = self.t_s.len() - 1;
        let hint = hint.min(last - 1);
        let (lo, hi) = if self.t_s[hint] <= t_s {
            // Bracket [hint + step/2, hint + step] with doubling steps.
            let mut step = 1;
            while hint + step < last && self.t_s[hint + step] <= t_s {
                step *= 2;
            }
            (hint + step / 2, (hint + step).min(last) + 1)
        } else {
            (0, hint + 1)
        };
        let k = (lo + self.t_s[lo..hi].partition_point(|t| *t <= t_s)).clamp(1, last) - 1;
        let span = self.t_s[k + 1] - self.t_s[k];
        let u = if span > 0.0 {
            ((t_s - self.t_s[k]) / span).clamp(0.0, 1.0)
        } else {
            1.0
        };
        (k, if t_s.is_nan() { 0.0 } else { u })
    }
}
