//! The robot side of every robot protocol: the robot controller as a simulated cell plays it
//! ([`RobotEndpoint`], opened from [`RobotSide`]), sending its state to the controller and
//! receiving its corrections, with the same settings as the controller side so that both agree
//! on the protocol by construction.

use crate::egm::{EgmConfig, EgmRobotEndpoint};
use crate::fanuc_stream::motion::StreamLimits;
use crate::fanuc_stream::robot::FanucStreamRobotEndpoint;
use crate::rsi::{CorrectionMode, RsiRobotEndpoint};
use crate::rtde::{PathOffsetModel, RtdeRobotEndpoint};
use crate::simple_tcp::SimpleTcpRobotEndpoint;
use crate::simple_udp::SimpleUdpRobotEndpoint;
use crate::staubli::StaubliRobotEndpoint;
use crate::{LinkError, ReceivedCorrection, RobotSideLink, RobotState};
use serde::Deserialize;
use std::net::SocketAddr;
use std::sync::atomic::{AtomicBool, Ordering};
use std::time::{Duration, Instant};

/// Robot protocol (`robot.kind`).
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
    /// FANUC Stream Motion (J519): deflex streams the joints ([`crate::fanuc_stream`]).
    FanucStream,
    /// Universal Robots RTDE (deflex connects to the controller's port 30004; a URScript
    /// program applies the correction through `path_offset`).
    UrRtde,
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
            RobotKind::FanucStream => "FANUC Stream Motion",
            RobotKind::UrRtde => "UR RTDE",
        }
    }

    /// The name in `CELL.toml` (`kuka-rsi`, …).
    pub fn key(self) -> &'static str {
        match self {
            RobotKind::KukaRsi => "kuka-rsi",
            RobotKind::AbbEgm => "abb-egm",
            RobotKind::Staubli => "staubli",
            RobotKind::SimpleUdp => "simple-udp",
            RobotKind::SimpleTcp => "simple-tcp",
            RobotKind::FanucStream => "fanuc-stream",
            RobotKind::UrRtde => "ur-rtde",
        }
    }

    /// Whether the robot's replies echo its telegram's cycle id (RSI's IPOC, the Stäubli
    /// acknowledgement, the Stream Motion command's sequence number), so a late reply is never
    /// taken for the current one. The other protocols carry no echo: the first reply after a
    /// state is its answer.
    pub fn echoes_cycle(self) -> bool {
        matches!(
            self,
            RobotKind::KukaRsi | RobotKind::Staubli | RobotKind::FanucStream
        )
    }
}

/// How the robot side of a protocol is opened: the protocol, where the controller listens and
/// the protocol's settings (a `CELL.toml`'s `[robot]`, read by `deflex-app`).
#[derive(Clone, Debug, PartialEq)]
pub struct RobotSide {
    /// The protocol.
    pub kind: RobotKind,
    /// Where the controller listens (`robot.bind`).
    pub controller: SocketAddr,
    /// The RSI correction mode.
    pub rsi_mode: CorrectionMode,
    /// The EGM settings.
    pub egm: EgmConfig,
    /// The Stäubli VAL3 program's watchdog.
    pub staubli_watchdog: Duration,
    /// UR RTDE: the first correction register (`robot.rtde_register`).
    pub rtde_register: u8,
    /// UR RTDE: the URScript program's path offset (alpha filter, maximum offset, watchdog).
    pub path_offset: PathOffsetModel,
    /// FANUC Stream Motion: where the controller itself listens (`robot.peer`; the device,
    /// deflex, sends first), its cycle and the thresholds it reports and enforces.
    pub stream: Option<StreamSide>,
}

/// The FANUC controller's end of a Stream Motion session ([`RobotSide::stream`]).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct StreamSide {
    /// Where the controller listens (its port 60015 on a real controller).
    pub address: SocketAddr,
    /// Its interpolation cycle (s): 0.008 or 0.004.
    pub period_s: f64,
    /// The velocity, acceleration and jerk thresholds it reports and enforces.
    pub limits: StreamLimits,
}

impl RobotSide {
    /// The robot controller of [`RobotSide::kind`], bound on an ephemeral loopback port and
    /// sending its state to [`RobotSide::controller`]. A simple TCP robot (a UR script)
    /// connects to the controller: it retries for up to `wait` until the controller listens, or
    /// until `stop` is set. A UR RTDE controller is a server: it listens on
    /// [`RobotSide::controller`] (the address `deflex run` connects to).
    pub fn open(&self, wait: Duration, stop: &AtomicBool) -> Result<RobotEndpoint, LinkError> {
        let pc = self.controller;
        let local = "127.0.0.1:0";
        let link = match self.kind {
            RobotKind::KukaRsi => {
                EndpointLink::Other(Box::new(RsiRobotEndpoint::new(local, pc, self.rsi_mode)?))
            }
            RobotKind::AbbEgm => {
                let mut ep = EgmRobotEndpoint::new(local, pc)?;
                ep.set_seven_axis(self.egm.seven_axis);
                EndpointLink::Egm(Box::new(ep), self.egm)
            }
            RobotKind::Staubli => EndpointLink::Other(Box::new(StaubliRobotEndpoint::new(
                local,
                pc,
                self.staubli_watchdog,
            )?)),
            RobotKind::SimpleUdp => {
                EndpointLink::Other(Box::new(SimpleUdpRobotEndpoint::new(local, pc)?))
            }
            RobotKind::FanucStream => {
                let Some(side) = self.stream else {
                    return Err(LinkError::NoPeer {
                        protocol: crate::Protocol::FanucStream,
                    });
                };
                EndpointLink::Fanuc(Box::new(FanucStreamRobotEndpoint::bind(
                    side.address,
                    side.period_s,
                    side.limits,
                )?))
            }
            RobotKind::UrRtde => EndpointLink::Rtde(Box::new(RtdeRobotEndpoint::bind(
                pc,
                self.rtde_register,
                self.path_offset,
            )?)),
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
            kind: self.kind,
            link,
        })
    }
}

enum EndpointLink {
    Egm(Box<EgmRobotEndpoint>, EgmConfig),
    Rtde(Box<RtdeRobotEndpoint>),
    Fanuc(Box<FanucStreamRobotEndpoint>),
    Other(Box<dyn RobotSideLink + Send>),
}

/// A robot controller of a protocol as a simulated cell plays it ([`RobotSide::open`]).
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
            EndpointLink::Rtde(l) => l.as_mut(),
            EndpointLink::Fanuc(l) => l.as_mut(),
            EndpointLink::Other(l) => l.as_mut(),
        }
    }

    /// The UR controller's flange sensor reading of this cycle (raw, sensor axes), streamed as
    /// `ft_raw_wrench` with the next state; other protocols carry no wrench (false).
    pub fn set_flange_wrench(&mut self, w: &deflex_model::Wrench) -> bool {
        if let EndpointLink::Rtde(ep) = &mut self.link {
            ep.set_flange_wrench(w);
            true
        } else {
            false
        }
    }

    /// True while an RTDE client streams the flange sensor's wrench.
    pub fn flange_sensor_streaming(&self) -> bool {
        matches!(&self.link, EndpointLink::Rtde(ep) if ep.flange_sensor_streaming())
    }

    /// The correction the robot applies in a cycle whose answer did not come: a UR program's
    /// `path_offset` keeps running on the registers (and ramps out after its watchdog); the
    /// other protocols keep what they applied (`None`).
    pub fn unanswered_cycle(&mut self) -> Option<crate::Correction> {
        match &mut self.link {
            EndpointLink::Rtde(ep) => ep.unanswered_cycle(),
            _ => None,
        }
    }

    /// Whether the robot follows the joints a device streams (FANUC Stream Motion) rather than
    /// running its own program and taking corrections.
    pub fn follows_joint_stream(&self) -> bool {
        matches!(self.link, EndpointLink::Fanuc(_))
    }

    /// The joints the robot is commanded to by a joint stream (rad): the last command it
    /// accepted; `None` before the first, or for a robot running its own program.
    pub fn joint_command(&self) -> Option<[f64; 6]> {
        match &self.link {
            EndpointLink::Fanuc(l) => l.commanded_rad(),
            _ => None,
        }
    }

    /// The UR RTDE endpoint, for a UR RTDE robot.
    pub fn rtde(&mut self) -> Option<&mut RtdeRobotEndpoint> {
        match &mut self.link {
            EndpointLink::Rtde(ep) => Some(ep),
            _ => None,
        }
    }

    /// A joint stream is over: the device sent its stop packet (always false for a robot
    /// running its own program).
    pub fn stream_ended(&self) -> bool {
        match &self.link {
            EndpointLink::Fanuc(l) => l.stopped(),
            _ => false,
        }
    }

    /// The cycle id the answer to the last state sent must echo: the state's own
    /// ([`RobotState::cycle_id`]), or for Stream Motion the sequence number of the controller's
    /// last status packet.
    pub fn expected_cycle_id(&self, state_cycle_id: u64) -> u64 {
        match &self.link {
            EndpointLink::Fanuc(l) => u64::from(l.sequence()),
            _ => state_cycle_id,
        }
    }

    /// Whether replies echo the state's cycle id ([`RobotKind::echoes_cycle`]).
    pub fn echoes_cycle(&self) -> bool {
        self.kind.echoes_cycle()
    }

    /// What the robot controller knows of its own tool: the TCP orientation in base axes. An
    /// ABB controller expresses the corrections it receives in the frame `robot.egm_frame`
    /// (which follows the tool); the other protocols do not need it.
    pub fn set_tcp_rotation(&mut self, tcp_in_base: &nalgebra::Rotation3<f64>) {
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
