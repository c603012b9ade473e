//! The cell configuration: robot controller, F/T sensor, laser tracker, true robot (plant),
//! process (sheet or fixture), part placement and the error sources of a real cell.
//! `CellConfig::default()` is the paper's cell (Johra et al. 2022, Section 4) with a real tool on
//! the TX200; [`CellConfig::for_robot`] gives the cell of another robot ([`crate::profile`]).
//! Every value can be overridden from TOML, on top of the chosen robot's cell:
//!
//! ```toml
//! [cell.controller]
//! rate_hz = 250.0
//! correction_delay_s = 0.008
//! [cell.sensor]
//! rate_hz = 1000.0
//! tool_mass_kg = 3.2
//! [cell.sheet]
//! rm_mpa = 300.0
//! [cell.errors]
//! servo = false
//! ```
//!
//! Units are SI unless a field name says otherwise (`_mm`, `_deg`, `_mpa`). Every number is
//! checked at load: NaN and infinities are refused, and so are magnitudes outside the documented
//! range of each field (the message names the field and the range).
//!
//! A correction controller may legitimately read the controller section and the *nominal*
//! mounting and tool of the sensor section (what a real integrator knows from drawings and
//! datasheets); it must never read `plant`, `sheet`, `process` or the `*_error*` fields, which
//! are the hidden truth of the twin.

use crate::error::SimError;
use crate::plant::PlantConfig;
use crate::sheet::SheetConfig;
use deflex_model::Pose;
use deflex_model::spatial::pose_from_xyz_rpy;
use serde::{Deserialize, Serialize};

/// The emulated robot controller (Stäubli CS8 with Alter, KUKA KRC with RSI, a UR with
/// `servoj`, an ABB with EGM): interpolation, and the path the external correction takes to the
/// drives (`[cell.controller]`; not the correction law's `deflex_control::ControllerConfig`).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct RobotControllerConfig {
    /// Interpolation rate (Hz), 10–10 000. The CS8 runs at 250 Hz (paper, Section 4.2).
    pub rate_hz: f64,
    /// Transport delay between `set_correction` and the start of its effect (s, 0–1). Alter and
    /// RSI apply a correction one to three cycles after reception; 8 ms = 2 cycles at 250 Hz.
    pub correction_delay_s: f64,
    /// Time constant of the first-order filter of the interpolator on the correction (s, 0–1).
    pub correction_filter_s: f64,
    /// Bandwidth of the joint servo loops as seen by an external correction (Hz, 0 = ideal,
    /// else 0.5 to rate/4): a second-order response with damping 0.7. The nominal path is
    /// feed-forwarded by the interpolator and tracked exactly; a correction is not. Large arms
    /// close their position loops at roughly 5–20 Hz. Applied when `[cell.errors] servo` is on.
    pub servo_bandwidth_hz: f64,
    /// Look-ahead of the controller's streaming interface (s, 0–1): UR's `servoj` smooths the
    /// stream over `lookahead_time` (0.03–0.2 s, default 0.1 s, UR script manual), ABB EGM
    /// filters its corrections; modelled as a moving average over this time. 0 for Alter/RSI.
    /// Applied when `[cell.errors] servo` is on.
    pub lookahead_s: f64,
    /// Largest translation correction (m, norm, ≤ 0.1).
    pub max_correction_m: f64,
    /// Largest rotation correction (rad, norm, ≤ 0.5).
    pub max_correction_rad: f64,
    /// Largest translation correction speed (m/s, norm, ≤ 1).
    pub max_correction_speed_m_s: f64,
    /// Largest rotation correction speed (rad/s, norm, ≤ 10).
    pub max_correction_speed_rad_s: f64,
    /// Feed rate of rapid (G0) moves (mm/s, 0.1–2000).
    pub rapid_feed_mm_s: f64,
}

impl Default for RobotControllerConfig {
    /// A Stäubli CS8 with Alter (the paper's TX200).
    fn default() -> Self {
        RobotControllerConfig {
            rate_hz: 250.0,
            correction_delay_s: 0.008,
            correction_filter_s: 0.010,
            servo_bandwidth_hz: 10.0,
            lookahead_s: 0.0,
            max_correction_m: 0.010,
            max_correction_rad: 0.02,
            max_correction_speed_m_s: 0.050,
            max_correction_speed_rad_s: 0.2,
            rapid_feed_mm_s: 50.0,
        }
    }
}

/// 6-axis force/torque sensor between flange and tool. Defaults: ATI Omega160 with the
/// SI-1500-240 calibration (full scale Fx, Fy ±1500 N, Fz ±3750 N, Tx, Ty, Tz ±240 N·m, as listed
/// in ATI's Omega160 datasheet next to SI-1000-120 = [1000 1000 2500 120 120 120] and
/// SI-2500-400 = [2500 2500 6250 400 400 400]); resolution about 1/4 N and 1/40 N·m (Net F/T
/// Omega160 datasheet), used here as the 1σ noise. The paper's load cell is an Omega160 read by
/// two NI 9215 modules at 100 Hz; the twin samples at 1 kHz by default (an ATI Net F/T streams
/// up to 7 kHz) so a controller can average or decimate as it likes.
///
/// `sensor_in_flange_*`, `tool_mass_kg` and `tool_com_in_sensor_m` are the **nominal** values
/// (drawings, datasheets): what a controller is told. The true sensor sits at the nominal pose
/// plus `mounting_error_*` and the true tool differs by `tool_*_error*` when the corresponding
/// `[cell.errors]` switches are on.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct SensorConfig {
    /// Sample rate (Hz), 100 to 7000.
    pub rate_hz: f64,
    /// Nominal sensor frame origin in the flange frame (m, |·| ≤ 2). Default: on a 30 mm
    /// adapter plate on the flange, the tool below it.
    pub sensor_in_flange_xyz_m: [f64; 3],
    /// Nominal sensor frame orientation in the flange frame (roll, pitch, yaw, rad, |·| ≤ 2π).
    pub sensor_in_flange_rpy: [f64; 3],
    /// Nominal mass of everything below the sensor's sensing plane: tool holder, punch (kg,
    /// 0–1000).
    pub tool_mass_kg: f64,
    /// Nominal centre of mass of that tool in the sensor frame (m, |·| ≤ 2).
    pub tool_com_in_sensor_m: [f64; 3],
    /// Gaussian noise, 1σ, per channel `[Fx, Fy, Fz, Tx, Ty, Tz]` (N, N·m, 0–1000). Applied when
    /// `[cell.errors] sensor_noise` is on.
    pub noise_sigma: [f64; 6],
    /// Constant offset of the unloaded sensor (N, N·m, |·| ≤ 10⁴): what a tare removes.
    pub bias: [f64; 6],
    /// Saturation limits ± per channel (N, N·m, 0–10⁶).
    pub range: [f64; 6],
    /// Gravity (m/s², 0–30), along −z of the world.
    pub gravity_m_s2: f64,
    /// Gain error per channel (relative, |·| ≤ 0.5): the reading is (1 + g) times the load.
    /// Default ±1 % (ATI quotes a measurement uncertainty of about 1–1.5 % of full scale for its
    /// calibrations at 95 % confidence). Applied when `[cell.errors] sensor_gain` is on.
    pub gain_error: [f64; 6],
    /// Drift of the bias with the sensor's warm-up (N/s, N·m/s, |·| ≤ 10): linear over the
    /// run. Default about 4 N of Fz over the 500 s cone (an estimate: strain-gauge sensors drift
    /// with temperature, and a tool heated by forming friction warms the sensor by a few kelvin).
    /// Applied when `[cell.errors] bias_drift` is on.
    pub bias_drift_per_s: [f64; 6],
    /// True sensor origin minus the nominal one, flange frame (m, |·| ≤ 0.05). Default about
    /// 1 mm (machining and assembly of the adapter). Applied when `[cell.errors] mounting` is on.
    pub mounting_error_xyz_m: [f64; 3],
    /// True sensor orientation relative to the nominal one (roll, pitch, yaw, rad, |·| ≤ 0.1).
    /// Default 0.5° about the tool axis (the dowel-pin clocking of the adapter) and 0.1° of tilt.
    /// Applied when `[cell.errors] mounting` is on.
    pub mounting_error_rpy: [f64; 3],
    /// True tool mass minus the nominal one (kg, |·| ≤ 10). Default +0.15 kg (hoses, screws,
    /// lubricant not on the drawing). Applied when `[cell.errors] tool_load` is on.
    pub tool_mass_error_kg: f64,
    /// True tool centre of mass minus the nominal one, sensor frame (m, |·| ≤ 0.1). Default
    /// about 5 mm. Applied when `[cell.errors] tool_load` is on.
    pub tool_com_error_m: [f64; 3],
}

impl Default for SensorConfig {
    fn default() -> Self {
        SensorConfig {
            rate_hz: 1000.0,
            sensor_in_flange_xyz_m: [0.0, 0.0, 0.030],
            sensor_in_flange_rpy: [0.0, 0.0, 0.0],
            tool_mass_kg: 3.2,
            tool_com_in_sensor_m: [0.003, -0.002, 0.075],
            noise_sigma: [0.25, 0.25, 0.25, 0.025, 0.025, 0.025],
            bias: [4.1, -2.7, 6.3, 0.21, -0.17, 0.05],
            range: [1500.0, 1500.0, 3750.0, 240.0, 240.0, 240.0],
            gravity_m_s2: 9.80665,
            gain_error: [0.010, -0.008, 0.012, -0.010, 0.008, 0.005],
            bias_drift_per_s: [0.004, -0.003, 0.008, 0.0004, -0.0003, 0.0001],
            mounting_error_xyz_m: [0.6e-3, -0.4e-3, 0.8e-3],
            mounting_error_rpy: [0.0015, -0.001, 0.0087],
            tool_mass_error_kg: 0.15,
            tool_com_error_m: [0.003, 0.002, 0.004],
        }
    }
}

/// Laser tracker (API Radian class).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct TrackerConfig {
    /// Output rate (Hz), at most 50 in this twin (what the paper logged).
    pub rate_hz: f64,
    /// Tracker head position in the world frame (m, |·| ≤ 100).
    pub position_m: [f64; 3],
    /// Distance-independent noise, 1σ per axis (m, 0–0.01). API's Radian lists ±(10 µm +
    /// 5 µm/m); the twin uses that envelope as 1σ, which is pessimistic.
    pub sigma_const_m: f64,
    /// Distance-proportional noise, 1σ per axis per metre of range (m/m, 0–0.01).
    pub sigma_per_m: f64,
    /// Samples averaged per static reading in a campaign (1–1000). Default 1: the ±(10 µm +
    /// 5 µm/m) specification is taken as the uncertainty of a reading as delivered, since
    /// averaging removes only the white part of a real tracker's error.
    pub samples_per_reading: u32,
    /// Error of the tracker → robot-base registration, translation (m, |·| ≤ 0.01). Default
    /// about 20 µm: a best fit of a handful of reference points measured to the tracker's
    /// accuracy. Applied in campaigns when `[cell.errors] tracker_registration` is on.
    pub registration_error_xyz_m: [f64; 3],
    /// Registration error, rotation (roll, pitch, yaw, rad, |·| ≤ 0.01). Default about 20 µrad
    /// (20 µm over the 1 m spread of the reference points).
    pub registration_error_rpy: [f64; 3],
}

impl Default for TrackerConfig {
    fn default() -> Self {
        TrackerConfig {
            rate_hz: 50.0,
            position_m: [2.8, -1.6, 0.3],
            sigma_const_m: 10e-6,
            sigma_per_m: 5e-6,
            samples_per_reading: 1,
            registration_error_xyz_m: [15e-6, -12e-6, 20e-6],
            registration_error_rpy: [20e-6, -15e-6, 25e-6],
        }
    }
}

/// Where the part is, which robot holds the tool, and the tool.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct PartConfig {
    /// Robot (built-in name or robot file) whose description gives the nominal kinematics; the
    /// plant is derived from the same description.
    pub robot: String,
    /// Origin of the part frame R_p in R0 (mm, |·| ≤ 10⁵): the paper's [1500 0 −183].
    pub origin_mm: [f64; 3],
    /// Joint configuration near the part origin (deg, |·| ≤ 720), the IK seed: the paper's
    /// [0 49.7 89.3 0 41 0].
    pub seed_q_deg: [f64; 6],
    /// The tool, flange → TCP (the ball centre): translation (m, |·| ≤ 2). Replaces the robot
    /// file's tool. Default for the TX200: 0.2 m along the flange axis (a forming tool of a
    /// 15 mm ball on a 185 mm shank below the sensor and its adapter), whereas the built-in
    /// `tx200` has its TCP at the flange.
    pub tool_xyz_m: [f64; 3],
    /// The tool's orientation (roll, pitch, yaw, rad).
    pub tool_rpy: [f64; 3],
    /// Where the baseplate tilts, in R0 (m, |·| ≤ 5), as the model is told it (the robot's
    /// datasheet: the TX200's baseplate is 0.642 m below its shoulder-height R0); absent: the
    /// robot file's `[base] pivot`.
    pub base_pivot_m: Option<[f64; 3]>,
    /// The description of `robot` when it names a robot file (not a built-in robot): read by
    /// the caller, since the twin reads no file (`crate::twin::cell_for_robot`). Not part of
    /// the TOML.
    #[serde(skip)]
    pub description: Option<deflex_model::Robot>,
}

impl Default for PartConfig {
    fn default() -> Self {
        PartConfig {
            robot: "tx200".into(),
            origin_mm: [1500.0, 0.0, -183.0],
            seed_q_deg: deflex_model::TX200_FORMING_Q_DEG,
            tool_xyz_m: [0.0, 0.0, 0.200],
            tool_rpy: [0.0; 3],
            base_pivot_m: Some([0.0, 0.0, -0.642]),
            description: None,
        }
    }
}

/// Which process the tool meets.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum ProcessKind {
    /// Incremental sheet forming ([`crate::sheet`]).
    #[default]
    Sheet,
    /// Pressing on a stiff fixture ([`crate::fixture`]): a plunge, a press fit, a friction-stir
    /// plunge.
    Fixture,
    /// A force set along the path ([`crate::fixture::PrescribedForce`]): force-controlled
    /// forming, constant-pressure finishing, a press fit. The force is ramped over the first
    /// [`ProcessConfig::prescribed_ramp_mm`] of travel in contact to
    /// [`ProcessConfig::prescribed_force_n`] and held, whatever the depth the tool reaches.
    Prescribed,
}

/// The process: a sheet to form or a fixture to press on.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct ProcessConfig {
    /// `sheet` (default) or `fixture`.
    pub kind: ProcessKind,
    /// Contact stiffness of the fixture and workpiece under the tool (N/m, 10⁴–10⁹); with
    /// `prescribed`, the stiffness of the surface until the prescribed force is reached.
    pub fixture_stiffness_n_m: f64,
    /// `prescribed`: the force held along the path (N, 1–20 000).
    pub prescribed_force_n: f64,
    /// `prescribed`: travel in contact over which the force is ramped up (mm, 0–10 000).
    pub prescribed_ramp_mm: f64,
}

impl Default for ProcessConfig {
    fn default() -> Self {
        ProcessConfig {
            kind: ProcessKind::Sheet,
            fixture_stiffness_n_m: 1e7,
            prescribed_force_n: 1000.0,
            prescribed_ramp_mm: 30.0,
        }
    }
}

/// The error sources of a real cell, each on by default (their levels and sources are
/// documented with their fields). Switching one off gives the ideal version of that part.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct ErrorSources {
    /// Residual joint offsets and link-length errors of the calibrated robot
    /// (`plant.joint_offset_error_rad`, `plant.link_error_m`, `plant.tool_error_m`).
    pub geometry: bool,
    /// Servo bandwidth and look-ahead on the correction path (`controller.servo_bandwidth_hz`,
    /// `controller.lookahead_s`); the transport delay and the interpolator filter are always on.
    pub servo: bool,
    /// F/T gain error (`sensor.gain_error`).
    pub sensor_gain: bool,
    /// Temperature drift of the F/T bias (`sensor.bias_drift_per_s`).
    pub bias_drift: bool,
    /// F/T noise (`sensor.noise_sigma`).
    pub sensor_noise: bool,
    /// Sensor mounting differs from the nominal one the controller is told
    /// (`sensor.mounting_error_*`).
    pub mounting: bool,
    /// Tool mass and centre of mass differ from the nominal ones the controller is told
    /// (`sensor.tool_mass_error_kg`, `sensor.tool_com_error_m`).
    pub tool_load: bool,
    /// Tracker registration error in campaigns (`tracker.registration_error_*`).
    pub tracker_registration: bool,
}

impl Default for ErrorSources {
    fn default() -> Self {
        ErrorSources::all(true)
    }
}

impl ErrorSources {
    /// Every source on (`true`) or off.
    pub fn all(on: bool) -> ErrorSources {
        ErrorSources {
            geometry: on,
            servo: on,
            sensor_gain: on,
            bias_drift: on,
            sensor_noise: on,
            mounting: on,
            tool_load: on,
            tracker_registration: on,
        }
    }

    /// `(name, on)` for tables.
    pub fn list(&self) -> [(&'static str, bool); 8] {
        [
            ("geometry", self.geometry),
            ("servo", self.servo),
            ("sensor_gain", self.sensor_gain),
            ("bias_drift", self.bias_drift),
            ("sensor_noise", self.sensor_noise),
            ("mounting", self.mounting),
            ("tool_load", self.tool_load),
            ("tracker_registration", self.tracker_registration),
        ]
    }
}

/// What is recorded.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct LogConfig {
    /// Rate of the stored log (Hz, 0.1–1000, at most the controller rate); the summary
    /// statistics use every controller cycle. A run stores at most [`MAX_LOG_ROWS`] rows.
    pub rate_hz: f64,
}

impl Default for LogConfig {
    fn default() -> Self {
        LogConfig { rate_hz: 50.0 }
    }
}

/// Longest simulated run (s): 4 h, about 3.6 million cycles at 250 Hz.
pub const MAX_RUN_S: f64 = 4.0 * 3600.0;
/// Most rows a forming log stores (about 0.4 GB of memory at most).
pub const MAX_LOG_ROWS: f64 = 1.0e6;

/// The twin's cell TOML document: its settings under `[cell]` (typed first pass of
/// [`CellConfig::from_toml_str_with`]).
#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct TwinCellToml {
    #[serde(default)]
    cell: CellConfig,
}

/// The whole simulated cell. `Default` is the paper's cell.
#[derive(Clone, Debug, PartialEq, Default, Serialize, Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct CellConfig {
    /// Robot controller emulation.
    pub controller: RobotControllerConfig,
    /// Force/torque sensor.
    pub sensor: SensorConfig,
    /// Laser tracker.
    pub tracker: TrackerConfig,
    /// Part placement, robot and tool.
    pub part: PartConfig,
    /// The true robot (hidden from controllers and calibration).
    pub plant: PlantConfig,
    /// The sheet and forming law (hidden from controllers).
    pub sheet: SheetConfig,
    /// Sheet forming or a stiff fixture (hidden from controllers).
    pub process: ProcessConfig,
    /// The error sources of a real cell, each switchable.
    pub errors: ErrorSources,
    /// Logging.
    pub log: LogConfig,
}

impl CellConfig {
    /// Parse a TOML text whose settings live under `[cell]` / `[cell.<section>]`, on top of the
    /// cell of the built-in robot it names in `[cell.part] robot` (default: the paper's TX200
    /// cell).
    pub fn from_toml_str(text: &str) -> Result<CellConfig, SimError> {
        Self::from_toml_str_for(text, None)
    }

    /// [`CellConfig::from_toml_str`] for a built-in robot chosen outside the file (`--robot`),
    /// which wins over the file's `[cell.part] robot`.
    pub fn from_toml_str_for(text: &str, robot: Option<&str>) -> Result<CellConfig, SimError> {
        Self::from_toml_str_with(text, robot, &|spec| {
            Err(SimError::NotBuiltin {
                spec: spec.to_string(),
            })
        })
    }

    /// [`CellConfig::from_toml_str_for`] where a robot spec that is not a built-in name is
    /// resolved by `robot_file` (the caller reads the robot file: `crate::twin::load_cell`).
    pub fn from_toml_str_with(
        text: &str,
        robot: Option<&str>,
        robot_file: &dyn Fn(&str) -> Result<deflex_model::Robot, SimError>,
    ) -> Result<CellConfig, SimError> {
        // First pass on the user's text alone: types, unknown keys and line numbers are the
        // file's own.
        let typed: TwinCellToml =
            toml::from_str(text).map_err(|e| SimError::config("cell", e.to_string()))?;
        let value: toml::Table =
            toml::from_str(text).map_err(|e| SimError::config("cell", e.to_string()))?;
        let file_cell = match value.get("cell") {
            Some(toml::Value::Table(t)) => t.clone(),
            _ => toml::Table::new(),
        };
        let spec = robot
            .map(str::to_string)
            .unwrap_or_else(|| typed.cell.part.robot.clone());
        // Then the file's keys over the chosen robot's cell.
        let base = match deflex_model::builtin(&spec) {
            Some(_) => CellConfig::for_robot(&spec)?,
            None if spec.trim().is_empty() => CellConfig::for_robot(&spec)?,
            None => CellConfig::for_robot_description(&spec, robot_file(&spec)?)?,
        };
        let mut merged = toml::Table::try_from(&base)
            .map_err(|e| SimError::config("cell", format!("internal: {e}")))?;
        merge(&mut merged, file_cell);
        if let Some(toml::Value::Table(part)) = merged.get_mut("part") {
            part.insert("robot".into(), toml::Value::String(spec));
        }
        let mut config: CellConfig = toml::Value::Table(merged)
            .try_into()
            .map_err(|e: toml::de::Error| SimError::config("cell", e.to_string()))?;
        config.part.description = base.part.description;
        config.validate()?;
        Ok(config)
    }

    /// Nominal pose of the sensor frame in the flange frame (what a controller is told).
    pub fn sensor_in_flange(&self) -> Pose {
        pose_from_xyz_rpy(
            self.sensor.sensor_in_flange_xyz_m,
            self.sensor.sensor_in_flange_rpy,
        )
    }

    /// True pose of the sensor frame in the flange frame (with the mounting error when on).
    pub fn true_sensor_in_flange(&self) -> Pose {
        if self.errors.mounting {
            self.sensor_in_flange()
                * pose_from_xyz_rpy(
                    self.sensor.mounting_error_xyz_m,
                    self.sensor.mounting_error_rpy,
                )
        } else {
            self.sensor_in_flange()
        }
    }

    /// Nominal tool mass below the sensor (kg).
    pub fn tool_mass_kg(&self) -> f64 {
        self.sensor.tool_mass_kg
    }

    /// Nominal tool centre of mass in the sensor frame (m).
    pub fn tool_com_in_sensor_m(&self) -> [f64; 3] {
        self.sensor.tool_com_in_sensor_m
    }

    /// True tool mass and centre of mass (sensor frame) with the tool-load error when on.
    pub fn true_tool_load(&self) -> (f64, [f64; 3]) {
        let s = &self.sensor;
        if self.errors.tool_load {
            (
                s.tool_mass_kg + s.tool_mass_error_kg,
                std::array::from_fn(|i| s.tool_com_in_sensor_m[i] + s.tool_com_error_m[i]),
            )
        } else {
            (s.tool_mass_kg, s.tool_com_in_sensor_m)
        }
    }

    /// Robot controller period (s).
    pub fn robot_period_s(&self) -> f64 {
        1.0 / self.controller.rate_hz
    }

    /// Sensor sample period (s).
    pub fn sensor_period_s(&self) -> f64 {
        1.0 / self.sensor.rate_hz
    }

    /// Part frame R_p in the world as programmed (axes parallel to R0).
    pub fn part_frame(&self) -> Pose {
        let o = self.part.origin_mm;
        pose_from_xyz_rpy([o[0] * 1e-3, o[1] * 1e-3, o[2] * 1e-3], [0.0; 3])
    }

    /// The tool of the cell (flange → TCP).
    pub fn tool(&self) -> Pose {
        pose_from_xyz_rpy(self.part.tool_xyz_m, self.part.tool_rpy)
    }

    /// The nominal robot model with the cell's tool and base pivot: what the robot controller
    /// believes and what a calibration starts from (its stiffnesses are the description's).
    pub fn nominal_robot(&self) -> Result<deflex_model::Robot, SimError> {
        let mut robot = match &self.part.description {
            Some(robot) => robot.clone(),
            None => {
                deflex_model::builtin(&self.part.robot).ok_or_else(|| SimError::NotBuiltin {
                    spec: self.part.robot.clone(),
                })?
            }
        };
        robot.tool = self.tool();
        if let Some(pivot) = self.part.base_pivot_m {
            robot.base_pivot = nalgebra::Vector3::from(pivot);
        }
        crate::plant::check_six_joints(&robot)?;
        Ok(robot)
    }

    /// The flange placement after the last joint frame of the nominal robot (the description's
    /// `flange`, read as data by the plant).
    pub fn flange(&self, robot: &deflex_model::Robot) -> Pose {
        robot.flange
    }

    /// The cell's forming force level (N): the Aerens level of the paper's cone (its default
    /// step-down and wall angle) on the cell's sheet. 1260 N for the TX200 cell.
    pub fn forming_force_level_n(&self) -> f64 {
        let s = &self.sheet;
        let dh = crate::sheet::scallop_height_mm(
            s.tool_diameter_mm / 2.0,
            s.default_step_down_mm,
            s.default_wall_angle_deg,
        );
        crate::sheet::aerens_fz(
            s.rm_mpa,
            s.thickness_mm,
            s.tool_diameter_mm,
            dh,
            s.default_wall_angle_deg,
        )
    }

    /// The IK seed (rad).
    pub fn seed_q_rad(&self) -> [f64; 6] {
        self.part.seed_q_deg.map(f64::to_radians)
    }
}

/// Deep merge of TOML tables: `overlay` wins, tables merge key by key.
fn merge(base: &mut toml::Table, overlay: toml::Table) {
    for (key, value) in overlay {
        match (base.get_mut(&key), value) {
            (Some(toml::Value::Table(b)), toml::Value::Table(o)) => merge(b, o),
            (_, value) => {
                base.insert(key, value);
            }
        }
    }
}

mod ranges;
