//! The planner's options, their bounds (named after the `deflex plan` flags) and the cell they
//! resolve to for a robot.

use crate::stiffness::campaign_cell::{
    BasePoint, DEFAULT_CLEARANCE_M, DEFAULT_HANGING_DROP_M, Floor, LoadKind, MAX_DEAD_WEIGHT_KG,
    MAX_PLAN_FORCE_N, Obstacles, PointSet, TableOption, default_base_point, default_floor_z,
    default_table,
};
use crate::stiffness::{CalibError, PlanError};
use deflex_model::Robot;
use nalgebra::{Point3, Vector3};

/// Most load cases a plan may ask for.
pub const MAX_LOAD_CASES: usize = 1000;
/// Most random configurations tried.
pub const MAX_CONFIGURATIONS: usize = 2000;
/// Most dead weights (each is a candidate per configuration and attachment).
pub const MAX_DEAD_WEIGHTS: usize = 4;
/// Tracker noise accepted for the expected standard errors (m).
pub const NOISE_RANGE_M: [f64; 2] = [1e-9, 1e-2];
/// Longest bracket lever arm (m).
pub const MAX_BRACKET_M: f64 = 2.0;
/// Settings of [`plan_experiments`](super::plan_experiments). The error messages name the `deflex plan` flags.
#[derive(Clone, Debug)]
pub struct PlanOptions {
    /// Cable tension (N); dead weights set their own force.
    pub max_force_n: f64,
    /// Total number of load cases (axis-by-axis ones included).
    pub load_cases: usize,
    /// Random configurations tried (each with every load and attachment).
    pub configurations: usize,
    /// Tracker noise (m) for the expected standard errors.
    pub noise_sigma_m: f64,
    /// Random seed.
    pub seed: u64,
    /// Plan for every eDoF of the model family (x, y, z per joint, base x/y tilt), not only the
    /// model's: what the structure search needs. Absent eDoFs get the median stiffness.
    pub full_family: bool,
    /// The base reflector `M0`: only base eDoFs move it, which separates a baseplate tilt from
    /// the x/y eDoFs of joint 1 (the paper's M1 saw the tilt, Section 3.1).
    pub base_point: BasePoint,
    /// The points measured on the arm besides the TCP.
    pub points: PointSet,
    /// The floor under the robot. Off in [`PlanOptions::default`] (library callers such as the
    /// demo's twin, which has nothing to collide with, keep their plans); `deflex plan` uses
    /// [`Floor::Default`].
    pub floor: Floor,
    /// The work table in front of the robot. Off in [`PlanOptions::default`]; `deflex plan`
    /// uses [`TableOption::Default`].
    pub table: TableOption,
    /// Clearance above the floor and the table (m).
    pub clearance_m: f64,
    /// Free height a hanging load needs below its attachment (m).
    pub hanging_drop_m: f64,
    /// Cable or dead weights.
    pub load: LoadKind,
    /// Off-axis load point in the TCP frame (m): loads act at the TCP and at this bracket point
    /// (measured as `BR`), so that their moments load the wrist.
    pub bracket_m: Option<[f64; 3]>,
}

impl PlanOptions {
    /// The defaults of `deflex plan`: [`PlanOptions::default`] with the floor and the table
    /// checked at their default heights ([`crate::stiffness::campaign_cell`]).
    pub fn for_a_real_cell() -> PlanOptions {
        PlanOptions {
            floor: Floor::Default,
            table: TableOption::Default,
            ..PlanOptions::default()
        }
    }
}

impl Default for PlanOptions {
    fn default() -> Self {
        PlanOptions {
            max_force_n: 1500.0,
            load_cases: 24,
            configurations: 600,
            noise_sigma_m: 15e-6,
            seed: 1,
            full_family: false,
            base_point: BasePoint::Default,
            points: PointSet::Standard,
            floor: Floor::Off,
            table: TableOption::Off,
            clearance_m: DEFAULT_CLEARANCE_M,
            hanging_drop_m: DEFAULT_HANGING_DROP_M,
            load: LoadKind::cable_all_axes(),
            bracket_m: None,
        }
    }
}

/// Check every option against its bound, naming the `deflex plan` flag.
pub(super) fn check_options(robot: &Robot, o: &PlanOptions) -> Result<(), PlanError> {
    use PlanError as E;
    if !(o.max_force_n.is_finite() && o.max_force_n > 0.0 && o.max_force_n <= MAX_PLAN_FORCE_N) {
        return Err(E::option(
            "--max-force-N",
            format!("a force in (0, {MAX_PLAN_FORCE_N:e}] N"),
            o.max_force_n,
        ));
    }
    if !(1..=MAX_LOAD_CASES).contains(&o.load_cases) {
        return Err(E::option(
            "--load-cases",
            format!("1 to {MAX_LOAD_CASES}"),
            o.load_cases,
        ));
    }
    if !(1..=MAX_CONFIGURATIONS).contains(&o.configurations) {
        return Err(E::option(
            "--configurations",
            format!("1 to {MAX_CONFIGURATIONS}"),
            o.configurations,
        ));
    }
    if !(o.noise_sigma_m >= NOISE_RANGE_M[0] && o.noise_sigma_m <= NOISE_RANGE_M[1]) {
        return Err(E::option(
            "--noise-um",
            format!(
                "{} to {} µm",
                NOISE_RANGE_M[0] * 1e6,
                NOISE_RANGE_M[1] * 1e6
            ),
            format!("{} µm", o.noise_sigma_m * 1e6),
        ));
    }
    if !(0.0..=1.0).contains(&o.clearance_m) {
        return Err(E::option("--clearance-m", "0 to 1 m", o.clearance_m));
    }
    if !(0.0..=5.0).contains(&o.hanging_drop_m) {
        return Err(E::option("--hanging-drop-m", "0 to 5 m", o.hanging_drop_m));
    }
    let length = |v: f64| v.is_finite() && v.abs() <= 100.0;
    if let Floor::At(z) = o.floor
        && !length(z)
    {
        return Err(E::option("--floor-z-m", "a height within ±100 m", z));
    }
    if let TableOption::At(t) = o.table
        && !(t.x_m.iter().chain(&t.y_m).all(|v| length(*v))
            && length(t.top_z_m)
            && t.x_m[0] < t.x_m[1]
            && t.y_m[0] < t.y_m[1])
    {
        return Err(E::option(
            "--table",
            "x_min,x_max,y_min,y_max,top_z (m) with min < max, within ±100 m",
            // The text the derived `Debug` gave before the type was renamed `WorkTable` (the
            // message unchanged).
            format!(
                "Table {{ x_m: {:?}, y_m: {:?}, top_z_m: {:?} }}",
                t.x_m, t.y_m, t.top_z_m
            ),
        ));
    }
    if let BasePoint::At(p) = o.base_point
        && !p.iter().all(|v| v.is_finite() && v.abs() <= 10.0)
    {
        return Err(E::option(
            "--base-point-m",
            "a position within ±10 m of R0",
            format!("{p:?}"),
        ));
    }
    if let Some(b) = o.bracket_m {
        let norm = Vector3::from(b).norm();
        if !(b.iter().all(|v| v.is_finite()) && (1e-3..=MAX_BRACKET_M).contains(&norm)) {
            return Err(E::option(
                "--bracket-m",
                format!("an offset of 1 mm to {MAX_BRACKET_M} m in the TCP frame"),
                format!("{b:?}"),
            ));
        }
    }
    if let PointSet::Custom(points) = &o.points {
        for p in points {
            if p.link > robot.joint_count() {
                return Err(E::PointLink {
                    point: p.name.clone(),
                    link: p.link,
                    joints: robot.joint_count(),
                });
            }
        }
    }
    match &o.load {
        LoadKind::Cable { directions } => {
            if directions.is_empty()
                || directions.len() > 26
                || !directions
                    .iter()
                    .all(|d| (Vector3::from(*d).norm() - 1.0).abs() < 1e-9)
            {
                return Err(E::option(
                    "--cable-directions",
                    "1 to 26 unit directions",
                    format!("{} direction(s)", directions.len()),
                ));
            }
        }
        LoadKind::DeadWeight { masses_kg } => check_masses(robot, masses_kg)?,
    }
    Ok(())
}

/// Dead weights: 1 to [`MAX_DEAD_WEIGHTS`] masses, each positive, at most
/// [`MAX_DEAD_WEIGHT_KG`] and weighing at most [`MAX_PLAN_FORCE_N`], on a robot with gravity.
fn check_masses(robot: &Robot, masses_kg: &[f64]) -> Result<(), PlanError> {
    let g = robot.gravity.norm();
    if g == 0.0 {
        return Err(PlanError::NoGravity {
            robot: robot.name.clone(),
        });
    }
    if masses_kg.is_empty() || masses_kg.len() > MAX_DEAD_WEIGHTS {
        return Err(PlanError::option(
            "--masses-kg",
            format!("1 to {MAX_DEAD_WEIGHTS} masses"),
            masses_kg.len(),
        ));
    }
    for &m in masses_kg {
        if !(m.is_finite() && m > 0.0 && m <= MAX_DEAD_WEIGHT_KG && m * g <= MAX_PLAN_FORCE_N) {
            return Err(PlanError::option(
                "--masses-kg",
                format!(
                    "masses in (0, {MAX_DEAD_WEIGHT_KG}] kg whose weight is at most {MAX_PLAN_FORCE_N:e} N"
                ),
                m,
            ));
        }
    }
    Ok(())
}

/// Resolve the floor, the table and the base point of the options for `robot`.
pub(super) fn resolve_setup(
    robot: &Robot,
    o: &PlanOptions,
) -> Result<(Obstacles, Option<[f64; 3]>), CalibError> {
    let floor_z = match o.floor {
        Floor::Default => Some(default_floor_z(robot)?),
        Floor::At(z) => Some(z),
        Floor::Off => None,
    };
    let table = match o.table {
        TableOption::Default => {
            let floor = match floor_z {
                Some(z) => z,
                None => default_floor_z(robot).map_err(|_| PlanError::TableWithoutFloor {
                    robot: robot.name.clone(),
                })?,
            };
            Some(default_table(robot, floor))
        }
        TableOption::At(t) => Some(t),
        TableOption::Off => None,
    };
    let floor_in_r0 = floor_z.map(|z| {
        robot
            .base
            .inverse_transform_point(&Point3::new(
                robot.base.translation.vector.x,
                robot.base.translation.vector.y,
                z,
            ))
            .z
    });
    let base_point = match o.base_point {
        BasePoint::Default => Some(default_base_point(floor_in_r0)),
        BasePoint::At(p) => Some(p),
        BasePoint::Off => None,
    };
    Ok((
        Obstacles {
            floor_z_m: floor_z,
            table,
            clearance_m: o.clearance_m,
            hanging_drop_m: o.hanging_drop_m,
        },
        base_point,
    ))
}
