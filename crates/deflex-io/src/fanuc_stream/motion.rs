//! The joint motion a Stream Motion link commands: the controller's limits
//! ([`StreamLimits`]), the pre-planned path ([`StreamTrajectory`], built before the session,
//! time-parametrised with jerk-limited start and stop), the approach from wherever the robot
//! stands to the path's start ([`Approach`], a minimum-jerk move within the limits) and the
//! last line of defence every target passes ([`MotionLimiter`]: no commanded step beyond the
//! velocity and acceleration limits, ever, and a jerk-limited braking to rest).
//!
//! All SI: radians, rad/s, rad/s², rad/s³. Nothing here allocates after construction.

// Per-axis arithmetic over several arrays reads best with an index.
#![allow(clippy::needless_range_loop)]

/// Robot axes a Stream Motion link commands (the first six of the packet's nine).
pub const AXES: usize = 6;

/// Per-axis limits of the commanded joint motion.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct StreamLimits {
    /// Velocity (rad/s).
    pub velocity: [f64; AXES],
    /// Acceleration (rad/s²).
    pub acceleration: [f64; AXES],
    /// Jerk (rad/s³).
    pub jerk: [f64; AXES],
}

impl StreamLimits {
    /// The same limits on every axis.
    pub const fn uniform(velocity: f64, acceleration: f64, jerk: f64) -> Self {
        StreamLimits {
            velocity: [velocity; AXES],
            acceleration: [acceleration; AXES],
            jerk: [jerk; AXES],
        }
    }

    /// True if every limit is finite and positive.
    pub fn is_valid(&self) -> bool {
        self.velocity
            .iter()
            .chain(&self.acceleration)
            .chain(&self.jerk)
            .all(|v| v.is_finite() && *v > 0.0)
    }

    /// Every limit multiplied by `factor` (a safety margin below the controller's own).
    pub fn scaled(&self, factor: f64) -> Self {
        StreamLimits {
            velocity: self.velocity.map(|v| v * factor),
            acceleration: self.acceleration.map(|v| v * factor),
            jerk: self.jerk.map(|v| v * factor),
        }
    }

    /// The tighter of `self` and `other`, axis by axis.
    pub fn min(&self, other: &StreamLimits) -> Self {
        let m = |a: [f64; AXES], b: [f64; AXES]| std::array::from_fn(|i| a[i].min(b[i]));
        StreamLimits {
            velocity: m(self.velocity, other.velocity),
            acceleration: m(self.acceleration, other.acceleration),
            jerk: m(self.jerk, other.jerk),
        }
    }
}

impl Default for StreamLimits {
    /// Conservative limits for a 200 kg-class arm streamed with corrections: 1 rad/s,
    /// 5 rad/s², 100 rad/s³ on every axis.
    fn default() -> Self {
        StreamLimits::uniform(1.0, 5.0, 100.0)
    }
}

/// The commanded motion, one axis vector per cycle: positions, velocities and accelerations of
/// the last command, and the limiter every new target passes.
///
/// [`MotionLimiter::step_towards`] moves towards a target so that, whatever the target (a
/// jump, a NaN is refused earlier), the command's velocity and acceleration stay within the
/// limits and its jerk within the jerk limit unless the velocity limit is reached;
/// [`MotionLimiter::brake`] brings the motion to rest with the acceleration and jerk limits.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct MotionLimiter {
    period_s: f64,
    limits: StreamLimits,
    q: [f64; AXES],
    v: [f64; AXES],
    a: [f64; AXES],
}

impl MotionLimiter {
    /// A limiter at rest at `q` (rad), for commands every `period_s`.
    pub fn new(period_s: f64, limits: StreamLimits, q: [f64; AXES]) -> Self {
        MotionLimiter {
            period_s,
            limits,
            q,
            v: [0.0; AXES],
            a: [0.0; AXES],
        }
    }

    /// The last command (rad).
    pub fn position(&self) -> [f64; AXES] {
        self.q
    }

    /// The last command's velocity (rad/s).
    pub fn velocity(&self) -> [f64; AXES] {
        self.v
    }

    /// The limits.
    pub fn limits(&self) -> &StreamLimits {
        &self.limits
    }

    /// True once the command is at rest (velocity and acceleration below 1e-9 rad/s, rad/s²).
    pub fn at_rest(&self) -> bool {
        self.v.iter().chain(&self.a).all(|x| x.abs() < 1e-9)
    }

    /// The next command towards `target` (rad), within the limits.
    pub fn step_towards(&mut self, target: &[f64; AXES]) -> [f64; AXES] {
        let t = self.period_s;
        for i in 0..AXES {
            let (vmax, amax, jmax) = (
                self.limits.velocity[i],
                self.limits.acceleration[i],
                self.limits.jerk[i],
            );
            let v_want = (target[i] - self.q[i]) / t;
            let a_want = (v_want - self.v[i]) / t;
            let j = ((a_want - self.a[i]) / t).clamp(-jmax, jmax);
            let a = (self.a[i] + j * t).clamp(-amax, amax);
            self.advance(i, a, vmax);
        }
        self.q
    }

    /// The next command of a stop: decelerates to rest keeping the velocity, acceleration and
    /// jerk limits, as fast as they allow without reversing (the velocity may still grow while
    /// a positive acceleration is being taken back at the jerk limit), then holds.
    pub fn brake(&mut self) -> [f64; AXES] {
        let t = self.period_s;
        for i in 0..AXES {
            let (vmax, amax, jmax) = (
                self.limits.velocity[i],
                self.limits.acceleration[i],
                self.limits.jerk[i],
            );
            let (v, a) = (self.v[i], self.a[i]);
            if v == 0.0 {
                // At rest but still accelerating: take the acceleration back at the jerk limit.
                let a_new = if a.abs() <= jmax * t {
                    0.0
                } else {
                    a - a.signum() * jmax * t
                };
                self.advance(i, a_new, vmax);
                continue;
            }
            // In the frame where the velocity is positive: the braking deceleration x of this
            // step is the largest the jerk and acceleration limits allow such that ramping it
            // back to zero at the jerk limit does not reverse the motion.
            let s = v.signum();
            let (w, b) = (v.abs(), s * a);
            let lo = -(b + jmax * t).min(amax);
            let hi = -(b - jmax * t).max(-amax);
            let budget = |x: f64| x * t + ramp_down(x, jmax * t) * t;
            let x = if budget(lo) > w {
                lo
            } else if budget(hi) <= w {
                hi
            } else {
                let (mut l, mut h) = (lo, hi);
                for _ in 0..60 {
                    let m = 0.5 * (l + h);
                    if budget(m) <= w {
                        l = m;
                    } else {
                        h = m;
                    }
                }
                l
            };
            let mut w_new = (w - x * t).min(vmax);
            if w_new.abs() < 1e-12 {
                w_new = 0.0;
            }
            self.a[i] = s * (w_new - w) / t;
            self.v[i] = s * w_new;
            self.q[i] += self.v[i] * t;
        }
        self.q
    }

    /// Applies acceleration `a` on axis `i`, with the velocity kept within ±`vmax` (and the
    /// acceleration that results from that clamp recorded).
    fn advance(&mut self, i: usize, a: f64, vmax: f64) {
        let t = self.period_s;
        let v = (self.v[i] + a * t).clamp(-vmax, vmax);
        self.a[i] = (v - self.v[i]) / t;
        self.v[i] = v;
        self.q[i] += v * t;
    }
}

/// What a deceleration `x` still takes off the velocity, per unit period, when it is ramped back
/// to zero by `step` per cycle: Σ max(x − m·step, 0) over m ≥ 1.
fn ramp_down(x: f64, step: f64) -> f64 {
    if x <= step {
        return 0.0;
    }
    let n = ((x / step).ceil() - 1.0).max(0.0);
    n * x - step * n * (n + 1.0) / 2.0
}

/// A minimum-jerk move from the robot's position to the path's start, timed so that its peak
/// velocity, acceleration and jerk stay within the limits on every axis.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Approach {
    from: [f64; AXES],
    to: [f64; AXES],
    cycles: u64,
}

/// Peak velocity, acceleration and jerk of the quintic 10u³ − 15u⁴ + 6u⁵ over a unit move in
/// unit time.
const QUINTIC_PEAKS: [f64; 3] = [1.875, 5.773_502_691_896_258, 60.0];

impl Approach {
    /// The move from `from` to `to` (rad) with commands every `period_s` within `limits` (its
    /// duration rounded up to whole cycles, at least one).
    pub fn new(from: [f64; AXES], to: [f64; AXES], period_s: f64, limits: &StreamLimits) -> Self {
        let mut duration: f64 = 0.0;
        for i in 0..AXES {
            let d = (to[i] - from[i]).abs();
            duration = duration
                .max(QUINTIC_PEAKS[0] * d / limits.velocity[i])
                .max((QUINTIC_PEAKS[1] * d / limits.acceleration[i]).sqrt())
                .max((QUINTIC_PEAKS[2] * d / limits.jerk[i]).cbrt());
        }
        Approach {
            from,
            to,
            cycles: ((duration / period_s).ceil() as u64).max(1),
        }
    }

    /// Cycles of the move.
    pub fn cycles(&self) -> u64 {
        self.cycles
    }

    /// The target at cycle `k` (the end from `cycles()` on).
    pub fn at(&self, k: u64) -> [f64; AXES] {
        let u = (k as f64 / self.cycles as f64).clamp(0.0, 1.0);
        let s = u * u * u * (10.0 - 15.0 * u + 6.0 * u * u);
        std::array::from_fn(|i| self.from[i] + (self.to[i] - self.from[i]) * s)
    }
}

/// Why a trajectory cannot be streamed.
#[derive(Debug, Clone, Copy, PartialEq, thiserror::Error)]
pub enum TrajectoryError {
    /// Fewer than two waypoints.
    #[error("a stream needs at least two waypoints, got {got}")]
    TooShort {
        /// Waypoints given.
        got: usize,
    },
    /// A waypoint's time does not increase or a value is not finite.
    #[error("waypoint {index}: times must increase and every value must be finite")]
    BadWaypoint {
        /// Its index.
        index: usize,
    },
    /// The period or the ramp is not positive and finite.
    #[error("period {period_s} s and ramp {ramp_s} s must be positive and finite")]
    BadTiming {
        /// The period (s).
        period_s: f64,
        /// The ramp (s).
        ramp_s: f64,
    },
    /// The sampled trajectory breaks a limit.
    #[error(
        "axis {axis} at cycle {cycle}: the path needs {needed:.4} where the limit is {limit:.4} \
         ({what}); slow the feed down or raise the limit"
    )]
    BeyondLimit {
        /// Axis (1-based).
        axis: usize,
        /// Cycle.
        cycle: usize,
        /// `rad/s`, `rad/s²`, `rad/s³`.
        what: &'static str,
        /// What the path needs.
        needed: f64,
        /// The limit.
        limit: f64,
    },
}

/// The joint targets of the whole path, one per controller cycle (rad), starting and ending at
/// rest. Built once before the session (it allocates here, never while streaming).
#[derive(Debug, Clone, PartialEq)]
pub struct StreamTrajectory {
    period_s: f64,
    points: Vec<[f64; AXES]>,
}

impl StreamTrajectory {
    /// Samples waypoints `(t_s, q_rad)` every `period_s`, with the path's time warped so that
    /// its speed rises from rest over `ramp_s` and falls back to rest over `ramp_s` at the end
    /// with a C² (quintic smoothstep) speed profile: the stream starts and stops with bounded
    /// jerk. Between waypoints the joints are interpolated linearly in time, then smoothed by
    /// three passes of a centred moving average over [`SMOOTHING_CYCLES`] cycles (the ends held),
    /// which rounds the waypoints' corners so that a velocity change Δv at a corner needs at
    /// most Δv/(n·T) of acceleration and Δv/(n·T)² of jerk. The whole stream lasts the
    /// waypoints' span plus `ramp_s` plus the held ends (`6·(n / 2)` cycles). Checked against `limits` (velocity,
    /// acceleration and jerk of the samples).
    pub fn from_waypoints(
        period_s: f64,
        ramp_s: f64,
        waypoints: &[(f64, [f64; AXES])],
        limits: &StreamLimits,
    ) -> Result<Self, TrajectoryError> {
        if !(period_s.is_finite() && period_s > 0.0 && ramp_s.is_finite() && ramp_s > 0.0) {
            return Err(TrajectoryError::BadTiming { period_s, ramp_s });
        }
        if waypoints.len() < 2 {
            return Err(TrajectoryError::TooShort {
                got: waypoints.len(),
            });
        }
        for (index, w) in waypoints.iter().enumerate() {
            let finite = w.0.is_finite() && w.1.iter().all(|v| v.is_finite());
            if !finite || (index > 0 && w.0 <= waypoints[index - 1].0) {
                return Err(TrajectoryError::BadWaypoint { index });
            }
        }
        let t0 = waypoints[0].0;
        let span = waypoints[waypoints.len() - 1].0 - t0;
        let ramp = ramp_s.min(span);
        let total = span + ramp;
        let cycles = (total / period_s).ceil() as usize;
        let mut points = Vec::with_capacity(cycles + 1);
        let mut seg = 0;
        for k in 0..=cycles {
            let tau = t0 + warp((k as f64 * period_s).min(total), span, ramp);
            while seg + 2 < waypoints.len() && waypoints[seg + 1].0 < tau {
                seg += 1;
            }
            let (ta, qa) = waypoints[seg];
            let (tb, qb) = waypoints[seg + 1];
            let u = ((tau - ta) / (tb - ta)).clamp(0.0, 1.0);
            points.push(std::array::from_fn(|i| qa[i] + (qb[i] - qa[i]) * u));
        }
        smooth(&mut points, SMOOTHING_CYCLES);
        let trajectory = StreamTrajectory { period_s, points };
        trajectory.check(limits)?;
        Ok(trajectory)
    }

    /// Samples given directly, one per cycle (checked against `limits`).
    pub fn from_samples(
        period_s: f64,
        points: Vec<[f64; AXES]>,
        limits: &StreamLimits,
    ) -> Result<Self, TrajectoryError> {
        if !(period_s.is_finite() && period_s > 0.0) {
            return Err(TrajectoryError::BadTiming {
                period_s,
                ramp_s: 0.0,
            });
        }
        if points.len() < 2 {
            return Err(TrajectoryError::TooShort { got: points.len() });
        }
        if let Some(index) = points.iter().position(|p| !p.iter().all(|v| v.is_finite())) {
            return Err(TrajectoryError::BadWaypoint { index });
        }
        let trajectory = StreamTrajectory { period_s, points };
        trajectory.check(limits)?;
        Ok(trajectory)
    }

    /// Checks the samples' velocity, acceleration and jerk (finite differences) against
    /// `limits`.
    pub fn check(&self, limits: &StreamLimits) -> Result<(), TrajectoryError> {
        let t = self.period_s;
        let p = &self.points;
        for k in 1..p.len() {
            for i in 0..AXES {
                // Velocity, jerk and acceleration by backward differences, where the samples
                // reach back far enough, in the order they are reported.
                let differences = [
                    (
                        Some((p[k][i] - p[k - 1][i]) / t),
                        limits.velocity[i],
                        "rad/s",
                    ),
                    (
                        (k >= 3).then(|| {
                            (p[k][i] - 3.0 * p[k - 1][i] + 3.0 * p[k - 2][i] - p[k - 3][i])
                                / (t * t * t)
                        }),
                        limits.jerk[i],
                        "rad/s³",
                    ),
                    (
                        (k >= 2).then(|| (p[k][i] - 2.0 * p[k - 1][i] + p[k - 2][i]) / (t * t)),
                        limits.acceleration[i],
                        "rad/s²",
                    ),
                ];
                for (value, limit, what) in differences {
                    if let Some(value) = value
                        && value.abs() > limit
                    {
                        return Err(TrajectoryError::BeyondLimit {
                            axis: i + 1,
                            cycle: k,
                            what,
                            needed: value.abs(),
                            limit,
                        });
                    }
                }
            }
        }
        Ok(())
    }

    /// The cycle period (s).
    pub fn period_s(&self) -> f64 {
        self.period_s
    }

    /// The targets, one per cycle (rad).
    pub fn points(&self) -> &[[f64; AXES]] {
        &self.points
    }

    /// Number of cycles.
    pub fn len(&self) -> usize {
        self.points.len()
    }

    /// Never true (a trajectory has at least two points).
    pub fn is_empty(&self) -> bool {
        self.points.is_empty()
    }

    /// Duration (s).
    pub fn duration_s(&self) -> f64 {
        (self.points.len() - 1) as f64 * self.period_s
    }
}

/// Width (cycles) of the moving average that rounds the waypoints' corners.
pub const SMOOTHING_CYCLES: usize = 9;

/// Three passes of a centred moving average of `width` samples (odd), after holding the first
/// and last samples for `3·(width / 2)` cycles each: the ends stay exactly where they are, at
/// rest.
fn smooth(points: &mut Vec<[f64; AXES]>, width: usize) {
    let h = width / 2;
    // Held ends, as long as the three passes' reach: the first and last samples stay exact.
    let (first, last) = (points[0], points[points.len() - 1]);
    points.splice(0..0, std::iter::repeat_n(first, 3 * h));
    points.extend(std::iter::repeat_n(last, 3 * h));
    let n = points.len();
    let mut buf = points.clone();
    for _ in 0..3 {
        for (k, out) in buf.iter_mut().enumerate() {
            let mut sum = [0.0; AXES];
            for d in 0..=2 * h {
                let idx = (k + d).saturating_sub(h).min(n - 1);
                for (s, v) in sum.iter_mut().zip(&points[idx]) {
                    *s += v;
                }
            }
            *out = sum.map(|s| s / (2 * h + 1) as f64);
        }
        points.copy_from_slice(&buf);
    }
}

/// Path time reached at stream time `t` when the speed ramps up over `ramp` and down over
/// `ramp` before `span + ramp` (speed profile: quintic smoothstep; its integral over a ramp is
/// `ramp / 2`).
fn warp(t: f64, span: f64, ramp: f64) -> f64 {
    let total = span + ramp;
    let rising = |t: f64| {
        let u = (t / ramp).clamp(0.0, 1.0);
        ramp * u * u * u * u * (2.5 - 3.0 * u + u * u)
    };
    if t <= ramp {
        rising(t)
    } else if t >= total - ramp {
        span - rising(total - t)
    } else {
        ramp / 2.0 + (t - ramp)
    }
}

/// The correction's share of the motion: three cascaded first-order filters of time constant τ
/// between the runtime's joint correction (bounded by ±M per axis) and what is added to the
/// path. Whatever the input does within ±M, the output's velocity stays within 2M/τ, its
/// acceleration within 4M/τ² and its jerk within 8M/τ³ ([`CorrectionFilter::for_share`] picks
/// τ so that these fit a share of the limits): the path (checked within the rest of the
/// limits) plus the filtered correction keeps every limit.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct CorrectionFilter {
    alpha: f64,
    tau_s: f64,
    stages: [[f64; AXES]; 3],
}

impl CorrectionFilter {
    /// The filter whose output keeps within `share` of `limits` for inputs within ±`bound_rad`,
    /// at commands every `period_s`.
    pub fn for_share(period_s: f64, limits: &StreamLimits, share: f64, bound_rad: f64) -> Self {
        let m = bound_rad;
        let mut tau: f64 = period_s;
        for i in 0..AXES {
            tau = tau
                .max(2.0 * m / (share * limits.velocity[i]))
                .max((4.0 * m / (share * limits.acceleration[i])).sqrt())
                .max((8.0 * m / (share * limits.jerk[i])).cbrt());
        }
        CorrectionFilter {
            alpha: 1.0 - (-period_s / tau).exp(),
            tau_s: tau,
            stages: [[0.0; AXES]; 3],
        }
    }

    /// The time constant (s).
    pub fn tau_s(&self) -> f64 {
        self.tau_s
    }

    /// One cycle: the filtered correction for input `dq` (rad).
    pub fn step(&mut self, dq: &[f64; AXES]) -> [f64; AXES] {
        let a = self.alpha;
        for i in 0..AXES {
            self.stages[0][i] += a * (dq[i] - self.stages[0][i]);
            self.stages[1][i] += a * (self.stages[0][i] - self.stages[1][i]);
            self.stages[2][i] += a * (self.stages[1][i] - self.stages[2][i]);
        }
        self.stages[2]
    }

    /// The current output (rad).
    pub fn output(&self) -> [f64; AXES] {
        self.stages[2]
    }
}
