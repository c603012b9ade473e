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

use crate::cell_config::{CellConfig, ControllerConfig, PartConfig, SensorConfig};
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
    /// `deflex_load::cell_for_robot` reads it).
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
            Maker::StaubliTx200 => CellConfig::default(),
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

/// Joint values (deg) that put the TCP of `robot` (with its tool) at `p` (world, m) pointing
/// down, trying a few seeds; `None` when none converges within the joint limits.
fn ik_down(robot: &Robot, p: &Vector3<f64>, seeds: &[[f64; 6]]) -> Option<[f64; 6]> {
    let target = Pose::from_parts((*p).into(), tool_down());
    let options = IkOptions {
        position_tolerance_m: 1e-9,
        orientation_tolerance_rad: 1e-9,
        ..IkOptions::default()
    };
    for seed in seeds {
        let seed_rad: Vec<f64> = seed.iter().map(|d| d.to_radians()).collect();
        if let Ok(solution) = robot.inverse_kinematics(&target, &seed_rad, &options) {
            let within = robot
                .joints
                .iter()
                .zip(&solution.q)
                .all(|(j, q)| match j.limits {
                    Some([lo, hi]) => *q >= lo && *q <= hi,
                    None => true,
                });
            if within {
                return Some(std::array::from_fn(|i| solution.q[i].to_degrees()));
            }
        }
    }
    None
}

/// Seeds for the tool-down IK: elbow-up postures around the robot.
fn seeds() -> Vec<[f64; 6]> {
    let mut out = Vec::new();
    for q1 in [0.0, 180.0, 90.0, -90.0] {
        for (q2, q3) in [
            (-90.0, 90.0),
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
/// * **part**: 0.45 of the reach in front of the base, 0.1 of it below the shoulder (for the
///   UR10e: 0.72 m in front, 20 mm above the mounting face: a sheet clamped in a frame on the
///   robot's table), tool pointing down ([`place_part_among`]).
pub fn ur_cell(robot: &Robot) -> Result<CellConfig, SimError> {
    let mut cell = CellConfig {
        controller: ControllerConfig {
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
    cell.part.tool_xyz_m = [0.0, 0.0, 0.150];
    cell.part.base_pivot_m = None;
    let mut with_tool = robot.clone();
    with_tool.tool = cell.tool();
    let (origin, seed) = place_part_among(&with_tool, &[0.45, 0.5, 0.4], &[-0.1, 0.0, -0.2])?;
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
