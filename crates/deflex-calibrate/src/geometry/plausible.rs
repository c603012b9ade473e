//! How far a calibration may move a robot from its nominal geometry.
//!
//! A manufacturing or assembly error is millimetres and milliradians: no arm leaves the factory
//! with a link a quarter of a metre longer than its data sheet, a joint a quarter turn off, or a
//! probe half a metre from the flange. A least-squares fit does not know that: given another
//! robot's readings, it reshapes the nominal arm into the other one (lengths changed by
//! decimetres, offsets by π/2, the set-up moved by metres) and fits them to a fraction of a
//! millimetre. These bounds, scaled by the arm's size, say where the fitted model stops being
//! "this robot, calibrated" and becomes "another robot" (or another target, or a rough guess
//! for a start).
//!
//! | parameter | bound on the change from the start |
//! | --- | --- |
//! | DH length `a`, `d` | 2 % of the arm's size + 10 mm |
//! | DH angle θ, α, β (modulo 2π) | 0.1 rad (5.7°) |
//! | set-up translation (from the registration on the nominal robot) | 5 % of the arm's size + 20 mm |
//! | set-up rotation (from that registration) | 0.1 rad |
//! | target position on the flange | 5 % of the arm's size + 20 mm |
//! | target frame rotation | 0.2 rad |
//! | joint term: harmonic amplitude, backlash, joint-map coefficient | 0.02 rad |
//! | `register`: a known set-up re-registered | moved by the arm's size (its working volume) |
//! | `register`: a target registered | its offset from the flange: half the arm's size |
//!
//! A new set-up that `register` places is not bounded: a tracker may stand anywhere.
//!
//! The arm's size ([`arm_size_m`]) is the sum of the lengths of the joint placements and the
//! tool: 1.54 m for a UR10 (a DH length may change by 41 mm), 2.19 m for a Stäubli TX200
//! (54 mm). Compliances, masses and torsion terms are physical quantities with their own
//! checks, not geometric changes, and are not bounded here.

use crate::geometry::fit::{Estimate, FitResult};
use crate::geometry::joint_maps::JointMaps;
use crate::geometry::params::{DhField, EgModel, Param, Unit};
use deflex_model::{NamedPose, Robot};
use std::f64::consts::PI;

/// Bounds on the change of each geometric parameter (module documentation).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ChangeBounds {
    /// The arm's size the length bounds scale with (m).
    pub arm_size_m: f64,
    /// DH lengths `a`, `d` (m).
    pub dh_length_m: f64,
    /// DH angles θ, α, β, compared modulo 2π (rad).
    pub dh_angle_rad: f64,
    /// Set-up translations (m).
    pub setup_translation_m: f64,
    /// Set-up rotations (rad).
    pub setup_rotation_rad: f64,
    /// Target positions on the flange (m).
    pub target_m: f64,
    /// Target frame rotations (rad).
    pub target_rotation_rad: f64,
    /// Joint terms: harmonic amplitudes, backlash and joint-map coefficients (rad).
    pub joint_term_rad: f64,
    /// `register`: how far a known set-up may move (m).
    pub setup_move_m: f64,
    /// `register`: how far from the flange a registered target may sit (m).
    pub target_offset_m: f64,
}

impl ChangeBounds {
    /// The bounds of the module documentation for `robot`.
    pub fn for_robot(robot: &Robot) -> ChangeBounds {
        let size = arm_size_m(robot);
        ChangeBounds {
            arm_size_m: size,
            dh_length_m: 0.02 * size + 0.010,
            dh_angle_rad: 0.1,
            setup_translation_m: 0.05 * size + 0.020,
            setup_rotation_rad: 0.1,
            target_m: 0.05 * size + 0.020,
            target_rotation_rad: 0.2,
            joint_term_rad: 0.02,
            setup_move_m: size,
            target_offset_m: 0.5 * size,
        }
    }

    /// The bound on `param`'s change, or `None` when it is not a geometric parameter.
    pub fn bound(&self, param: Param) -> Option<f64> {
        match param {
            Param::Dh(_, DhField::A | DhField::D) => Some(self.dh_length_m),
            Param::Dh(_, DhField::Theta | DhField::Alpha | DhField::Beta) => {
                Some(self.dh_angle_rad)
            }
            Param::SetupTranslation(..) => Some(self.setup_translation_m),
            Param::SetupRotation(..) => Some(self.setup_rotation_rad),
            Param::Target(..) => Some(self.target_m),
            Param::TargetRotation(..) => Some(self.target_rotation_rad),
            Param::Harmonic { .. } | Param::Backlash(_) => Some(self.joint_term_rad),
            Param::Compliance(_)
            | Param::Mass(_)
            | Param::FirstMoment(..)
            | Param::Torsion { .. } => None,
        }
    }
}

/// The arm's size: the sum of the lengths of its joint placements and its tool (m).
pub fn arm_size_m(robot: &Robot) -> f64 {
    robot
        .joints
        .iter()
        .map(|j| j.placement.translation.vector.norm())
        .sum::<f64>()
        + robot.tool.translation.vector.norm()
}

/// A parameter a fit moved further than its bound.
#[derive(Clone, Debug, PartialEq)]
pub struct LargeChange {
    /// The parameter's name (`J2.d`, `setup[A].tx`).
    pub name: String,
    /// Its change from the start (SI; angles wrapped to (−π, π]).
    pub change: f64,
    /// The bound it exceeds (SI).
    pub bound: f64,
    /// The unit.
    pub unit: Unit,
}

impl std::fmt::Display for LargeChange {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        let (factor, label) = self.unit.display();
        write!(
            f,
            "{} {:+.0} {label} (bound ±{:.0} {label})",
            self.name,
            self.change * factor,
            self.bound * factor
        )
    }
}

/// The change of an estimate from its start: angles (radian parameters) wrapped to (−π, π], so
/// that a joint offset moved by a full turn is no change.
pub fn change_of(estimate: &Estimate) -> f64 {
    let change = estimate.value - estimate.start;
    if estimate.unit == Unit::Radian {
        wrap_angle(change)
    } else {
        change
    }
}

fn wrap_angle(angle: f64) -> f64 {
    let wrapped = angle.rem_euclid(2.0 * PI);
    if wrapped > PI {
        wrapped - 2.0 * PI
    } else {
        wrapped
    }
}

/// Everything a fit changed beyond its bound: its estimates ([`large_changes`]) and its joint
/// maps' coefficients ([`large_map_coefficients`]), largest excess first.
pub fn large_fit_changes(result: &FitResult, bounds: &ChangeBounds) -> Vec<LargeChange> {
    let mut large = large_changes(&result.estimates, bounds);
    if let Some(maps) = &result.model.joint_maps {
        large.extend(large_map_coefficients(maps, bounds));
        sort_by_excess(&mut large);
    }
    large
}

/// The joint-map coefficients beyond [`ChangeBounds::joint_term_rad`] (`J2.map[k]`, k the
/// knot), largest first: a map is a joint's angle error, which is milliradians.
pub fn large_map_coefficients(maps: &JointMaps, bounds: &ChangeBounds) -> Vec<LargeChange> {
    let mut large: Vec<LargeChange> = maps
        .maps
        .iter()
        .flat_map(|map| {
            map.coefficients
                .iter()
                .enumerate()
                .filter(|(_, c)| !c.is_finite() || c.abs() > bounds.joint_term_rad)
                .map(|(k, &c)| LargeChange {
                    name: format!("J{}.map[{k}]", map.joint + 1),
                    change: c,
                    bound: bounds.joint_term_rad,
                    unit: Unit::Radian,
                })
        })
        .collect();
    sort_by_excess(&mut large);
    large
}

/// The estimates whose change from the start exceeds its bound, largest excess (change ÷ bound)
/// first. A change that is not finite exceeds every bound and comes first.
pub fn large_changes(estimates: &[Estimate], bounds: &ChangeBounds) -> Vec<LargeChange> {
    let mut large: Vec<LargeChange> = estimates
        .iter()
        .filter_map(|e| {
            let bound = bounds.bound(e.param)?;
            let change = change_of(e);
            (!change.is_finite() || change.abs() > bound).then(|| LargeChange {
                name: e.name.clone(),
                change,
                bound,
                unit: e.unit,
            })
        })
        .collect();
    sort_by_excess(&mut large);
    large
}

fn sort_by_excess(large: &mut [LargeChange]) {
    large.sort_by(|a, b| {
        let excess = |c: &LargeChange| {
            if c.change.is_finite() {
                (c.change / c.bound).abs()
            } else {
                f64::INFINITY
            }
        };
        excess(b).total_cmp(&excess(a))
    });
}

/// What a registration moved beyond its bounds: the set-up `setup` (when `calibrated_setups`,
/// the set-ups as calibrated, held it) by more than the arm's size, the target `target` (when
/// one was registered) further from the flange than half of it. `after` is the model as
/// registered.
pub fn large_registration_moves(
    calibrated_setups: &[NamedPose],
    after: &EgModel,
    setup: usize,
    target: Option<usize>,
    bounds: &ChangeBounds,
) -> Vec<LargeChange> {
    let mut large = Vec::new();
    if let (Some(old), Some(new)) = (calibrated_setups.get(setup), after.setups.get(setup)) {
        let moved = (new.pose.translation.vector - old.pose.translation.vector).norm();
        if !moved.is_finite() || moved > bounds.setup_move_m {
            large.push(LargeChange {
                name: format!("setup[{}] moved", new.name),
                change: moved,
                bound: bounds.setup_move_m,
                unit: Unit::Metre,
            });
        }
    }
    if let Some(t) = target.and_then(|t| after.targets.get(t)) {
        let offset = t.position.norm();
        if !offset.is_finite() || offset > bounds.target_offset_m {
            large.push(LargeChange {
                name: format!("target[{}] from the flange", t.name),
                change: offset,
                bound: bounds.target_offset_m,
                unit: Unit::Metre,
            });
        }
    }
    large
}
