//! Protocol-independent data types and the link traits.
//!
//! Everything here is SI: metres, radians, newtons, newton-metres, with the
//! model's spatial types ([`Pose`], [`Wrench`], `Rotation3`). Protocol units
//! (millimetres and degrees for KUKA RSI and ABB EGM, sensor counts for the ATI
//! Net F/T) and the vendors' orientation conventions
//! ([`deflex_model::conventions`]) are converted inside the protocol modules.
//!
//! Two sides exist for every robot protocol:
//! * the **controller side** ([`RobotLink`]): receives the robot state every
//!   interpolation cycle and answers with a Cartesian [`Correction`];
//! * the **robot side** ([`RobotSideLink`]): what a simulated cell uses to play
//!   the robot controller: it sends the state and receives the correction.
//!
//! The force sensor has [`ForceSensorLink`] on the controller side; the
//! simulated sensor uses the concrete server type of [`crate::netft`].

use crate::error::LinkError;
use deflex_model::{MAX_JOINTS, Pose, Wrench};
use nalgebra::Rotation3;
use std::time::Duration;

/// What the robot controller reports every cycle.
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct RobotState {
    /// Measured joint positions in radians (axis 1 first); the first
    /// [`RobotState::joint_count`] are valid, the rest are zero.
    pub q_rad: [f64; MAX_JOINTS],
    /// Number of joint values the telegram carried (KUKA RSI and Stäubli: 6;
    /// ABB EGM: what the robot sends; the simple line links: 1 to 8).
    pub joint_count: usize,
    /// Measured TCP pose in the robot base frame (m), when the protocol carries it.
    pub tcp_pose: Option<Pose>,
    /// Cycle identifier: KUKA IPOC, EGM or deflex sequence number, or the
    /// sequence number of the simple line protocol.
    pub cycle_id: u64,
    /// Robot controller clock in seconds when the protocol carries one
    /// (EGM `tm`, deflex timestamp). Receive time is the caller's business.
    pub robot_time_s: Option<f64>,
    /// Protocol-specific status word: deflex status bits (see
    /// [`crate::staubli`]), 0 otherwise.
    pub status: u32,
    /// The robot's own count of answers that came too late or not at all,
    /// where the protocol carries one (KUKA RSI `Delay D`, cumulative).
    pub late_answers: Option<u32>,
}

impl RobotState {
    /// A state carrying the joint values `q` (at most [`MAX_JOINTS`]; extra
    /// values are dropped), everything else default.
    pub fn with_joints(q: &[f64]) -> Self {
        let mut s = RobotState::default();
        s.set_joints(q);
        s
    }

    /// Sets the joint values (at most [`MAX_JOINTS`]).
    pub fn set_joints(&mut self, q: &[f64]) {
        let n = q.len().min(MAX_JOINTS);
        self.q_rad = [0.0; MAX_JOINTS];
        self.q_rad[..n].copy_from_slice(&q[..n]);
        self.joint_count = n;
    }

    /// The valid joint values.
    pub fn joints(&self) -> &[f64] {
        &self.q_rad[..self.joint_count.min(MAX_JOINTS)]
    }
}

/// A Cartesian correction of the tool path, expressed in the robot base axes.
///
/// This is always the **total** correction with respect to the nominal path
/// (absolute); protocols that transmit increments compute them internally.
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct Correction {
    /// Translation in metres along base x, y, z.
    pub dp_m: [f64; 3],
    /// Rotation vector in radians about base x, y, z (axis × angle).
    pub dphi_rad: [f64; 3],
}

impl Correction {
    /// The zero correction.
    pub const ZERO: Correction = Correction {
        dp_m: [0.0; 3],
        dphi_rad: [0.0; 3],
    };

    /// True if all six components are finite numbers.
    pub fn is_finite(&self) -> bool {
        self.dp_m
            .iter()
            .chain(self.dphi_rad.iter())
            .all(|v| v.is_finite())
    }

    /// The six components as one screw `[dx, dy, dz, φx, φy, φz]`: translation in metres
    /// along base x, y, z, then the rotation vector in radians about base x, y, z.
    pub fn to_array(&self) -> [f64; 6] {
        let [x, y, z] = self.dp_m;
        let [rx, ry, rz] = self.dphi_rad;
        [x, y, z, rx, ry, rz]
    }

    /// Inverse of [`Correction::to_array`]: `[dx, dy, dz, φx, φy, φz]` with the translation in
    /// metres and the rotation vector in radians, both in base axes.
    pub fn from_array(v: [f64; 6]) -> Self {
        let [x, y, z, rx, ry, rz] = v;
        Correction {
            dp_m: [x, y, z],
            dphi_rad: [rx, ry, rz],
        }
    }
}

/// A correction received by the robot side, with the cycle it answers.
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct ReceivedCorrection {
    /// Total correction (already accumulated for incremental protocols).
    pub correction: Correction,
    /// Cycle identifier echoed by the controller (IPOC, acknowledged
    /// sequence number...), 0 when the protocol has none.
    pub cycle_id: u64,
    /// A joint-space correction (rad, axis 1 first) when the controller
    /// answered in joint space (KUKA RSI `AK`); `correction` is then zero.
    pub joint_correction_rad: Option<[f64; 6]>,
}

/// One force/torque sample from the sensor: the wrench it measured (SI) and what the
/// transport says about it (sequence, status word, samples missing before it).
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct WrenchSample {
    /// `[fx, fy, fz]` in N then `[mx, my, mz]` in N·m, in the sensor's axes and about its
    /// origin.
    pub wrench: Wrench,
    /// Transport sequence number (Net F/T `rdt_sequence`).
    pub sequence: u32,
    /// Sensor status word; non-zero means a fault is flagged.
    pub status: u32,
    /// Number of samples missing between the previous sample and this one
    /// (0 when contiguous).
    pub gap: u32,
}

impl WrenchSample {
    /// True if the sensor flags a fault in its status word.
    pub fn is_fault(&self) -> bool {
        self.status != 0
    }
}

/// Controller side of a robot link: receive the state, answer with a
/// correction. Neither call allocates after construction.
pub trait RobotLink {
    /// Waits up to `timeout` for the next state message. `Ok(None)` on
    /// timeout; a malformed packet is an error and the link stays usable.
    fn receive(&mut self, timeout: Duration) -> Result<Option<RobotState>, LinkError>;
    /// Sends the total correction for the current cycle.
    fn send_correction(&mut self, correction: &Correction) -> Result<(), LinkError>;
    /// Whether this link answers with joint corrections
    /// ([`RobotLink::send_joint_correction`]) instead of Cartesian ones.
    fn answers_in_joint_space(&self) -> bool {
        false
    }
    /// Sends a joint-space correction (rad, axis 1 first) for the current
    /// cycle. Only links that [answer in joint space](RobotLink::answers_in_joint_space)
    /// implement it.
    fn send_joint_correction(&mut self, dq_rad: &[f64]) -> Result<(), LinkError> {
        let _ = dq_rad;
        Err(LinkError::InvalidValue {
            protocol: self.protocol(),
            reason: "this link does not send joint corrections",
        })
    }
    /// Tells the link the orientation of the TCP in the robot base frame for
    /// the cycle being answered, from the model's forward kinematics at the
    /// reported joints. Links whose correction frame follows the tool (ABB
    /// EGM) use it; others ignore it.
    fn set_tcp_rotation(&mut self, rotation: &Rotation3<f64>) {
        let _ = rotation;
    }
    /// The protocol, for messages.
    fn protocol(&self) -> crate::Protocol;
    /// What the link has accepted, answered, refused and dropped so far (all zero for a link
    /// that does not count).
    fn counters(&self) -> crate::LinkCounters {
        crate::LinkCounters::default()
    }
}

/// Robot side of a robot link (used by the simulated cell).
pub trait RobotSideLink {
    /// Sends the state of the current cycle.
    fn send_state(&mut self, state: &RobotState) -> Result<(), LinkError>;
    /// Waits up to `timeout` for the controller's answer. `Ok(None)` on timeout.
    fn receive_correction(
        &mut self,
        timeout: Duration,
    ) -> Result<Option<ReceivedCorrection>, LinkError>;
}

/// Controller side of a force/torque sensor link.
pub trait ForceSensorLink {
    /// Asks the sensor to start streaming.
    fn start(&mut self) -> Result<(), LinkError>;
    /// Asks the sensor to zero its current reading (software bias).
    fn bias(&mut self) -> Result<(), LinkError>;
    /// Waits up to `timeout` for the next sample. `Ok(None)` on timeout.
    fn receive(&mut self, timeout: Duration) -> Result<Option<WrenchSample>, LinkError>;
    /// Asks the sensor to stop streaming.
    fn stop(&mut self) -> Result<(), LinkError>;
}
