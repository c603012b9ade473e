//! Calibration and validation campaigns on the twin (SIMULATED), written in the measurement
//! format of `deflex_calibrate::measurements`.
//!
//! * [`run_campaign`]: a plan (load cases: configuration, load by cable tension or dead weight,
//!   points to measure, all named in the robot description's coordinates) → for each load case
//!   the tracker reads every point unloaded, the load is applied **to the plant**, the tracker
//!   reads the points again; the row's displacement is the difference of the two (averaged)
//!   readings, its `sigma_m` the tracker's 1σ for it, and the reported wrench is what the load
//!   cell measured (nominal load plus sensor noise). The points are the plant's material points
//!   (its geometry errors move them) and the tracker reports them through its registration to the
//!   robot base, with the registration error when `[cell.errors] tracker_registration` is on. The
//!   plant's hysteresis state carries over from one load case to the next, as on the real robot.
//! * [`validation_grid`]: a grid of TCP positions, tool pointing down, each loaded by dead
//!   weights ([`GridParams`]; the paper's 200 poses on a 0.6 × 0.6 m plane at z = 0.1 m, 600 N
//!   and 1100 N, Section 3.2, Figs. 10–13, are the TX200's defaults), as a plan.
//! * [`spiral`]: a spiral tracked at the tracker rate with a dead weight at the TCP
//!   ([`SpiralParams`]; Fig. 14 for the TX200). The spiral is tracked twice, unloaded and loaded;
//!   the displacement is the difference of the two tracked positions at each sample.

use crate::cell_config::CellConfig;
use crate::error::SimError;
use crate::plant::Plant;
use crate::profile::Maker;
use crate::tracker::LaserTracker;
use deflex_calibrate::measurements::{FileHeader, MeasurementRow, format_rows_with_header};
use deflex_model::spatial::pose_from_xyz_rpy;
use deflex_model::{IkOptions, Pose, Robot, Wrench};
use nalgebra::{Point3, Rotation3, Vector3};
use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;
use rand_distr::StandardNormal;

/// Most rows a campaign plan may have (a campaign file of about 0.2 GB).
pub const MAX_CAMPAIGN_ROWS: usize = 1_000_000;

/// The plant of a cell, built the way every campaign needs it.
fn cell_plant(config: &CellConfig) -> Result<(Robot, Plant), SimError> {
    let nominal = config.nominal_robot()?;
    let flange = config.flange(&nominal);
    let plant = Plant::new(&config.plant, &nominal, &flange, config.errors.geometry)?;
    Ok((nominal, plant))
}

/// The tracker's view of the robot base: the registration, with its error when on.
fn registration(config: &CellConfig) -> Pose {
    if config.errors.tracker_registration {
        pose_from_xyz_rpy(
            config.tracker.registration_error_xyz_m,
            config.tracker.registration_error_rpy,
        )
    } else {
        Pose::identity()
    }
}

/// Run a measurement campaign on the plant for the plan rows (rows of one load case must share
/// the configuration and the load). Output rows keep the plan's order.
pub fn run_campaign(
    config: &CellConfig,
    plan: &[MeasurementRow],
    seed: u64,
) -> Result<Vec<MeasurementRow>, SimError> {
    config.validate()?;
    if plan.len() > MAX_CAMPAIGN_ROWS {
        return Err(SimError::Path(format!(
            "the plan has {} rows; a simulated campaign takes at most {MAX_CAMPAIGN_ROWS}",
            plan.len()
        )));
    }
    let (_, mut plant) = cell_plant(config)?;
    let seen = registration(config);
    let (mut tracker, mut rng) = instruments(config, seed);
    let sigma = config.sensor.noise_sigma;
    let mut out = Vec::with_capacity(plan.len());
    let mut start = 0;
    while start < plan.len() {
        let case = &plan[start].load_case;
        let end = start
            + plan[start..]
                .iter()
                .take_while(|r| &r.load_case == case)
                .count();
        let rows = &plan[start..end];
        let first = &rows[0];
        if first.q_rad.len() != 6 {
            return Err(SimError::Path(format!(
                "load case {case}: the twin's robot has 6 joints, the plan gives {}",
                first.q_rad.len()
            )));
        }
        for r in rows {
            if r.q_rad != first.q_rad || r.wrench != first.wrench {
                return Err(SimError::Path(format!(
                    "load case {case}: all its rows must share the configuration and the load"
                )));
            }
            let finite = r.q_rad.iter().all(|v| v.is_finite() && v.abs() <= 100.0)
                && r.wrench.iter().all(|v| v.is_finite() && v.abs() <= 1e6)
                && r.point_m
                    .iter()
                    .chain(&r.load_point_m)
                    .all(|v| v.is_finite() && v.abs() <= 100.0);
            if !finite {
                return Err(SimError::Path(format!(
                    "load case {case}: joint values, wrench and points must be finite (|q| ≤ 100 rad, \
                     |w| ≤ 10⁶ N or N·m, |p| ≤ 100 m)"
                )));
            }
        }
        let mut q = [0.0; 6];
        q.copy_from_slice(&first.q_rad);
        plant.set_configuration(&q);
        let wrench = Wrench::from_row_slice(&first.wrench);
        let points: Vec<(Vector3<f64>, Vector3<f64>)> = rows
            .iter()
            .map(|r| {
                (
                    plant.material_point(r.point_link, &Vector3::from(r.point_m)),
                    plant.material_point(r.load_link, &Vector3::from(r.load_point_m)),
                )
            })
            .collect();
        let read = |tracker: &mut LaserTracker, p: &Vector3<f64>| {
            tracker.measure_static(&(seen * Point3::from(*p)).coords)
        };
        // Unloaded readings (the hysteresis of earlier cases may leave a small offset).
        let mut unloaded = Vec::with_capacity(rows.len());
        for (r, (p, a)) in rows.iter().zip(&points) {
            let at = plant.loaded_point(r.point_link, p, r.load_link, a, &Wrench::zeros());
            unloaded.push(read(&mut tracker, &at));
        }
        // The load cell's reading of the applied load.
        let mut measured_wrench = first.wrench;
        for (w, s) in measured_wrench.iter_mut().zip(sigma) {
            *w += s * rng.sample::<f64, _>(StandardNormal);
        }
        for ((r, (p, a)), (u, su)) in rows.iter().zip(&points).zip(unloaded) {
            let at = plant.loaded_point(r.point_link, p, r.load_link, a, &wrench);
            let (l, sl) = read(&mut tracker, &at);
            let disp = l - u;
            out.push(MeasurementRow {
                wrench: measured_wrench,
                point_m: [u.x, u.y, u.z],
                displacement_m: Some([disp.x, disp.y, disp.z]),
                sigma_m: Some((su * su + sl * sl).sqrt()),
                rotation_rad: None,
                ..r.clone()
            });
        }
        // Unload: the wrist reducers keep part of the lost motion.
        for (r, (p, a)) in rows.iter().zip(&points) {
            plant.loaded_point(r.point_link, p, r.load_link, a, &Wrench::zeros());
        }
        start = end;
    }
    Ok(out)
}

/// A campaign file's text: the `# SIMULATED` header naming what was measured and the robot the
/// twin played, then the rows in the measurement format. The robot lines (`# robot:`,
/// `# geometry:`, which `deflex_calibrate::stiffness` reads and checks) are those of `plan_header` when the
/// campaign measured a plan that names its robot (the point coordinates are the plan's), else
/// those of the twin's nominal robot (its cell's tool included).
pub fn campaign_text(
    config: &CellConfig,
    rows: &[MeasurementRow],
    what: &str,
    seed: u64,
    plan_header: Option<&FileHeader>,
) -> Result<String, SimError> {
    let note = format!(
        "SIMULATED deflex digital-twin campaign ({what}) of `{}`, seed {seed}: not a measurement",
        config.part.robot
    );
    let robot_lines = match plan_header {
        Some(header) if header.robot.is_some() && header.geometry.is_some() => header.clone(),
        _ => FileHeader::for_robot(&config.nominal_robot()?),
    };
    Ok(format_rows_with_header(&robot_lines, rows, &[&note]))
}

fn instruments(config: &CellConfig, seed: u64) -> (LaserTracker, ChaCha8Rng) {
    let mut tracker_rng = ChaCha8Rng::seed_from_u64(seed);
    tracker_rng.set_stream(3);
    let mut load_rng = ChaCha8Rng::seed_from_u64(seed);
    load_rng.set_stream(4);
    (LaserTracker::new(&config.tracker, tracker_rng), load_rng)
}

fn ik_down(
    robot: &Robot,
    rotation: &Rotation3<f64>,
    p: &Vector3<f64>,
    seed: &mut [f64],
    what: &str,
) -> Result<[f64; 6], SimError> {
    let target = Pose::from_parts((*p).into(), *rotation);
    let options = IkOptions {
        position_tolerance_m: 1e-10,
        orientation_tolerance_rad: 1e-10,
        ..IkOptions::default()
    };
    let solution = robot
        .inverse_kinematics(&target, seed, &options)
        .map_err(|source| SimError::Unreachable {
            what: what.to_string(),
            source,
        })?;
    seed.copy_from_slice(&solution.q);
    let mut q = [0.0; 6];
    q.copy_from_slice(&solution.q);
    Ok(q)
}

/// A validation grid: TCP positions on a horizontal rectangle, tool pointing down, each loaded
/// by dead weights along −z.
#[derive(Clone, Debug, PartialEq)]
pub struct GridParams {
    /// Centre of the rectangle (x, y, m, world).
    pub center_xy_m: [f64; 2],
    /// Size along x and y (m, each within (0, 5]).
    pub size_xy_m: [f64; 2],
    /// Height of the plane (m, world, |·| ≤ 5).
    pub height_m: f64,
    /// Positions along x and y (2–200 each, at most 10 000 in all).
    pub points_xy: [usize; 2],
    /// Dead weights (N, 1 to 10 values within (0, 10⁵]).
    pub loads_n: Vec<f64>,
}

impl GridParams {
    /// The paper's grid (Section 3.2, Figs. 10–13): 10 × 20 = 200 positions regularly spaced
    /// over a 0.6 × 0.6 m square at z = 0.1 m centred on (x, y) = (1.5, 0) m (the ISF work
    /// area), 600 N and 1100 N.
    pub fn paper() -> GridParams {
        GridParams {
            center_xy_m: [1.5, 0.0],
            size_xy_m: [0.6, 0.6],
            height_m: 0.1,
            points_xy: [10, 20],
            loads_n: vec![600.0, 1100.0],
        }
    }

    /// The default grid of a cell: the paper's for the TX200; for another robot, centred over
    /// its part, 0.283 m above it (as the paper's is above its part), a square scaled to the
    /// robot's reach (0.6 m for the TX200's 2.39 m with the tool), the same 10 × 20 positions,
    /// and dead weights of 0.48 and 0.87 times the cell's forming force level (600 and 1100 N
    /// against the TX200 cell's 1.26 kN).
    pub fn for_cell(config: &CellConfig) -> Result<GridParams, SimError> {
        let robot = config.nominal_robot()?;
        if Maker::of(&config.part.robot, &robot.name) == Maker::StaubliTx200 {
            return Ok(GridParams::paper());
        }
        let o = config.part.origin_mm.map(|v| v * 1e-3);
        let scale = cell_scale(&robot);
        let level = config.forming_force_level_n();
        Ok(GridParams {
            center_xy_m: [o[0], o[1]],
            size_xy_m: [0.6 * scale, 0.6 * scale],
            height_m: o[2] + 0.283 * scale,
            points_xy: [10, 20],
            loads_n: vec![round_load(0.48 * level), round_load(0.87 * level)],
        })
    }

    /// Positions along each axis for a step (m): `round(size/step) + 1`.
    pub fn points_for_step(size_m: f64, step_m: f64) -> Result<usize, SimError> {
        crate::range_check::bounded_open("grid step", step_m, 5.0, "m")?;
        let n = (size_m / step_m).round() + 1.0;
        if !(2.0..=200.0).contains(&n) {
            return Err(SimError::config(
                "grid step",
                format!("gives {n} positions along a {size_m} m side; 2 to 200 are allowed"),
            ));
        }
        Ok(n as usize)
    }

    /// Check the ranges; messages name the option.
    pub fn validate(&self) -> Result<(), SimError> {
        use crate::range_check::{all_bounded, bounded, bounded_open};
        all_bounded("grid center", &self.center_xy_m, 100.0, "m")?;
        for (i, v) in self.size_xy_m.iter().enumerate() {
            bounded_open(&format!("grid size[{i}]"), *v, 5.0, "m")?;
        }
        bounded("grid height", self.height_m, -5.0, 5.0, "m")?;
        for (i, n) in self.points_xy.iter().enumerate() {
            if !(2..=200).contains(n) {
                return Err(SimError::config(
                    &format!("grid points[{i}]"),
                    format!("must be within 2..200, got {n}"),
                ));
            }
        }
        if self.loads_n.is_empty() || self.loads_n.len() > 10 {
            return Err(SimError::config(
                "grid loads",
                format!("give 1 to 10 loads, got {}", self.loads_n.len()),
            ));
        }
        for (i, l) in self.loads_n.iter().enumerate() {
            bounded_open(&format!("grid loads[{i}]"), *l, 1e5, "N")?;
        }
        Ok(())
    }
}

/// Reach of the robot with its tool relative to the TX200 with its 0.2 m tool (2.394 m).
fn cell_scale(robot: &Robot) -> f64 {
    let reach: f64 = robot
        .joints
        .iter()
        .skip(1)
        .map(|j| j.placement.translation.vector.norm())
        .sum::<f64>()
        + robot.tool.translation.vector.norm();
    (reach / 2.394).clamp(0.1, 3.0)
}

fn round_load(n: f64) -> f64 {
    ((n / 10.0).round() * 10.0).max(10.0)
}

/// A validation grid as a plan ([`GridParams`]): the positions in serpentine order (close IK
/// seeds), each loaded by every dead weight at the TCP. Load cases are labelled
/// `grid<load>N-<index>`.
pub fn validation_grid(
    config: &CellConfig,
    params: &GridParams,
) -> Result<Vec<MeasurementRow>, SimError> {
    params.validate()?;
    let robot = config.nominal_robot()?;
    let seed_q = config.seed_q_rad();
    let rotation = robot
        .tcp_pose(&seed_q)
        .map_err(|e| SimError::config("part.seed_q_deg", e.to_string()))?
        .rotation;
    let mut seed = seed_q.to_vec();
    let [nx, ny] = params.points_xy;
    let [sx, sy] = params.size_xy_m;
    let [cx, cy] = params.center_xy_m;
    let mut rows = Vec::with_capacity(params.loads_n.len() * nx * ny);
    let mut index = 0;
    for iy in 0..ny {
        for k in 0..nx {
            // Serpentine order keeps IK seeds close.
            let ix = if iy % 2 == 0 { k } else { nx - 1 - k };
            let x = cx - sx / 2.0 + sx * ix as f64 / (nx - 1) as f64;
            let y = cy - sy / 2.0 + sy * iy as f64 / (ny - 1) as f64;
            let p = Vector3::new(x, y, params.height_m);
            let q = ik_down(
                &robot,
                &rotation,
                &p,
                &mut seed,
                &format!("grid pose ({x:.3}, {y:.3}, {:.3}) m", params.height_m),
            )?;
            index += 1;
            for &load in &params.loads_n {
                rows.push(MeasurementRow {
                    load_case: format!("grid{load:.0}N-{index:03}"),
                    q_rad: q.to_vec(),
                    wrench: [0.0, 0.0, -load, 0.0, 0.0, 0.0],
                    load_link: 6,
                    load_point_m: [p.x, p.y, p.z],
                    point: "TCP".into(),
                    point_link: 6,
                    point_m: [p.x, p.y, p.z],
                    displacement_m: None,
                    sigma_m: None,
                    rotation_rad: None,
                    purpose: Some(format!(
                        "validation grid {load:.0} N dead weight (Figs. 10-13)"
                    )),
                });
            }
        }
    }
    Ok(rows)
}

/// Spiral settings (Fig. 14).
#[derive(Clone, Debug, PartialEq)]
pub struct SpiralParams {
    /// Centre (m, world, |·| ≤ 100).
    pub center_m: [f64; 3],
    /// Initial radius (m, within (0, 5]).
    pub initial_radius_m: f64,
    /// Radius lost per turn (m, within (0, 1]).
    pub pitch_m: f64,
    /// Length (m, within (0, 100]).
    pub length_m: f64,
    /// Speed (m/s, within [0.001, 1]).
    pub speed_m_s: f64,
    /// Dead weight (N, along −z, within (0, 10⁵]).
    pub load_n: f64,
}

impl Default for SpiralParams {
    /// The paper's spiral: 0.25 m initial radius, 2.7 m long, 0.2 m above the ISF work area
    /// (z = 0.3 m), 600 N, 10 mm/s. The pitch is not published; 50 mm per turn.
    fn default() -> Self {
        SpiralParams {
            center_m: [1.5, 0.0, 0.3],
            initial_radius_m: 0.25,
            pitch_m: 0.05,
            length_m: 2.7,
            speed_m_s: 0.010,
            load_n: 600.0,
        }
    }
}

/// Most samples a spiral may take (about 28 h at 50 Hz… bounded to keep the rows in memory).
pub const MAX_SPIRAL_SAMPLES: f64 = 200_000.0;

impl SpiralParams {
    /// The default spiral of a cell: the paper's for the TX200; for another robot, centred over
    /// its part 0.483 m above it, every length scaled to the robot's reach like the grid, and a
    /// dead weight of 0.48 times the cell's forming force level.
    pub fn for_cell(config: &CellConfig) -> Result<SpiralParams, SimError> {
        let robot = config.nominal_robot()?;
        if Maker::of(&config.part.robot, &robot.name) == Maker::StaubliTx200 {
            return Ok(SpiralParams::default());
        }
        let o = config.part.origin_mm.map(|v| v * 1e-3);
        let scale = cell_scale(&robot);
        Ok(SpiralParams {
            center_m: [o[0], o[1], o[2] + 0.483 * scale],
            initial_radius_m: 0.25 * scale,
            pitch_m: 0.05 * scale,
            length_m: 2.7 * scale,
            speed_m_s: 0.010,
            load_n: round_load(0.48 * config.forming_force_level_n()),
        })
    }

    /// Check the ranges; messages name the option.
    pub fn validate(&self) -> Result<(), SimError> {
        use crate::range_check::{all_bounded, bounded, bounded_open};
        all_bounded("spiral center", &self.center_m, 100.0, "m")?;
        bounded_open("spiral radius", self.initial_radius_m, 5.0, "m")?;
        bounded_open("spiral pitch", self.pitch_m, 1.0, "m")?;
        bounded_open("spiral length", self.length_m, 100.0, "m")?;
        bounded("spiral speed", self.speed_m_s, 0.001, 1.0, "m/s")?;
        bounded_open("spiral load", self.load_n, 1e5, "N")?;
        let samples = self.length_m / self.speed_m_s * 50.0;
        if samples > MAX_SPIRAL_SAMPLES {
            return Err(SimError::config(
                "spiral length",
                format!(
                    "{samples:.0} tracker samples at this speed; at most {MAX_SPIRAL_SAMPLES:.0}"
                ),
            ));
        }
        Ok(())
    }
}

/// Track the spiral with the dead weight hanging at the TCP: one measurement row per tracker
/// sample (50 Hz: 13 500 rows for the paper's spiral). Each sample is tracked unloaded and
/// loaded; the row's displacement is the difference.
pub fn spiral(
    config: &CellConfig,
    params: &SpiralParams,
    seed: u64,
) -> Result<Vec<MeasurementRow>, SimError> {
    config.validate()?;
    params.validate()?;
    let (robot, mut plant) = cell_plant(config)?;
    let seen = registration(config);
    let (mut tracker, mut rng) = instruments(config, seed);
    let seed_q = config.seed_q_rad();
    let rotation = robot
        .tcp_pose(&seed_q)
        .map_err(|e| SimError::config("part.seed_q_deg", e.to_string()))?
        .rotation;
    let mut ik_seed = seed_q.to_vec();
    let dt = tracker.period_s();
    let samples = (params.length_m / params.speed_m_s / dt).floor() as usize + 1;
    let b = params.pitch_m / (2.0 * std::f64::consts::PI);
    let wrench = Wrench::new(0.0, 0.0, -params.load_n, 0.0, 0.0, 0.0);
    let center = Vector3::from(params.center_m);
    let (mut theta, mut travelled) = (0.0f64, 0.0f64);
    let mut rows = Vec::with_capacity(samples);
    for k in 0..samples {
        let target_length = k as f64 * dt * params.speed_m_s;
        // Advance θ along the arc length (small steps, exact enough at 0.2 mm per sample).
        while travelled < target_length {
            let r = params.initial_radius_m - b * theta;
            if r <= 0.0 {
                return Err(SimError::Path(
                    "spiral reaches its centre: shorten it".into(),
                ));
            }
            let dtheta = 1e-4 / r;
            travelled += (r * r + b * b).sqrt() * dtheta;
            theta += dtheta;
        }
        let r = params.initial_radius_m - b * theta;
        let p = center + Vector3::new(r * theta.cos(), r * theta.sin(), 0.0);
        let q = ik_down(
            &robot,
            &rotation,
            &p,
            &mut ik_seed,
            &format!("spiral sample {k}"),
        )?;
        plant.set_configuration(&q);
        let tcp = plant.material_point(6, &p);
        let unloaded = plant.loaded_point(6, &tcp, 6, &tcp, &Wrench::zeros());
        let loaded = plant.loaded_point(6, &tcp, 6, &tcp, &wrench);
        let before = tracker.measure(&(seen * Point3::from(unloaded)).coords);
        let after = tracker.measure(&(seen * Point3::from(loaded)).coords);
        let disp = after - before;
        let mut measured = [0.0, 0.0, -params.load_n, 0.0, 0.0, 0.0];
        for (w, s) in measured.iter_mut().zip(config.sensor.noise_sigma) {
            *w += s * rng.sample::<f64, _>(StandardNormal);
        }
        rows.push(MeasurementRow {
            load_case: format!("spiral-{k:05}"),
            q_rad: q.to_vec(),
            wrench: measured,
            load_link: 6,
            load_point_m: [p.x, p.y, p.z],
            point: "TCP".into(),
            point_link: 6,
            point_m: [before.x, before.y, before.z],
            displacement_m: Some([disp.x, disp.y, disp.z]),
            sigma_m: Some(tracker.sigma_at(&unloaded) * std::f64::consts::SQRT_2),
            rotation_rad: None,
            purpose: Some(format!("spiral (Fig. 14), t = {:.2} s", k as f64 * dt)),
        });
    }
    Ok(rows)
}
