//! `CELL.toml`: everything `deflex run` needs: robot link, sensor link, sensor mounting and
//! tool, model file, gains of eq. 17, limits, safety, log path. SI units throughout, the unit in
//! each key's name. Unknown keys are errors (typos must not silently fall back to defaults);
//! every error names the file and the field. The documented example is
//! `docs/cell.example.toml`.

mod controller_config;
mod feedforward;
mod links;
mod validate;

pub use validate::{BOUNDS, bounds_of};

use crate::limiter::LimiterConfig;
use crate::pid::PidGains;
use crate::safety::SafetyConfig;
use crate::wrench::STANDARD_GRAVITY;
use serde::Deserialize;
use std::net::SocketAddr;
use std::path::{Path, PathBuf};

/// A configuration problem, naming the file and the field.
#[derive(Debug, thiserror::Error)]
pub enum ConfigError {
    /// The file could not be read.
    #[error("{path}: cannot read: {source}")]
    Read {
        /// File.
        path: String,
        /// Cause.
        source: std::io::Error,
    },
    /// TOML syntax or type error (the message names the key and line).
    #[error("{path}: {message}")]
    Parse {
        /// File.
        path: String,
        /// Parser message.
        message: String,
    },
    /// A value is invalid.
    #[error("{path}: field `{field}`: {message}")]
    Invalid {
        /// File.
        path: String,
        /// Dotted field name.
        field: String,
        /// Why.
        message: String,
    },
}

/// Robot protocol.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Deserialize)]
#[serde(rename_all = "kebab-case")]
pub enum RobotKind {
    /// KUKA RSI, XML over UDP.
    KukaRsi,
    /// ABB EGM path correction.
    AbbEgm,
    /// Stäubli VAL3 `alter` program (deflex binary protocol).
    Staubli,
    /// Text lines over UDP.
    SimpleUdp,
    /// The same text lines over TCP (the controller listens; a UR script connects to it).
    SimpleTcp,
}

impl RobotKind {
    /// The protocol's name for people ("KUKA RSI", "ABB EGM", …).
    pub fn name(self) -> &'static str {
        match self {
            RobotKind::KukaRsi => "KUKA RSI",
            RobotKind::AbbEgm => "ABB EGM",
            RobotKind::Staubli => "Stäubli",
            RobotKind::SimpleUdp => "simple UDP",
            RobotKind::SimpleTcp => "simple TCP",
        }
    }
}

/// `[robot]`: the robot link.
#[derive(Clone, Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct RobotSection {
    /// Protocol.
    pub kind: RobotKind,
    /// Local address the controller listens on (e.g. `0.0.0.0:59152` for RSI).
    pub bind: SocketAddr,
    /// The robot controller's address: the link answers only it (port 0: any port of that
    /// IP; the simple TCP link compares the IP only). Absent: the link locks to the first host
    /// that sends a valid telegram, for the whole session.
    #[serde(default)]
    pub peer: Option<SocketAddr>,
    /// RSI correction interpretation: `absolute` (default) or `relative`.
    #[serde(default = "default_mode")]
    pub correction_mode: String,
    /// RSI `<Sen Type>`.
    #[serde(default = "default_sen_type")]
    pub sen_type: String,
    /// RSI answers: `cartesian` (`RKorr`, default) or `joint` (`AK`, joint corrections from the
    /// Cartesian one through the model's Jacobian).
    #[serde(default = "default_rsi_answer")]
    pub rsi_answer: String,
    /// Element of joint answers: `AK` (default, the ROS-Industrial set-ups) or `AKorr`.
    #[serde(default = "default_rsi_joint_tag")]
    pub rsi_joint_tag: String,
    /// ABB EGM: frame of `pathCorr`: `tool` (default: the sensor frame of `EGMActMove`,
    /// attached to the tool), `work-object` or `base`.
    #[serde(default = "default_egm_frame")]
    pub egm_frame: String,
    /// ABB EGM: orientation of `EGMActMove`'s sensor frame in the tool frame (roll, pitch, yaw,
    /// rad), for `egm_frame = "tool"`.
    #[serde(default)]
    pub egm_sensor_rpy_rad: [f64; 3],
    /// ABB EGM: orientation of the work object in the robot base frame (roll, pitch, yaw, rad),
    /// for `egm_frame = "work-object"`.
    #[serde(default)]
    pub egm_work_object_rpy_rad: [f64; 3],
    /// Robot interpolation cycle (s), the reply deadline: 0.004 for RSI.
    #[serde(default = "default_cycle")]
    pub cycle_s: f64,
    /// Silence after which the robot link counts as lost (s).
    #[serde(default = "default_timeout")]
    pub timeout_s: f64,
}

/// Sensor protocol.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Deserialize)]
#[serde(rename_all = "kebab-case")]
pub enum SensorKind {
    /// ATI Net F/T RDT over UDP.
    Netft,
}

/// `[sensor]`: the force/torque sensor link.
#[derive(Clone, Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct SensorSection {
    /// Protocol.
    pub kind: SensorKind,
    /// Sensor address (`<ip>:49152`).
    pub address: SocketAddr,
    /// Local address (default: any port on all interfaces).
    #[serde(default = "default_sensor_bind")]
    pub bind: SocketAddr,
    /// Counts per newton.
    #[serde(default = "default_counts")]
    pub counts_per_force: f64,
    /// Counts per newton-metre.
    #[serde(default = "default_counts")]
    pub counts_per_torque: f64,
    /// Silence after which the sensor counts as lost (s).
    #[serde(default = "default_timeout")]
    pub timeout_s: f64,
    /// Range of each channel `[fx, fy, fz, mx, my, mz]` (N, N·m); beyond it a reading is garbage.
    #[serde(default = "default_range")]
    pub range: [f64; 6],
}

/// `[mounting]`: sensor pose on the flange and the tool beyond it.
#[derive(Clone, Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct MountingSection {
    /// Sensor origin in the flange frame (m).
    #[serde(default)]
    pub sensor_xyz_m: [f64; 3],
    /// Sensor orientation in the flange frame, roll–pitch–yaw (rad).
    #[serde(default)]
    pub sensor_rpy_rad: [f64; 3],
    /// Tool mass beyond the sensor (kg).
    #[serde(default)]
    pub tool_mass_kg: f64,
    /// Tool centre of mass in the sensor frame (m).
    #[serde(default)]
    pub tool_com_m: [f64; 3],
    /// Gravity in world axes (m/s²).
    #[serde(default = "default_gravity")]
    pub gravity_m_s2: [f64; 3],
    /// Known bias (sensor frame, gravity excluded); when absent a tare is taken at start.
    #[serde(default)]
    pub bias: Option<[f64; 6]>,
    /// Tare duration at start, out of contact (s).
    #[serde(default = "default_tare")]
    pub tare_s: f64,
    /// Low-pass cut-off on the wrench (Hz); absent = off.
    #[serde(default)]
    pub lowpass_hz: Option<f64>,
}

/// `[model]`: the calibrated elasto-geometrical model.
#[derive(Clone, Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct ModelSection {
    /// Model TOML/URDF path (relative to the config file) or a built-in name.
    pub file: String,
}

/// `[control]`: the law of eq. 17.
#[derive(Clone, Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct ControlSection {
    /// Control rate (Hz).
    #[serde(default = "default_rate")]
    pub rate_hz: f64,
    /// K_c.
    #[serde(default = "default_kc")]
    pub kc: f64,
    /// T_i (s).
    #[serde(default = "default_ti")]
    pub ti_s: f64,
    /// T_d (s).
    #[serde(default = "default_td")]
    pub td_s: f64,
    /// Derivative filter ratio N (T_f = T_d/N).
    #[serde(default = "default_n")]
    pub derivative_filter_n: f64,
    /// Corrected axes, any of `x y z rx ry rz`.
    #[serde(default = "default_axes")]
    pub axes: Vec<String>,
    /// Try SCHED_FIFO for the loop threads.
    #[serde(default = "default_true")]
    pub realtime: bool,
    /// Also lock memory (mlockall).
    #[serde(default = "default_true")]
    pub lock_memory: bool,
}

/// `[limits]`: limiter and safety.
#[derive(Clone, Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct LimitsSection {
    /// Largest |ξ| per position axis (m).
    #[serde(default = "default_max_m")]
    pub max_correction_m: f64,
    /// Largest |ξ| per rotation axis (rad).
    #[serde(default = "default_max_rad")]
    pub max_correction_rad: f64,
    /// Largest rate per position axis (m/s).
    #[serde(default = "default_rate_m")]
    pub max_rate_m_s: f64,
    /// Largest rate per rotation axis (rad/s).
    #[serde(default = "default_rate_rad")]
    pub max_rate_rad_s: f64,
    /// Ramp-in duration (s).
    #[serde(default = "default_ramp")]
    pub ramp_in_s: f64,
    /// Ramp-out duration (s).
    #[serde(default = "default_ramp")]
    pub ramp_out_s: f64,
    /// Force norm limit at the TCP (N).
    #[serde(default = "default_max_force")]
    pub max_force_n: f64,
    /// Torque norm limit at the TCP (N·m).
    #[serde(default = "default_max_torque")]
    pub max_torque_nm: f64,
    /// Largest joint change per control cycle (rad).
    #[serde(default = "default_joint_step")]
    pub max_joint_step_rad: f64,
    /// `zero` (ramp ξ to 0, default) or `hold`.
    #[serde(default = "default_safe")]
    pub safe_action: String,
    /// Watch for contact runaway (stiff contact making the correction positive feedback).
    #[serde(default = "default_true")]
    pub runaway_guard: bool,
    /// Estimated loop gain through the contact above which the guard acts.
    #[serde(default = "default_runaway_gain")]
    pub runaway_gain_limit: f64,
    /// Estimated loop gain below which the guard releases its hold.
    #[serde(default = "default_runaway_release")]
    pub runaway_release_gain: f64,
    /// Forgetting time of the guard's estimate (s).
    #[serde(default = "default_runaway_window")]
    pub runaway_window_s: f64,
    /// Motion along the corrected direction needed to trust the estimate (m).
    #[serde(default = "default_runaway_travel")]
    pub runaway_min_travel_m: f64,
    /// Consecutive control cycles above the limit before the guard acts.
    #[serde(default = "default_runaway_confirm")]
    pub runaway_confirm_cycles: u32,
    /// Duration of the guard's withdrawal ramp (s).
    #[serde(default = "default_runaway_withdraw")]
    pub runaway_withdraw_s: f64,
    /// Rate at which a released hold gives the correction back (m/s).
    #[serde(default = "default_runaway_release_rate")]
    pub runaway_release_rate_m_s: f64,
    /// `withdraw` (ramp the correction along its direction to zero, warn; default), `hold` (stop
    /// it growing, warn) or `fault`.
    #[serde(default = "default_runaway_action")]
    pub runaway_action: String,
}

/// `[feedforward]`: the online correction on top of an offline compensation
/// ([`crate::feedforward`]).
#[derive(Clone, Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct FeedForwardSection {
    /// `compensated_path.csv` of `deflex compensate` (relative to the config file).
    pub table: String,
    /// `feed-forward` (the robot runs the original program; default) or `precompensated` (the
    /// robot runs the compensated program).
    #[serde(default = "default_ff_mode")]
    pub mode: String,
    /// `arc-length` (default) or `time`.
    #[serde(default = "default_ff_index")]
    pub index: String,
    /// Feed-forward mode: read the table this much path time ahead (s).
    #[serde(default)]
    pub lead_s: f64,
    /// Farther than this from the path, the TCP is off the path (m).
    #[serde(default = "default_ff_offset")]
    pub max_offset_m: f64,
    /// Arc length searched ahead per control cycle (m).
    #[serde(default = "default_ff_window")]
    pub window_m: f64,
    /// Time index: the table's time at the controller's start (s).
    #[serde(default)]
    pub time_offset_s: f64,
}

/// `[log]`.
#[derive(Clone, Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct LogSection {
    /// CSV path (relative to the config file).
    pub path: String,
    /// Ring buffer capacity (records).
    #[serde(default = "default_ring")]
    pub ring_capacity: usize,
}

/// A whole `CELL.toml`.
#[derive(Clone, Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct CellFile {
    /// Robot link.
    pub robot: RobotSection,
    /// Sensor link.
    pub sensor: SensorSection,
    /// Mounting and tool.
    #[serde(default = "default_mounting")]
    pub mounting: MountingSection,
    /// Model.
    pub model: ModelSection,
    /// Gains.
    #[serde(default = "default_control")]
    pub control: ControlSection,
    /// Limits.
    #[serde(default = "default_limits")]
    pub limits: LimitsSection,
    /// Log; absent = no CSV.
    #[serde(default)]
    pub log: Option<LogSection>,
    /// Feed-forward from an offline compensation; absent = the online correction alone.
    #[serde(default)]
    pub feedforward: Option<FeedForwardSection>,
    /// Directory of the file (for relative paths); set by [`CellFile::load`].
    #[serde(skip)]
    pub base_dir: PathBuf,
    /// Path of the file, for messages.
    #[serde(skip)]
    pub origin: String,
}

fn default_mode() -> String {
    "absolute".into()
}
fn default_rsi_answer() -> String {
    "cartesian".into()
}
fn default_rsi_joint_tag() -> String {
    "AK".into()
}
fn default_egm_frame() -> String {
    "tool".into()
}
fn default_runaway_gain() -> f64 {
    crate::runaway::RunawayConfig::default().gain_limit
}
fn default_runaway_release() -> f64 {
    crate::runaway::RunawayConfig::default().release_gain
}
fn default_runaway_window() -> f64 {
    crate::runaway::RunawayConfig::default().window_s
}
fn default_runaway_travel() -> f64 {
    crate::runaway::RunawayConfig::default().min_travel_m
}
fn default_runaway_confirm() -> u32 {
    crate::runaway::RunawayConfig::default().confirm_cycles
}
fn default_runaway_withdraw() -> f64 {
    crate::runaway::RunawayConfig::default().withdraw_s
}
fn default_runaway_release_rate() -> f64 {
    crate::runaway::RunawayConfig::default().release_rate_m_s
}
fn default_runaway_action() -> String {
    crate::runaway::RunawayConfig::default()
        .action
        .name()
        .into()
}
fn default_sen_type() -> String {
    "ImFree".into()
}
fn default_cycle() -> f64 {
    0.004
}
fn default_timeout() -> f64 {
    0.05
}
fn default_sensor_bind() -> SocketAddr {
    SocketAddr::from(([0, 0, 0, 0], 0))
}
fn default_counts() -> f64 {
    1_000_000.0
}
fn default_range() -> [f64; 6] {
    SafetyConfig::default().sensor_range
}
fn default_gravity() -> [f64; 3] {
    [0.0, 0.0, -STANDARD_GRAVITY]
}
fn default_tare() -> f64 {
    0.2
}
fn default_mounting() -> MountingSection {
    toml::from_str("").expect("mounting defaults")
}
fn default_rate() -> f64 {
    100.0
}
fn default_kc() -> f64 {
    PidGains::default().kc
}
fn default_ti() -> f64 {
    PidGains::default().ti_s
}
fn default_td() -> f64 {
    PidGains::default().td_s
}
fn default_n() -> f64 {
    PidGains::default().derivative_filter_n
}
fn default_axes() -> Vec<String> {
    AXES.iter().map(|s| s.to_string()).collect()
}
fn default_true() -> bool {
    true
}
fn default_control() -> ControlSection {
    toml::from_str("").expect("control defaults")
}
fn default_max_m() -> f64 {
    LimiterConfig::default().max_abs[0]
}
fn default_max_rad() -> f64 {
    LimiterConfig::default().max_abs[3]
}
fn default_rate_m() -> f64 {
    LimiterConfig::default().max_rate[0]
}
fn default_rate_rad() -> f64 {
    LimiterConfig::default().max_rate[3]
}
fn default_ramp() -> f64 {
    0.5
}
fn default_max_force() -> f64 {
    SafetyConfig::default().max_force_n
}
fn default_max_torque() -> f64 {
    SafetyConfig::default().max_torque_nm
}
fn default_joint_step() -> f64 {
    SafetyConfig::default().max_joint_step_rad
}
fn default_safe() -> String {
    "zero".into()
}
fn default_limits() -> LimitsSection {
    toml::from_str("").expect("limits defaults")
}
fn default_ring() -> usize {
    8192
}
fn default_ff_mode() -> String {
    crate::feedforward::FeedForwardMode::FeedForward
        .name()
        .into()
}
fn default_ff_index() -> String {
    crate::feedforward::PathIndex::ArcLength.name().into()
}
fn default_ff_offset() -> f64 {
    crate::feedforward::FeedForwardConfig::default().max_offset_m
}
fn default_ff_window() -> f64 {
    crate::feedforward::FeedForwardConfig::default().window_m
}

/// Axis names in ξ order.
pub const AXES: [&str; 6] = ["x", "y", "z", "rx", "ry", "rz"];

impl CellFile {
    /// Reads and validates a file.
    pub fn load(path: &Path) -> Result<Self, ConfigError> {
        let origin = path.display().to_string();
        let text = std::fs::read_to_string(path).map_err(|source| ConfigError::Read {
            path: origin.clone(),
            source,
        })?;
        let base = path.parent().map(Path::to_path_buf).unwrap_or_default();
        Self::parse(&text, &origin, base)
    }

    /// Parses and validates text; `origin` names it in errors, `base_dir` resolves relative paths.
    pub fn parse(text: &str, origin: &str, base_dir: PathBuf) -> Result<Self, ConfigError> {
        let mut cell: CellFile = toml::from_str(text).map_err(|e| ConfigError::Parse {
            path: origin.to_string(),
            message: e.to_string().trim_end().to_string(),
        })?;
        cell.base_dir = base_dir;
        cell.origin = origin.to_string();
        cell.validate()?;
        Ok(cell)
    }

    /// The model specification: a path resolved against the file's directory when it exists
    /// there, otherwise the text as given (built-in names).
    pub fn model_spec(&self) -> String {
        let p = self.base_dir.join(&self.model.file);
        if Path::new(&self.model.file).is_relative() && p.exists() {
            p.display().to_string()
        } else {
            self.model.file.clone()
        }
    }

    /// The log path resolved against the file's directory.
    pub fn log_path(&self) -> Option<PathBuf> {
        self.log.as_ref().map(|l| self.base_dir.join(&l.path))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    const MINIMAL: &str = r#"
[robot]
kind = "kuka-rsi"
bind = "127.0.0.1:59152"
[sensor]
kind = "netft"
address = "127.0.0.1:49152"
[model]
file = "tx200"
"#;

    #[test]
    fn minimal_file_gets_paper_defaults() {
        let cell = CellFile::parse(MINIMAL, "cell.toml", PathBuf::new()).unwrap();
        let c = cell.controller_config();
        assert_eq!(c.period_s, 0.01);
        assert_eq!(c.gains, PidGains::default());
        assert_eq!(c.limiter.enabled, [true; 6]);
        assert_eq!(cell.model_spec(), "tx200");
    }

    #[test]
    fn the_documented_example_parses() {
        let text = include_str!("../../../docs/cell.example.toml");
        let cell = CellFile::parse(text, "cell.example.toml", PathBuf::new()).unwrap();
        assert_eq!(cell.robot.kind, RobotKind::KukaRsi);
    }

    #[test]
    fn errors_name_file_and_field() {
        let bad = format!("{MINIMAL}[limits]\nsafe_action = \"explode\"\n");
        let e = CellFile::parse(&bad, "cell.toml", PathBuf::new())
            .unwrap_err()
            .to_string();
        assert!(
            e.contains("cell.toml") && e.contains("limits.safe_action"),
            "{e}"
        );
        let typo = format!("{MINIMAL}[control]\nkp = 1.0\n");
        let e = CellFile::parse(&typo, "cell.toml", PathBuf::new())
            .unwrap_err()
            .to_string();
        assert!(e.contains("cell.toml") && e.contains("kp"), "{e}");
        let axes = format!("{MINIMAL}[control]\naxes = [\"x\", \"w\"]\n");
        let e = CellFile::parse(&axes, "cell.toml", PathBuf::new())
            .unwrap_err()
            .to_string();
        assert!(e.contains("control.axes") && e.contains("\"w\""), "{e}");
        let e = CellFile::parse(
            &MINIMAL.replace("kuka-rsi", "fanuc"),
            "cell.toml",
            PathBuf::new(),
        )
        .unwrap_err()
        .to_string();
        assert!(e.contains("cell.toml") && e.contains("fanuc"), "{e}");
    }

    /// Every numeric field has a bound; absurd values are refused with the field named.
    #[test]
    fn every_number_is_bounded_and_named() {
        let cases = [
            ("[control]\nrate_hz = 1e-300\n", "control.rate_hz"),
            ("[control]\nrate_hz = 0.001\n", "control.rate_hz"),
            ("[control]\nrate_hz = 1e300\n", "control.rate_hz"),
            ("[control]\nrate_hz = nan\n", "control.rate_hz"),
            ("[control]\nkc = inf\n", "control.kc"),
            (
                "[log]\npath = \"x.csv\"\nring_capacity = 2000000000000000000\n",
                "log.ring_capacity",
            ),
            (
                "[log]\npath = \"x.csv\"\nring_capacity = 2e18\n",
                "ring_capacity",
            ),
            ("[limits]\nramp_out_s = 1e9\n", "limits.ramp_out_s"),
            (
                "[limits]\nmax_correction_m = 5.0\n",
                "limits.max_correction_m",
            ),
            ("[limits]\nmax_force_n = 0.0\n", "limits.max_force_n"),
            (
                "[limits]\nrunaway_gain_limit = 0.2\nrunaway_release_gain = 0.3\n",
                "limits.runaway_release_gain",
            ),
            (
                "[limits]\nrunaway_action = \"panic\"\n",
                "limits.runaway_action",
            ),
            ("[mounting]\ntare_s = 1e12\n", "mounting.tare_s"),
            (
                "[mounting]\nsensor_xyz_m = [0.0, 0.0, 1e300]\n",
                "mounting.sensor_xyz_m[2]",
            ),
            ("[mounting]\nlowpass_hz = 1e-9\n", "mounting.lowpass_hz"),
            (
                "[mounting]\nbias = [0.0, 0.0, nan, 0.0, 0.0, 0.0]\n",
                "mounting.bias[2]",
            ),
        ];
        for (extra, field) in cases {
            let text = format!("{MINIMAL}{extra}");
            let e = CellFile::parse(&text, "cell.toml", PathBuf::new())
                .err()
                .unwrap_or_else(|| panic!("accepted: {extra}"))
                .to_string();
            assert!(
                e.contains("cell.toml") && e.contains(field),
                "{extra} → {e}"
            );
        }
        for (robot_extra, field) in [
            ("cycle_s = 1e300\n", "robot.cycle_s"),
            ("cycle_s = 0.0\n", "robot.cycle_s"),
            ("timeout_s = nan\n", "robot.timeout_s"),
            ("cycle_s = 0.012\ntimeout_s = 0.004\n", "robot.timeout_s"),
            ("egm_frame = \"flange\"\n", "robot.egm_frame"),
            ("rsi_answer = \"both\"\n", "robot.rsi_answer"),
            ("rsi_joint_tag = \"AX\"\n", "robot.rsi_joint_tag"),
            ("sen_type = \"Im Free\"\n", "robot.sen_type"),
        ] {
            let text = MINIMAL.replace(
                "bind = \"127.0.0.1:59152\"\n",
                &format!("bind = \"127.0.0.1:59152\"\n{robot_extra}"),
            );
            let e = CellFile::parse(&text, "cell.toml", PathBuf::new())
                .err()
                .unwrap_or_else(|| panic!("accepted: {robot_extra}"))
                .to_string();
            assert!(e.contains(field), "{robot_extra} → {e}");
        }
        // The documented example stays inside every bound it states.
        for (field, lo, hi, _) in BOUNDS {
            assert!(lo < hi, "{field}");
        }
    }

    #[test]
    fn link_settings_follow_the_file() {
        let text = MINIMAL.replace(
            "bind = \"127.0.0.1:59152\"\n",
            "bind = \"127.0.0.1:0\"\nrsi_answer = \"joint\"\nrsi_joint_tag = \"AKorr\"\n\
             egm_frame = \"work-object\"\negm_work_object_rpy_rad = [0.0, 0.0, 1.5707963267948966]\n",
        );
        let cell = CellFile::parse(&text, "cell.toml", PathBuf::new()).unwrap();
        assert_eq!(
            cell.rsi_config().answer,
            deflex_io::rsi::RsiAnswer::Joint(deflex_io::rsi::JointTag::AKorr)
        );
        let egm = cell.egm_config(7);
        assert!(egm.seven_axis);
        assert_eq!(egm.frame, deflex_io::egm::EgmFrame::WorkObject);
        // Yaw 90°: the work object's x is the base's y.
        assert!((egm.work_object_in_base[1][0] - 1.0).abs() < 1e-12);
        assert!(cell.open_robot_link(6).unwrap().answers_in_joint_space());
    }

    /// A compensated-path table (the columns `deflex compensate` writes), `rows` rows along x.
    fn table_text(rows: usize, status_of_row_2: &str) -> String {
        let mut t = String::from(
            "# SIMULATED\nindex,s_m,t_s,x_m,y_m,z_m,rx_rad,ry_rad,rz_rad,dx_m,dy_m,dz_m,drx_rad,dry_rad,\
             drz_rad,fx_N,fy_N,fz_N,mx_Nm,my_Nm,mz_Nm,defl_x_m,defl_y_m,defl_z_m,defl_rx_rad,\
             defl_ry_rad,defl_rz_rad,status\n",
        );
        for i in 0..rows {
            let s = i as f64 * 1e-3;
            let status = if i == 2 { status_of_row_2 } else { "ok" };
            t.push_str(&format!(
                "{i},{s},{},{},0,-0.18,0,0,0,0,0,-1e-4,0,0,0,0,0,100,0,0,0,0,0,1e-4,0,0,0,{status}\n",
                s / 0.01,
                1.5 + s
            ));
        }
        t
    }

    #[test]
    fn feedforward_section_reads_its_table() {
        let dir = std::env::temp_dir().join(format!("deflex-ff-config-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        std::fs::write(dir.join("good.csv"), table_text(5, "ok")).unwrap();
        std::fs::write(
            dir.join("failed.csv"),
            table_text(5, "compensated:out_of_reach"),
        )
        .unwrap();
        let robot = deflex_model::builtin("tx200").unwrap();
        let with = |extra: &str| {
            CellFile::parse(
                &format!("{MINIMAL}[feedforward]\n{extra}"),
                "cell.toml",
                dir.clone(),
            )
        };
        let cell =
            with("table = \"good.csv\"\nmode = \"precompensated\"\nindex = \"time\"\n").unwrap();
        let ff = cell.feedforward(&robot).unwrap().unwrap();
        assert_eq!(ff.table().len(), 5);
        assert!((ff.table().length_m() - 0.004).abs() < 1e-12);
        let c = ff.config();
        assert_eq!(
            (c.mode, c.index),
            (
                crate::feedforward::FeedForwardMode::Precompensated,
                crate::feedforward::PathIndex::Time
            )
        );
        assert_eq!(c.window_m, 0.005);
        // Without the section: none.
        let plain = CellFile::parse(MINIMAL, "cell.toml", dir.clone()).unwrap();
        assert!(plain.feedforward(&robot).unwrap().is_none());
        // Failed points, a missing file: the file and the line or the field named.
        let e = with("table = \"failed.csv\"\n")
            .unwrap()
            .feedforward(&robot)
            .unwrap_err()
            .to_string();
        assert!(
            e.contains("feedforward.table")
                && e.contains("failed.csv:5")
                && e.contains("out_of_reach"),
            "{e}"
        );
        let e = with("table = \"missing.csv\"\n")
            .unwrap()
            .feedforward(&robot)
            .unwrap_err()
            .to_string();
        assert!(e.contains("missing.csv"), "{e}");
        for (extra, field) in [
            (
                "table = \"good.csv\"\nmode = \"twice\"\n",
                "feedforward.mode",
            ),
            (
                "table = \"good.csv\"\nindex = \"angle\"\n",
                "feedforward.index",
            ),
            ("table = \"good.csv\"\nlead_s = 5.0\n", "feedforward.lead_s"),
            ("table = \"good.csv\"\nlead_s = nan\n", "feedforward.lead_s"),
            (
                "table = \"good.csv\"\nmax_offset_m = 0.0\n",
                "feedforward.max_offset_m",
            ),
            (
                "table = \"good.csv\"\nwindow_m = 1e9\n",
                "feedforward.window_m",
            ),
            (
                "table = \"good.csv\"\ntime_offset_s = -1.0\n",
                "feedforward.time_offset_s",
            ),
            (
                "table = \"good.csv\"\nmode = \"precompensated\"\nlead_s = 0.02\n",
                "feedforward.lead_s",
            ),
            ("table = \" \"\n", "feedforward.table"),
            ("mode = \"feed-forward\"\n", "table"),
        ] {
            let e = with(extra)
                .err()
                .unwrap_or_else(|| panic!("accepted: {extra}"))
                .to_string();
            assert!(
                e.contains("cell.toml") && e.contains(field),
                "{extra} → {e}"
            );
        }
        let _ = std::fs::remove_dir_all(&dir);
    }

    /// docs/cell.example.toml documents every key of every section (read from this file's
    /// struct definitions, so a new key without documentation fails here).
    #[test]
    fn the_example_documents_every_key() {
        let source = include_str!("config.rs");
        let example = include_str!("../../../docs/cell.example.toml");
        let mut in_section = false;
        let mut checked = 0;
        for line in source.lines() {
            if line.starts_with("pub struct ") && line.contains("Section") {
                in_section = true;
            } else if line.starts_with('}') {
                in_section = false;
            } else if in_section
                && let Some(rest) = line.trim().strip_prefix("pub ")
                && let Some((name, _)) = rest.split_once(':')
            {
                let documented = example
                    .lines()
                    .any(|l| l.trim_start_matches("# ").starts_with(&format!("{name} =")));
                assert!(
                    documented,
                    "docs/cell.example.toml does not document `{name}`"
                );
                checked += 1;
            }
        }
        assert!(checked > 40, "{checked}");
    }
}
