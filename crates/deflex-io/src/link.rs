//! Protocol-independent data types and the link traits.
//!
//! Everything here is SI: metres, radians, newtons, newton-metres. Protocol
//! units (millimetres and degrees for KUKA RSI and ABB EGM, sensor counts for
//! the ATI Net F/T) are converted inside the protocol modules.
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
use std::time::Duration;

/// Largest number of joint values a [`RobotState`] carries (the model's `MAX_JOINTS`).
pub const MAX_JOINTS: usize = 8;

/// A Cartesian pose: position and KUKA-style ZYX Euler angles.
///
/// The rotation is `R = Rz(a) · Ry(b) · Rx(c)` (KUKA A about z, B about y,
/// C about x, applied in that order about the moving axes).
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct Pose6 {
    /// Position in metres.
    pub position_m: [f64; 3],
    /// ZYX Euler angles `[a, b, c]` in radians (a about z, b about y, c about x).
    pub zyx_rad: [f64; 3],
}

impl Pose6 {
    /// Rotation matrix (row-major) of this pose's orientation.
    pub fn rotation(&self) -> [[f64; 3]; 3] {
        zyx_to_matrix(self.zyx_rad)
    }

    /// Orientation as a unit quaternion `[w, x, y, z]`.
    pub fn quaternion(&self) -> [f64; 4] {
        matrix_to_quaternion(&self.rotation())
    }

    /// Builds a pose from a position and a unit quaternion `[w, x, y, z]`
    /// (the quaternion is normalised; a zero quaternion gives identity).
    pub fn from_quaternion(position_m: [f64; 3], q_wxyz: [f64; 4]) -> Self {
        Pose6 {
            position_m,
            zyx_rad: matrix_to_zyx(&quaternion_to_matrix(q_wxyz)),
        }
    }
}

/// What the robot controller reports every cycle.
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct RobotState {
    /// Measured joint positions in radians (axis 1 first); the first
    /// [`RobotState::joint_count`] are valid, the rest are zero.
    pub q_rad: [f64; MAX_JOINTS],
    /// Number of joint values the telegram carried (KUKA RSI and Stäubli: 6;
    /// ABB EGM: what the robot sends; the simple line links: 1 to 8).
    pub joint_count: usize,
    /// Measured TCP pose in the robot base frame, when the protocol carries it.
    pub tcp_pose: Option<Pose6>,
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

    /// Rotation part as KUKA ZYX Euler angles `[a, b, c]` in radians.
    pub fn zyx_rad(&self) -> [f64; 3] {
        matrix_to_zyx(&rotvec_to_matrix(self.dphi_rad))
    }

    /// Builds a correction from a translation and KUKA ZYX Euler angles.
    pub fn from_zyx(dp_m: [f64; 3], zyx_rad: [f64; 3]) -> Self {
        Correction {
            dp_m,
            dphi_rad: matrix_to_rotvec(&zyx_to_matrix(zyx_rad)),
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

/// One force/torque sample from the sensor, in SI units.
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct WrenchSample {
    /// `[fx, fy, fz]` in N then `[mx, my, mz]` in N·m, sensor frame.
    pub wrench: [f64; 6],
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
    /// Tells the link the orientation of the TCP in the robot base frame
    /// (row-major rotation matrix) for the cycle being answered, from the
    /// model's forward kinematics at the reported joints. Links whose
    /// correction frame follows the tool (ABB EGM) use it; others ignore it.
    fn set_tcp_rotation(&mut self, rotation: &[[f64; 3]; 3]) {
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

// ---------------------------------------------------------------- rotations

/// `Rᵀ v` for a row-major rotation `R`: a base-axes vector expressed in the
/// axes of the frame whose orientation (in base axes) is `R`.
#[inline]
pub fn rotation_transpose_apply(r: &[[f64; 3]; 3], v: [f64; 3]) -> [f64; 3] {
    std::array::from_fn(|j| (0..3).map(|i| r[i][j] * v[i]).sum())
}

/// `Rz(a) · Ry(b) · Rx(c)` for `zyx = [a, b, c]`, row-major.
pub fn zyx_to_matrix(zyx: [f64; 3]) -> [[f64; 3]; 3] {
    let (sa, ca) = zyx[0].sin_cos();
    let (sb, cb) = zyx[1].sin_cos();
    let (sc, cc) = zyx[2].sin_cos();
    [
        [ca * cb, ca * sb * sc - sa * cc, ca * sb * cc + sa * sc],
        [sa * cb, sa * sb * sc + ca * cc, sa * sb * cc - ca * sc],
        [-sb, cb * sc, cb * cc],
    ]
}

/// Inverse of [`zyx_to_matrix`]; `b` is in `[-π/2, π/2]`.
pub fn matrix_to_zyx(r: &[[f64; 3]; 3]) -> [f64; 3] {
    let sb = (-r[2][0]).clamp(-1.0, 1.0);
    let b = sb.asin();
    if sb.abs() > 1.0 - 1e-12 {
        // Gimbal lock: only a ∓ c is defined; choose c = 0.
        let a = (-r[0][1]).atan2(r[1][1]);
        [a, b, 0.0]
    } else {
        [r[1][0].atan2(r[0][0]), b, r[2][1].atan2(r[2][2])]
    }
}

/// Rodrigues formula: rotation vector (axis × angle, rad) to matrix.
pub fn rotvec_to_matrix(v: [f64; 3]) -> [[f64; 3]; 3] {
    let th2 = v[0] * v[0] + v[1] * v[1] + v[2] * v[2];
    let th = th2.sqrt();
    let (a, b) = if th < 1e-8 {
        (1.0 - th2 / 6.0, 0.5 - th2 / 24.0)
    } else {
        (th.sin() / th, (1.0 - th.cos()) / th2)
    };
    let [x, y, z] = v;
    [
        [
            1.0 - b * (y * y + z * z),
            -a * z + b * x * y,
            a * y + b * x * z,
        ],
        [
            a * z + b * x * y,
            1.0 - b * (x * x + z * z),
            -a * x + b * y * z,
        ],
        [
            -a * y + b * x * z,
            a * x + b * y * z,
            1.0 - b * (x * x + y * y),
        ],
    ]
}

/// Inverse of [`rotvec_to_matrix`] (angle in `[0, π]`).
pub fn matrix_to_rotvec(r: &[[f64; 3]; 3]) -> [f64; 3] {
    let q = matrix_to_quaternion(r);
    let s = (q[1] * q[1] + q[2] * q[2] + q[3] * q[3]).sqrt();
    if s < 1e-12 {
        return [2.0 * q[1], 2.0 * q[2], 2.0 * q[3]];
    }
    let angle = 2.0 * s.atan2(q[0]);
    [q[1] / s * angle, q[2] / s * angle, q[3] / s * angle]
}

/// Rotation matrix to unit quaternion `[w, x, y, z]` with `w ≥ 0`.
pub fn matrix_to_quaternion(r: &[[f64; 3]; 3]) -> [f64; 4] {
    let tr = r[0][0] + r[1][1] + r[2][2];
    let q = if tr > 0.0 {
        let s = (tr + 1.0).sqrt() * 2.0;
        [
            0.25 * s,
            (r[2][1] - r[1][2]) / s,
            (r[0][2] - r[2][0]) / s,
            (r[1][0] - r[0][1]) / s,
        ]
    } else if r[0][0] > r[1][1] && r[0][0] > r[2][2] {
        let s = (1.0 + r[0][0] - r[1][1] - r[2][2]).sqrt() * 2.0;
        [
            (r[2][1] - r[1][2]) / s,
            0.25 * s,
            (r[0][1] + r[1][0]) / s,
            (r[0][2] + r[2][0]) / s,
        ]
    } else if r[1][1] > r[2][2] {
        let s = (1.0 + r[1][1] - r[0][0] - r[2][2]).sqrt() * 2.0;
        [
            (r[0][2] - r[2][0]) / s,
            (r[0][1] + r[1][0]) / s,
            0.25 * s,
            (r[1][2] + r[2][1]) / s,
        ]
    } else {
        let s = (1.0 + r[2][2] - r[0][0] - r[1][1]).sqrt() * 2.0;
        [
            (r[1][0] - r[0][1]) / s,
            (r[0][2] + r[2][0]) / s,
            (r[1][2] + r[2][1]) / s,
            0.25 * s,
        ]
    };
    if q[0] < 0.0 {
        [-q[0], -q[1], -q[2], -q[3]]
    } else {
        q
    }
}

/// Unit quaternion `[w, x, y, z]` (normalised here) to rotation matrix.
pub fn quaternion_to_matrix(q: [f64; 4]) -> [[f64; 3]; 3] {
    let n = (q[0] * q[0] + q[1] * q[1] + q[2] * q[2] + q[3] * q[3]).sqrt();
    if !n.is_finite() || n <= 1e-300 {
        return [[1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [0.0, 0.0, 1.0]];
    }
    let [w, x, y, z] = [q[0] / n, q[1] / n, q[2] / n, q[3] / n];
    [
        [
            1.0 - 2.0 * (y * y + z * z),
            2.0 * (x * y - w * z),
            2.0 * (x * z + w * y),
        ],
        [
            2.0 * (x * y + w * z),
            1.0 - 2.0 * (x * x + z * z),
            2.0 * (y * z - w * x),
        ],
        [
            2.0 * (x * z - w * y),
            2.0 * (y * z + w * x),
            1.0 - 2.0 * (x * x + y * y),
        ],
    ]
}
