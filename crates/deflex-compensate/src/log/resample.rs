//! Resampling a log on the path's arc length.
//!
//! Each usable row is projected on the path polyline, **monotonically**: from the segment of
//! the previous row, over a window of [`ResampleOptions::window_m`] of arc length ahead (at least
//! three times the distance between the two rows), the closest point. The window keeps a helical
//! path's neighbouring turn (0.24 mm below on the paper's cone) from capturing the projection
//! even when the logged positions are several millimetres off the path (a compensated or
//! corrected run). The search starts at the path's first point, so the log must be of a run
//! of this path from its start (rows before the tool reaches the start, an approach or a dwell
//! elsewhere, are skipped as off the path). Rows farther than
//! [`ResampleOptions::max_offset_m`] from the path are counted and skipped.
//!
//! **The rows as the tool moved along the path.** Only a row that advances along the path
//! (its arc length beyond the last kept row's by more than 1 µm) is kept: a standstill logs a
//! pile of rows at one place (a dwell, the end of the program with the force fading while the
//! tool rests, a pause in contact), and averaging them with the few rows of the pass would
//! weigh the pass by the time spent, not by the path. On an unseen plant, 200 rows logged at
//! rest at the end swamped the 12 moving rows of the last millimetre and halved the last
//! waypoints' force (the compensation then cut the max error 3.36 → 1.63 mm instead of
//! → 0.18 mm). The kept rows define the wrench as a function of arc length, linear between
//! rows (weighted by path advance); each path point gets its mean over ±
//! [`ResampleOptions::half_width_m`] of arc length (a box filter against sensor noise,
//! integrated exactly over the linear pieces; 0: the value itself), the window cut at the
//! ends of the log. Path points beyond the logged arc length by more than
//! [`ResampleOptions::coverage_tolerance_m`] are an error: the log does not cover the path.
//!
//! The commanded TCP of the rows, and the measured one when the log has it, are resampled the
//! same way (one profile of twelve values: wrench, commanded, measured).

use super::WrenchLog;
use crate::error::LogError;
use crate::path::TcpPath;
use deflex_model::Wrench;
use nalgebra::{SVector, Vector3};

/// Settings of [`resample_on_path`].
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ResampleOptions {
    /// Arc length searched ahead of the previous row's projection (m).
    pub window_m: f64,
    /// Rows farther than this from the path are skipped (m).
    pub max_offset_m: f64,
    /// Half width of the box filter on arc length (m); 0: plain linear interpolation.
    pub half_width_m: f64,
    /// Path points this far before the first or after the last logged arc length get the first
    /// or last wrench; farther ones make the log not cover the path (m).
    pub coverage_tolerance_m: f64,
}

impl Default for ResampleOptions {
    fn default() -> Self {
        ResampleOptions {
            window_m: 0.005,
            max_offset_m: 0.02,
            half_width_m: 0.0005,
            coverage_tolerance_m: 0.002,
        }
    }
}

/// Wrenches on the path points from a log.
#[derive(Clone, Debug, PartialEq)]
pub struct Resampled {
    /// One per path point.
    pub wrenches: Vec<Wrench>,
    /// The logged run's commanded TCP at each path point (world, m).
    pub commanded_m: Vec<Vector3<f64>>,
    /// The logged run's measured TCP at each path point (world, m), when every row has one.
    pub measured_m: Option<Vec<Vector3<f64>>>,
    /// Rows used (near the path, advancing along it).
    pub used_rows: usize,
    /// Rows near the path that did not advance along it (a standstill, a backward jitter):
    /// not used.
    pub standstill_rows: usize,
    /// Rows skipped because they lie farther than `max_offset_m` from the path.
    pub off_path_rows: usize,
    /// Arc length of the first and last used row (m).
    pub covered_m: [f64; 2],
    /// Largest distance of a used row from the path (m).
    pub max_offset_m: f64,
}

/// A kept row must lie this far along the path beyond the previous kept one (m): more than the
/// jitter of a robot at rest (encoder noise, the inverse kinematics of a log's joints), less
/// than a row's advance at the slowest feed worth compensating.
const ADVANCE_M: f64 = 1e-6;

/// What a kept row carries: wrench (6), commanded TCP (3), measured TCP (3, zero without).
type Row = SVector<f64, 12>;

/// The rows' values as a function of arc length: linear between the kept rows `(s_k, w_k)`
/// (strictly increasing `s`), with the running integral `P_k = ∫_{s_0}^{s_k} w ds`
/// (trapezoids, exact for the linear pieces).
struct Profile {
    knots: Vec<(f64, Row)>,
    integral: Vec<Row>,
}

impl Profile {
    fn new(knots: Vec<(f64, Row)>) -> Profile {
        let mut integral = Vec::with_capacity(knots.len());
        let mut sum = Row::zeros();
        integral.push(sum);
        for pair in knots.windows(2) {
            sum += (pair[0].1 + pair[1].1) * (0.5 * (pair[1].0 - pair[0].0));
            integral.push(sum);
        }
        Profile { knots, integral }
    }

    /// The piece holding `s` (clamped): `k` with `s_k ≤ s ≤ s_{k+1}`.
    fn piece(&self, s: f64) -> usize {
        let k = self.knots.partition_point(|(sk, _)| *sk <= s);
        k.saturating_sub(1).min(self.knots.len().saturating_sub(2))
    }

    /// `w(s)`, clamped to the first and last rows outside them.
    fn value(&self, s: f64) -> Row {
        let n = self.knots.len();
        if n == 1 || s <= self.knots[0].0 {
            return self.knots[0].1;
        }
        if s >= self.knots[n - 1].0 {
            return self.knots[n - 1].1;
        }
        let k = self.piece(s);
        let (s0, w0) = self.knots[k];
        let (s1, w1) = self.knots[k + 1];
        w0 + (w1 - w0) * ((s - s0) / (s1 - s0))
    }

    /// `∫_{s_0}^{x} w ds` for `x` within the rows.
    fn integral_to(&self, x: f64) -> Row {
        let k = self.piece(x);
        let (s0, w0) = self.knots[k];
        let (s1, w1) = self.knots[(k + 1).min(self.knots.len() - 1)];
        let t = if s1 > s0 { (x - s0) / (s1 - s0) } else { 0.0 };
        self.integral[k] + (w0 + (w1 - w0) * (0.5 * t)) * (x - s0)
    }

    /// The mean of `w` over `[s − h, s + h]` cut to the rows (the value at `s` when `h = 0` or
    /// the cut window is empty).
    fn mean(&self, s: f64, h: f64) -> Row {
        let n = self.knots.len();
        let a = (s - h).max(self.knots[0].0);
        let b = (s + h).min(self.knots[n - 1].0);
        if h <= 0.0 || b - a <= ADVANCE_M {
            return self.value(s);
        }
        (self.integral_to(b) - self.integral_to(a)) / (b - a)
    }
}

/// Closest point of segment `j` of the path to `p`: `(distance, arc length)`.
fn project(path: &TcpPath, j: usize, p: &Vector3<f64>) -> (f64, f64) {
    let points = path.points();
    let a = points[j].pose.translation.vector;
    let b = points[j + 1].pose.translation.vector;
    let ab = b - a;
    let length2 = ab.norm_squared();
    let t = if length2 > 0.0 {
        ((p - a).dot(&ab) / length2).clamp(0.0, 1.0)
    } else {
        0.0
    };
    let closest = a + ab * t;
    (
        (p - closest).norm(),
        points[j].arc_length_m + t * length2.sqrt(),
    )
}

/// Resample a log's wrenches on the path's points (see the module documentation).
pub fn resample_on_path(
    log: &WrenchLog,
    path: &TcpPath,
    options: &ResampleOptions,
) -> Result<Resampled, LogError> {
    let segments = path.len() - 1;
    let mut located: Vec<(f64, Row)> = Vec::with_capacity(log.samples.len());
    let mut off_path_rows = 0;
    let mut max_offset: f64 = 0.0;
    let mut current: usize = 0;
    let mut current_s: f64 = 0.0;
    let mut last_position: Option<Vector3<f64>> = None;
    for sample in &log.samples {
        let p = &sample.position_m;
        let j = current;
        let step = last_position.map_or(0.0, |q| (p - q).norm());
        // The window runs ahead of the last row's place on the path, not of its segment's
        // start: a segment longer than the window must not hide the next one.
        let reach = current_s.max(path.points()[j].arc_length_m) + options.window_m.max(3.0 * step);
        let range_end = path.points()[j..]
            .partition_point(|pt| pt.arc_length_m <= reach)
            .max(1)
            + j;
        let range_start = j;
        let range_end = range_end.max(range_start + 1).min(segments);
        let mut best: Option<(f64, f64, usize)> = None;
        for k in range_start..range_end {
            let (distance, s) = project(path, k, p);
            if best.is_none_or(|(d, _, _)| distance < d) {
                best = Some((distance, s, k));
            }
        }
        match best {
            Some((distance, s, k)) if distance <= options.max_offset_m => {
                max_offset = max_offset.max(distance);
                current = k;
                current_s = s;
                last_position = Some(*p);
                let mut row = Row::zeros();
                row.fixed_rows_mut::<6>(0).copy_from(&sample.wrench);
                row.fixed_rows_mut::<3>(6).copy_from(&sample.commanded_m);
                if let Some(m) = sample.measured_m {
                    row.fixed_rows_mut::<3>(9).copy_from(&m);
                }
                located.push((s, row));
            }
            _ => off_path_rows += 1,
        }
    }
    if located.is_empty() {
        return Err(LogError::NoRowNearPath {
            file: log.file.clone(),
            rows: log.samples.len(),
            max_offset_mm: options.max_offset_m * 1e3,
        });
    }
    // The rows as the tool moved: each kept row advances along the path.
    let located_rows = located.len();
    let mut knots: Vec<(f64, Row)> = Vec::with_capacity(located.len());
    for (s, w) in located {
        if knots.last().is_none_or(|(last, _)| s > last + ADVANCE_M) {
            knots.push((s, w));
        }
    }
    let standstill_rows = located_rows - knots.len();
    let first = knots[0].0;
    let last = knots[knots.len() - 1].0;
    let tolerance = options.coverage_tolerance_m;
    if let Some(index) = path
        .points()
        .iter()
        .position(|p| p.arc_length_m < first - tolerance || p.arc_length_m > last + tolerance)
    {
        return Err(LogError::PartialCoverage {
            file: log.file.clone(),
            from_mm: first * 1e3,
            to_mm: last * 1e3,
            length_mm: path.length_m() * 1e3,
            first_uncovered: index,
        });
    }
    let profile = Profile::new(knots);
    let h = options.half_width_m;
    let mut wrenches = Vec::with_capacity(path.len());
    let mut commanded_m = Vec::with_capacity(path.len());
    let mut measured_m = Vec::with_capacity(if log.measured { path.len() } else { 0 });
    for point in path.points() {
        let row = profile.mean(point.arc_length_m, h);
        wrenches.push(Wrench::from(row.fixed_rows::<6>(0)));
        commanded_m.push(Vector3::from(row.fixed_rows::<3>(6)));
        if log.measured {
            measured_m.push(Vector3::from(row.fixed_rows::<3>(9)));
        }
    }
    Ok(Resampled {
        wrenches,
        commanded_m,
        measured_m: log.measured.then_some(measured_m),
        used_rows: located_rows - standstill_rows,
        standstill_rows,
        off_path_rows,
        covered_m: [first, last],
        max_offset_m: max_offset,
    })
}
