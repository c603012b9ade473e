//! Path error and lag at force ramps of a forming run (SIMULATED).
//!
//! **Ramps** are found once per part, on the *uncorrected* run: a ramp starts where the
//! vertical force rises through 5 % of the run's largest force after having been below it for
//! at least [`QUIET_S`] (the tool entering the sheet: the path's start, each plunge after a
//! retract); its **step** is the largest force within [`STEP_WINDOW_S`] after that, at least
//! [`MIN_STEP_FRACTION`] of the run's largest force (the paper's cone has no such ramp: its
//! force builds up with the depth over the first 100 s), and its reference point is the arc length of the desired path where the force first reaches 50 % of
//! the step. Arc length, not time, because a compensated program spends a different time on a
//! plunge (it plunges deeper) and every run is compared at the same place on the part.
//!
//! **Lag metrics**, for each run and each ramp, from the run's first log row at or past the
//! ramp's reference arc length:
//! * `ramp_error_integral_mm_s`: the integral of the path error norm over the next
//!   [`INTEGRAL_WINDOW_S`] (mm·s; mean over the ramps). A loop that lags the ramp carries the
//!   full deflection until it catches up; one that anticipates it (a feed-forward) does not.
//! * `ramp_settle_s`: the time from that row until the error norm falls below
//!   [`SETTLE_THRESHOLD_MM`] and stays below it for [`SETTLE_HOLD_S`] (mean over the ramps; a
//!   ramp that does not settle within [`SETTLE_WINDOW_S`] counts as the whole window, and is
//!   counted in `ramps_not_settled`). The hold keeps one noisy sample from counting; it is
//!   short, so that a later corner of the path (a spike of the error of its own) does not
//!   count against the ramp.

use deflex_sim::FormingRun;
use serde::Serialize;

/// Force below 5 % of the largest for this long before a ramp (s).
pub const QUIET_S: f64 = 0.05;
/// A ramp's step is at least this fraction of the run's largest force.
pub const MIN_STEP_FRACTION: f64 = 0.25;
/// The step of a ramp: the largest force within this time after its start (s).
pub const STEP_WINDOW_S: f64 = 3.0;
/// The error integral runs over this time from the 50 % point (s).
pub const INTEGRAL_WINDOW_S: f64 = 1.0;
/// Settled: the error norm stays below this (mm).
pub const SETTLE_THRESHOLD_MM: f64 = 0.2;
/// … for this long (s) …
pub const SETTLE_HOLD_S: f64 = 0.2;
/// … within this window from the 50 % point (s).
pub const SETTLE_WINDOW_S: f64 = 2.0;

/// Arc length of the desired path at each log row (m): the cumulative distance between the
/// rows' desired positions, which move along the reference polyline.
pub fn desired_arc_length(run: &FormingRun) -> Vec<f64> {
    let mut s = 0.0;
    let mut previous: Option<nalgebra::Vector3<f64>> = None;
    run.log
        .rows
        .iter()
        .map(|r| {
            if let Some(p) = previous {
                s += (r.truth.desired_m - p).norm();
            }
            previous = Some(r.truth.desired_m);
            s
        })
        .collect()
}

/// The force ramps of an (uncorrected) run: the reference arc length of each (m).
pub fn ramps(run: &FormingRun) -> Vec<f64> {
    let rows = &run.log.rows;
    let arc = desired_arc_length(run);
    let peak = rows
        .iter()
        .map(|r| r.truth.wrench[2])
        .fold(0.0f64, f64::max);
    if peak <= 0.0 {
        return Vec::new();
    }
    let low = 0.05 * peak;
    let mut out = Vec::new();
    let mut quiet_since = Some(f64::NEG_INFINITY);
    let mut i = 0;
    while i < rows.len() {
        let f = rows[i].truth.wrench[2];
        let t = rows[i].time_s;
        if f < low {
            quiet_since.get_or_insert(t);
            i += 1;
            continue;
        }
        let was_quiet = quiet_since.is_some_and(|q| t - q >= QUIET_S || q == f64::NEG_INFINITY);
        quiet_since = None;
        if was_quiet {
            let end = rows[i..].partition_point(|r| r.time_s <= t + STEP_WINDOW_S) + i;
            let step = rows[i..end]
                .iter()
                .map(|r| r.truth.wrench[2])
                .fold(0.0f64, f64::max);
            if step < MIN_STEP_FRACTION * peak {
                i += 1;
                continue;
            }
            if let Some(k) = (i..end).find(|&k| rows[k].truth.wrench[2] >= 0.5 * step) {
                out.push(arc[k]);
            }
        }
        i += 1;
    }
    out
}

/// Error and lag numbers of one run.
#[derive(Clone, Debug, Default, PartialEq, Serialize)]
#[allow(non_snake_case)]
pub struct ErrorNumbers {
    /// Largest path error norm (mm).
    pub max_error_mm: f64,
    /// RMS of the path error norm over the run (mm).
    pub rms_error_mm: f64,
    /// Largest and RMS path error norm over the logged rows in contact (contact force norm at
    /// least [`CONTACT_FORCE_N`]): the error that forms the part, without the transients in the
    /// air after a retract (mm); `None` when never in contact.
    pub max_contact_error_mm: Option<f64>,
    /// See `max_contact_error_mm`.
    pub rms_contact_error_mm: Option<f64>,
    /// Mean over the ramps of ∫|e| dt over [`INTEGRAL_WINDOW_S`] from the 50 % point (mm·s);
    /// `None` without a ramp.
    pub ramp_error_integral_mm_s: Option<f64>,
    /// Mean over the ramps of the time to settle below [`SETTLE_THRESHOLD_MM`] (s); `None`
    /// without a ramp.
    pub ramp_settle_s: Option<f64>,
    /// Ramps that did not settle within [`SETTLE_WINDOW_S`].
    pub ramps_not_settled: usize,
    /// Largest contact force norm (N).
    pub max_force_N: f64,
}

/// A logged row is *in contact* when the contact force norm is at least this (N).
pub const CONTACT_FORCE_N: f64 = 20.0;

/// The numbers of `run` at the ramps `ramps` (reference arc lengths, m).
pub fn error_numbers(run: &FormingRun, ramps: &[f64]) -> ErrorNumbers {
    let rows = &run.log.rows;
    let arc = desired_arc_length(run);
    let error_mm: Vec<f64> = rows
        .iter()
        .map(|r| r.truth.path_error_m().norm() * 1e3)
        .collect();
    let (mut integral, mut settle, mut not_settled) = (0.0, 0.0, 0);
    for &s in ramps {
        let start = arc.partition_point(|a| *a < s);
        let Some(t0) = rows.get(start).map(|r| r.time_s) else {
            continue;
        };
        let mut area = 0.0;
        for k in start + 1..rows.len() {
            let (ta, tb) = (rows[k - 1].time_s, rows[k].time_s);
            if ta >= t0 + INTEGRAL_WINDOW_S {
                break;
            }
            let tb_c = tb.min(t0 + INTEGRAL_WINDOW_S);
            area += 0.5 * (error_mm[k - 1] + error_mm[k]) * (tb_c - ta);
        }
        integral += area;
        // The first row from which the error stays below the threshold for the hold time.
        let mut below_since: Option<f64> = None;
        let mut settled = None;
        for k in start..rows.len() {
            let t = rows[k].time_s;
            if t > t0 + SETTLE_WINDOW_S {
                break;
            }
            if error_mm[k] < SETTLE_THRESHOLD_MM {
                let since = *below_since.get_or_insert(t);
                if t - since >= SETTLE_HOLD_S - 1e-9 {
                    settled = Some(since - t0);
                    break;
                }
            } else {
                below_since = None;
            }
        }
        match settled {
            Some(s) => settle += s,
            None => {
                settle += SETTLE_WINDOW_S;
                not_settled += 1;
            }
        }
    }
    let n = ramps.len() as f64;
    let mean = |total: f64| (!ramps.is_empty()).then(|| total / n);
    let (mut contact_max, mut contact_sq, mut contact_rows) = (0.0f64, 0.0, 0usize);
    for (r, e) in rows.iter().zip(&error_mm) {
        if r.truth.force_norm_n() >= CONTACT_FORCE_N {
            contact_max = contact_max.max(*e);
            contact_sq += e * e;
            contact_rows += 1;
        }
    }
    let in_contact = contact_rows > 0;
    ErrorNumbers {
        max_error_mm: run.summary.max_error_norm_mm,
        rms_error_mm: run.summary.rms_error_norm_mm,
        max_contact_error_mm: in_contact.then_some(contact_max),
        rms_contact_error_mm: in_contact.then(|| (contact_sq / contact_rows as f64).sqrt()),
        ramp_error_integral_mm_s: mean(integral),
        ramp_settle_s: mean(settle),
        ramps_not_settled: not_settled,
        max_force_N: run.summary.max_force_norm_N,
    }
}
