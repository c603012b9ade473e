//! The link factory, both sides of a `CELL.toml` in one place:
//!
//! * the **controller side** (`deflex run`): the robot link of `robot.kind` bound on
//!   `robot.bind`, with its peer lock, answer kind (RSI `RKorr` or joint `AK`/`AKorr`) and
//!   correction frame (EGM), and the Net F/T client of `[sensor]`;
//! * the **robot side** (`deflex cell --sim`, tests): the robot controller of `robot.kind` as a
//!   simulated cell plays it, sending its state towards `robot.bind` ([`RobotSide`]), and a
//!   Net F/T server answering on `sensor.address`.
//!
//! Both sides read the same settings (RSI correction mode, EGM frame and seven-axis layout,
//! Stäubli watchdog = the robot timeout, Net F/T scaling), so a simulated cell and `deflex run`
//! agree on the protocol by construction.

use crate::cell::config::{CellFile, RobotKind, RsiAnswerKind, SensorKind};
use crate::cell::stream_path::{StreamPathError, stream_trajectory};
use deflex_io::egm::{EgmConfig, EgmLink};
use deflex_io::fanuc_stream::link::{DEFAULT_CORRECTION_SHARE, FanucStreamConfig, FanucStreamLink};
use deflex_io::fanuc_stream::motion::{StreamLimits, StreamTrajectory};
use deflex_io::netft::{NetFtCalibration, NetFtClient, NetFtSensorServer};
use deflex_io::robot_side::{RobotSide, StreamSide};
use deflex_io::rsi::{CorrectionMode, RsiAnswer, RsiConfig, RsiLink};
use deflex_io::rtde::{PathOffsetModel, RtdeLink, RtdeLinkConfig, RtdeSensor};
use deflex_io::simple_tcp::SimpleTcpLink;
use deflex_io::simple_udp::{ReplyStyle, SimpleUdpLink};
use deflex_io::staubli::StaubliLink;
use deflex_io::{ForceSensorLink, LinkError, PeerPolicy, RobotLink};
use deflex_model::spatial::rotation_from_rpy;
use deflex_sim::twin::cell_server::CellSides;
use std::net::SocketAddr;
use std::time::Duration;

/// How long `deflex run` retries a refused connection to a UR controller's RTDE server (the
/// controller booting, `deflex cell --sim` starting).
pub const RTDE_CONNECT_WAIT: Duration = Duration::from_secs(10);

/// An RTDE address with port 0 replaced by the controller's RTDE port 30004.
fn with_rtde_port(mut a: SocketAddr) -> SocketAddr {
    if a.port() == 0 {
        a.set_port(deflex_io::rtde::DEFAULT_PORT);
    }
    a
}

/// Why the ends of a simulated cell could not be made from a `CELL.toml`.
#[derive(Debug, thiserror::Error)]
pub enum CellSidesError {
    /// The CELL.toml's model cannot be loaded.
    #[error("{origin}: model.file: {error}")]
    Model {
        /// The CELL.toml.
        origin: String,
        /// Why.
        error: deflex_model::ModelError,
    },
    /// The twin refuses its settings.
    #[error(transparent)]
    Twin(#[from] deflex_sim::SimError),
    /// `sensor.kind = "ur-rtde"` without the UR controller that streams it.
    #[error(
        "{origin}: sensor.kind = \"ur-rtde\": the simulated cell streams the flange sensor from \
         its UR controller only: set robot.kind = \"ur-rtde\" and sensor.address = robot.peer \
         ({robot})"
    )]
    UrSensorWithoutUrRobot {
        /// The CELL.toml.
        origin: String,
        /// The controller's address.
        robot: SocketAddr,
    },
}

impl CellFile {
    /// The ends of the simulated cell of this `CELL.toml` (`deflex cell --sim`) for the twin
    /// `twin`: the robot side of `robot.kind` for the robot the twin plays, the Net F/T server
    /// of `[sensor]` and the controller's model of `model.file`.
    pub fn cell_sides(&self, twin: &deflex_sim::CellConfig) -> Result<CellSides, CellSidesError> {
        let model =
            crate::load::load_robot(&self.model_spec()).map_err(|error| CellSidesError::Model {
                origin: self.origin.clone(),
                error,
            })?;
        let joints = twin.nominal_robot()?.joint_count();
        let sensor_over_rtde = self.sensor.kind == SensorKind::UrRtde;
        if sensor_over_rtde
            && (self.robot.kind != RobotKind::UrRtde
                || with_rtde_port(self.sensor.address) != self.robot_link_address())
        {
            return Err(CellSidesError::UrSensorWithoutUrRobot {
                origin: self.origin.clone(),
                robot: self.robot_link_address(),
            });
        }
        Ok(CellSides {
            sensor_over_rtde,
            origin: self.origin.clone(),
            robot: self.robot_side(joints),
            sensor_address: self.sensor.address,
            sensor_calibration: self.calibration(),
            model,
        })
    }

    /// The RSI correction mode of `robot.correction_mode`.
    pub fn rsi_mode(&self) -> CorrectionMode {
        self.robot.correction_mode
    }

    /// The RSI link settings of `[robot]`.
    pub fn rsi_config(&self) -> RsiConfig {
        let r = &self.robot;
        RsiConfig {
            sen_type: r.sen_type.clone(),
            estr: None,
            mode: r.correction_mode,
            answer: match r.rsi_answer {
                RsiAnswerKind::Cartesian => RsiAnswer::Cartesian,
                RsiAnswerKind::Joint => RsiAnswer::Joint(r.rsi_joint_tag),
            },
        }
    }

    /// The ABB EGM link settings of `[robot]`, for a model with `joint_count` joints (seven:
    /// ABB's seven-axis layout). The measurement age is one control period.
    pub fn egm_config(&self, joint_count: usize) -> EgmConfig {
        let r = &self.robot;
        EgmConfig {
            frame: r.egm_frame,
            sensor_in_tool: rotation_from_rpy(r.egm_sensor_rpy_rad),
            work_object_in_base: rotation_from_rpy(r.egm_work_object_rpy_rad),
            age_ms: (1000.0 / self.control.rate_hz).round().clamp(0.0, 1000.0) as u32,
            seven_axis: joint_count == 7,
        }
    }

    /// The Net F/T count scaling of `[sensor]`.
    pub fn calibration(&self) -> NetFtCalibration {
        NetFtCalibration {
            counts_per_force: self.sensor.counts_per_force,
            counts_per_torque: self.sensor.counts_per_torque,
        }
    }

    /// Controller side: binds the robot link of `robot.kind` on `robot.bind`, locked to
    /// `robot.peer` when set (otherwise to the first valid sender), for a model of
    /// `joint_count` joints.
    pub fn open_robot_link(
        &self,
        joint_count: usize,
    ) -> Result<Box<dyn RobotLink + Send>, LinkError> {
        let r = &self.robot;
        let policy = if r.kind == RobotKind::UrRtde {
            // deflex connects to the configured controller: no listener to lock.
            PeerPolicy::FirstLocalSender
        } else {
            self.peer_policy()?
        };
        Ok(match r.kind {
            RobotKind::KukaRsi => {
                let mut link = RsiLink::bind(r.bind, self.rsi_config())?;
                link.set_peer_policy(policy);
                Box::new(link)
            }
            RobotKind::AbbEgm => {
                let mut link = EgmLink::bind(r.bind, self.egm_config(joint_count))?;
                link.set_peer_policy(policy);
                Box::new(link)
            }
            RobotKind::Staubli => {
                let mut link = StaubliLink::bind(r.bind)?;
                link.set_peer_policy(policy);
                Box::new(link)
            }
            RobotKind::SimpleUdp => {
                let mut link = SimpleUdpLink::bind(r.bind, ReplyStyle::default())?;
                link.set_peer_policy(policy);
                Box::new(link)
            }
            RobotKind::SimpleTcp => {
                let mut link = SimpleTcpLink::bind(r.bind)?;
                link.set_peer_policy(policy);
                Box::new(link)
            }
            RobotKind::UrRtde => Box::new(RtdeLink::connect(
                self.robot_link_address(),
                RtdeLinkConfig {
                    register: r.rtde_register,
                    connect_wait: RTDE_CONNECT_WAIT,
                },
            )?),
            RobotKind::FanucStream => {
                let trajectory = self
                    .stream_trajectory()
                    .map_err(|_| LinkError::InvalidValue {
                        protocol: deflex_io::Protocol::FanucStream,
                        reason: "robot.stream_path cannot be streamed (CellFile::stream_trajectory \
                             says why)",
                    })?;
                let mut link = FanucStreamLink::bind(r.bind, self.stream_config()?, trajectory)?;
                // The controller's own limit tables, when it answers them (else the file's).
                link.query_thresholds(Duration::from_millis(200))?;
                Box::new(link)
            }
        })
    }

    /// FANUC Stream Motion: the link settings of `[robot]` (the controller at `robot.peer`,
    /// port 60015 when 0; the limits `robot.stream_*`; lost after `robot.timeout_s`, at least ten
    /// cycles; a late status after `robot.stream_late_after_s`, at least a cycle, else five
    /// cycles).
    pub fn stream_config(&self) -> Result<FanucStreamConfig, LinkError> {
        let r = &self.robot;
        let mut controller = r.peer.ok_or(LinkError::NoPeer {
            protocol: deflex_io::Protocol::FanucStream,
        })?;
        if controller.port() == 0 {
            controller.set_port(deflex_io::fanuc_stream::DEFAULT_PORT);
        }
        let mut cfg = FanucStreamConfig::new(controller, r.cycle_s);
        cfg.limits = self.stream_limits();
        cfg.lost_after = Duration::from_secs_f64(r.timeout_s.max(10.0 * r.cycle_s));
        if let Some(late) = r.stream_late_after_s {
            cfg.late_after = Duration::from_secs_f64(late.max(r.cycle_s));
        }
        Ok(cfg)
    }

    /// FANUC Stream Motion: the limits of `robot.stream_*`.
    pub fn stream_limits(&self) -> StreamLimits {
        let r = &self.robot;
        StreamLimits {
            velocity: r.stream_velocity_rad_s,
            acceleration: r.stream_acceleration_rad_s2,
            jerk: r.stream_jerk_rad_s3,
        }
    }

    /// FANUC Stream Motion: the trajectory of `robot.stream_path`, sampled at `robot.cycle_s`
    /// with `robot.stream_ramp_s`, within the path's share of the limits.
    pub fn stream_trajectory(&self) -> Result<StreamTrajectory, StreamPathError> {
        let r = &self.robot;
        let path = self
            .base_dir
            .join(r.stream_path.as_deref().unwrap_or_default());
        let share = 1.0 - DEFAULT_CORRECTION_SHARE;
        stream_trajectory(
            &path,
            r.cycle_s,
            r.stream_ramp_s,
            &self.stream_limits().scaled(share),
        )
    }

    /// Where the robot link is: `robot.bind`, or for `ur-rtde` the controller's RTDE address
    /// `robot.peer` (port 0: 30004) that deflex connects to.
    pub fn robot_link_address(&self) -> SocketAddr {
        match (self.robot.kind, self.robot.peer) {
            (RobotKind::UrRtde, Some(p)) => with_rtde_port(p),
            _ => self.robot.bind,
        }
    }

    /// The URScript program's path offset for `ur-rtde` (and the twin's model of it): the alpha
    /// filter of `robot.ur_alpha_filter`; a maximum offset of √3 times the per-axis limits of
    /// `[limits]` (the norm of the largest correction deflex sends, so the controller's limit is
    /// a second net that never cuts a correction deflex allows); the offset ramped out once the
    /// sequence register has not advanced for `robot.timeout_s`.
    pub fn path_offset_model(&self) -> PathOffsetModel {
        let cycles = (self.robot.timeout_s / deflex_io::rtde::server::CONTROLLER_PERIOD_S).ceil();
        PathOffsetModel::new(
            self.robot.ur_alpha_filter,
            self.limits.max_correction_m * 3f64.sqrt(),
            self.limits.max_correction_rad * 3f64.sqrt(),
            cycles.clamp(1.0, 1e6) as u32,
        )
    }

    /// The robot link's peer policy from `robot.peer`, `robot.bind` and `robot.allow_any_peer`
    /// ([`deflex_io::validate_peer`]; a loaded file has passed it already). Its
    /// [`PeerPolicy::warning`] is what a session without a peer prints at start.
    pub fn peer_policy(&self) -> Result<PeerPolicy, LinkError> {
        let r = &self.robot;
        deflex_io::validate_peer(r.bind, r.peer, r.allow_any_peer).map_err(LinkError::from)
    }

    /// Controller side: binds the sensor client of `[sensor]`. A ROS 2 sensor
    /// (`sensor.kind = "ros2"`) is opened by the `deflex-ros2` bridge, a layer above this one,
    /// and handed to [`crate::cell::cell_run::CellRun::start_with`]; here it is an error.
    pub fn open_sensor_link(&self) -> Result<Box<dyn ForceSensorLink + Send>, LinkError> {
        Ok(match self.sensor.kind {
            SensorKind::Netft => Box::new(NetFtClient::new(
                self.sensor.bind,
                self.sensor.address,
                self.calibration(),
            )?),
            SensorKind::UrRtde => Box::new(RtdeSensor::connect(
                with_rtde_port(self.sensor.address),
                RTDE_CONNECT_WAIT,
            )?),
            SensorKind::Ros2 => {
                return Err(LinkError::InvalidValue {
                    protocol: deflex_io::Protocol::Ros2,
                    reason: "sensor.kind = \"ros2\" is opened by the ROS 2 bridge (deflex-ros2)",
                });
            }
        })
    }

    /// Robot side: the settings of the robot controller of `robot.kind` as a simulated cell
    /// plays it, for a robot of `joint_count` joints, sending its state to `robot.bind`.
    pub fn robot_side(&self, joint_count: usize) -> RobotSide {
        RobotSide {
            kind: self.robot.kind,
            controller: self.robot_link_address(),
            rsi_mode: self.rsi_mode(),
            egm: self.egm_config(joint_count),
            // The VAL3 program's watchdog: the robot's own timeout.
            staubli_watchdog: Duration::from_secs_f64(self.robot.timeout_s.clamp(1e-3, 10.0)),
            rtde_register: self.robot.rtde_register,
            path_offset: self.path_offset_model(),
            // FANUC Stream Motion: the controller listens at `robot.peer` (port 0: 60015).
            stream: (self.robot.kind == RobotKind::FanucStream)
                .then_some(self.robot.peer)
                .flatten()
                .map(|mut address| {
                    if address.port() == 0 {
                        address.set_port(deflex_io::fanuc_stream::DEFAULT_PORT);
                    }
                    StreamSide {
                        address,
                        period_s: self.robot.cycle_s,
                        limits: self.stream_limits(),
                    }
                }),
        }
    }

    /// Sensor side: a Net F/T server answering on `sensor.address` with the scaling of
    /// `[sensor]`.
    pub fn open_sensor_server(&self) -> Result<NetFtSensorServer, LinkError> {
        NetFtSensorServer::bind(self.sensor.address, self.calibration())
    }
}
