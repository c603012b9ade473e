//! Feed-forward plus feedback: the online correction on top of an offline compensation
//! (`deflex compensate`, its `compensated_path.csv`).
//!
//! ## Two modes
//!
//! * **Feed-forward** ([`FeedForwardMode::FeedForward`]): the robot runs the *original* program;
//!   the controller adds the predicted correction `f(s) = −δ_pred(s)` (the table's predicted
//!   deflection at the compensated configuration) to its output, so the feedback only has to
//!   correct what the prediction got wrong. With `lead_s` the feed-forward is read that much
//!   path time ahead, to cover the robot's delay in applying a correction.
//! * **Pre-compensated** ([`FeedForwardMode::Precompensated`]): the robot runs the *compensated*
//!   program (`commanded = desired ⊕ c(s)`, the table's compensation `c`); the controller sends
//!   only its feedback, and accounts for `c` in its tracking error, so it does not correct the
//!   deflection a second time.
//!
//! ## What the loop converges to, and why it cannot double-correct
//!
//! Let `u` be the robot's total offset from the desired path. The controller knows it as
//! `u = p(s) + ξ_fb`, where `p(s)` is the **prior** at the robot's place on the path — `f(s)` in
//! feed-forward mode (the controller sends it), `c(s)` in pre-compensated mode (the program
//! contains it) — and `ξ_fb` is the PID's output. The real TCP is `ŝ_real = s_des + u + δŝ`
//! (eq. 5–7 with the prior in the set-point), so the tracking error is
//!
//! `ε = s_des − ŝ_real = −ξ_fb − (δŝ + p(s))`.
//!
//! This is the loop of [`crate::pid`] with `δŝ` replaced by `δŝ + p(s)`: [`crate::pid::Pid::solve`]
//! is called with that sum, and the controller sends `ξ = ξ_fb + f(s + lead)` (feed-forward) or
//! `ξ = ξ_fb` (pre-compensated). With the integral, the loop settles where `ε = 0`:
//!
//! `ξ_fb → −(δŝ + p)`, i.e. `u = p + ξ_fb → −δŝ`,
//!
//! the same fixed point as the online correction alone (`ξ → −δŝ`): the robot's total offset
//! cancels the deflection the model estimates from the *measured* wrench, whatever the prior.
//! The feedback only carries the residual: `δ_pred − δŝ` in feed-forward mode (zero when the
//! prediction is right: the process's deviation from the predicted wrench and the change of the
//! model's compliance along it), `−c − δŝ` in pre-compensated mode. A correction of twice the
//! deflection would need `u = −2δŝ`, i.e. `ε = δŝ ≠ 0`, which the integral does not leave
//! standing. A controller *not* told about a compensated program (no `[feedforward]`) settles
//! at `ξ = −δŝ` on top of `c ≈ −δ`: `u ≈ −2δ`, the double correction this module prevents.
//!
//! The prior is an exogenous input of the loop: the loop's own dynamics (the PID against the
//! robot's and the contact's compliance, and its stability condition against a stiff contact,
//! [`crate::runaway`]) are unchanged. What changes is the transient: at a force ramp the
//! prior moves with the path, without waiting for the wrench to be measured and the integral to
//! build up. The limiter bounds the *sent* correction (feed-forward included) in size and rate,
//! and anti-windup tracks `ξ_fb = ξ_sent − f`.
//!
//! ## Indexing the table
//!
//! * **Arc length** ([`PathIndex::ArcLength`], default): every cycle, the robot's place on its
//!   *program* — the TCP from forward kinematics of the reported joints (the *commanded* TCP:
//!   motor encoders do not see the deflection) minus the controller's own last correction ξ —
//!   is projected on the program's polyline (the desired path in feed-forward mode, the
//!   compensated one `desired ⊕ c` in pre-compensated mode), **monotonically**: from the
//!   current point, forward, over at most `window_m` of arc length and
//!   [`MAX_SEGMENTS_PER_CYCLE`] table segments, the closest point (the earliest on a tie).
//!   Taking the correction out matters where the path runs along the correction (a plunge): the
//!   raw TCP, offset by a feed-forward that follows the arc length, would feed back into the
//!   arc length it is projected to (a lagging loop of gain `|dc/ds| / |dz/ds|`, close to 1 on a
//!   plunge into the sheet); the robot's place on its program does not depend on the
//!   correction, up to the robot's delay in applying it. The arc length never decreases, and a helix's next turn or
//!   a pocket's next pass, further along than `window_m`, cannot capture it. Tracking starts
//!   at the path's first point: until the TCP comes within `max_offset_m` of the first
//!   `window_m` of the path (an approach move), the state is *acquiring* and the prior is zero.
//!   It then runs for the whole session (a stop and restart of the controller keeps it: one
//!   table is one run of the program).
//! * **Time** ([`PathIndex::Time`]): the table's time column (the path at its programmed
//!   feeds, no acceleration) at the time since the controller's first start plus
//!   `time_offset_s`. Only for a robot that follows the feeds exactly from that instant
//!   (simulation, a test bench); the robot's place is still checked against the program's
//!   point at that time.
//!
//! **Off the path**: when the TCP is farther than `max_offset_m` from the point found, the prior
//! is zero (the rate limit smooths the change) and [`deflex_telemetry::Flags::FEEDFORWARD_OFF_PATH`]
//! is set; in arc-length mode the arc length is kept, so the tracker locks on again when the
//! TCP comes back within the window. **After the end** the arc length stays at the path's end:
//! the prior is the last point's while the TCP stays within `max_offset_m` of it, zero beyond.
//! A TCP that leaves the path and joins it again more than `window_m` further on is not found
//! again (the flag stays on). In pre-compensated mode a zero prior off the path means the
//! controller does not know the program's compensation there: keep approach moves out of
//! contact.
//!
//! Every per-cycle call is allocation-free and does bounded work.

mod table;

pub use table::{FeedForwardPoint, FeedForwardTable};

use nalgebra::Vector3;

/// Most table segments examined per control cycle (arc-length tracking).
pub const MAX_SEGMENTS_PER_CYCLE: usize = 64;
/// Largest predicted deflection or compensation accepted in a table, position (m) and rotation
/// (rad): the compensation's own limits (`deflex compensate`).
pub const MAX_TABLE_POSITION_M: f64 = 0.05;
/// See [`MAX_TABLE_POSITION_M`].
pub const MAX_TABLE_ROTATION_RAD: f64 = 0.1;
/// Largest |coordinate| of a table position (m).
pub const MAX_TABLE_COORDINATE_M: f64 = 100.0;

/// How the prior is used (see the module documentation).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum FeedForwardMode {
    /// The robot runs the original program; the controller adds `−δ_pred`.
    FeedForward,
    /// The robot runs the compensated program; the controller accounts for its compensation.
    Precompensated,
}

impl FeedForwardMode {
    /// The name used in `CELL.toml`.
    pub fn name(self) -> &'static str {
        match self {
            FeedForwardMode::FeedForward => "feed-forward",
            FeedForwardMode::Precompensated => "precompensated",
        }
    }
}

/// How the table is indexed.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum PathIndex {
    /// Arc length tracked monotonically from the commanded TCP.
    ArcLength,
    /// Time since the controller's first start.
    Time,
}

impl PathIndex {
    /// The name used in `CELL.toml`.
    pub fn name(self) -> &'static str {
        match self {
            PathIndex::ArcLength => "arc-length",
            PathIndex::Time => "time",
        }
    }
}

/// Settings of the feed-forward (`[feedforward]` of `CELL.toml`).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct FeedForwardConfig {
    /// Mode.
    pub mode: FeedForwardMode,
    /// Index.
    pub index: PathIndex,
    /// Feed-forward mode: read the feed-forward this much path time ahead (s).
    pub lead_s: f64,
    /// Farther than this from the path, the TCP is off the path (m).
    pub max_offset_m: f64,
    /// Arc length searched ahead per cycle (m).
    pub window_m: f64,
    /// Time index: table time at the controller's first start (s).
    pub time_offset_s: f64,
}

impl Default for FeedForwardConfig {
    /// Feed-forward mode, arc-length index, no lead, 5 mm off-path distance, 5 mm window.
    fn default() -> Self {
        FeedForwardConfig {
            mode: FeedForwardMode::FeedForward,
            index: PathIndex::ArcLength,
            lead_s: 0.0,
            max_offset_m: 0.005,
            window_m: 0.005,
            time_offset_s: 0.0,
        }
    }
}

/// A quantity of a feed-forward table, named in errors (the runtime names the file's column).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum FeedForwardColumn {
    /// Arc length along the desired path (m).
    ArcLength,
    /// Time at the programmed feeds (s).
    Time,
    /// Coordinate `i` (x, y, z) of the commanded TCP, desired + compensation (m, world).
    CommandedPosition(usize),
    /// Component `i` (x, y, z, rx, ry, rz) of the predicted deflection.
    Deflection(usize),
    /// Component `i` (x, y, z, rx, ry, rz) of the compensation.
    Compensation(usize),
}

const AXIS_NAMES: [&str; 6] = ["x", "y", "z", "rx", "ry", "rz"];

impl std::fmt::Display for FeedForwardColumn {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        let axis = |i: &usize| AXIS_NAMES.get(*i).copied().unwrap_or("?");
        match self {
            FeedForwardColumn::ArcLength => f.write_str("arc length"),
            FeedForwardColumn::Time => f.write_str("time"),
            FeedForwardColumn::CommandedPosition(i) => write!(f, "commanded position {}", axis(i)),
            FeedForwardColumn::Deflection(i) => write!(f, "deflection {}", axis(i)),
            FeedForwardColumn::Compensation(i) => write!(f, "compensation {}", axis(i)),
        }
    }
}

/// A compensated-path table that cannot be used as a feed-forward, with the point (0-based, in
/// table order) and the values that make it so.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum FeedForwardError {
    /// Fewer than two points, or a path of zero length.
    TooShort {
        /// Points.
        points: usize,
        /// Path length (m).
        length_m: f64,
    },
    /// Arc length or time decreases.
    NotMonotone {
        /// The point.
        point: usize,
        /// Arc length or time.
        column: FeedForwardColumn,
        /// Its value.
        value: f64,
        /// The previous point's value.
        previous: f64,
    },
    /// A value beyond its bound ([`MAX_TABLE_POSITION_M`], [`MAX_TABLE_ROTATION_RAD`],
    /// [`MAX_TABLE_COORDINATE_M`]).
    OutOfBounds {
        /// The point.
        point: usize,
        /// The quantity.
        column: FeedForwardColumn,
        /// Its value.
        value: f64,
        /// The bound on its magnitude.
        limit: f64,
    },
    /// A setting out of its bounds.
    Setting {
        /// Field of `[feedforward]`.
        field: &'static str,
        /// Value.
        value: f64,
        /// What was expected.
        expected: &'static str,
    },
}

impl std::fmt::Display for FeedForwardError {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            FeedForwardError::TooShort { points, length_m } => write!(
                f,
                "a feed-forward table needs at least two rows and a path of positive length; \
                 got {points} row(s), {length_m} m"
            ),
            FeedForwardError::NotMonotone {
                point,
                column,
                value,
                previous,
            } => write!(
                f,
                "point {point}: {column} decreases ({value} after {previous})"
            ),
            FeedForwardError::OutOfBounds {
                point,
                column,
                value,
                limit,
            } => write!(f, "point {point}: {column}: {value} is beyond ±{limit}"),
            FeedForwardError::Setting {
                field,
                value,
                expected,
            } => write!(f, "feedforward.{field}: expected {expected}, got {value}"),
        }
    }
}

impl std::error::Error for FeedForwardError {}

/// The polyline the robot's place is tracked on, with the unit direction and length of each
/// segment (zero for a zero-length segment; the last point's entry unused).
#[derive(Clone, Debug)]
struct Polyline {
    points: Vec<Vector3<f64>>,
    direction: Vec<Vector3<f64>>,
    length: Vec<f64>,
}

impl Polyline {
    fn new(points: &[Vector3<f64>]) -> Polyline {
        let mut direction = Vec::with_capacity(points.len());
        let mut length = Vec::with_capacity(points.len());
        for k in 0..points.len() {
            let d = points
                .get(k + 1)
                .map_or(Vector3::zeros(), |b| b - points[k]);
            let l = d.norm();
            length.push(l);
            direction.push(if l > 0.0 { d / l } else { Vector3::zeros() });
        }
        Polyline {
            points: points.to_vec(),
            direction,
            length,
        }
    }
}

/// Where the tracker is.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum TrackState {
    /// Not yet on the path's start (arc length) or not started (time).
    Acquiring,
    /// On the path.
    OnPath,
    /// Farther than `max_offset_m` from the path.
    OffPath,
}

/// What the feed-forward gives one control cycle (base axes).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct FeedForwardStep {
    /// The prior `p(s)` the robot already has at its place on the path: added to δŝ in the
    /// PID's error.
    pub prior: [f64; 6],
    /// What the controller adds to its output: `f(s + lead)` in feed-forward mode, zero in
    /// pre-compensated mode.
    pub sent: [f64; 6],
    /// Arc length of the robot's place on the path (m); NaN while acquiring.
    pub path_s_m: f64,
    /// Distance of the TCP from the path's commanded point there (m).
    pub offset_m: f64,
    /// Tracking state.
    pub state: TrackState,
}

impl FeedForwardStep {
    /// No feed-forward this cycle (none set, or the robot's pose unknown).
    pub(crate) fn none() -> Self {
        Self::off(TrackState::OffPath, f64::NAN, f64::NAN)
    }

    fn off(state: TrackState, path_s_m: f64, offset_m: f64) -> Self {
        FeedForwardStep {
            prior: [0.0; 6],
            sent: [0.0; 6],
            path_s_m,
            offset_m,
            state,
        }
    }
}

/// The table with its tracking state (see the module documentation). Per-cycle calls do not
/// allocate.
#[derive(Clone, Debug)]
pub struct FeedForward {
    table: FeedForwardTable,
    track: Polyline,
    config: FeedForwardConfig,
    locked: bool,
    segment: usize,
    fraction: f64,
    t0: Option<f64>,
}

/// Checks the settings' bounds (those documented in `docs/cell.example.toml`).
pub fn check_config(config: &FeedForwardConfig) -> Result<(), FeedForwardError> {
    let check = |field, value: f64, lo: f64, hi: f64, expected| {
        if value >= lo && value <= hi {
            Ok(())
        } else {
            Err(FeedForwardError::Setting {
                field,
                value,
                expected,
            })
        }
    };
    check("lead_s", config.lead_s, 0.0, 1.0, "0 to 1 s")?;
    check(
        "max_offset_m",
        config.max_offset_m,
        1e-4,
        0.1,
        "1e-4 to 0.1 m",
    )?;
    check("window_m", config.window_m, 1e-3, 1.0, "1e-3 to 1 m")?;
    check(
        "time_offset_s",
        config.time_offset_s,
        0.0,
        1e6,
        "0 to 1e6 s",
    )
}

impl FeedForward {
    /// A feed-forward over `table` with `config` (checked against its bounds).
    pub fn new(
        table: FeedForwardTable,
        config: FeedForwardConfig,
    ) -> Result<FeedForward, FeedForwardError> {
        check_config(&config)?;
        let track = Polyline::new(match config.mode {
            FeedForwardMode::FeedForward => &table.desired,
            FeedForwardMode::Precompensated => &table.commanded,
        });
        Ok(FeedForward {
            track,
            table,
            config,
            locked: false,
            segment: 0,
            fraction: 0.0,
            t0: None,
        })
    }

    /// Settings.
    pub fn config(&self) -> &FeedForwardConfig {
        &self.config
    }

    /// The table.
    pub fn table(&self) -> &FeedForwardTable {
        &self.table
    }

    /// The controller started at `now_s`: the time index's origin (the first start only).
    pub fn start(&mut self, now_s: f64) {
        if self.t0.is_none() && now_s.is_finite() {
            self.t0 = Some(now_s);
        }
    }

    /// Forget the tracking (a new run of the program).
    pub fn reset(&mut self) {
        self.locked = false;
        self.segment = 0;
        self.fraction = 0.0;
        self.t0 = None;
    }

    /// Closest point to `x` on segment `k` with fraction at least `from`: (fraction, squared
    /// distance). No square root, no division: `t = (x − a)·e` clamped to `[from·L, L]`,
    /// `|x − a − t e|² = |x − a|² − 2 t (x − a)·e + t²`.
    #[inline]
    fn project(&self, x: &Vector3<f64>, k: usize, from: f64) -> (f64, f64) {
        let r = x - self.track.points[k];
        let length = self.track.length[k];
        let along = r.dot(&self.track.direction[k]);
        let t = along.clamp(from * length, length);
        let d2 = (r.norm_squared() - 2.0 * t * along + t * t).max(0.0);
        let u = if length > 0.0 { t / length } else { 1.0 };
        (u, d2)
    }

    /// Monotone search from `(segment, fraction)` over the window: the closest point
    /// `(segment, fraction, distance)`.
    fn search(&self, x: &Vector3<f64>, segment: usize, fraction: f64) -> (usize, f64, f64) {
        let last = self.table.len() - 2;
        let horizon = self.table.s_m[segment]
            + fraction * self.segment_length(segment)
            + self.config.window_m;
        let (u0, d0) = self.project(x, segment, fraction);
        let mut best = (segment, u0, d0);
        let end = (segment + MAX_SEGMENTS_PER_CYCLE).min(last + 1);
        for k in segment + 1..end {
            if self.table.s_m[k] > horizon {
                break;
            }
            // Every 8 segments: no point of the path from a_k to the horizon is closer than
            // |x − a_k| − (horizon − s_k) (triangle inequality, the path being no longer than
            // its arc length): stop when that cannot beat the best.
            if (k - segment).is_multiple_of(8) {
                let reach = horizon - self.table.s_m[k];
                let to_start = (x - self.track.points[k]).norm();
                if to_start - reach > 0.0 && (to_start - reach).powi(2) >= best.2 {
                    break;
                }
            }
            let (u, d2) = self.project(x, k, 0.0);
            if d2 < best.2 {
                best = (k, u, d2);
            }
        }
        (best.0, best.1, best.2.sqrt())
    }

    fn segment_length(&self, k: usize) -> f64 {
        self.table.s_m[k + 1] - self.table.s_m[k]
    }

    /// One control cycle: `place_world` is where the robot is on its *program* (world frame of
    /// the model): the commanded TCP (forward kinematics of the reported joints) minus the
    /// controller's own correction (see the module documentation); `now_s` the controller
    /// time.
    pub fn update(&mut self, place_world: &Vector3<f64>, now_s: f64) -> FeedForwardStep {
        let tcp_world = place_world;
        if !tcp_world.iter().all(|v| v.is_finite()) {
            return FeedForwardStep::off(TrackState::OffPath, f64::NAN, f64::NAN);
        }
        let (k, u, offset) = match self.config.index {
            PathIndex::ArcLength => {
                let (k, u, d) = self.search(
                    tcp_world,
                    self.segment,
                    if self.locked { self.fraction } else { 0.0 },
                );
                if !self.locked {
                    if d > self.config.max_offset_m {
                        return FeedForwardStep::off(TrackState::Acquiring, f64::NAN, d);
                    }
                    self.locked = true;
                }
                if d > self.config.max_offset_m {
                    let s = self.table.s_m[self.segment]
                        + self.fraction * self.segment_length(self.segment);
                    return FeedForwardStep::off(TrackState::OffPath, s, d);
                }
                self.segment = k;
                self.fraction = u;
                (k, u, d)
            }
            PathIndex::Time => {
                let Some(t0) = self.t0 else {
                    return FeedForwardStep::off(TrackState::Acquiring, f64::NAN, f64::NAN);
                };
                let (k, u) = self
                    .table
                    .locate_time(now_s - t0 + self.config.time_offset_s, self.segment);
                self.segment = k;
                let (a, b) = (&self.track.points[k], &self.track.points[k + 1]);
                let d = (tcp_world - (a + (b - a) * u)).norm();
                let s = self.table.s_m[k] + u * self.segment_length(k);
                if d.is_nan() || d > self.config.max_offset_m {
                    return FeedForwardStep::off(TrackState::OffPath, s, d);
                }
                (k, u, d)
            }
        };
        let s = self.table.s_m[k] + u * self.segment_length(k);
        let (prior, sent) = match self.config.mode {
            FeedForwardMode::Precompensated => (
                FeedForwardTable::lerp6(&self.table.compensation, k, u),
                [0.0; 6],
            ),
            FeedForwardMode::FeedForward => {
                let here = FeedForwardTable::lerp6(&self.table.deflection, k, u).map(|v| -v);
                let sent = if self.config.lead_s > 0.0 {
                    let t = self.table.t_s[k] + u * (self.table.t_s[k + 1] - self.table.t_s[k]);
                    let (kl, ul) = self.table.locate_time(t + self.config.lead_s, k);
                    FeedForwardTable::lerp6(&self.table.deflection, kl, ul).map(|v| -v)
                } else {
                    here
                };
                (here, sent)
            }
        };
        FeedForwardStep {
            prior,
            sent,
            path_s_m: s,
            offset_m: offset,
            state: TrackState::OnPath,
        }
    }
}
