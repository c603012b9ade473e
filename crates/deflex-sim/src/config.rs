//! The cell configuration: robot controller, F/T sensor, laser tracker, true robot (plant),
//! sheet and part placement. `CellConfig::default()` is the paper's cell (Johra et al. 2022,
//! Section 4); every value can be overridden from TOML:
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
//! ```
//!
//! Units are SI unless a field name says otherwise (`_mm`, `_deg`, `_mpa`).
//!
//! A correction controller may legitimately read the controller, sensor and part sections (what a
//! real integrator knows about the hardware: rates, sensor mounting, tool mass); it must never
//! read `plant` or `sheet`, which are the hidden truth of the twin.

use crate::error::SimError;
use crate::plant::PlantConfig;
use crate::sheet::SheetConfig;
use deflex_model::Pose;
use deflex_model::spatial::pose_from_xyz_rpy;
use serde::{Deserialize, Serialize};

/// Robot controller emulation (Stäubli CS8 with Alter, or KUKA RSI).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct ControllerConfig {
    /// Interpolation rate (Hz). The CS8 runs at 250 Hz (paper, Section 4.2).
    pub rate_hz: f64,
    /// Transport delay between `set_correction` and the start of its effect (s). Alter and RSI
    /// apply a correction one to three cycles after reception; 8 ms = 2 cycles at 250 Hz.
    pub correction_delay_s: f64,
    /// Time constant of the first-order filter on the correction (s).
    pub correction_filter_s: f64,
    /// Largest translation correction (m, norm).
    pub max_correction_m: f64,
    /// Largest rotation correction (rad, norm).
    pub max_correction_rad: f64,
    /// Largest translation correction speed (m/s, norm).
    pub max_correction_speed_m_s: f64,
    /// Largest rotation correction speed (rad/s, norm).
    pub max_correction_speed_rad_s: f64,
    /// Feed rate of rapid (G0) moves (mm/s).
    pub rapid_feed_mm_s: f64,
}

impl Default for ControllerConfig {
    fn default() -> Self {
        ControllerConfig {
            rate_hz: 250.0,
            correction_delay_s: 0.008,
            correction_filter_s: 0.010,
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
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct SensorConfig {
    /// Sample rate (Hz), 100 to 7000.
    pub rate_hz: f64,
    /// Sensor frame origin in the flange frame (m). The built-in TX200 model puts the TCP (the
    /// centre of the hemispherical tip) at its last frame, so the sensor sits 150 mm up the tool
    /// from the TCP: z = −0.150 m.
    pub sensor_in_flange_xyz_m: [f64; 3],
    /// Sensor frame orientation in the flange frame (roll, pitch, yaw, rad).
    pub sensor_in_flange_rpy: [f64; 3],
    /// Mass of everything below the sensor's sensing plane: tool holder, punch (kg).
    pub tool_mass_kg: f64,
    /// Centre of mass of that tool in the sensor frame (m).
    pub tool_com_in_sensor_m: [f64; 3],
    /// Gaussian noise, 1σ, per channel `[Fx, Fy, Fz, Tx, Ty, Tz]` (N, N·m).
    pub noise_sigma: [f64; 6],
    /// Constant offset of the unloaded sensor (N, N·m): what a tare removes.
    pub bias: [f64; 6],
    /// Saturation limits ± per channel (N, N·m).
    pub range: [f64; 6],
    /// Gravity (m/s²), along −z of the world.
    pub gravity_m_s2: f64,
}

impl Default for SensorConfig {
    fn default() -> Self {
        SensorConfig {
            rate_hz: 1000.0,
            sensor_in_flange_xyz_m: [0.0, 0.0, -0.150],
            sensor_in_flange_rpy: [0.0, 0.0, 0.0],
            tool_mass_kg: 3.2,
            tool_com_in_sensor_m: [0.003, -0.002, 0.075],
            noise_sigma: [0.25, 0.25, 0.25, 0.025, 0.025, 0.025],
            bias: [4.1, -2.7, 6.3, 0.21, -0.17, 0.05],
            range: [1500.0, 1500.0, 3750.0, 240.0, 240.0, 240.0],
            gravity_m_s2: 9.80665,
        }
    }
}

/// Laser tracker (API Radian class).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct TrackerConfig {
    /// Output rate (Hz), at most 50 in this twin (what the paper logged).
    pub rate_hz: f64,
    /// Tracker head position in the world frame (m).
    pub position_m: [f64; 3],
    /// Distance-independent noise, 1σ per axis (m). API's Radian lists ±(10 µm + 5 µm/m); the
    /// twin uses that envelope as 1σ, which is pessimistic.
    pub sigma_const_m: f64,
    /// Distance-proportional noise, 1σ per axis per metre of range (m/m).
    pub sigma_per_m: f64,
    /// Samples averaged per static reading in a campaign. Default 1: the ±(10 µm + 5 µm/m)
    /// specification is taken as the uncertainty of a reading as delivered, since averaging
    /// removes only the white part of a real tracker's error.
    pub samples_per_reading: usize,
}

impl Default for TrackerConfig {
    fn default() -> Self {
        TrackerConfig {
            rate_hz: 50.0,
            position_m: [2.8, -1.6, 0.3],
            sigma_const_m: 10e-6,
            sigma_per_m: 5e-6,
            samples_per_reading: 1,
        }
    }
}

/// Where the part is and how the robot holds the tool.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct PartConfig {
    /// Robot model of the nominal kinematics (built-in name or TOML path). The plant shares this
    /// geometry; only its elasticity differs.
    pub robot: String,
    /// Origin of the part frame R_p in R0 (mm): the paper's [1500 0 −183].
    pub origin_mm: [f64; 3],
    /// Joint configuration near the part origin (deg), the IK seed: the paper's
    /// [0 49.7 89.3 0 41 0].
    pub seed_q_deg: [f64; 6],
}

impl Default for PartConfig {
    fn default() -> Self {
        PartConfig {
            robot: "tx200".into(),
            origin_mm: [1500.0, 0.0, -183.0],
            seed_q_deg: deflex_model::TX200_FORMING_Q_DEG,
        }
    }
}

/// What is recorded.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct LogConfig {
    /// Rate of the stored log (Hz); the summary statistics use every controller cycle.
    pub rate_hz: f64,
}

impl Default for LogConfig {
    fn default() -> Self {
        LogConfig { rate_hz: 50.0 }
    }
}

/// The whole simulated cell. `Default` is the paper's cell.
#[derive(Clone, Debug, PartialEq, Default, Serialize, Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct CellConfig {
    /// Robot controller emulation.
    pub controller: ControllerConfig,
    /// Force/torque sensor.
    pub sensor: SensorConfig,
    /// Laser tracker.
    pub tracker: TrackerConfig,
    /// Part placement and nominal robot.
    pub part: PartConfig,
    /// The true robot (hidden from controllers and calibration).
    pub plant: PlantConfig,
    /// The sheet and forming law (hidden from controllers).
    pub sheet: SheetConfig,
    /// Logging.
    pub log: LogConfig,
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct CellFile {
    #[serde(default)]
    cell: CellConfig,
}

impl CellConfig {
    /// Parse a TOML text whose settings live under `[cell]` / `[cell.<section>]`.
    pub fn from_toml_str(text: &str) -> Result<CellConfig, SimError> {
        let file: CellFile =
            toml::from_str(text).map_err(|e| SimError::config("cell", e.to_string()))?;
        file.cell.validate()?;
        Ok(file.cell)
    }

    /// Read a TOML file (see [`CellConfig::from_toml_str`]).
    pub fn load(path: &std::path::Path) -> Result<CellConfig, SimError> {
        let text = std::fs::read_to_string(path).map_err(|e| SimError::output(path, e))?;
        Self::from_toml_str(&text).map_err(|e| match e {
            SimError::Config { field, message } => SimError::Config {
                field: format!("{}: {field}", path.display()),
                message,
            },
            other => other,
        })
    }

    /// Check physical ranges.
    pub fn validate(&self) -> Result<(), SimError> {
        let c = &self.controller;
        positive("controller.rate_hz", c.rate_hz)?;
        non_negative("controller.correction_delay_s", c.correction_delay_s)?;
        non_negative("controller.correction_filter_s", c.correction_filter_s)?;
        positive("controller.max_correction_m", c.max_correction_m)?;
        positive("controller.max_correction_rad", c.max_correction_rad)?;
        positive(
            "controller.max_correction_speed_m_s",
            c.max_correction_speed_m_s,
        )?;
        positive(
            "controller.max_correction_speed_rad_s",
            c.max_correction_speed_rad_s,
        )?;
        positive("controller.rapid_feed_mm_s", c.rapid_feed_mm_s)?;
        let s = &self.sensor;
        if !(100.0..=7000.0).contains(&s.rate_hz) {
            return Err(SimError::config(
                "sensor.rate_hz",
                format!("must be within 100..7000 Hz, got {}", s.rate_hz),
            ));
        }
        non_negative("sensor.tool_mass_kg", s.tool_mass_kg)?;
        for (i, v) in s.noise_sigma.iter().enumerate() {
            non_negative(&format!("sensor.noise_sigma[{i}]"), *v)?;
        }
        for (i, v) in s.range.iter().enumerate() {
            positive(&format!("sensor.range[{i}]"), *v)?;
        }
        let t = &self.tracker;
        if !(t.rate_hz > 0.0 && t.rate_hz <= 50.0) {
            return Err(SimError::config(
                "tracker.rate_hz",
                format!("must be within (0, 50] Hz, got {}", t.rate_hz),
            ));
        }
        non_negative("tracker.sigma_const_m", t.sigma_const_m)?;
        non_negative("tracker.sigma_per_m", t.sigma_per_m)?;
        if t.samples_per_reading == 0 {
            return Err(SimError::config(
                "tracker.samples_per_reading",
                "must be at least 1",
            ));
        }
        positive("log.rate_hz", self.log.rate_hz)?;
        self.plant.validate()?;
        self.sheet.validate()?;
        Ok(())
    }

    /// Pose of the sensor frame in the flange frame.
    pub fn sensor_in_flange(&self) -> Pose {
        pose_from_xyz_rpy(
            self.sensor.sensor_in_flange_xyz_m,
            self.sensor.sensor_in_flange_rpy,
        )
    }

    /// Tool mass below the sensor (kg).
    pub fn tool_mass_kg(&self) -> f64 {
        self.sensor.tool_mass_kg
    }

    /// Tool centre of mass in the sensor frame (m).
    pub fn tool_com_in_sensor_m(&self) -> [f64; 3] {
        self.sensor.tool_com_in_sensor_m
    }

    /// Robot controller period (s).
    pub fn robot_period_s(&self) -> f64 {
        1.0 / self.controller.rate_hz
    }

    /// Sensor sample period (s).
    pub fn sensor_period_s(&self) -> f64 {
        1.0 / self.sensor.rate_hz
    }

    /// Part frame R_p in the world (axes parallel to R0).
    pub fn part_frame(&self) -> Pose {
        let o = self.part.origin_mm;
        pose_from_xyz_rpy([o[0] * 1e-3, o[1] * 1e-3, o[2] * 1e-3], [0.0; 3])
    }

    /// The nominal robot model (what the robot controller believes; no stiffness used).
    pub fn nominal_robot(&self) -> Result<deflex_model::Robot, SimError> {
        Ok(deflex_model::load_robot(&self.part.robot)?)
    }

    /// The IK seed (rad).
    pub fn seed_q_rad(&self) -> [f64; 6] {
        self.part.seed_q_deg.map(f64::to_radians)
    }
}

pub(crate) fn positive(field: &str, value: f64) -> Result<(), SimError> {
    if value.is_finite() && value > 0.0 {
        Ok(())
    } else {
        Err(SimError::config(
            field,
            format!("must be a positive finite number, got {value}"),
        ))
    }
}

pub(crate) fn non_negative(field: &str, value: f64) -> Result<(), SimError> {
    if value.is_finite() && value >= 0.0 {
        Ok(())
    } else {
        Err(SimError::config(
            field,
            format!("must be a finite number ≥ 0, got {value}"),
        ))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn toml_cell_sections_override_defaults() {
        let text = "[cell.controller]\nrate_hz = 500.0\n[cell.sensor]\nrate_hz = 7000.0\ntool_mass_kg = 5.0\n\
                    [cell.sheet]\nrm_mpa = 250.0\n[cell.plant]\nj2_j3_coupling = 0.0\n";
        let config = CellConfig::from_toml_str(text).unwrap();
        assert_eq!(config.controller.rate_hz, 500.0);
        assert_eq!(config.robot_period_s(), 0.002);
        assert_eq!(config.sensor.rate_hz, 7000.0);
        assert_eq!(config.tool_mass_kg(), 5.0);
        assert_eq!(config.sheet.rm_mpa, 250.0);
        assert_eq!(config.tracker, TrackerConfig::default());
        assert_eq!(
            CellConfig::from_toml_str("").unwrap(),
            CellConfig::default()
        );
        let sensor = config.sensor_in_flange();
        assert!((sensor.translation.vector.z + 0.150).abs() < 1e-12);
    }

    #[test]
    fn bad_values_are_refused_with_the_field_name() {
        let e = CellConfig::from_toml_str("[cell.sensor]\nrate_hz = 20000.0\n").unwrap_err();
        assert!(e.to_string().contains("sensor.rate_hz"), "{e}");
        let e = CellConfig::from_toml_str("[cell.sensor]\nrate = 1.0\n").unwrap_err();
        assert!(e.to_string().contains("rate"), "{e}");
        let e = CellConfig::from_toml_str("[cell.tracker]\nrate_hz = 100.0\n").unwrap_err();
        assert!(e.to_string().contains("tracker.rate_hz"), "{e}");
    }
}
