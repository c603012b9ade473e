//! The calibration cell as the planner sees it: the floor and the work table the arm must clear,
//! the points the tracker measures, how loads are applied (a cable or dead weights, at the TCP
//! or at an off-axis bracket) and the default load level. [`crate::stiffness::plan`] draws configurations
//! and loads within these rules.
//!
//! **Floor** (on by default): a horizontal plane every joint origin, the flange, the TCP, every
//! measured point and every load point stays [`DEFAULT_CLEARANCE_M`] above. Its default height
//! ([`default_floor_z`]), in this order:
//! 1. the base pivot (`[base] pivot`) when the robot file puts it below R0: the baseplate;
//! 2. the built-in Stäubli TX200's geometry (any model of it, calibrated or not), whose R0 is at
//!    the shoulder: 0.642 m below R0 (the datasheet's shoulder height);
//! 3. R0's origin, when joint 2's origin is at least 5 cm above it at zero joint values (R0 on
//!    the mounting flange, as for UR, KUKA and ABB arms);
//! 4. otherwise the floor is unknown and the planner asks for it (`--floor-z-m` or `--no-floor`).
//!
//! **Table** (on by default): a work table in front of the robot (world +x from joint 1's axis),
//! a box from the floor to its top that no joint origin, no point of the segments between them
//! and no measured or load point enters (with the clearance). Default ([`default_table`]), scaled
//! by the arm's reach R ([`Robot::reach_bound`]): x from 0.5 R to 0.85 R ahead of joint 1's
//! axis, y within ±0.3 R, top 0.2 R above the floor. For the TX200 (R = 2.19 m) that is
//! x 1.10–1.87 m, top at z = −0.20 m: the paper's forming frame (part at x = 1.5 m,
//! z = −0.18 m).
//!
//! **Loads.** A cable ([`LoadKind::Cable`]) pulls with a set tension along one of the given
//! directions: tension only (a cable never pushes), the direction being where the cable leads
//! from the attachment to its anchor or pulley; +z needs an overhead anchor. A dead weight
//! ([`LoadKind::DeadWeight`]) hangs from the attachment: force m·g along the robot file's
//! gravity. A weight, or a cable leading down (z component below −0.7), needs
//! [`DEFAULT_HANGING_DROP_M`] of free height below the attachment, above the floor and the table.
//! Loads act at the TCP and, with a bracket ([`PlanOptions::bracket_m`]), also at a point offset
//! from the TCP in the TCP frame: a lever arm that makes the load's moment turn the wrist, so
//! the J6 eDoFs become identifiable. The bracket point is measured too (`BR`).
//!
//! **Default load level** ([`default_force_n`]): the force whose median TCP deflection over
//! random configurations, with the robot file's stiffnesses, is [`TARGET_DEFLECTION_M`]
//! (2.5 mm), capped at half the arm's weight when the robot file gives link masses, rounded to
//! two significant digits: 1400 N for the TX200, 140 N for a UR10e.
//!
//! [`PlanOptions::bracket_m`]: crate::stiffness::plan::PlanOptions::bracket_m

use crate::measurements::points::PointSpec;
use crate::stiffness::{CalibError, DirectionError, PlanError};
use deflex_model::{Data, Robot};
use nalgebra::{Point3, Vector3};
use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;

/// Clearance kept above the floor and the table (m).
pub const DEFAULT_CLEARANCE_M: f64 = 0.05;
/// Free height a dead weight (or a cable leading down) needs below its attachment (m).
pub const DEFAULT_HANGING_DROP_M: f64 = 0.3;
/// Median TCP deflection the default load level aims at (m).
pub const TARGET_DEFLECTION_M: f64 = 2.5e-3;
/// Largest load the planner accepts (N): 100 kN.
pub const MAX_PLAN_FORCE_N: f64 = 1e5;
/// Largest dead weight (kg).
pub const MAX_DEAD_WEIGHT_KG: f64 = 1e4;
/// Shoulder height of the Stäubli TX200 above its floor (m, datasheet): its R0 is at the
/// shoulder.
pub const TX200_SHOULDER_HEIGHT_M: f64 = 0.642;

/// A plane or its absence: the default rule, a given height, or no check.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Floor {
    /// [`default_floor_z`].
    Default,
    /// This world height (m).
    At(f64),
    /// No floor check.
    Off,
}

/// A work table: a box from the floor to `top_z_m` over a rectangle (world, m).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct WorkTable {
    /// x range (min, max).
    pub x_m: [f64; 2],
    /// y range (min, max).
    pub y_m: [f64; 2],
    /// Height of the top.
    pub top_z_m: f64,
}

/// The table option: the default table, a given one, or none.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum TableOption {
    /// [`default_table`].
    Default,
    /// This table.
    At(WorkTable),
    /// No table check.
    Off,
}

/// The base reflector M0 (on the base casting or the floor plate, link 0): where, or none.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum BasePoint {
    /// [`default_base_point`].
    Default,
    /// At this position in R0 (m).
    At([f64; 3]),
    /// No base reflector.
    Off,
}

/// The points measured on the arm besides the TCP (and the bracket and M0).
#[derive(Clone, Debug, PartialEq)]
pub enum PointSet {
    /// Two mid-arm points ([`standard_points`]), like the paper's M2, M3.
    Standard,
    /// These points only.
    Custom(Vec<PointSpec>),
}

/// How loads are applied.
#[derive(Clone, Debug, PartialEq)]
pub enum LoadKind {
    /// A cable at the planner's tension along one of these world directions (unit vectors
    /// from the attachment towards the anchor).
    Cable {
        /// Allowed directions.
        directions: Vec<[f64; 3]>,
    },
    /// Dead weights of these masses (kg), along gravity.
    DeadWeight {
        /// Masses (kg).
        masses_kg: Vec<f64>,
    },
}

impl LoadKind {
    /// A cable along ±x, ±y, ±z of the world.
    pub fn cable_all_axes() -> LoadKind {
        LoadKind::Cable {
            directions: vec![
                [1.0, 0.0, 0.0],
                [-1.0, 0.0, 0.0],
                [0.0, 1.0, 0.0],
                [0.0, -1.0, 0.0],
                [0.0, 0.0, 1.0],
                [0.0, 0.0, -1.0],
            ],
        }
    }
}

/// Parse cable directions: comma-separated `x`, `-x`, `y`, `-y`, `z`, `-z` (world axes).
pub fn parse_directions(text: &str) -> Result<Vec<[f64; 3]>, DirectionError> {
    let mut out: Vec<[f64; 3]> = Vec::new();
    for item in text.split(',').map(str::trim) {
        let (sign, axis) = match item.strip_prefix('-') {
            Some(rest) => (-1.0, rest),
            None => (1.0, item.strip_prefix('+').unwrap_or(item)),
        };
        let index = match axis {
            "x" => 0,
            "y" => 1,
            "z" => 2,
            _ => {
                return Err(DirectionError {
                    text: item.chars().take(20).collect(),
                });
            }
        };
        let mut d = [0.0; 3];
        d[index] = sign;
        if !out.contains(&d) {
            out.push(d);
        }
    }
    Ok(out)
}

/// Random joint values within the limits (uniform; ±π for a joint without limits).
pub fn random_q(robot: &Robot, rng: &mut impl Rng) -> Vec<f64> {
    robot
        .joints
        .iter()
        .map(|j| {
            let [lo, hi] = j
                .limits
                .unwrap_or([-std::f64::consts::PI, std::f64::consts::PI]);
            if hi > lo { rng.gen_range(lo..hi) } else { lo }
        })
        .collect()
}

/// Measured points of a load case: the TCP (last link) and the middle of the two links at the
/// middle of the arm (links ⌈N/2⌉ and ⌈N/2⌉ − 1), named `M<link>`. A point too close to its
/// joint axis is moved 0.1 m along x_k so that it sees the joint's z-eDoF.
pub fn standard_points(robot: &Robot, data: &Data) -> Vec<(String, usize, Vector3<f64>)> {
    let n = robot.joint_count();
    let mut out = vec![("TCP".to_string(), n, data.tcp_position())];
    let m = n.div_ceil(2);
    for link in [m, m.saturating_sub(1)] {
        if link == 0 || link >= n {
            continue;
        }
        let frame = data.link_frame(link);
        let o = frame.translation.vector;
        let next = data.link_frame(link + 1).translation.vector;
        let mut p = 0.5 * (o + next);
        let z: Vector3<f64> = frame.rotation.matrix().column(2).into_owned();
        let radial = (p - o) - z * z.dot(&(p - o));
        if radial.norm() < 0.05 {
            p += frame.rotation.matrix().column(0) * 0.1;
        }
        out.push((format!("M{link}"), link, p));
    }
    out
}

/// World position of a point given in a link frame.
pub fn point_in_world(data: &Data, link: usize, position_m: &[f64; 3]) -> Vector3<f64> {
    data.link_frame(link)
        .transform_point(&Point3::from(*position_m))
        .coords
}

/// Where the default base reflector M0 sits, in R0: 0.3 m along x0 from joint 1's axis, at
/// 0.3 m below R0 or, when the floor is higher, 0.15 m above the floor (on a bracket fixed to
/// the floor plate). `floor_in_r0_z` is the floor's height in R0, when known.
pub fn default_base_point(floor_in_r0_z: Option<f64>) -> [f64; 3] {
    let z = match floor_in_r0_z {
        Some(f) => (-0.3_f64).max(f + 0.15),
        None => -0.3,
    };
    [0.3, 0.0, z]
}

/// The default floor height (world z, m) by the rules of the module documentation, or an
/// error asking for it.
pub fn default_floor_z(robot: &Robot) -> Result<f64, CalibError> {
    let world_of_r0 = |p: Vector3<f64>| robot.base.transform_point(&Point3::from(p)).coords.z;
    if robot.base_pivot.z < 0.0 {
        return Ok(world_of_r0(robot.base_pivot));
    }
    let tx200 = deflex_model::builtin("tx200").map(|r| r.geometry_fingerprint());
    if tx200.as_deref() == Some(robot.geometry_fingerprint().as_str()) {
        return Ok(world_of_r0(Vector3::new(
            0.0,
            0.0,
            -TX200_SHOULDER_HEIGHT_M,
        )));
    }
    let mut data = Data::new();
    robot.forward_kinematics(&mut data, &vec![0.0; robot.joint_count()])?;
    let second = data
        .link_frame(robot.joint_count().min(2))
        .translation
        .vector;
    let r0 = robot.base.translation.vector;
    if second.z - r0.z >= 0.05 {
        return Ok(r0.z);
    }
    Err(PlanError::FloorUnknown {
        robot: robot.name.clone(),
        shoulder_above_r0_m: second.z - r0.z,
    }
    .into())
}

/// The default work table for a floor at `floor_z` (see the module documentation).
pub fn default_table(robot: &Robot, floor_z: f64) -> WorkTable {
    let reach = robot.reach_bound();
    let axis = robot.base.translation.vector;
    WorkTable {
        x_m: [axis.x + 0.5 * reach, axis.x + 0.85 * reach],
        y_m: [axis.y - 0.3 * reach, axis.y + 0.3 * reach],
        top_z_m: floor_z + 0.2 * reach,
    }
}

/// Round to two significant digits.
fn two_digits(x: f64) -> f64 {
    if x <= 0.0 || !x.is_finite() {
        return x;
    }
    let scale = 10f64.powf(x.log10().floor() - 1.0);
    (x / scale).round() * scale
}

/// The default load level for `robot` (N), see the module documentation; an error when the
/// robot has no eDoF (nothing deflects).
pub fn default_force_n(robot: &Robot) -> Result<f64, CalibError> {
    let mut rng = ChaCha8Rng::seed_from_u64(7);
    let mut data = Data::new();
    let mut compliances = Vec::new();
    for _ in 0..200 {
        let q: Vec<f64> = random_q(robot, &mut rng);
        robot.forward_kinematics(&mut data, &q)?;
        for axis in 0..3 {
            let mut w = deflex_model::Wrench::zeros();
            w[axis] = 1.0;
            let d = robot.tcp_deflection(&data, &w);
            compliances.push(Vector3::new(d[0], d[1], d[2]).norm());
        }
    }
    compliances.sort_by(f64::total_cmp);
    let median = compliances[compliances.len() / 2];
    if !(median.is_finite() && median > 0.0) {
        return Err(PlanError::NoDeflection {
            robot: robot.name.clone(),
        }
        .into());
    }
    let mut force = TARGET_DEFLECTION_M / median;
    let mass: f64 = robot
        .joints
        .iter()
        .filter_map(|j| j.inertia.as_ref().map(|i| i.mass_kg))
        .sum();
    let g = robot.gravity.norm();
    if mass > 0.0 && g > 0.0 {
        force = force.min(0.5 * mass * g);
    }
    Ok(two_digits(force).clamp(1.0, MAX_PLAN_FORCE_N))
}

/// The floor, table and clearances a configuration must respect.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Obstacles {
    /// Floor height (world z, m), when checked.
    pub floor_z_m: Option<f64>,
    /// The table, when checked.
    pub table: Option<WorkTable>,
    /// Clearance above both (m).
    pub clearance_m: f64,
    /// Free height needed below a hanging load's attachment (m).
    pub hanging_drop_m: f64,
}

impl Obstacles {
    fn above_floor(&self, p: &Vector3<f64>, extra: f64) -> bool {
        self.floor_z_m
            .is_none_or(|floor| p.z >= floor + self.clearance_m + extra)
    }

    fn clear_of_table(&self, p: &Vector3<f64>, extra: f64) -> bool {
        let Some(t) = self.table else { return true };
        let c = self.clearance_m;
        let over = p.x >= t.x_m[0] - c
            && p.x <= t.x_m[1] + c
            && p.y >= t.y_m[0] - c
            && p.y <= t.y_m[1] + c;
        !over || p.z >= t.top_z_m + c + extra
    }

    /// Whether the arm at `data` (joint origins, the segments between them, flange and TCP)
    /// and the `points` clear the floor and the table.
    pub fn arm_clear(&self, robot: &Robot, data: &Data, points: &[Vector3<f64>]) -> bool {
        let mut chain: Vec<Vector3<f64>> = (0..=robot.joint_count())
            .map(|i| data.link_frame(i).translation.vector)
            .collect();
        chain.push(data.flange.translation.vector);
        chain.push(data.tcp_position());
        let ok = |p: &Vector3<f64>| self.above_floor(p, 0.0) && self.clear_of_table(p, 0.0);
        // The base frame may sit on the floor itself: check it against the table only.
        if !chain[1..].iter().all(ok) || !points.iter().all(ok) {
            return false;
        }
        if self.table.is_some() {
            for pair in chain.windows(2) {
                let length = (pair[1] - pair[0]).norm();
                let steps = (length / 0.02).ceil().clamp(1.0, 1000.0) as usize;
                for k in 1..steps {
                    let p = pair[0] + (pair[1] - pair[0]) * (k as f64 / steps as f64);
                    if !self.clear_of_table(&p, 0.0) {
                        return false;
                    }
                }
            }
        }
        true
    }

    /// Whether a load hanging from `attachment` (a dead weight, or a cable leading down) has
    /// its free drop above the floor and the table.
    pub fn hanging_clear(&self, attachment: &Vector3<f64>) -> bool {
        self.above_floor(attachment, self.hanging_drop_m)
            && self.clear_of_table(attachment, self.hanging_drop_m)
    }
}

/// Joint values wrapped into the limits: each value replaced by its equivalent modulo 2π with
/// the smallest magnitude that lies within the joint's limits (unchanged when none does).
pub fn wrap_into_limits(robot: &Robot, q: &mut [f64]) {
    for (value, joint) in q.iter_mut().zip(&robot.joints) {
        let limits = joint.limits.unwrap_or([f64::NEG_INFINITY, f64::INFINITY]);
        *value = wrapped(*value, limits);
    }
}

/// `value` modulo 2π with the smallest magnitude within `[lo, hi]`, or `value` when no
/// equivalent lies within.
pub fn wrapped(value: f64, [lo, hi]: [f64; 2]) -> f64 {
    use std::f64::consts::TAU;
    if !value.is_finite() {
        return value;
    }
    let turns = (value / TAU).round();
    let mut best: Option<f64> = None;
    for k in -3..=3 {
        let candidate = value - (turns + f64::from(k)) * TAU;
        let candidate = if (candidate - value).abs() < 1e-12 {
            value
        } else {
            candidate
        };
        if candidate >= lo
            && candidate <= hi
            && best.is_none_or(|b| candidate.abs() < b.abs() - 1e-12)
        {
            best = Some(candidate);
        }
    }
    best.unwrap_or(value)
}

/// The joints without limits, an error naming the first, when the planner needs limits.
pub fn require_limits(robot: &Robot) -> Result<(), CalibError> {
    if let Some((i, joint)) = robot
        .joints
        .iter()
        .enumerate()
        .find(|(_, j)| j.limits.is_none())
    {
        return Err(PlanError::NoLimits {
            joint: i + 1,
            name: joint.name.clone(),
            robot: robot.name.clone(),
        }
        .into());
    }
    Ok(())
}
