//! The sections of `CELL.toml`, one struct each, with their keys. Every choice is an enum
//! (deserialised from its documented kebab-case name, anything else refused with the choices
//! listed); every key that may be left out has its default in the section's [`Default`] impl;
//! the keys without a default are in [`REQUIRED_KEYS`]. `docs/cell.example.toml` documents
//! every key (a test reads this file to check it).

use super::choices::{
    CorrectionAxis, CorrectionModeDef, EgmFrameDef, FeedForwardModeDef, JointTagDef, PathIndexDef,
    RobotKind, Ros2Qos, Ros2Topic, RsiAnswerKind, RunawayActionDef, SafeActionDef, SensorKind,
};
use deflex_control::{
    FeedForwardConfig, FeedForwardMode, LimiterConfig, ModelCheckConfig, PathIndex, PidGains,
    RunawayAction, RunawayConfig, SafeAction, SafetyConfig,
};
use deflex_io::egm::EgmFrame;
use deflex_io::rsi::{CorrectionMode, JointTag};
use serde::Deserialize;
use std::net::SocketAddr;

/// Keys that have no default, `(section, key)`: a file that leaves one out is refused naming it.
pub const REQUIRED_KEYS: &[(&str, &str)] = &[
    ("robot", "kind"),
    ("robot", "bind"),
    ("sensor", "kind"),
    ("sensor", "address"),
    ("model", "file"),
    ("feedforward", "table"),
    ("log", "path"),
];

/// `[robot]`: the robot link.
#[derive(Clone, Debug, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct RobotSection {
    /// Protocol (required).
    pub kind: RobotKind,
    /// Local address the controller listens on (e.g. `0.0.0.0:59152` for RSI; required, except
    /// for `ur-rtde`, where deflex connects to the robot and does not listen).
    pub bind: SocketAddr,
    /// The robot controller's address: the link answers only it (port 0: any port of that
    /// IP; the simple TCP link compares the IP only). Absent: the link locks to the first host
    /// that sends a valid telegram, for the whole session. For `ur-rtde` (required): the
    /// controller's RTDE server that deflex connects to (port 0: 30004).
    pub peer: Option<SocketAddr>,
    /// Without `peer`, let the first host on the network that sends a valid message own the
    /// session (default `false`: a network `bind` without `peer` is refused; a loopback `bind`
    /// without `peer` accepts the first local sender, with a warning at start).
    pub allow_any_peer: bool,
    /// RSI correction interpretation: `absolute` (default) or `relative`.
    #[serde(with = "CorrectionModeDef")]
    pub correction_mode: CorrectionMode,
    /// RSI `<Sen Type>`.
    pub sen_type: String,
    /// RSI answers: `cartesian` (`RKorr`, default) or `joint` (`AK`, joint corrections from the
    /// Cartesian one through the model's Jacobian).
    pub rsi_answer: RsiAnswerKind,
    /// Element of joint answers: `AK` (default, the ROS-Industrial set-ups) or `AKorr`.
    #[serde(with = "JointTagDef")]
    pub rsi_joint_tag: JointTag,
    /// ABB EGM: frame of `pathCorr`: `tool` (default: the sensor frame of `EGMActMove`,
    /// attached to the tool), `work-object` or `base`.
    #[serde(with = "EgmFrameDef")]
    pub egm_frame: EgmFrame,
    /// ABB EGM: orientation of `EGMActMove`'s sensor frame in the tool frame (roll, pitch, yaw,
    /// rad), for `egm_frame = "tool"`.
    pub egm_sensor_rpy_rad: [f64; 3],
    /// ABB EGM: orientation of the work object in the robot base frame (roll, pitch, yaw, rad),
    /// for `egm_frame = "work-object"`.
    pub egm_work_object_rpy_rad: [f64; 3],
    /// Robot interpolation cycle (s), the reply deadline: 0.004 for RSI.
    pub cycle_s: f64,
    /// Silence after which the robot link counts as lost (s).
    pub timeout_s: f64,
    /// FANUC Stream Motion: the compensated path deflex streams (`compensated_path.csv` of
    /// `deflex compensate`, relative to the CELL.toml; required for `fanuc-stream`).
    pub stream_path: Option<String>,
    /// FANUC Stream Motion: joint velocity limits, axes 1–6 (rad/s; the controller's tables may
    /// tighten them).
    pub stream_velocity_rad_s: [f64; 6],
    /// FANUC Stream Motion: joint acceleration limits (rad/s²).
    pub stream_acceleration_rad_s2: [f64; 6],
    /// FANUC Stream Motion: joint jerk limits (rad/s³).
    pub stream_jerk_rad_s3: [f64; 6],
    /// FANUC Stream Motion: the path's start and stop ramps (s).
    pub stream_ramp_s: f64,
    /// `ur-rtde`: the first register of the correction: `input_double_register_N … N+5` (m, rad,
    /// base axes), `input_int_register_N` (sequence), `output_int_register_N` (the script's
    /// heartbeat); 24–42 (RTDE clients own 24–47). The URScript program's `REG` must match.
    pub rtde_register: u8,
    /// `ur-rtde`: the alpha of `path_offset_set_alpha_filter` in the URScript program (0.001–1,
    /// 1 = no filter): `applied = alpha · register + (1 − alpha) · applied` every 2 ms.
    pub ur_alpha_filter: f64,
    /// FANUC Stream Motion: a status later than this after the previous one stops the stream
    /// (s); `None`: five cycles.
    pub stream_late_after_s: Option<f64>,
}

impl Default for RobotSection {
    /// The defaults of the optional keys (`kind` and `bind` are required, [`REQUIRED_KEYS`]).
    fn default() -> Self {
        RobotSection {
            kind: RobotKind::KukaRsi,
            bind: SocketAddr::from(([0, 0, 0, 0], 59152)),
            peer: None,
            allow_any_peer: false,
            correction_mode: CorrectionMode::Absolute,
            sen_type: "ImFree".into(),
            rsi_answer: RsiAnswerKind::Cartesian,
            rsi_joint_tag: JointTag::Ak,
            egm_frame: EgmFrame::Tool,
            egm_sensor_rpy_rad: [0.0; 3],
            egm_work_object_rpy_rad: [0.0; 3],
            cycle_s: 0.004,
            timeout_s: SafetyConfig::default().robot_timeout_s,
            stream_path: None,
            stream_velocity_rad_s: [1.0; 6],
            stream_acceleration_rad_s2: [5.0; 6],
            stream_jerk_rad_s3: [100.0; 6],
            stream_ramp_s: 0.5,
            rtde_register: 24,
            ur_alpha_filter: 0.5,
            stream_late_after_s: None,
        }
    }
}

/// `[sensor]`: the force/torque sensor link.
#[derive(Clone, Debug, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct SensorSection {
    /// Protocol (required).
    pub kind: SensorKind,
    /// Sensor address (`<ip>:49152` for a Net F/T; the controller's RTDE address `<ip>:30004`
    /// for `ur-rtde`; required).
    pub address: SocketAddr,
    /// Local address (default: any port on all interfaces).
    pub bind: SocketAddr,
    /// Counts per newton.
    pub counts_per_force: f64,
    /// Counts per newton-metre.
    pub counts_per_torque: f64,
    /// Silence after which the sensor counts as lost (s).
    pub timeout_s: f64,
    /// Range of each channel `[fx, fy, fz, mx, my, mz]` (N, N·m); beyond it a reading is garbage.
    pub range: [f64; 6],
    /// `ros2` only: the `geometry_msgs/WrenchStamped` topic (an absolute ROS name).
    pub topic: String,
    /// `ros2` only: a message whose stamp is older than this (or as far in the future), on
    /// this machine's clock, is refused as stale (s).
    pub max_age_s: f64,
    /// `ros2` only: messages held between the DDS reader and the sensor thread (and the DDS
    /// reader's history depth); beyond, the oldest is dropped and counted.
    pub queue_depth: usize,
}

impl Default for SensorSection {
    /// The defaults of the optional keys (`kind` and `address` are required).
    fn default() -> Self {
        SensorSection {
            kind: SensorKind::Netft,
            address: SocketAddr::from(([0, 0, 0, 0], 49152)),
            bind: SocketAddr::from(([0, 0, 0, 0], 0)),
            counts_per_force: 1_000_000.0,
            counts_per_torque: 1_000_000.0,
            timeout_s: SafetyConfig::default().sensor_timeout_s,
            range: SafetyConfig::default().sensor_range,
            topic: "/ft_sensor/wrench".into(),
            max_age_s: 0.05,
            queue_depth: 16,
        }
    }
}

/// `[mounting]`: sensor pose on the flange and the tool beyond it.
#[derive(Clone, Debug, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct MountingSection {
    /// Sensor origin in the flange frame (m).
    pub sensor_xyz_m: [f64; 3],
    /// Sensor orientation in the flange frame, roll–pitch–yaw (rad).
    pub sensor_rpy_rad: [f64; 3],
    /// Tool mass beyond the sensor (kg).
    pub tool_mass_kg: f64,
    /// Tool centre of mass in the sensor frame (m).
    pub tool_com_m: [f64; 3],
    /// Gravity in world axes (m/s²).
    pub gravity_m_s2: [f64; 3],
    /// Known bias (sensor frame, gravity excluded); when absent a tare is taken at start.
    pub bias: Option<[f64; 6]>,
    /// Tare duration at start, out of contact (s).
    pub tare_s: f64,
    /// Low-pass cut-off on the wrench (Hz); absent = off.
    pub lowpass_hz: Option<f64>,
}

impl Default for MountingSection {
    /// Sensor at the flange, no tool, standard gravity along −z, a tare of 0.2 s, no low-pass.
    fn default() -> Self {
        MountingSection {
            sensor_xyz_m: [0.0; 3],
            sensor_rpy_rad: [0.0; 3],
            tool_mass_kg: 0.0,
            tool_com_m: [0.0; 3],
            gravity_m_s2: [0.0, 0.0, -deflex_control::wrench::STANDARD_GRAVITY],
            bias: None,
            tare_s: 0.2,
            lowpass_hz: None,
        }
    }
}

/// `[model]`: the calibrated elasto-geometrical model.
#[derive(Clone, Debug, Default, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct ModelSection {
    /// Model TOML/URDF path (relative to the config file) or a built-in name (required).
    pub file: String,
}

/// `[control]`: the law of eq. 17.
#[derive(Clone, Debug, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct ControlSection {
    /// Control rate (Hz).
    pub rate_hz: f64,
    /// K_c.
    pub kc: f64,
    /// T_i (s).
    pub ti_s: f64,
    /// T_d (s).
    pub td_s: f64,
    /// Derivative filter ratio N (T_f = T_d/N).
    pub derivative_filter_n: f64,
    /// Corrected axes, any of `x y z rx ry rz`.
    pub axes: Vec<CorrectionAxis>,
    /// Try SCHED_FIFO for the loop threads.
    pub realtime: bool,
    /// Also lock memory (mlockall).
    pub lock_memory: bool,
}

impl Default for ControlSection {
    /// 100 Hz, the paper's gains ([`PidGains::default`]), every axis, real-time scheduling and
    /// locked memory tried.
    fn default() -> Self {
        let gains = PidGains::default();
        ControlSection {
            rate_hz: 100.0,
            kc: gains.kc,
            ti_s: gains.ti_s,
            td_s: gains.td_s,
            derivative_filter_n: gains.derivative_filter_n,
            axes: CorrectionAxis::ALL.to_vec(),
            realtime: true,
            lock_memory: true,
        }
    }
}

/// `[limits]`: limiter and safety.
#[derive(Clone, Debug, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct LimitsSection {
    /// Largest |ξ| per position axis (m).
    pub max_correction_m: f64,
    /// Largest |ξ| per rotation axis (rad).
    pub max_correction_rad: f64,
    /// Largest rate per position axis (m/s).
    pub max_rate_m_s: f64,
    /// Largest rate per rotation axis (rad/s).
    pub max_rate_rad_s: f64,
    /// Ramp-in duration (s).
    pub ramp_in_s: f64,
    /// Ramp-out duration (s).
    pub ramp_out_s: f64,
    /// Force norm limit at the TCP (N).
    pub max_force_n: f64,
    /// Torque norm limit at the TCP (N·m).
    pub max_torque_nm: f64,
    /// Largest joint change per control cycle (rad).
    pub max_joint_step_rad: f64,
    /// `zero` (ramp ξ to 0, default) or `hold`.
    #[serde(with = "SafeActionDef")]
    pub safe_action: SafeAction,
    /// Watch for contact runaway (stiff contact making the correction positive feedback).
    pub runaway_guard: bool,
    /// Estimated loop gain through the contact above which the guard acts.
    pub runaway_gain_limit: f64,
    /// Estimated loop gain below which the guard releases its hold.
    pub runaway_release_gain: f64,
    /// Forgetting time of the guard's estimate (s).
    pub runaway_window_s: f64,
    /// Motion along the corrected direction needed to trust the estimate (m).
    pub runaway_min_travel_m: f64,
    /// Consecutive control cycles above the limit before the guard acts.
    pub runaway_confirm_cycles: u32,
    /// Duration of the guard's withdrawal ramp (s).
    pub runaway_withdraw_s: f64,
    /// Rate at which a released hold gives the correction back (m/s).
    pub runaway_release_rate_m_s: f64,
    /// `withdraw` (ramp the correction along its direction to zero, warn; default), `hold` (stop
    /// it growing, warn) or `fault`.
    #[serde(with = "RunawayActionDef")]
    pub runaway_action: RunawayAction,
}

impl Default for LimitsSection {
    /// The limiter's, the supervision's and the runaway guard's defaults
    /// ([`LimiterConfig::default`], [`SafetyConfig::default`], [`RunawayConfig::default`]), with
    /// 0.5 s ramps.
    fn default() -> Self {
        let limiter = LimiterConfig::default();
        let safety = SafetyConfig::default();
        let runaway = RunawayConfig::default();
        LimitsSection {
            max_correction_m: limiter.max_abs[0],
            max_correction_rad: limiter.max_abs[3],
            max_rate_m_s: limiter.max_rate[0],
            max_rate_rad_s: limiter.max_rate[3],
            ramp_in_s: 0.5,
            ramp_out_s: 0.5,
            max_force_n: safety.max_force_n,
            max_torque_nm: safety.max_torque_nm,
            max_joint_step_rad: safety.max_joint_step_rad,
            safe_action: SafeAction::Zero,
            runaway_guard: runaway.enabled,
            runaway_gain_limit: runaway.gain_limit,
            runaway_release_gain: runaway.release_gain,
            runaway_window_s: runaway.window_s,
            runaway_min_travel_m: runaway.min_travel_m,
            runaway_confirm_cycles: runaway.confirm_cycles,
            runaway_withdraw_s: runaway.withdraw_s,
            runaway_release_rate_m_s: runaway.release_rate_m_s,
            runaway_action: runaway.action,
        }
    }
}

/// `[model_check]`: the TCP pose the robot reports (KUKA RSI `RIst`, ABB EGM feedback, UR RTDE `actual_TCP_pose`) against
/// the model's forward kinematics at the same joints ([`deflex_control::model_check`]).
#[derive(Clone, Debug, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct ModelCheckSection {
    /// Make the check (where the protocol reports a pose).
    pub enabled: bool,
    /// Largest distance between the reported TCP and the model's (m).
    pub position_tolerance_m: f64,
    /// Largest rotation between the reported TCP orientation and the model's (rad).
    pub orientation_tolerance_rad: f64,
}

impl Default for ModelCheckSection {
    /// On, 5 mm, 10 mrad ([`ModelCheckConfig::default`]).
    fn default() -> Self {
        let c = ModelCheckConfig::default();
        ModelCheckSection {
            enabled: c.enabled,
            position_tolerance_m: c.position_tolerance_m,
            orientation_tolerance_rad: c.orientation_tolerance_rad,
        }
    }
}

/// `[feedforward]`: the online correction on top of an offline compensation
/// ([`deflex_control::feedforward`]).
#[derive(Clone, Debug, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct FeedForwardSection {
    /// `compensated_path.csv` of `deflex compensate` (relative to the config file; required).
    pub table: String,
    /// `feed-forward` (the robot runs the original program; default) or `precompensated` (the
    /// robot runs the compensated program).
    #[serde(with = "FeedForwardModeDef")]
    pub mode: FeedForwardMode,
    /// `arc-length` (default) or `time`.
    #[serde(with = "PathIndexDef")]
    pub index: PathIndex,
    /// Feed-forward mode: read the table this much path time ahead (s).
    pub lead_s: f64,
    /// Farther than this from the path, the TCP is off the path (m).
    pub max_offset_m: f64,
    /// Arc length searched ahead per control cycle (m).
    pub window_m: f64,
    /// Time index: the table's time at the controller's start (s).
    pub time_offset_s: f64,
}

impl Default for FeedForwardSection {
    /// The feed-forward's defaults ([`FeedForwardConfig::default`]; `table` is required).
    fn default() -> Self {
        let c = FeedForwardConfig::default();
        FeedForwardSection {
            table: String::new(),
            mode: c.mode,
            index: c.index,
            lead_s: c.lead_s,
            max_offset_m: c.max_offset_m,
            window_m: c.window_m,
            time_offset_s: c.time_offset_s,
        }
    }
}

/// `[log]`.
#[derive(Clone, Debug, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct LogSection {
    /// CSV path (relative to the config file; required).
    pub path: String,
    /// Capacity of the telemetry ring the log reads from (control cycles).
    pub ring_capacity: usize,
}

impl Default for LogSection {
    /// 8192 cycles (82 s at 100 Hz) of telemetry held for the log writer (`path` is required).
    fn default() -> Self {
        LogSection {
            path: String::new(),
            ring_capacity: 8192,
        }
    }
}

/// `[ros2]`: deflex on the ROS 2 graph (the `deflex-ros2` bridge). Present: `deflex run`
/// publishes `topics` under `namespace`; needed by `sensor.kind = "ros2"`.
#[derive(Clone, Debug, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct Ros2Section {
    /// DDS domain (`ROS_DOMAIN_ID`).
    pub domain_id: u16,
    /// Namespace of the topics and of the node (an absolute ROS name, `/` for none).
    pub namespace: String,
    /// Node name.
    pub node_name: String,
    /// QoS profile of the published topics and of the sensor subscription.
    pub qos: Ros2Qos,
    /// History depth of the QoS (keep last).
    pub depth: usize,
    /// Rate of the published cycle topics (Hz); the bridge sends the newest cycle at most this
    /// often (at most the control rate).
    pub publish_rate_hz: f64,
    /// Rate of `diagnostics` between changes of phase, flags or fault (Hz).
    pub diagnostics_rate_hz: f64,
    /// The topics published.
    pub topics: Vec<Ros2Topic>,
    /// Frame id of the robot base (positions, TCP wrench, δŝ, ξ).
    pub base_frame: String,
    /// Frame id of the F/T sensor (raw and compensated wrench; the frame `sensor.kind = "ros2"`
    /// expects in the messages it takes).
    pub sensor_frame: String,
    /// Frame id of the TCP.
    pub tcp_frame: String,
}

impl Default for Ros2Section {
    /// Domain 0, namespace `/deflex`, node `deflex`, sensor-data QoS of depth 10, 100 Hz,
    /// diagnostics at 10 Hz, every topic, frames `base`, `ft_sensor`, `tcp`.
    fn default() -> Self {
        Ros2Section {
            domain_id: 0,
            namespace: "/deflex".into(),
            node_name: "deflex".into(),
            qos: Ros2Qos::SensorData,
            depth: 10,
            publish_rate_hz: 100.0,
            diagnostics_rate_hz: 10.0,
            topics: Ros2Topic::ALL.to_vec(),
            base_frame: "base".into(),
            sensor_frame: "ft_sensor".into(),
            tcp_frame: "tcp".into(),
        }
    }
}
