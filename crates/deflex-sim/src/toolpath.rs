//! Tool paths in the part frame R_p: a parametric frustum cone (contour or helical), a square
//! pyramid, and CAM G-code ([`crate::gcode`]). Coordinates are the TCP (the centre of the
//! hemispherical tip) in mm; the undeformed sheet's top surface is at z = −tool radius, so the
//! tool just touches it at z = 0, and the part axis is R_p's z axis.

use crate::error::SimError;
use serde::{Deserialize, Serialize};
use std::f64::consts::PI;

/// One point of a path: the TCP position in R_p (mm), reached with `feed_mm_s` from the previous
/// point (`None`: a rapid move at the controller's rapid feed).
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct Waypoint {
    /// Position in R_p (mm).
    pub p_mm: [f64; 3],
    /// Feed rate of the move ending here (mm/s); `None` = rapid (G0).
    pub feed_mm_s: Option<f64>,
}

/// A tool path: waypoints in R_p, followed with linear moves at their feed rates.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct ToolPath {
    /// Name for logs and plots.
    pub name: String,
    /// Waypoints; the first one is the start position.
    pub waypoints: Vec<Waypoint>,
    /// Nominal step-down (mm) and wall angle (deg) when known: they set the Aerens force level.
    pub step_down_mm: Option<f64>,
    /// Nominal wall angle (deg).
    pub wall_angle_deg: Option<f64>,
}

/// A frustum cone formed from the top down.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct ConeParams {
    /// TCP path diameter at the top (mm).
    pub top_diameter_mm: f64,
    /// Wall angle from the sheet plane (deg).
    pub wall_angle_deg: f64,
    /// Depth of the TCP path (mm).
    pub depth_mm: f64,
    /// Depth increment per revolution (mm).
    pub step_down_mm: f64,
    /// Helical (continuous z) or contour (constant-z circles with step-down moves).
    pub helical: bool,
    /// Feed rate (mm/s).
    pub feed_mm_s: f64,
    /// Angular discretisation (deg).
    pub angle_step_deg: f64,
}

impl Default for ConeParams {
    /// The paper's path (Section 4.1): 40 mm diameter, 45°, 15 mm deep, 10 mm/s. The step-down is
    /// not published; 0.24 mm makes the helical path ≈ 4.9 m long, i.e. the paper's ≈ 500 s.
    fn default() -> Self {
        ConeParams {
            top_diameter_mm: 40.0,
            wall_angle_deg: 45.0,
            depth_mm: 15.0,
            step_down_mm: 0.24,
            helical: true,
            feed_mm_s: 10.0,
            angle_step_deg: 5.0,
        }
    }
}

/// A square pyramid frustum formed from the top down (helical along the perimeter).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct PyramidParams {
    /// TCP path side length at the top (mm).
    pub top_side_mm: f64,
    /// Wall angle (deg).
    pub wall_angle_deg: f64,
    /// Depth (mm).
    pub depth_mm: f64,
    /// Depth increment per lap (mm).
    pub step_down_mm: f64,
    /// Feed rate (mm/s).
    pub feed_mm_s: f64,
    /// Longest straight segment between waypoints (mm).
    pub max_segment_mm: f64,
}

impl Default for PyramidParams {
    fn default() -> Self {
        PyramidParams {
            top_side_mm: 40.0,
            wall_angle_deg: 45.0,
            depth_mm: 15.0,
            step_down_mm: 0.3,
            feed_mm_s: 10.0,
            max_segment_mm: 2.0,
        }
    }
}

/// A plunge into a stiff fixture followed by a traverse under load (pressing, a friction-stir
/// plunge and weld): the second scenario of the twin ([`crate::fixture`]).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct PlungeParams {
    /// Start height of the TCP above the surface contact (mm).
    pub approach_mm: f64,
    /// Programmed interference below the surface contact (mm).
    pub depth_mm: f64,
    /// Feed of the approach and the plunge (mm/s).
    pub plunge_feed_mm_s: f64,
    /// Length of the traverse at depth, along x of R_p (mm).
    pub traverse_mm: f64,
    /// Feed of the traverse (mm/s).
    pub traverse_feed_mm_s: f64,
}

impl Default for PlungeParams {
    /// 5 mm approach, 1 mm interference at 0.5 mm/s, 20 mm traverse at 2 mm/s (about 19 s).
    fn default() -> Self {
        PlungeParams {
            approach_mm: 5.0,
            depth_mm: 1.0,
            plunge_feed_mm_s: 0.5,
            traverse_mm: 20.0,
            traverse_feed_mm_s: 2.0,
        }
    }
}

fn check(field: &str, value: f64) -> Result<(), SimError> {
    if value.is_finite() && value > 0.0 {
        Ok(())
    } else {
        Err(SimError::Path(format!(
            "{field} must be positive and finite, got {value}"
        )))
    }
}

fn check_wall(angle: f64, depth: f64, top_half: f64) -> Result<(), SimError> {
    if !(angle > 0.0 && angle < 90.0) {
        return Err(SimError::Path(format!(
            "wall angle must be within (0, 90) deg, got {angle}"
        )));
    }
    let inset = depth / angle.to_radians().tan();
    if inset >= top_half {
        return Err(SimError::Path(format!(
            "a {depth} mm deep wall at {angle}° closes before the bottom: the top half-width \
             {top_half} mm must exceed {inset:.3} mm"
        )));
    }
    Ok(())
}

impl ToolPath {
    /// The paper's frustum cone (Section 4.1, [`ConeParams::default`]).
    pub fn paper_cone() -> ToolPath {
        ToolPath::cone(&ConeParams::default()).expect("default cone is valid")
    }

    /// A frustum cone: starts at (r₀, 0, 0), turns counter-clockwise seen from above, and ends
    /// with one full contour at the final depth.
    pub fn cone(p: &ConeParams) -> Result<ToolPath, SimError> {
        check("top_diameter_mm", p.top_diameter_mm)?;
        check("depth_mm", p.depth_mm)?;
        check("step_down_mm", p.step_down_mm)?;
        check("feed_mm_s", p.feed_mm_s)?;
        check("angle_step_deg", p.angle_step_deg)?;
        let r0 = p.top_diameter_mm / 2.0;
        check_wall(p.wall_angle_deg, p.depth_mm, r0)?;
        let tan = p.wall_angle_deg.to_radians().tan();
        let radius = |depth: f64| r0 - depth / tan;
        let per_rev = (360.0 / p.angle_step_deg).ceil() as usize;
        let dtheta = 2.0 * PI / per_rev as f64;
        let feed = Some(p.feed_mm_s);
        let point = |r: f64, theta: f64, z: f64| Waypoint {
            p_mm: [r * theta.cos(), r * theta.sin(), z],
            feed_mm_s: feed,
        };
        let mut waypoints = vec![Waypoint {
            p_mm: [r0, 0.0, 0.0],
            feed_mm_s: None,
        }];
        let revolutions = p.depth_mm / p.step_down_mm;
        if p.helical {
            let steps = (revolutions * per_rev as f64).ceil() as usize;
            for k in 1..=steps {
                let depth = (p.depth_mm * k as f64 / steps as f64).min(p.depth_mm);
                let theta = dtheta * k as f64 * (revolutions * per_rev as f64 / steps as f64);
                waypoints.push(point(radius(depth), theta, -depth));
            }
            let theta_end = dtheta * steps as f64 * (revolutions * per_rev as f64 / steps as f64);
            for k in 1..=per_rev {
                waypoints.push(point(
                    radius(p.depth_mm),
                    theta_end + dtheta * k as f64,
                    -p.depth_mm,
                ));
            }
        } else {
            let levels = revolutions.ceil() as usize;
            for level in 0..=levels {
                let depth = (p.step_down_mm * level as f64).min(p.depth_mm);
                let r = radius(depth);
                // Step-down move to the new level, then one contour.
                waypoints.push(point(r, 0.0, -depth));
                for k in 1..=per_rev {
                    waypoints.push(point(r, dtheta * k as f64, -depth));
                }
            }
        }
        waypoints.dedup_by(|a, b| distance(a, b) < 1e-9);
        Ok(ToolPath {
            name: format!(
                "cone Ø{} mm, {}°, {} mm deep, Δz {} mm ({})",
                p.top_diameter_mm,
                p.wall_angle_deg,
                p.depth_mm,
                p.step_down_mm,
                if p.helical { "helical" } else { "contour" }
            ),
            waypoints,
            step_down_mm: Some(p.step_down_mm),
            wall_angle_deg: Some(p.wall_angle_deg),
        })
    }

    /// A square pyramid frustum centred on the part axis, descending continuously along the
    /// perimeter (one lap per step-down), then one lap at the final depth.
    pub fn pyramid(p: &PyramidParams) -> Result<ToolPath, SimError> {
        check("top_side_mm", p.top_side_mm)?;
        check("depth_mm", p.depth_mm)?;
        check("step_down_mm", p.step_down_mm)?;
        check("feed_mm_s", p.feed_mm_s)?;
        check("max_segment_mm", p.max_segment_mm)?;
        let a0 = p.top_side_mm / 2.0;
        check_wall(p.wall_angle_deg, p.depth_mm, a0)?;
        let tan = p.wall_angle_deg.to_radians().tan();
        let feed = Some(p.feed_mm_s);
        // Perimeter parameter u ∈ [0, 4): side k from corner k to corner k+1 (counter-clockwise).
        let corners = [[1.0, -1.0], [1.0, 1.0], [-1.0, 1.0], [-1.0, -1.0]];
        let at = |u: f64, half: f64| -> [f64; 2] {
            let k = (u.floor() as usize).min(3);
            let f = u - k as f64;
            let a = corners[k];
            let b = corners[(k + 1) % 4];
            [
                half * (a[0] + (b[0] - a[0]) * f),
                half * (a[1] + (b[1] - a[1]) * f),
            ]
        };
        let per_side = (p.top_side_mm / p.max_segment_mm).ceil().max(1.0) as usize;
        let per_lap = 4 * per_side;
        let laps = p.depth_mm / p.step_down_mm;
        let steps = (laps * per_lap as f64).ceil() as usize;
        let start = at(0.0, a0);
        let mut waypoints = vec![Waypoint {
            p_mm: [start[0], start[1], 0.0],
            feed_mm_s: None,
        }];
        for k in 1..=steps + per_lap {
            let s = k.min(steps) as f64 / steps as f64;
            let depth = p.depth_mm * s;
            let u = (k as f64 / per_side as f64) % 4.0;
            let xy = at(u, a0 - depth / tan);
            waypoints.push(Waypoint {
                p_mm: [xy[0], xy[1], -depth],
                feed_mm_s: feed,
            });
        }
        Ok(ToolPath {
            name: format!(
                "pyramid {} mm, {}°, {} mm deep, Δz {} mm",
                p.top_side_mm, p.wall_angle_deg, p.depth_mm, p.step_down_mm
            ),
            waypoints,
            step_down_mm: Some(p.step_down_mm),
            wall_angle_deg: Some(p.wall_angle_deg),
        })
    }

    /// A plunge and traverse ([`PlungeParams`]): from `approach_mm` above the contact down to
    /// `depth_mm` below it, along x for `traverse_mm`, back up.
    pub fn plunge(p: &PlungeParams) -> Result<ToolPath, SimError> {
        check("approach_mm", p.approach_mm)?;
        check("depth_mm", p.depth_mm)?;
        check("plunge_feed_mm_s", p.plunge_feed_mm_s)?;
        check("traverse_mm", p.traverse_mm)?;
        check("traverse_feed_mm_s", p.traverse_feed_mm_s)?;
        let at = |x: f64, z: f64, feed: Option<f64>| Waypoint {
            p_mm: [x, 0.0, z],
            feed_mm_s: feed,
        };
        let plunge = Some(p.plunge_feed_mm_s);
        let x0 = -p.traverse_mm / 2.0;
        let x1 = p.traverse_mm / 2.0;
        Ok(ToolPath {
            name: format!(
                "plunge {} mm into the fixture, {} mm traverse",
                p.depth_mm, p.traverse_mm
            ),
            waypoints: vec![
                at(x0, p.approach_mm, None),
                at(x0, 0.0, plunge),
                at(x0, -p.depth_mm, plunge),
                at(x1, -p.depth_mm, Some(p.traverse_feed_mm_s)),
                at(x1, p.approach_mm, plunge),
            ],
            step_down_mm: Some(p.depth_mm),
            wall_angle_deg: Some(45.0),
        })
    }

    /// Path length (mm).
    pub fn length_mm(&self) -> f64 {
        self.waypoints
            .windows(2)
            .map(|w| distance(&w[0], &w[1]))
            .sum()
    }

    /// Time to follow the path (s), rapid moves at `rapid_feed_mm_s`.
    pub fn duration_s(&self, rapid_feed_mm_s: f64) -> f64 {
        self.waypoints
            .windows(2)
            .map(|w| distance(&w[0], &w[1]) / w[1].feed_mm_s.unwrap_or(rapid_feed_mm_s))
            .sum()
    }

    /// The first part of the path, up to `max_length_mm` of travel (for short runs and tests).
    pub fn truncated(&self, max_length_mm: f64) -> ToolPath {
        let mut out = self.clone();
        let mut travelled = 0.0;
        let mut keep = 1;
        for w in self.waypoints.windows(2) {
            if travelled >= max_length_mm {
                break;
            }
            travelled += distance(&w[0], &w[1]);
            keep += 1;
        }
        out.waypoints.truncate(keep);
        out.name = format!("{} (first {max_length_mm} mm)", self.name);
        out
    }

    /// The same path with every feed move longer than `max_segment_mm` split into equal moves at
    /// the same feed (a rapid stays one rapid move): the geometry and the timing do not change, but an
    /// offline compensation, which moves each waypoint, then acts along a move instead of only
    /// at its ends (a plunge into the sheet written as one move reaches its force halfway).
    /// At most [`crate::gcode::MAX_WAYPOINTS`] waypoints.
    pub fn subdivided(&self, max_segment_mm: f64) -> Result<ToolPath, SimError> {
        if !(max_segment_mm.is_finite() && (1e-3..=1e4).contains(&max_segment_mm)) {
            return Err(SimError::Path(format!(
                "the longest move must be within 0.001 ..= 10000 mm, got {max_segment_mm}"
            )));
        }
        let mut waypoints = Vec::with_capacity(self.waypoints.len());
        if let Some(first) = self.waypoints.first() {
            waypoints.push(*first);
        }
        for w in self.waypoints.windows(2) {
            // A rapid stays one move: it is in the air, and a robot program writes it as one.
            let pieces = if w[1].feed_mm_s.is_none() {
                1.0
            } else {
                (distance(&w[0], &w[1]) / max_segment_mm).ceil().max(1.0)
            };
            if waypoints.len() as f64 + pieces > crate::gcode::MAX_WAYPOINTS as f64 {
                return Err(SimError::Path(format!(
                    "\"{}\" split into moves of at most {max_segment_mm} mm has more than {} waypoints",
                    self.name,
                    crate::gcode::MAX_WAYPOINTS
                )));
            }
            let pieces = pieces as usize;
            for k in 1..=pieces {
                let f = k as f64 / pieces as f64;
                waypoints.push(Waypoint {
                    p_mm: std::array::from_fn(|i| w[0].p_mm[i] + f * (w[1].p_mm[i] - w[0].p_mm[i])),
                    feed_mm_s: w[1].feed_mm_s,
                });
            }
        }
        Ok(ToolPath {
            name: format!("{} (moves ≤ {max_segment_mm} mm)", self.name),
            waypoints,
            step_down_mm: self.step_down_mm,
            wall_angle_deg: self.wall_angle_deg,
        })
    }

    /// Check the path is usable: at least two distinct points, finite values, positive feeds.
    pub fn validate(&self) -> Result<(), SimError> {
        if self.waypoints.len() < 2 {
            return Err(SimError::Path(format!(
                "\"{}\" needs at least two waypoints",
                self.name
            )));
        }
        for (i, w) in self.waypoints.iter().enumerate() {
            if !w.p_mm.iter().all(|v| v.is_finite()) {
                return Err(SimError::Path(format!("waypoint {i} is not finite")));
            }
            if let Some(f) = w.feed_mm_s
                && !(f.is_finite() && f > 0.0)
            {
                return Err(SimError::Path(format!(
                    "waypoint {i}: feed must be positive, got {f}"
                )));
            }
        }
        if self.length_mm() <= 0.0 {
            return Err(SimError::Path(format!("\"{}\" has zero length", self.name)));
        }
        Ok(())
    }
}

fn distance(a: &Waypoint, b: &Waypoint) -> f64 {
    let d = [
        a.p_mm[0] - b.p_mm[0],
        a.p_mm[1] - b.p_mm[1],
        a.p_mm[2] - b.p_mm[2],
    ];
    (d[0] * d[0] + d[1] * d[1] + d[2] * d[2]).sqrt()
}
