//! Circular and helical arcs (`G2`/`G3`): the centre from `I J K` or from `R`, the sweep, and
//! the interpolation to a chord tolerance.
//!
//! ## Conventions (RS274/NGC, Fanuc)
//!
//! The plane's axes `(a₁, a₂)` and its normal `n` are right-handed: `G17` (X, Y; Z), `G18`
//! (Z, X; Y), `G19` (Y, Z; X). `G3` turns counter-clockwise seen from the positive end of `n`
//! (a positive rotation about `n`), `G2` clockwise. The motion along `n` is linear in the angle
//! (a helix). The radius goes linearly from the start's to the end's (CAM output rounds the
//! end point; a difference beyond [`RADIUS_TOLERANCE_MM`] and [`RADIUS_TOLERANCE_REL`] of the
//! radius is an error). Start and end at the same place in the plane with `I J K` is a full
//! circle (times `P` turns).
//!
//! `R`: the centre lies on the perpendicular bisector of the chord at `h = √(R² − (d/2)²)`; on
//! the chord's left (seen from `+n`, travelling from start to end) for `G3` with `R > 0` and for
//! `G2` with `R < 0` (the arc of more than 180°), on its right otherwise. A `G2` arc under 180°
//! from left to right therefore bulges towards `+a₂`.
//!
//! ## Chord tolerance
//!
//! A chord spanning `Δθ` on a circle of radius `r` leaves the arc by the sagitta
//! `r (1 − cos(Δθ/2))`; the arc is cut into `⌈|sweep| / Δθ_max⌉` equal steps with
//! `Δθ_max = 2 acos(1 − tol / r_max)`, so no chord is farther than `tol` from the arc.

use crate::gcode::Plane;

/// Largest accepted difference of the start and end radii (mm) when also beyond
/// [`RADIUS_TOLERANCE_REL`] of the radius.
pub const RADIUS_TOLERANCE_MM: f64 = 0.01;
/// Largest accepted relative difference of the start and end radii.
pub const RADIUS_TOLERANCE_REL: f64 = 1e-3;
/// Largest arc radius (mm).
pub const MAX_RADIUS_MM: f64 = 10_000.0;
/// Most full turns of one arc (`P`).
pub const MAX_TURNS: u32 = 1000;

/// Start and end on the same spot of the plane: a full circle (mm).
const SAME_POINT_MM: f64 = 1e-4;

/// Why an arc's geometry does not close, with the numbers that say so (mm).
#[derive(Clone, Copy, Debug, PartialEq, thiserror::Error)]
pub enum ArcError {
    /// An `R` arc whose start and end coincide.
    #[error("an R arc whose start and end are the same point: a full circle needs I, J, K")]
    RadiusFullCircle,
    /// An `R` value out of range.
    #[error("radius {radius_mm} mm is not within (0, {MAX_RADIUS_MM}] mm")]
    RadiusOutOfRange {
        /// The signed `R` value (mm).
        radius_mm: f64,
    },
    /// An `R` smaller than half the chord: no arc joins the points.
    #[error(
        "radius {radius_mm:.4} mm is smaller than half the chord ({half_chord_mm:.4} mm): no arc joins the points"
    )]
    RadiusTooSmall {
        /// |R| (mm).
        radius_mm: f64,
        /// Half the start–end distance (mm).
        half_chord_mm: f64,
    },
    /// The radius at the start or the end is zero or too large.
    #[error(
        "radius {start_mm:.4} mm at the start and {end_mm:.4} mm at the end: expected within (0, \
         {MAX_RADIUS_MM}] mm (is the centre on the start point?)"
    )]
    CentreRadius {
        /// Start–centre distance (mm).
        start_mm: f64,
        /// End–centre distance (mm).
        end_mm: f64,
    },
    /// The end is not on the start's circle.
    #[error(
        "the end is {end_mm:.4} mm from the centre, the start {start_mm:.4} mm: the radii differ by \
         {difference_mm:.4} mm (more than {RADIUS_TOLERANCE_MM} mm and {} % of the radius)",
        RADIUS_TOLERANCE_REL * 100.0
    )]
    RadiiDiffer {
        /// Start–centre distance (mm).
        start_mm: f64,
        /// End–centre distance (mm).
        end_mm: f64,
        /// |start − end| (mm).
        difference_mm: f64,
    },
    /// A centre coordinate beyond the coordinate bound
    /// ([`crate::gcode::ReadOptions::max_coordinate_mm`]).
    #[error("the centre {centre_mm:.3} mm is beyond ±{max_mm} mm")]
    CentreOutOfRange {
        /// The centre coordinate (mm).
        centre_mm: f64,
        /// The bound (mm).
        max_mm: f64,
    },
    /// A `P` word outside 1 ..= [`MAX_TURNS`].
    #[error("P{turns}: the number of turns must be 1 ..= {MAX_TURNS}")]
    Turns {
        /// The number of turns asked for.
        turns: u32,
    },
}

/// The in-plane coordinates of `p` relative to `c`.
fn planar(p: &[f64; 3], c: &[f64; 3], plane: Plane) -> (f64, f64) {
    let (a1, a2, _) = plane.axes();
    (p[a1] - c[a1], p[a2] - c[a2])
}

/// The centre of an `R` arc (see the module documentation).
pub fn center_from_radius(
    start: &[f64; 3],
    end: &[f64; 3],
    radius: f64,
    plane: Plane,
    ccw: bool,
) -> Result<[f64; 3], ArcError> {
    let (a1, a2, _) = plane.axes();
    let (dx, dy) = (end[a1] - start[a1], end[a2] - start[a2]);
    let d = dx.hypot(dy);
    if d < SAME_POINT_MM {
        return Err(ArcError::RadiusFullCircle);
    }
    let r = radius.abs();
    if !(r > 0.0 && r <= MAX_RADIUS_MM) {
        return Err(ArcError::RadiusOutOfRange { radius_mm: radius });
    }
    let half = d / 2.0;
    if r < half - RADIUS_TOLERANCE_MM {
        return Err(ArcError::RadiusTooSmall {
            radius_mm: r,
            half_chord_mm: half,
        });
    }
    let h = (r * r - half * half).max(0.0).sqrt();
    let left = if ccw == (radius > 0.0) { 1.0 } else { -1.0 };
    // Left normal of the chord direction (dx, dy)/d: (−dy, dx)/d.
    let mut c = *start;
    c[a1] = start[a1] + dx / 2.0 - left * h * dy / d;
    c[a2] = start[a2] + dy / 2.0 + left * h * dx / d;
    Ok(c)
}

/// The checked geometry of an arc: start angle and radius, sweep (rad, signed: positive
/// counter-clockwise about the normal), end radius.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Sweep {
    /// Angle of the start about the centre in the plane (rad, from the plane's first axis).
    pub theta0: f64,
    /// Signed sweep (rad; positive counter-clockwise about the normal), full turns included.
    pub sweep: f64,
    /// Radius at the start (mm).
    pub r0: f64,
    /// Radius at the end (mm).
    pub r1: f64,
}

/// Angles, radii and sweep of an arc; errors when it does not close.
pub fn sweep(
    start: &[f64; 3],
    end: &[f64; 3],
    center: &[f64; 3],
    plane: Plane,
    ccw: bool,
    turns: u32,
) -> Result<Sweep, ArcError> {
    let (u0, v0) = planar(start, center, plane);
    let (u1, v1) = planar(end, center, plane);
    let (r0, r1) = (u0.hypot(v0), u1.hypot(v1));
    if !(r0 > 1e-6 && r0 <= MAX_RADIUS_MM && r1 > 1e-6 && r1 <= MAX_RADIUS_MM) {
        return Err(ArcError::CentreRadius {
            start_mm: r0,
            end_mm: r1,
        });
    }
    let difference = (r0 - r1).abs();
    if difference > RADIUS_TOLERANCE_MM && difference > RADIUS_TOLERANCE_REL * r0.max(r1) {
        return Err(ArcError::RadiiDiffer {
            start_mm: r0,
            end_mm: r1,
            difference_mm: difference,
        });
    }
    if turns == 0 || turns > MAX_TURNS {
        return Err(ArcError::Turns { turns });
    }
    let theta0 = v0.atan2(u0);
    let theta1 = v1.atan2(u1);
    let tau = std::f64::consts::TAU;
    let same = (u1 - u0).hypot(v1 - v0) < SAME_POINT_MM;
    // Counter-clockwise sweep in (0, 2π]; a full circle when start and end coincide.
    let mut ccw_sweep = (theta1 - theta0).rem_euclid(tau);
    if same || ccw_sweep == 0.0 {
        ccw_sweep = tau;
    }
    let sweep = if ccw {
        ccw_sweep + tau * f64::from(turns - 1)
    } else {
        let cw = (tau - ccw_sweep).rem_euclid(tau);
        let cw = if same || cw == 0.0 { tau } else { cw };
        -(cw + tau * f64::from(turns - 1))
    };
    Ok(Sweep {
        theta0,
        sweep,
        r0,
        r1,
    })
}

/// Steps of an arc for a chord tolerance (see the module documentation).
pub fn steps(s: &Sweep, tolerance_mm: f64) -> f64 {
    let r = s.r0.max(s.r1);
    if r <= tolerance_mm {
        return 1.0;
    }
    let max_step = 2.0 * (1.0 - tolerance_mm / r).acos();
    (s.sweep.abs() / max_step).ceil().max(1.0)
}

/// Point `k` of `n` of the arc (`k = n` is the end exactly).
pub fn point(
    s: &Sweep,
    start: &[f64; 3],
    end: &[f64; 3],
    center: &[f64; 3],
    plane: Plane,
    k: usize,
    n: usize,
) -> [f64; 3] {
    if k >= n {
        return *end;
    }
    let (a1, a2, normal) = plane.axes();
    let f = k as f64 / n as f64;
    let theta = s.theta0 + s.sweep * f;
    let r = s.r0 + (s.r1 - s.r0) * f;
    let mut p = [0.0; 3];
    p[a1] = center[a1] + r * theta.cos();
    p[a2] = center[a2] + r * theta.sin();
    p[normal] = start[normal] + (end[normal] - start[normal]) * f;
    p
}
