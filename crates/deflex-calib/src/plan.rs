//! Experiment planning: which configurations, loads and points to measure.
//!
//! 1. **Candidates**: random configurations within the joint limits (required; angles rounded
//!    to 0.1° inside the limits and wrapped to their smallest equivalent, so no −259° reaches
//!    the technician), kept only when the arm, the measured points and the loads clear the
//!    floor and the work table ([`crate::cell`]); each loaded by a cable along each allowed
//!    direction or by each dead weight, at the TCP and, with a bracket, at the bracket point.
//! 2. **Axis by axis** (the paper's Fig. 7 and Tables A1/A2, generalised): for every eDoF, the
//!    candidate where that eDoF's share of the predicted displacement (eq. 15, all measured
//!    points) is largest while being clearly visible (≥ 10 σ).
//! 3. **D-optimal completion**: greedily add the candidate that maximises `log det F` of the
//!    Fisher information `F = Σ JᵀJ/σ²` of the relative compliances `c_e / c_e,nominal`, up to
//!    the requested number of load cases.
//!
//! The expected standard error of every stiffness follows from `F⁻¹` (relative SE of k equals
//! relative SE of c to first order); that of every centre shift the calibration fits from the
//! calibration's own covariance `(JᵀWJ)⁻¹` at the nominal model ([`expected_shift_se`]). An
//! eDoF this plan cannot identify (infinite expected SE) gets no axis-by-axis case, so the
//! technician's sheet and the table agree. Each load case measures the TCP, the bracket point
//! `BR` when there is a bracket, the mid-arm points ([`standard_points`], or the user's) and a
//! reflector on the base (`M0`, [`BasePoint`]), like the paper's M1..M3.

use crate::CalibError;
pub use crate::cell::{
    BasePoint, Floor, LoadKind, PointSet, PointSpec, Table, TableOption, standard_points,
};
use crate::cell::{
    DEFAULT_CLEARANCE_M, DEFAULT_HANGING_DROP_M, MAX_DEAD_WEIGHT_KG, MAX_PLAN_FORCE_N, Obstacles,
    default_base_point, default_floor_z, default_table, point_in_world, require_limits,
    wrap_into_limits,
};
use crate::data::MeasurementRow;
use crate::design::{Design, EdofId, edof_label};
use crate::uncertainty::unscaled_covariance;
use deflex_model::{Axis, Data, EdofSite, Robot};
use nalgebra::{DMatrix, Point3, Vector3};
use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;

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

/// Settings of [`plan_experiments`]. The error messages name the `deflex plan` flags.
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
    /// checked at their default heights ([`crate::cell`]).
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

/// Expected precision of one stiffness under a plan.
#[derive(Clone, Debug)]
pub struct ExpectedSe {
    /// The eDoF.
    pub id: EdofId,
    /// Label.
    pub label: String,
    /// Nominal stiffness used (N·m/rad).
    pub nominal_k: f64,
    /// Expected standard error of k (N·m/rad); +∞ when not identifiable.
    pub se_k: f64,
    /// `se_k / nominal_k`.
    pub relative: f64,
}

impl ExpectedSe {
    /// Whether the plan can identify this eDoF (finite expected SE).
    pub fn identifiable(&self) -> bool {
        self.relative.is_finite()
    }
}

/// Expected precision of a centre shift the calibration will fit.
#[derive(Clone, Debug, PartialEq)]
pub struct ExpectedShiftSe {
    /// Joint (1-based).
    pub joint: usize,
    /// Nominal shift (m).
    pub nominal_m: f64,
    /// Expected standard error (m), fitted jointly with the compliances; +∞ when the campaign
    /// cannot see it.
    pub se_m: f64,
}

/// The axis-by-axis choice for one eDoF.
#[derive(Clone, Debug)]
pub struct AxisCase {
    /// The eDoF.
    pub id: EdofId,
    /// Load-case label in the plan.
    pub load_case: String,
    /// That eDoF's share of the summed per-eDoF displacement norms.
    pub share: f64,
    /// Its contribution, in units of the tracker σ.
    pub snr: f64,
}

/// The cell the plan was made for, as resolved from the options and the robot.
#[derive(Clone, Debug, PartialEq)]
pub struct PlanSetup {
    /// Cable tension (N), or the force of the heaviest dead weight.
    pub force_n: f64,
    /// How loads are applied.
    pub load: LoadKind,
    /// Bracket offset in the TCP frame (m), when used.
    pub bracket_m: Option<[f64; 3]>,
    /// Floor height (world z, m), when checked.
    pub floor_z_m: Option<f64>,
    /// The table, when checked.
    pub table: Option<Table>,
    /// The base reflector in R0 (m), when measured.
    pub base_point_r0_m: Option<[f64; 3]>,
    /// Configurations drawn and kept (clear of floor and table).
    pub configurations_drawn: usize,
    /// Configurations kept.
    pub configurations_kept: usize,
}

/// A measurement campaign.
#[derive(Clone, Debug)]
pub struct Plan {
    /// Rows in the plan format (no displacement).
    pub rows: Vec<MeasurementRow>,
    /// Axis-by-axis choices, for the eDoFs the plan can identify.
    pub axis_cases: Vec<AxisCase>,
    /// Expected SE of every planned stiffness.
    pub expected: Vec<ExpectedSe>,
    /// Expected SE of the centre shift of every joint with an x/y eDoF in the model.
    pub expected_shifts: Vec<ExpectedShiftSe>,
    /// `log det` of the final information matrix (relative parameters).
    pub log_det: f64,
    /// The cell as planned for.
    pub setup: PlanSetup,
}

/// Where the base reflector `M0` sat before it became configurable, in R0: 0.3 m forward of
/// and 0.3 m below the origin of R0 (the TX200's base casting). [`default_base_point`] keeps it
/// there when the floor allows.
pub const BASE_POINT_IN_R0_M: [f64; 3] = [0.3, 0.0, -0.3];

fn invalid(message: String) -> CalibError {
    CalibError::Invalid(message)
}

/// Check every option against its bound, naming the `deflex plan` flag.
fn check_options(robot: &Robot, o: &PlanOptions) -> Result<(), CalibError> {
    if !(o.max_force_n.is_finite() && o.max_force_n > 0.0 && o.max_force_n <= MAX_PLAN_FORCE_N) {
        return Err(invalid(format!(
            "--max-force-N: expected a force in (0, {MAX_PLAN_FORCE_N:e}] N, got {}",
            o.max_force_n
        )));
    }
    if !(1..=MAX_LOAD_CASES).contains(&o.load_cases) {
        return Err(invalid(format!(
            "--load-cases: expected 1 to {MAX_LOAD_CASES}, got {}",
            o.load_cases
        )));
    }
    if !(1..=MAX_CONFIGURATIONS).contains(&o.configurations) {
        return Err(invalid(format!(
            "--configurations: expected 1 to {MAX_CONFIGURATIONS}, got {}",
            o.configurations
        )));
    }
    if !(o.noise_sigma_m >= NOISE_RANGE_M[0] && o.noise_sigma_m <= NOISE_RANGE_M[1]) {
        return Err(invalid(format!(
            "--noise-um: expected {} to {} µm, got {} µm",
            NOISE_RANGE_M[0] * 1e6,
            NOISE_RANGE_M[1] * 1e6,
            o.noise_sigma_m * 1e6
        )));
    }
    if !(0.0..=1.0).contains(&o.clearance_m) {
        return Err(invalid(format!(
            "--clearance-m: expected 0 to 1 m, got {}",
            o.clearance_m
        )));
    }
    if !(0.0..=5.0).contains(&o.hanging_drop_m) {
        return Err(invalid(format!(
            "--hanging-drop-m: expected 0 to 5 m, got {}",
            o.hanging_drop_m
        )));
    }
    let length = |v: f64| v.is_finite() && v.abs() <= 100.0;
    if let Floor::At(z) = o.floor
        && !length(z)
    {
        return Err(invalid(format!(
            "--floor-z-m: expected a height within ±100 m, got {z}"
        )));
    }
    if let TableOption::At(t) = o.table
        && !(t.x_m.iter().chain(&t.y_m).all(|v| length(*v))
            && length(t.top_z_m)
            && t.x_m[0] < t.x_m[1]
            && t.y_m[0] < t.y_m[1])
    {
        return Err(invalid(format!(
            "--table: expected x_min,x_max,y_min,y_max,top_z (m) with min < max, within ±100 m, got {t:?}"
        )));
    }
    if let BasePoint::At(p) = o.base_point
        && !p.iter().all(|v| v.is_finite() && v.abs() <= 10.0)
    {
        return Err(invalid(format!(
            "--base-point-m: expected a position within ±10 m of R0, got {p:?}"
        )));
    }
    if let Some(b) = o.bracket_m {
        let norm = Vector3::from(b).norm();
        if !(b.iter().all(|v| v.is_finite()) && (1e-3..=MAX_BRACKET_M).contains(&norm)) {
            return Err(invalid(format!(
                "--bracket-m: expected an offset of 1 mm to {MAX_BRACKET_M} m in the TCP frame, got {b:?}"
            )));
        }
    }
    if let PointSet::Custom(points) = &o.points {
        for p in points {
            if p.link > robot.joint_count() {
                return Err(invalid(format!(
                    "point {}: link {} does not exist (0 = base … {} = last link)",
                    p.name,
                    p.link,
                    robot.joint_count()
                )));
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
                return Err(invalid(
                    "--cable-directions: expected 1 to 26 unit directions".into(),
                ));
            }
        }
        LoadKind::DeadWeight { masses_kg } => {
            let g = robot.gravity.norm();
            if g == 0.0 {
                return Err(invalid(format!(
                    "--load dead-weight: robot \"{}\" has no gravity, so a dead weight has no force",
                    robot.name
                )));
            }
            if masses_kg.is_empty() || masses_kg.len() > MAX_DEAD_WEIGHTS {
                return Err(invalid(format!(
                    "--masses-kg: expected 1 to {MAX_DEAD_WEIGHTS} masses, got {}",
                    masses_kg.len()
                )));
            }
            for &m in masses_kg {
                if !(m.is_finite()
                    && m > 0.0
                    && m <= MAX_DEAD_WEIGHT_KG
                    && m * g <= MAX_PLAN_FORCE_N)
                {
                    return Err(invalid(format!(
                        "--masses-kg: expected masses in (0, {MAX_DEAD_WEIGHT_KG}] kg whose weight is at most {MAX_PLAN_FORCE_N:e} N, got {m}"
                    )));
                }
            }
        }
    }
    Ok(())
}

/// Resolve the floor, the table and the base point of the options for `robot`.
fn resolve_setup(
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
                None => default_floor_z(robot).map_err(|_| {
                    invalid(format!(
                        "the default table stands on the floor, whose height is unknown for robot \"{}\": give --table or --no-table",
                        robot.name
                    ))
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

/// Round joint values to 0.1° without leaving the limits.
fn round_within_limits(robot: &Robot, q: &mut [f64]) {
    for (value, joint) in q.iter_mut().zip(&robot.joints) {
        let tenths = value.to_degrees() * 10.0;
        let mut rounded = tenths.round().to_radians() / 10.0;
        if let Some([lo, hi]) = joint.limits {
            if rounded < lo {
                rounded = tenths.ceil().to_radians() / 10.0;
            }
            if rounded > hi {
                rounded = tenths.floor().to_radians() / 10.0;
            }
        }
        *value = rounded;
    }
}

/// One candidate load case: its rows and the information it brings.
struct Candidate {
    rows: Vec<MeasurementRow>,
    /// Purpose words: how it is loaded (`cable`, `dead weight 140 kg`, `at the bracket`).
    loading: String,
    /// `U Uᵀ` with U the relative-compliance sensitivities in units of σ (p × p).
    info: DMatrix<f64>,
    /// Per eDoF: the norm of its sensitivity row (its displacement in σ).
    norms: Vec<f64>,
}

/// The measured points of a configuration: (label, link, world position).
fn measured_points(
    robot: &Robot,
    data: &Data,
    o: &PlanOptions,
    base_point: Option<[f64; 3]>,
) -> Vec<(String, usize, Vector3<f64>)> {
    let n = robot.joint_count();
    let mut points = vec![("TCP".to_string(), n, data.tcp_position())];
    if let Some(b) = o.bracket_m {
        points.push((
            "BR".to_string(),
            n,
            data.tcp.transform_point(&Point3::from(b)).coords,
        ));
    }
    match &o.points {
        PointSet::Standard => points.extend(standard_points(robot, data).into_iter().skip(1)),
        PointSet::Custom(list) => points.extend(list.iter().map(|p| {
            (
                p.name.clone(),
                p.link,
                point_in_world(data, p.link, &p.position_m),
            )
        })),
    }
    if let Some(m0) = base_point {
        points.push(("M0".to_string(), 0, point_in_world(data, 0, &m0)));
    }
    points
}

/// Draw configurations and build the candidate load cases with their information.
#[allow(clippy::too_many_arguments)]
fn candidates(
    robot: &Robot,
    o: &PlanOptions,
    obstacles: &Obstacles,
    base_point: Option<[f64; 3]>,
    edofs: &[EdofId],
    nominal: &[f64],
    shifts: &[f64],
) -> Result<(Vec<Candidate>, usize, usize), CalibError> {
    let n = robot.joint_count();
    let mut rng = ChaCha8Rng::seed_from_u64(o.seed);
    let mut data = Data::new();
    let loads: Vec<(Vector3<f64>, bool, String)> = match &o.load {
        LoadKind::Cable { directions } => directions
            .iter()
            .map(|d| {
                let d = Vector3::from(*d);
                (d * o.max_force_n, d.z < -0.7, "cable".to_string())
            })
            .collect(),
        LoadKind::DeadWeight { masses_kg } => masses_kg
            .iter()
            .map(|m| (robot.gravity * *m, true, format!("dead weight {m} kg")))
            .collect(),
    };
    let mut out = Vec::new();
    let (mut kept, mut drawn) = (0, 0);
    while kept < o.configurations && drawn < 20 * o.configurations {
        drawn += 1;
        let mut q: Vec<f64> = robot
            .joints
            .iter()
            .map(|j| {
                let [lo, hi] = j
                    .limits
                    .unwrap_or([-std::f64::consts::PI, std::f64::consts::PI]);
                if hi > lo { rng.gen_range(lo..hi) } else { lo }
            })
            .collect();
        round_within_limits(robot, &mut q);
        // The rows carry the joint values wrapped into the limits (what the technician types);
        // the information is computed at the values drawn, the same pose.
        let mut q_wrapped = q.clone();
        wrap_into_limits(robot, &mut q_wrapped);
        robot
            .forward_kinematics(&mut data, &q)
            .map_err(|e| invalid(e.to_string()))?;
        let points = measured_points(robot, &data, o, base_point);
        let positions: Vec<Vector3<f64>> = points.iter().map(|p| p.2).collect();
        if !obstacles.arm_clear(robot, &data, &positions) {
            continue;
        }
        kept += 1;
        let mut attachments = vec![("TCP", data.tcp_position())];
        if o.bracket_m.is_some() {
            attachments.push(("BR", points[1].2));
        }
        let mut batch: Vec<(Vec<MeasurementRow>, String)> = Vec::new();
        for (attachment, at) in &attachments {
            for (force, hanging, loading) in &loads {
                if *hanging && !obstacles.hanging_clear(at) {
                    continue;
                }
                let rows = points
                    .iter()
                    .map(|(name, link, p)| MeasurementRow {
                        load_case: String::new(),
                        q_rad: q_wrapped.clone(),
                        wrench: [force.x, force.y, force.z, 0.0, 0.0, 0.0],
                        load_link: n,
                        load_point_m: [at.x, at.y, at.z],
                        point: name.clone(),
                        point_link: *link,
                        point_m: [p.x, p.y, p.z],
                        displacement_m: None,
                        sigma_m: Some(o.noise_sigma_m),
                        rotation_rad: None,
                        purpose: None,
                    })
                    .collect();
                let loading = if *attachment == "BR" {
                    format!("{loading} at the bracket")
                } else {
                    loading.clone()
                };
                batch.push((rows, loading));
            }
        }
        if batch.is_empty() {
            continue;
        }
        out.extend(information(robot, batch, &q, edofs, nominal, shifts)?);
    }
    Ok((out, drawn, kept))
}

/// The information of each candidate of a batch (one configuration), from one design built at
/// the joint values drawn (`q_drawn`; the rows carry them wrapped).
fn information(
    robot: &Robot,
    batch: Vec<(Vec<MeasurementRow>, String)>,
    q_drawn: &[f64],
    edofs: &[EdofId],
    nominal: &[f64],
    shifts: &[f64],
) -> Result<Vec<Candidate>, CalibError> {
    let flat: Vec<MeasurementRow> = batch
        .iter()
        .flat_map(|b| b.0.iter())
        .map(|r| MeasurementRow {
            q_rad: q_drawn.to_vec(),
            ..r.clone()
        })
        .collect();
    let design = Design::build(robot, &flat, edofs, false)?;
    let p = edofs.len();
    let mut eq0 = 0;
    let mut out = Vec::with_capacity(batch.len());
    for (rows, loading) in batch {
        let m = 3 * rows.len();
        let mut u = DMatrix::<f64>::zeros(p, m);
        for e in 0..p {
            let s = design.shift_joint(e).map(|j| shifts[j - 1]).unwrap_or(0.0);
            for (b, coef) in design.col(e, s) {
                for k in 0..m {
                    u[(e, k)] += coef * design.x[(eq0 + k, b)] * nominal[e].recip();
                }
            }
        }
        eq0 += m;
        let info = &u * u.transpose();
        let norms: Vec<f64> = (0..p).map(|e| info[(e, e)].max(0.0).sqrt()).collect();
        out.push(Candidate {
            rows,
            loading,
            info,
            norms,
        });
    }
    Ok(out)
}

/// `log det` of a symmetric positive definite matrix, `None` when it is not (or not finite).
fn log_det(m: &DMatrix<f64>) -> Option<f64> {
    if !crate::all_finite(m) {
        return None;
    }
    let ch = m.clone().cholesky()?;
    Some(ch.l().diagonal().iter().map(|v| 2.0 * v.ln()).sum())
}

/// Relative SE of eDoF `e` from the information restricted to `set` (without the ridge).
fn relative_se(info: &DMatrix<f64>, ridge: f64, set: &[usize], e: usize) -> f64 {
    let m = set.len();
    let sub = DMatrix::from_fn(m, m, |i, j| {
        info[(set[i], set[j])] - if i == j { ridge } else { 0.0 }
    });
    let Some(pos) = set.iter().position(|&k| k == e) else {
        return f64::INFINITY;
    };
    let d: Vec<f64> = (0..m).map(|i| sub[(i, i)].max(0.0).sqrt()).collect();
    if d[pos] == 0.0 || !crate::all_finite(&sub) {
        return f64::INFINITY;
    }
    let scaled = DMatrix::from_fn(m, m, |i, j| {
        if d[i] > 0.0 && d[j] > 0.0 {
            sub[(i, j)] / (d[i] * d[j])
        } else if i == j {
            1.0
        } else {
            0.0
        }
    });
    let eig_min = scaled
        .clone()
        .symmetric_eigenvalues()
        .iter()
        .copied()
        .fold(f64::INFINITY, f64::min);
    if eig_min < 1e-10 {
        return f64::INFINITY;
    }
    match scaled.cholesky() {
        Some(ch) => ch.inverse()[(pos, pos)].max(0.0).sqrt() / d[pos],
        None => f64::INFINITY,
    }
}

/// Plan a campaign for `robot` (its geometry, eDoFs, stiffnesses and centre shifts are the
/// nominal model).
pub fn plan_experiments(robot: &Robot, options: &PlanOptions) -> Result<Plan, CalibError> {
    check_options(robot, options)?;
    require_limits(robot)?;
    let (obstacles, base_point) = resolve_setup(robot, options)?;
    let (edofs, nominal) = planned_edofs(robot, options.full_family);
    if edofs.is_empty() {
        return Err(invalid(format!(
            "robot \"{}\" has no eDoF to plan for (use the full model family)",
            robot.name
        )));
    }
    let shifts: Vec<f64> = robot.joints.iter().map(|j| j.center_shift).collect();
    let (cands, drawn, kept) = candidates(
        robot, options, &obstacles, base_point, &edofs, &nominal, &shifts,
    )?;
    if cands.is_empty() {
        return Err(invalid(format!(
            "no configuration out of {drawn} drawn keeps the arm{} clear of the floor (z = {}) and the table ({}): lower the floor or the table, or turn the checks off (--no-floor, --no-table)",
            if options.bracket_m.is_some() {
                ", the bracket"
            } else {
                ""
            },
            obstacles
                .floor_z_m
                .map_or("not checked".to_string(), |z| format!("{z:.3} m")),
            obstacles
                .table
                .map_or("not checked".to_string(), |t| format!(
                    "top at z = {:.3} m over x {:.3}…{:.3} m, y {:.3}…{:.3} m",
                    t.top_z_m, t.x_m[0], t.x_m[1], t.y_m[0], t.y_m[1]
                )),
        )));
    }
    let p = edofs.len();
    // Axis by axis: for every eDoF the candidate where its share is largest while ≥ 10 σ (or
    // the loudest one, when ≥ 3 σ).
    let mut picks: Vec<(EdofId, usize, f64, f64)> = Vec::new();
    for (e, &id) in edofs.iter().enumerate() {
        let mut best: Option<(f64, f64, usize)> = None;
        let mut loudest: Option<(f64, usize)> = None;
        for (c, cand) in cands.iter().enumerate() {
            let total: f64 = cand.norms.iter().sum();
            if total <= 0.0 {
                continue;
            }
            let share = cand.norms[e] / total;
            if cand.norms[e] >= 10.0 && best.is_none_or(|(s, ..)| share > s) {
                best = Some((share, cand.norms[e], c));
            }
            if loudest.is_none_or(|(s, _)| cand.norms[e] > s) {
                loudest = Some((cand.norms[e], c));
            }
        }
        let pick = best.or_else(|| {
            loudest.filter(|l| l.0 >= 3.0).map(|(snr, c)| {
                let total: f64 = cands[c].norms.iter().sum();
                (snr / total, snr, c)
            })
        });
        if let Some((share, snr, c)) = pick {
            picks.push((id, c, share, snr));
        }
    }
    let mut chosen: Vec<usize> = Vec::new();
    for &(_, c, ..) in &picks {
        if !chosen.contains(&c) {
            chosen.push(c);
        }
    }
    let axis_count = chosen.len();
    // Greedy D-optimal completion.
    let ridge = 1e-9;
    let mut info = DMatrix::<f64>::identity(p, p) * ridge;
    for &c in &chosen {
        info += &cands[c].info;
    }
    while chosen.len() < options.load_cases.max(axis_count) {
        let mut best: Option<(f64, usize)> = None;
        for (c, cand) in cands.iter().enumerate() {
            if chosen.contains(&c) {
                continue;
            }
            let Some(ld) = log_det(&(&info + &cand.info)) else {
                continue;
            };
            if best.is_none_or(|(b, _)| ld > b) {
                best = Some((ld, c));
            }
        }
        let Some((_, c)) = best else { break };
        info += &cands[c].info;
        chosen.push(c);
    }
    let log_det = log_det(&info).unwrap_or(f64::NEG_INFINITY);
    // Expected SE: the model's eDoFs from their joint information; an extra family eDoF (with
    // `full_family`) from the information of the model's eDoFs plus that one, i.e. its precision
    // if the structure search adds it.
    let own: Vec<usize> = (0..p)
        .filter(|&e| robot.stiffness(edofs[e].0, edofs[e].1).is_some())
        .collect();
    let expected: Vec<ExpectedSe> = edofs
        .iter()
        .enumerate()
        .map(|(e, &id)| {
            let mut set = own.clone();
            if !set.contains(&e) {
                set.push(e);
            }
            let rel = relative_se(&info, ridge, &set, e);
            ExpectedSe {
                id,
                label: edof_label(id),
                nominal_k: nominal[e],
                se_k: rel * nominal[e],
                relative: rel,
            }
        })
        .collect();
    // Only identifiable eDoFs keep their axis-by-axis case; a case that serves none of them
    // becomes a D-optimal one.
    let identifiable = |id: EdofId| expected.iter().any(|x| x.id == id && x.identifiable());
    let picks: Vec<_> = picks
        .into_iter()
        .filter(|(id, ..)| identifiable(*id))
        .collect();
    // Rows keep the selection order (axis-by-axis picks, then D-optimal); labels count the
    // cases that serve an identifiable eDoF (A01, A02, …) and the others (D01, …) separately.
    let order = chosen;
    let mut labels: Vec<String> = Vec::with_capacity(order.len());
    let (mut a, mut d) = (0, 0);
    for &c in &order {
        if picks.iter().any(|p| p.1 == c) {
            a += 1;
            labels.push(format!("A{a:02}"));
        } else {
            d += 1;
            labels.push(format!("D{d:02}"));
        }
    }
    let label_of = |i: usize| labels[i].clone();
    let axis_cases: Vec<AxisCase> = picks
        .iter()
        .map(|&(id, c, share, snr)| AxisCase {
            id,
            load_case: label_of(order.iter().position(|&k| k == c).unwrap_or(0)),
            share,
            snr,
        })
        .collect();
    let mut rows = Vec::new();
    for (i, &c) in order.iter().enumerate() {
        let served: Vec<String> = picks
            .iter()
            .filter(|p| p.1 == c)
            .map(|p| edof_label(p.0))
            .collect();
        let purpose = if served.is_empty() {
            format!("D-optimal; {}", cands[c].loading)
        } else {
            format!("axis-by-axis {}; {}", served.join(" "), cands[c].loading)
        };
        for r in &cands[c].rows {
            rows.push(MeasurementRow {
                load_case: label_of(i),
                purpose: Some(purpose.clone()),
                sigma_m: None,
                ..r.clone()
            });
        }
    }
    let expected_shifts = expected_shift_se(robot, &rows, options.noise_sigma_m)?;
    let force_n = match &options.load {
        LoadKind::Cable { .. } => options.max_force_n,
        LoadKind::DeadWeight { masses_kg } => {
            masses_kg.iter().copied().fold(0.0, f64::max) * robot.gravity.norm()
        }
    };
    Ok(Plan {
        rows,
        axis_cases,
        expected,
        expected_shifts,
        log_det,
        setup: PlanSetup {
            force_n,
            load: options.load.clone(),
            bracket_m: options.bracket_m,
            floor_z_m: obstacles.floor_z_m,
            table: obstacles.table,
            base_point_r0_m: base_point,
            configurations_drawn: drawn,
            configurations_kept: kept,
        },
    })
}

/// Expected standard error of every centre shift the calibration fits (joints with an x or y
/// eDoF in `robot`) if the campaign `rows` is measured with tracker noise `noise_sigma_m`:
/// the square root of the diagonal of `(JᵀWJ)⁻¹` at the nominal model, over the model's
/// compliances and those shifts together — the covariance the calibration reports (eq. 13–15
/// through [`crate::design`]), before any measurement.
pub fn expected_shift_se(
    robot: &Robot,
    rows: &[MeasurementRow],
    noise_sigma_m: f64,
) -> Result<Vec<ExpectedShiftSe>, CalibError> {
    let (ids, stiffness) = planned_edofs(robot, false);
    let joints: Vec<usize> = (1..=robot.joint_count())
        .filter(|&j| {
            ids.iter()
                .any(|&(site, axis)| site == EdofSite::Joint(j) && axis != Axis::Z)
        })
        .collect();
    if joints.is_empty() || rows.is_empty() {
        return Ok(Vec::new());
    }
    let rows: Vec<MeasurementRow> = rows
        .iter()
        .map(|r| MeasurementRow {
            sigma_m: Some(noise_sigma_m),
            ..r.clone()
        })
        .collect();
    let design = Design::build(robot, &rows, &ids, false)?;
    let idx: Vec<usize> = (0..ids.len()).collect();
    let compliances: Vec<f64> = stiffness.iter().map(|k| 1.0 / k).collect();
    let shifts: Vec<f64> = robot.joints.iter().map(|j| j.center_shift).collect();
    let covariance = unscaled_covariance(
        &design,
        &idx,
        &compliances,
        &shifts,
        &vec![true; idx.len()],
        joints.clone(),
    );
    Ok(joints
        .into_iter()
        .map(|j| ExpectedShiftSe {
            joint: j,
            nominal_m: shifts[j - 1],
            se_m: covariance
                .labels
                .iter()
                .position(|l| *l == Err(j))
                .map_or(f64::INFINITY, |p| covariance.cov[(p, p)].max(0.0).sqrt()),
        })
        .collect())
}

/// Lowest world height of the joint origins and the TCP (after forward kinematics).
pub fn lowest_point_z(robot: &Robot, data: &Data) -> f64 {
    (1..=robot.joint_count())
        .map(|i| data.link_frame(i).translation.vector.z)
        .fold(data.tcp_position().z, f64::min)
}

/// eDoFs to plan for and their nominal stiffness.
fn planned_edofs(robot: &Robot, full: bool) -> (Vec<EdofId>, Vec<f64>) {
    let own: Vec<(EdofId, f64)> = robot
        .edofs()
        .map(|e| ((e.site, e.axis), e.stiffness))
        .collect();
    if !full {
        return (
            own.iter().map(|e| e.0).collect(),
            own.iter().map(|e| e.1).collect(),
        );
    }
    let mut ks: Vec<f64> = own.iter().map(|e| e.1).collect();
    ks.sort_by(f64::total_cmp);
    let median = ks.get(ks.len() / 2).copied().unwrap_or(1e6);
    let mut ids: Vec<EdofId> = vec![(EdofSite::Base, Axis::X), (EdofSite::Base, Axis::Y)];
    for i in 1..=robot.joint_count() {
        for a in Axis::ALL {
            ids.push((EdofSite::Joint(i), a));
        }
    }
    let nominal = ids
        .iter()
        .map(|id| robot.stiffness(id.0, id.1).unwrap_or(median))
        .collect();
    (ids, nominal)
}
