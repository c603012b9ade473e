//! The compensated-path table as the controller reads it: loaded from `compensated_path.csv`
//! rows, checked, rotated into the robot's base axes, interpolated by arc length or time.

use super::{
    FeedForwardError, MAX_TABLE_COORDINATE_M, MAX_TABLE_POSITION_M, MAX_TABLE_ROTATION_RAD,
};
use deflex_compensate::table::{COMPENSATION, DEFLECTION, TableRow};
use deflex_model::Robot;
use nalgebra::Vector3;

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

impl FeedForwardTable {
    /// From the rows of a compensated-path table (`deflex_compensate::table::read_csv`, world
    /// frame of `robot`), checked: every status `ok`, arc length and time non-decreasing,
    /// deflections and compensations within [`MAX_TABLE_POSITION_M`] / [`MAX_TABLE_ROTATION_RAD`],
    /// positions within [`MAX_TABLE_COORDINATE_M`]. `file` names the table in errors.
    pub fn from_rows(
        rows: &[TableRow],
        robot: &Robot,
        file: &str,
    ) -> Result<FeedForwardTable, FeedForwardError> {
        let length_m = rows.last().map_or(0.0, |r| r.arc_length_m);
        if rows.len() < 2 || length_m.partial_cmp(&0.0) != Some(std::cmp::Ordering::Greater) {
            return Err(FeedForwardError::TooShort {
                file: file.to_string(),
                rows: rows.len(),
                length_m,
            });
        }
        let to_base = robot.base.rotation.inverse();
        let mut table = FeedForwardTable {
            s_m: Vec::with_capacity(rows.len()),
            t_s: Vec::with_capacity(rows.len()),
            desired: Vec::with_capacity(rows.len()),
            commanded: Vec::with_capacity(rows.len()),
            deflection: Vec::with_capacity(rows.len()),
            compensation: Vec::with_capacity(rows.len()),
        };
        for (i, row) in rows.iter().enumerate() {
            let bound = |column: &'static str, value: f64, limit: f64| {
                if value.abs() <= limit {
                    Ok(())
                } else {
                    Err(FeedForwardError::OutOfBounds {
                        file: file.to_string(),
                        line: row.line,
                        column,
                        value,
                        limit,
                    })
                }
            };
            if row.status != "ok" {
                return Err(FeedForwardError::NotCompensated {
                    file: file.to_string(),
                    line: row.line,
                    index: i,
                    status: row.status.clone(),
                });
            }
            if i > 0 {
                for (column, value, previous) in [
                    ("s_m", row.arc_length_m, rows[i - 1].arc_length_m),
                    ("t_s", row.time_s, rows[i - 1].time_s),
                ] {
                    if value < previous {
                        return Err(FeedForwardError::NotMonotone {
                            file: file.to_string(),
                            line: row.line,
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
                bound(DEFLECTION[k], row.deflection[k], limit)?;
                bound(COMPENSATION[k], row.compensation[k], limit)?;
            }
            let commanded = row.desired.translation.vector
                + Vector3::new(
                    row.compensation[0],
                    row.compensation[1],
                    row.compensation[2],
                );
            for (k, column) in ["x_m", "y_m", "z_m"].into_iter().enumerate() {
                bound(column, commanded[k], MAX_TABLE_COORDINATE_M)?;
            }
            table.s_m.push(row.arc_length_m);
            table.t_s.push(row.time_s);
            table.desired.push(row.desired.translation.vector);
            table.commanded.push(commanded);
            table
                .deflection
                .push(rotate6(&to_base, row.deflection.as_slice()));
            table
                .compensation
                .push(rotate6(&to_base, row.compensation.as_slice()));
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

    /// Linear interpolation of a per-point quantity on segment `k` at fraction `u`.
    pub(super) fn lerp6(values: &[[f64; 6]], k: usize, u: f64) -> [f64; 6] {
        let (a, b) = (&values[k], &values[(k + 1).min(values.len() - 1)]);
        std::array::from_fn(|i| a[i] + u * (b[i] - a[i]))
    }

    /// Segment and fraction at time `t_s` (clamped to the path), searched from segment `hint`:
    /// galloping forward from it when `t_s` lies ahead (the usual case: a lead, or the next
    /// cycle's time), so the search touches the table near the robot's place, not all of it.
    pub(super) fn locate_time(&self, t_s: f64, hint: usize) -> (usize, f64) {
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
