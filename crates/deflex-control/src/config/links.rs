//! From a `CELL.toml` to the controller-side links: the robot link of `robot.kind` with its
//! peer lock, answer kind and correction frame, and the force/torque sensor client.

use super::{CellFile, RobotKind, SensorKind};
use deflex_io::egm::{EgmConfig, EgmFrame, EgmLink};
use deflex_io::netft::{Calibration, NetFtClient};
use deflex_io::rsi::{CorrectionMode, JointTag, RsiAnswer, RsiConfig, RsiLink};
use deflex_io::simple_tcp::SimpleTcpLink;
use deflex_io::simple_udp::{ReplyStyle, SimpleUdpLink};
use deflex_io::staubli::StaubliLink;
use deflex_io::{ForceSensorLink, LinkError, RobotLink};
use deflex_model::spatial::pose_from_xyz_rpy;

fn rotation_rows(rpy: [f64; 3]) -> [[f64; 3]; 3] {
    let m = *pose_from_xyz_rpy([0.0; 3], rpy).rotation.matrix();
    std::array::from_fn(|i| std::array::from_fn(|j| m[(i, j)]))
}

impl CellFile {
    /// The RSI correction mode of `robot.correction_mode`.
    pub fn rsi_mode(&self) -> CorrectionMode {
        if self.robot.correction_mode == "relative" {
            CorrectionMode::Relative
        } else {
            CorrectionMode::Absolute
        }
    }

    /// The RSI link settings of `[robot]`.
    pub fn rsi_config(&self) -> RsiConfig {
        let r = &self.robot;
        RsiConfig {
            sen_type: r.sen_type.clone(),
            estr: None,
            mode: self.rsi_mode(),
            answer: if r.rsi_answer == "joint" {
                RsiAnswer::Joint(if r.rsi_joint_tag == "AKorr" {
                    JointTag::AKorr
                } else {
                    JointTag::Ak
                })
            } else {
                RsiAnswer::Cartesian
            },
        }
    }

    /// The ABB EGM link settings of `[robot]`, for a model with `joint_count` joints (seven:
    /// ABB's seven-axis layout). The measurement age is one control period.
    pub fn egm_config(&self, joint_count: usize) -> EgmConfig {
        let r = &self.robot;
        EgmConfig {
            frame: match r.egm_frame.as_str() {
                "base" => EgmFrame::Base,
                "work-object" => EgmFrame::WorkObject,
                _ => EgmFrame::Tool,
            },
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

    /// Binds the robot link of `robot.kind` on `robot.bind`, locked to `robot.peer` when set
    /// (otherwise to the first valid sender), for a model of `joint_count` joints.
    pub fn open_robot_link(
        &self,
        joint_count: usize,
    ) -> Result<Box<dyn RobotLink + Send>, LinkError> {
        let r = &self.robot;
        Ok(match r.kind {
            RobotKind::KukaRsi => {
                let mut link = RsiLink::bind(r.bind, self.rsi_config())?;
                if let Some(p) = r.peer {
                    link.expect_peer(p);
                }
                Box::new(link)
            }
            RobotKind::AbbEgm => {
                let mut link = EgmLink::bind(r.bind, self.egm_config(joint_count))?;
                if let Some(p) = r.peer {
                    link.expect_peer(p);
                }
                Box::new(link)
            }
            RobotKind::Staubli => {
                let mut link = StaubliLink::bind(r.bind)?;
                if let Some(p) = r.peer {
                    link.expect_peer(p);
                }
                Box::new(link)
            }
            RobotKind::SimpleUdp => {
                let mut link = SimpleUdpLink::bind(r.bind, ReplyStyle::default())?;
                if let Some(p) = r.peer {
                    link.expect_peer(p);
                }
                Box::new(link)
            }
            RobotKind::SimpleTcp => {
                let mut link = SimpleTcpLink::bind(r.bind)?;
                if let Some(p) = r.peer {
                    link.expect_peer(p);
                }
                Box::new(link)
            }
        })
    }

    /// Binds the sensor client of `[sensor]`.
    pub fn open_sensor_link(&self) -> Result<Box<dyn ForceSensorLink + Send>, LinkError> {
        Ok(match self.sensor.kind {
            SensorKind::Netft => Box::new(NetFtClient::new(
                self.sensor.bind,
                self.sensor.address,
                self.calibration(),
            )?),
        })
    }
}
