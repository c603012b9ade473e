//! The twin plays any 6-joint robot: the cell of a robot (built-in name or robot file) with a
//! plant derived from the robot's own geometry and stiffness, a controller profile of its maker,
//! a sensor, a tool, a part position and a process sized for it.
//!
//! * **`tx200`** (and any robot whose name says TX200): the paper's cell,
//!   [`CellConfig::default`], with the documented plant of [`crate::plant`].
//! * **Universal Robots** (`ur10e`, `ur10`, …): see [`ur_cell`]: a UR on a table forming a thin
//!   soft sheet at ≈ 150–200 N (a UR10e is rated for 12.5 kg of payload), an ATI Axia80 sensor,
//!   the `servoj` streaming interface at 500 Hz with its 0.1 s look-ahead.
//! * **Any other robot**: [`derived_plant`] for the plant, an RSI-like controller (KUKA) or an
//!   EGM-like one (ABB) by name, else RSI-like; the part placed by [`place_part`] at about half
//!   the reach in front of the robot with the tool pointing down.
//!
//! **Derived plant** (documented perturbations of the robot's own description): main z-springs
//! 15 % softer than the file's (as the TX200 twin's main joints are softer than Table 1); any x/y
//! spring of the file also 15 % softer; every other x/y axis gets a secondary spring 8× the
//! joint's plant z-stiffness (the TX200 twin's are 7–15×); a joint the file leaves rigid gets
//! 1.5× the stiffness of the joint before it (J6 from J5, as on the TX200 twin); base tilt about
//! x0/y0 at 3× the J1 plant stiffness, about the robot file's `[base] pivot` (R0's origin by
//! default: robots described from their mounting face); the J2/J3 coupling ρ = 0.1; wrist lost motion ±0.15 mrad (±0.05 mrad for
//! UR's strain-wave gears), taken up over a torque of 1.3·10⁻³ × the J5 plant stiffness with a
//! hysteresis of a quarter of it; the same residual geometry errors as the TX200 twin.
//!
//! The description's stiffnesses of the non-TX200 built-in robots are placeholders; so the
//! derived plant is a plausible robot, not the maker's.

use crate::cell_config::{CellConfig, PartConfig, RobotControllerConfig, SensorConfig};
use crate::error::SimError;
use crate::plant::PlantConfig;
use crate::sheet::SheetConfig;
use deflex_model::{Axis, EdofSite, IkOptions, Pose, Robot};
use nalgebra::{Rotation3, Vector3};

/// Robot makers the twin has a controller profile for.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Maker {
    /// Stäubli TX200: the paper's cell.
    StaubliTx200,
    /// Universal Robots (`servoj` streaming).
    UniversalRobots,
    /// KUKA (RSI).
    Kuka,
    /// ABB (EGM).
    Abb,
    /// Anything else (RSI-like controller).
    Other,
}

impl Maker {
    /// From the robot spec (built-in name or file) and the robot's name.
    pub fn of(spec: &str, name: &str) -> Maker {
        let text = format!(
            "{} {}",
            spec.to_ascii_lowercase(),
            name.to_ascii_lowercase()
        );
        if text.contains("tx200") {
            Maker::StaubliTx200
        } else if text.contains("ur3")
            || text.contains("ur5")
            || text.contains("ur10")
            || text.contains("ur16")
            || text.contains("ur20")
            || text.contains("ur30")
            || text.contains("universal robots")
        {
            Maker::UniversalRobots
        } else if text.contains("kuka") || text.contains("kr ") || text.contains("kr-") {
            Maker::Kuka
        } else if text.contains("abb") || text.contains("irb") {
            Maker::Abb
        } else {
            Maker::Other
        }
    }
}

impl CellConfig {
    /// The cell of a built-in robot: see the [module](crate::profile) documentation. The cell of
    /// a robot file is [`CellConfig::for_robot_description`] (the twin reads no file:
    /// `crate::twin::cell_for_robot` reads it).
    pub fn for_robot(spec: &str) -> Result<CellConfig, SimError> {
        if spec.trim().is_empty() {
            return Err(SimError::config("part.robot", "must name a robot"));
        }
        if spec == "tx200" {
            return Ok(CellConfig::default());
        }
        let robot = deflex_model::builtin(spec).ok_or_else(|| SimError::NotBuiltin {
            spec: spec.to_string(),
        })?;
        Self::for_robot_description(spec, robot)
    }

    /// The cell of the robot `robot`, read from the robot file `spec` (or built in as `spec`).
    pub fn for_robot_description(spec: &str, robot: Robot) -> Result<CellConfig, SimError> {
        if spec.trim().is_empty() {
            return Err(SimError::config("part.robot", "must name a robot"));
        }
        crate::plant::check_six_joints(&robot)?;
        let maker = Maker::of(spec, &robot.name);
        let mut cell = match maker {
            Maker::StaubliTx200 => {
                let mut cell = CellConfig::default();
                (cell.part.tool_xyz_m, cell.part.tool_rpy) =
                    forming_tool(&robot, cell.part.tool_xyz_m);
                cell
            }
            Maker::UniversalRobots => ur_cell(&robot)?,
            Maker::Kuka | Maker::Abb | Maker::Other => generic_cell(&robot, maker)?,
        };
        cell.part.robot = spec.to_string();
        if deflex_model::builtin(spec).is_none() {
            cell.part.description = Some(robot);
        }
        cell.validate()?;
        Ok(cell)
    }
}

/// The tool of a robot's cell, flange → TCP (translation in m, roll-pitch-yaw in rad): the
/// robot model's own tool when it has one, so that the model, `deflex compensate` and the twin
/// use one tool; else the cell's forming tool `default_xyz_m` along the flange's z axis.
pub fn forming_tool(robot: &Robot, default_xyz_m: [f64; 3]) -> ([f64; 3], [f64; 3]) {
    if robot.has_tool() {
        (
            robot.tool.translation.vector.into(),
            deflex_model::spatial::rpy_from_rotation(&robot.tool.rotation),
        )
    } else {
        (default_xyz_m, [0.0; 3])
    }
}

/// The plant derived from a robot's own stiffness (see the module documentation).
pub fn derived_plant(robot: &Robot, strain_wave_wrist: bool) -> PlantConfig {
    let soft = 0.85;
    let mut plant = PlantConfig {
        center_shift_m: std::array::from_fn(|i| {
            robot.joints.get(i).map_or(0.0, |j| j.center_shift)
        }),
        base_pivot_m: robot.base_pivot.into(),
        ..PlantConfig::default()
    };
    let mut previous_z: f64 = 1e5;
    for i in 0..6 {
        let site = EdofSite::Joint(i + 1);
        let z = robot
            .stiffness(site, Axis::Z)
            .map(|k| soft * k)
            .unwrap_or(1.5 * previous_z);
        previous_z = z;
        let mut k = [8.0 * z, 8.0 * z, z];
        for (a, axis) in [Axis::X, Axis::Y].into_iter().enumerate() {
            if let Some(value) = robot.stiffness(site, axis) {
                k[a] = soft * value;
            }
        }
        plant.joint_stiffness[i] =
            k.map(|v| v.clamp(crate::plant::MIN_STIFFNESS, crate::plant::MAX_STIFFNESS));
    }
    let j1 = plant.joint_stiffness[0][2];
    plant.base_stiffness = [3.0 * j1, 3.0 * j1, 0.0];
    for (a, axis) in Axis::ALL.into_iter().enumerate() {
        if let Some(k) = robot.base_stiffness.get(axis) {
            plant.base_stiffness[a] = soft * k;
        }
    }
    let lost = if strain_wave_wrist { 0.05e-3 } else { 0.15e-3 };
    plant.wrist_lost_motion_rad = [lost; 3];
    plant.wrist_takeup_torque_nm = (1.3e-3 * plant.joint_stiffness[4][2]).clamp(0.1, 1e4);
    plant.wrist_hysteresis_nm = 0.25 * plant.wrist_takeup_torque_nm;
    plant
}

/// The tool pointing down (tool z along −world z, tool x along world x).
fn tool_down() -> Rotation3<f64> {
    Rotation3::from_axis_angle(&Vector3::x_axis(), std::f64::consts::PI)
}

/// Least height a forming pose must keep between the arm and the floor, and between the links
/// that reach over the table (the elbow, the wrist, the flange) and the part's plane (m).
pub const POSE_CLEARANCE_M: f64 = 0.05;

/// The floor of a robot: its base pivot when below R0 (a baseplate bolted to the floor, the
/// TX200's 0.642 m below its shoulder-height R0), else R0's mounting plane (world z, m).
pub fn floor_z_m(robot: &Robot) -> f64 {
    let pivot = robot.base * nalgebra::Point3::from(robot.base_pivot);
    pivot.z.min(robot.base.translation.vector.z)
}

/// How far the arm at `q` (rad) stays clear (m; negative: it dips in): the least of the heights
/// of the joint origins from the second on above the floor, and of the joint origins from the
/// third on (elbow, wrist) and the flange above the higher of the floor and `part_z_m` (the
/// shoulder sits at the base, away from the part).
pub fn pose_clearance_m(robot: &Robot, q: &[f64], part_z_m: f64) -> Result<f64, SimError> {
    let mut data = deflex_model::Data::new();
    robot
        .forward_kinematics(&mut data, q)
        .map_err(deflex_model::ModelError::from)?;
    let floor = floor_z_m(robot);
    let over_table = floor.max(part_z_m);
    let mut clearance = f64::INFINITY;
    for i in 2..=robot.joint_count() {
        let z = data.link_frame(i).translation.vector.z;
        let above = if i >= 3 { over_table } else { floor };
        clearance = clearance.min(z - above);
    }
    Ok(clearance.min(data.flange.translation.vector.z - over_table))
}

/// Joint values (deg) that put the TCP of `robot` (with its tool) at `p` (world, m) pointing
/// down with the arm clear of the floor and the part's plane ([`POSE_CLEARANCE_M`]), trying a
/// few seeds; `None` when none converges within the joint limits and the clearance.
fn ik_down(robot: &Robot, p: &Vector3<f64>, seeds: &[[f64; 6]]) -> Option<[f64; 6]> {
    let target = Pose::from_parts((*p).into(), tool_down());
    let options = IkOptions {
        position_tolerance_m: 1e-9,
        orientation_tolerance_rad: 1e-9,
        ..IkOptions::default()
    };
    for seed in seeds {
        let seed_rad: Vec<f64> = seed.iter().map(|d| d.to_radians()).collect();
        if let Ok(mut solution) = robot.inverse_kinematics(&target, &seed_rad, &options) {
            // The same pose with each joint nearest zero (a Newton solution may wrap by 2π).
            for q in solution.q.iter_mut() {
                *q -= std::f64::consts::TAU * (*q / std::f64::consts::TAU).round();
            }
            let within = robot
                .joints
                .iter()
                .zip(&solution.q)
                .all(|(j, q)| match j.limits {
                    Some([lo, hi]) => *q >= lo && *q <= hi,
                    None => true,
                });
            let clear =
                pose_clearance_m(robot, &solution.q, p.z).is_ok_and(|c| c >= POSE_CLEARANCE_M);
            if within && clear {
                return Some(std::array::from_fn(|i| solution.q[i].to_degrees()));
            }
        }
    }
    None
}

/// Seeds for the tool-down IK: elbow-up postures around the robot (UR-like arms: shoulder
/// lifted, elbow bent down towards the part).
fn seeds() -> Vec<[f64; 6]> {
    let mut out = Vec::new();
    for q1 in [0.0, 180.0, 90.0, -90.0] {
        for (q2, q3) in [
            (-90.0, 90.0),
            (-60.0, 100.0),
            (-45.0, 110.0),
            (-30.0, 120.0),
            (45.0, 90.0),
            (-45.0, 45.0),
            (60.0, 60.0),
            (-60.0, -60.0),
        ] {
            for q5 in [-90.0, 90.0, 45.0, -45.0] {
                out.push([q1, q2, q3, -90.0, q5, 0.0]);
                out.push([q1, q2, q3, 0.0, q5, 0.0]);
            }
        }
    }
    out
}

/// Horizontal reach estimate (m): the lengths of the placements after joint 1 plus the tool.
fn reach_m(robot: &Robot) -> f64 {
    robot
        .joints
        .iter()
        .skip(1)
        .map(|j| j.placement.translation.vector.norm())
        .sum::<f64>()
        + robot.tool.translation.vector.norm()
}

/// A part position for a robot: the TCP at a fraction of the reach in front of the shoulder,
/// tool pointing down, such that the part's corners (±30 mm, 20 mm deep) are reachable too.
/// Returns the origin (mm, R0) and the seed configuration (deg).
pub fn place_part(robot: &Robot) -> Result<([f64; 3], [f64; 6]), SimError> {
    place_part_among(
        robot,
        &[0.55, 0.5, 0.6, 0.45, 0.65, 0.4],
        &[-0.25, -0.15, -0.35, 0.0, -0.5],
    )
}

/// [`place_part`] trying the given fractions of the reach (horizontal distance from the base)
/// and heights below the shoulder (fractions of the reach), in order.
pub fn place_part_among(
    robot: &Robot,
    fractions: &[f64],
    heights: &[f64],
) -> Result<([f64; 3], [f64; 6]), SimError> {
    let reach = reach_m(robot);
    let shoulder = robot.base
        * robot.joints[0].placement
        * nalgebra::Point3::from(robot.joints[1].placement.translation.vector);
    let seeds = seeds();
    for &fraction in fractions {
        for &height in heights {
            for azimuth in [0.0f64, 180.0, 90.0, -90.0] {
                let (s, c) = azimuth.to_radians().sin_cos();
                let origin = Vector3::new(
                    robot.base.translation.vector.x + c * fraction * reach,
                    robot.base.translation.vector.y + s * fraction * reach,
                    shoulder.z + height * reach,
                );
                // The part (20 mm deep) must sit on something above the floor.
                if origin.z - 0.02 < floor_z_m(robot) + POSE_CLEARANCE_M {
                    continue;
                }
                let Some(q) = ik_down(robot, &origin, &seeds) else {
                    continue;
                };
                let corners = [
                    Vector3::new(0.03, 0.03, -0.02),
                    Vector3::new(-0.03, 0.03, -0.02),
                    Vector3::new(0.03, -0.03, -0.02),
                    Vector3::new(-0.03, -0.03, -0.02),
                ];
                if corners
                    .iter()
                    .all(|d| ik_down(robot, &(origin + d), &[q]).is_some())
                {
                    return Ok(([origin.x * 1e3, origin.y * 1e3, origin.z * 1e3], q));
                }
            }
        }
    }
    Err(SimError::config(
        "part.origin_mm",
        format!(
            "found no reachable part position for \"{}\" with the tool pointing down: set \
             [cell.part] origin_mm and seed_q_deg in the twin file",
            robot.name
        ),
    ))
}

/// The cell of a Universal Robots arm (documented for the UR10e):
///
/// * **controller**: e-Series `servoj` streaming at 500 Hz; 4 ms of transport delay (two
///   cycles); the `lookahead_time` of 0.1 s (UR script manual default; range 0.03–0.2 s);
///   joint servos ≈ 15 Hz to a correction; no interpolator filter beyond the look-ahead.
/// * **sensor**: an ATI Axia80-M20 (calibration range 0: Fx, Fy ±500 N, Fz ±900 N, Tx, Ty, Tz
///   ±20 N·m, from ATI's Axia80 manual), 0.1 N / 0.003 N·m of noise (an estimate), on a 25 mm
///   plate; a 0.15 m tool of 1.0 kg below it (10 mm ball).
/// * **process**: a 0.5 mm AA3003-H14 sheet (Rm ≈ 150 MPa), 10 mm ball: the Aerens level of
///   the paper's cone is ≈ 170 N, in the 100–300 N a 12.5 kg-payload arm can push without
///   stalling; the same cone as the paper.
/// * **part**: 0.45 of the reach in front of the base, 0.06 of it below the shoulder (for the
///   UR10e: 0.72 m in front, about 0.1 m above the mounting face: a sheet clamped in a frame on
///   the robot's table), tool pointing down, the arm at least [`POSE_CLEARANCE_M`] above the
///   mounting plane and the sheet ([`place_part_among`]; the elbow once sat 174 mm below the
///   mounting plane).
pub fn ur_cell(robot: &Robot) -> Result<CellConfig, SimError> {
    let mut cell = CellConfig {
        controller: RobotControllerConfig {
            rate_hz: 500.0,
            correction_delay_s: 0.004,
            correction_filter_s: 0.0,
            servo_bandwidth_hz: 15.0,
            lookahead_s: 0.1,
            max_correction_m: 0.005,
            max_correction_rad: 0.02,
            max_correction_speed_m_s: 0.05,
            max_correction_speed_rad_s: 0.2,
            rapid_feed_mm_s: 50.0,
        },
        sensor: SensorConfig {
            sensor_in_flange_xyz_m: [0.0, 0.0, 0.025],
            tool_mass_kg: 1.0,
            tool_com_in_sensor_m: [0.002, -0.001, 0.06],
            noise_sigma: [0.1, 0.1, 0.1, 0.003, 0.003, 0.003],
            bias: [1.3, -0.8, 2.1, 0.05, -0.04, 0.01],
            range: [500.0, 500.0, 900.0, 20.0, 20.0, 20.0],
            bias_drift_per_s: [0.001, -0.001, 0.002, 0.0001, -0.0001, 0.00003],
            tool_mass_error_kg: 0.05,
            ..SensorConfig::default()
        },
        sheet: SheetConfig {
            thickness_mm: 0.5,
            rm_mpa: 150.0,
            tool_diameter_mm: 10.0,
            contact_stiffness_n_mm: 800.0,
            ..SheetConfig::default()
        },
        plant: derived_plant(robot, true),
        ..CellConfig::default()
    };
    (cell.part.tool_xyz_m, cell.part.tool_rpy) = forming_tool(robot, [0.0, 0.0, 0.150]);
    cell.part.base_pivot_m = None;
    let mut with_tool = robot.clone();
    with_tool.tool = cell.tool();
    let (origin, seed) = place_part_among(
        &with_tool,
        &[0.45, 0.5, 0.4],
        &[-0.06, -0.04, -0.02, 0.0, 0.05],
    )?;
    cell.part = PartConfig {
        origin_mm: origin,
        seed_q_deg: seed,
        ..cell.part
    };
    cell.tracker.position_m = [
        origin[0] * 1e-3 + 1.5,
        origin[1] * 1e-3 - 1.5,
        origin[2] * 1e-3 + 0.5,
    ];
    Ok(cell)
}

/// The cell of any other robot: the TX200 cell's sensor, tool and sheet, the derived plant, a
/// controller profile by maker (KUKA RSI: 250 Hz, 12 ms delay; ABB EGM: 250 Hz, 12 ms delay and
/// a 20 ms look-ahead filter; others like RSI), the part placed by [`place_part`].
pub fn generic_cell(robot: &Robot, maker: Maker) -> Result<CellConfig, SimError> {
    let mut cell = CellConfig {
        plant: derived_plant(robot, false),
        ..CellConfig::default()
    };
    (cell.part.tool_xyz_m, cell.part.tool_rpy) = forming_tool(robot, cell.part.tool_xyz_m);
    cell.part.base_pivot_m = None;
    cell.controller.correction_delay_s = 0.012;
    cell.controller.correction_filter_s = 0.0;
    if maker == Maker::Abb {
        cell.controller.lookahead_s = 0.020;
    }
    let mut with_tool = robot.clone();
    with_tool.tool = cell.tool();
    let (origin, seed) = place_part(&with_tool)?;
    cell.part.origin_mm = origin;
    cell.part.seed_q_deg = seed;
    cell.tracker.position_m = [
        origin[0] * 1e-3 + 1.5,
        origin[1] * 1e-3 - 1.5,
        origin[2] * 1e-3 + 0.5,
    ];
    Ok(cell)
}

/// A robot's twin cell as `deflex compensate`, `deflex sim` and `deflex demo` use it: where the
/// part is, the seed configuration, the tool, the sheet and its force level, and how far the
/// arm stays from the floor and the part's plane at the seed. Printed by `deflex sim robot` and
/// `deflex model show` (`Display`, and [`CellSummary::to_json`] with `--json`).
#[derive(Clone, Debug, PartialEq)]
pub struct CellSummary {
    /// The robot (built-in name or file).
    pub robot: String,
    /// Part frame origin in R0 (mm); axes parallel to R0's.
    pub part_origin_mm: [f64; 3],
    /// Seed configuration near the part origin (deg): the IK seed of the cell's paths.
    pub seed_q_deg: [f64; 6],
    /// The forming pose (deg): the TCP at the part origin with the seed's tool orientation, by
    /// inverse kinematics from the seed.
    pub forming_q_deg: [f64; 6],
    /// The tool, flange → TCP (m).
    pub tool_xyz_m: [f64; 3],
    /// Sheet thickness (mm), tensile strength (MPa), tool ball diameter (mm).
    pub sheet: [f64; 3],
    /// The forming force level of the paper's cone on this sheet (N).
    pub forming_force_n: f64,
    /// Lowest joint origin (after the first) or flange above the higher of the floor and the
    /// part's plane in the forming pose (m).
    pub clearance_m: f64,
    /// The floor (world z, m).
    pub floor_z_m: f64,
}

impl CellConfig {
    /// The cell's summary (see [`CellSummary`]).
    pub fn summary(&self) -> Result<CellSummary, SimError> {
        let robot = self.nominal_robot()?;
        let part_z = self.part.origin_mm[2] * 1e-3;
        let seed = self.seed_q_rad();
        let rotation = robot
            .tcp_pose(&seed)
            .map_err(deflex_model::ModelError::from)?
            .rotation;
        let target = Pose::from_parts(self.part_frame().translation, rotation);
        let forming = robot
            .inverse_kinematics(&target, &seed, &IkOptions::default())
            .map_err(|source| SimError::Unreachable {
                what: "part origin".into(),
                source,
            })?
            .q;
        Ok(CellSummary {
            forming_q_deg: std::array::from_fn(|i| forming[i].to_degrees()),
            robot: self.part.robot.clone(),
            part_origin_mm: self.part.origin_mm,
            seed_q_deg: self.part.seed_q_deg,
            tool_xyz_m: self.part.tool_xyz_m,
            sheet: [
                self.sheet.thickness_mm,
                self.sheet.rm_mpa,
                self.sheet.tool_diameter_mm,
            ],
            forming_force_n: self.forming_force_level_n(),
            clearance_m: pose_clearance_m(&robot, &forming, part_z)?,
            floor_z_m: floor_z_m(&robot),
        })
    }
}

impl CellSummary {
    /// SI JSON (`part_origin_m`, `seed_q_rad`, …).
    pub fn to_json(&self) -> serde_json::Value {
        serde_json::json!({
            "robot": self.robot,
            "part_origin_m": self.part_origin_mm.map(|v| v * 1e-3),
            "seed_q_rad": self.seed_q_deg.map(f64::to_radians),
            "forming_q_rad": self.forming_q_deg.map(f64::to_radians),
            "tool_xyz_m": self.tool_xyz_m,
            "sheet_thickness_m": self.sheet[0] * 1e-3,
            "sheet_rm_Pa": self.sheet[1] * 1e6,
            "tool_ball_diameter_m": self.sheet[2] * 1e-3,
            "forming_force_N": self.forming_force_n,
            "forming_pose_clearance_m": self.clearance_m,
            "floor_z_m": self.floor_z_m,
        })
    }
}

impl std::fmt::Display for CellSummary {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        let o = self.part_origin_mm;
        let q = self.seed_q_deg;
        writeln!(
            f,
            "twin cell of {} (SIMULATED; deflex compensate, sim and demo use it):",
            self.robot
        )?;
        writeln!(
            f,
            "  part frame origin (mm, R0 axes): {:.4}, {:.4}, {:.4}   (--part-xyz-mm)",
            o[0], o[1], o[2]
        )?;
        writeln!(
            f,
            "  seed configuration (deg): {:.6}, {:.6}, {:.6}, {:.6}, {:.6}, {:.6}   (--seed-deg)",
            q[0], q[1], q[2], q[3], q[4], q[5]
        )?;
        let q = self.forming_q_deg;
        writeln!(
            f,
            "  forming pose, TCP at the part origin (deg): {:.2}, {:.2}, {:.2}, {:.2}, {:.2}, {:.2}",
            q[0], q[1], q[2], q[3], q[4], q[5]
        )?;
        let t = self.tool_xyz_m;
        writeln!(
            f,
            "  tool, flange → TCP (mm): {:.4}, {:.4}, {:.4}   (the tool compensate, sim, cell and demo use: the robot model's own when it has one)",
            t[0] * 1e3,
            t[1] * 1e3,
            t[2] * 1e3
        )?;
        writeln!(
            f,
            "  sheet: {} mm, Rm {} MPa, {} mm ball; forming force level {:.0} N",
            self.sheet[0], self.sheet[1], self.sheet[2], self.forming_force_n
        )?;
        write!(
            f,
            "  in the forming pose the arm is {:.0} mm above the higher of the floor (z {:.0} mm) and the part's plane",
            self.clearance_m * 1e3,
            self.floor_z_m * 1e3
        )
    }
}
