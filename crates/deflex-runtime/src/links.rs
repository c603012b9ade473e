//! The link factory, both sides of a `CELL.toml` in one place:
//!
//! * the **controller side** (`deflex run`): the robot link of `robot.kind` bound on
//!   `robot.bind`, with its peer lock, answer kind (RSI `RKorr` or joint `AK`/`AKorr`) and
//!   correction frame (EGM), and the Net F/T client of `[sensor]`;
//! * the **robot side** (`deflex cell --sim`, tests): the robot controller of `robot.kind` as a
//!   simulated cell plays it, sending its state towards `robot.bind` ([`RobotEndpoint`]), and a
//!   Net F/T server answering on `sensor.address`.
//!
//! Both sides read the same settings (RSI correction mode, EGM frame and seven-axis layout,
//! Stäubli watchdog = the robot timeout, Net F/T scaling), so a simulated cell and `deflex run`
//! agree on the protocol by construction.

use crate::config::{CellFile, RobotKind, RsiAnswerKind, SensorKind};
use deflex_io::egm::{EgmConfig, EgmLink, EgmRobotEndpoint};
use deflex_io::netft::{Calibration, NetFtClient, NetFtSensorServer};
use deflex_io::rsi::{CorrectionMode, RsiAnswer, RsiConfig, RsiLink, RsiRobotEndpoint};
use deflex_io::simple_tcp::{SimpleTcpLink, SimpleTcpRobotEndpoint};
use deflex_io::simple_udp::{ReplyStyle, SimpleUdpLink, SimpleUdpRobotEndpoint};
use deflex_io::staubli::{StaubliLink, StaubliRobotEndpoint};
use deflex_io::{
    ForceSensorLink, LinkError, PeerPolicy, ReceivedCorrection, RobotLink, RobotSideLink,
    RobotState,
};
use deflex_model::spatial::pose_from_xyz_rpy;
use std::sync::atomic::{AtomicBool, Ordering};
use std::time::{Duration, Instant};

fn rotation_rows(rpy: [f64; 3]) -> [[f64; 3]; 3] {
    let m = *pose_from_xyz_rpy([0.0; 3], rpy).rotation.matrix();
    std::array::from_fn(|i| std::array::from_fn(|j| m[(i, j)]))
}

impl CellFile {
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
            sensor_in_tool: rotation_rows(r.egm_sensor_rpy_rad),
            work_object_in_base: rotation_rows(r.egm_work_object_rpy_rad),
            age_ms: (1000.0 / self.control.rate_hz).round().clamp(0.0, 1000.0) as u32,
            seven_axis: joint_count == 7,
        }
    }

    /// The Net F/T count scaling of `[sensor]`.
    pub fn calibration(&self) -> Calibration {
        Calibration {
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
        let policy = self.peer_policy()?;
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
        })
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
    /// and handed to [`crate::CellRun::start_with`]; here it is an error.
    pub fn open_sensor_link(&self) -> Result<Box<dyn ForceSensorLink + Send>, LinkError> {
        Ok(match self.sensor.kind {
            SensorKind::Netft => Box::new(NetFtClient::new(
                self.sensor.bind,
                self.sensor.address,
                self.calibration(),
            )?),
            SensorKind::Ros2 => {
                return Err(LinkError::InvalidValue {
                    protocol: deflex_io::Protocol::Ros2,
                    reason: "sensor.kind = \"ros2\" is opened by the ROS 2 bridge (deflex-ros2)",
                });
            }
        })
    }

    /// Robot side: the robot controller of `robot.kind` for a robot of `joint_count` joints,
    /// bound on an ephemeral loopback port and sending its state to `robot.bind`. A simple TCP
    /// robot (a UR script) connects to the controller: it retries for up to `wait` until
    /// `deflex run` listens, or until `stop` is set.
    pub fn open_robot_endpoint(
        &self,
        joint_count: usize,
        wait: Duration,
        stop: &AtomicBool,
    ) -> Result<RobotEndpoint, LinkError> {
        let pc = self.robot.bind;
        let local = "127.0.0.1:0";
        let link = match self.robot.kind {
            RobotKind::KukaRsi => {
                EndpointLink::Other(Box::new(RsiRobotEndpoint::new(local, pc, self.rsi_mode())?))
            }
            RobotKind::AbbEgm => {
                let config = self.egm_config(joint_count);
                let mut ep = EgmRobotEndpoint::new(local, pc)?;
                ep.set_seven_axis(config.seven_axis);
                EndpointLink::Egm(Box::new(ep), config)
            }
            // The VAL3 program's watchdog: the robot's own timeout.
            RobotKind::Staubli => EndpointLink::Other(Box::new(StaubliRobotEndpoint::new(
                local,
                pc,
                Duration::from_secs_f64(self.robot.timeout_s.clamp(1e-3, 10.0)),
            )?)),
            RobotKind::SimpleUdp => {
                EndpointLink::Other(Box::new(SimpleUdpRobotEndpoint::new(local, pc)?))
            }
            RobotKind::SimpleTcp => {
                let start = Instant::now();
                loop {
                    match SimpleTcpRobotEndpoint::connect(pc, Duration::from_millis(200)) {
                        Ok(ep) => break EndpointLink::Other(Box::new(ep)),
                        Err(e) if start.elapsed() > wait || stop.load(Ordering::SeqCst) => {
                            return Err(e);
                        }
                        Err(_) => std::thread::sleep(Duration::from_millis(50)),
                    }
                }
            }
        };
        Ok(RobotEndpoint {
            kind: self.robot.kind,
            link,
        })
    }

    /// Sensor side: a Net F/T server answering on `sensor.address` with the scaling of
    /// `[sensor]`.
    pub fn open_sensor_server(&self) -> Result<NetFtSensorServer, LinkError> {
        NetFtSensorServer::bind(self.sensor.address, self.calibration())
    }
}

enum EndpointLink {
    Egm(Box<EgmRobotEndpoint>, EgmConfig),
    Other(Box<dyn RobotSideLink + Send>),
}

/// The robot side of a `CELL.toml`: a robot controller of `robot.kind` as a simulated cell plays
/// it ([`CellFile::open_robot_endpoint`]).
pub struct RobotEndpoint {
    kind: RobotKind,
    link: EndpointLink,
}

impl RobotEndpoint {
    /// The protocol.
    pub fn kind(&self) -> RobotKind {
        self.kind
    }

    /// The link.
    pub fn link(&mut self) -> &mut dyn RobotSideLink {
        match &mut self.link {
            EndpointLink::Egm(l, _) => l.as_mut(),
            EndpointLink::Other(l) => l.as_mut(),
        }
    }

    /// Whether replies echo the state's cycle id ([`RobotKind::echoes_cycle`]).
    pub fn echoes_cycle(&self) -> bool {
        self.kind.echoes_cycle()
    }

    /// What the robot controller knows of its own tool: the TCP orientation in base axes. An
    /// ABB controller expresses the corrections it receives in the frame `robot.egm_frame`
    /// (which follows the tool); the other protocols do not need it.
    pub fn set_tcp_rotation(&mut self, tcp_in_base: &[[f64; 3]; 3]) {
        if let EndpointLink::Egm(ep, config) = &mut self.link {
            ep.set_correction_frame(&config.correction_frame(tcp_in_base));
        }
    }

    /// Sends the robot's state.
    pub fn send_state(&mut self, state: &RobotState) -> Result<(), LinkError> {
        self.link().send_state(state)
    }

    /// Waits up to `wait` for a correction.
    pub fn receive(&mut self, wait: Duration) -> Result<Option<ReceivedCorrection>, LinkError> {
        self.link().receive_correction(wait)
    }
}
