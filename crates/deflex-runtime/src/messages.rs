//! What the runtime's threads hand each other, as named plain-data messages. Each lives in a
//! [`SeqCell`](deflex_telemetry::SeqCell) written by exactly one thread: the latest value is read
//! lock-free and allocation-free by the others, never torn.
//!
//! | message | writer | readers |
//! |---|---|---|
//! | [`JointSample`] | robot-link thread (every telegram) | control thread |
//! | [`WrenchAccumulation`] | sensor thread (every sample) | control thread |
//! | [`CorrectionCommand`] | control thread (every cycle) | robot-link thread |
//!
//! The wrench stays a [`Wrench`] from the sensor thread to the estimate of eq. 15; the
//! correction command carries ξ, the TCP orientation as a [`Rotation3`] and the joint map as a
//! fixed-size matrix, all three from the same control cycle.

use crate::send_shaper::LinkDirective;
use bytemuck::{Pod, Zeroable};
use deflex_control::JointCorrectionMap;
use deflex_model::{MAX_JOINTS, Pose, Wrench};
use nalgebra::{Rotation3, Vector6};

/// [`JointSample::robot_late`] when the robot does not report its count of late answers.
pub const LATE_UNKNOWN: u64 = u64::MAX;

/// The robot's latest telegram: what the control thread needs of it.
#[repr(C)]
#[derive(Clone, Copy, Debug, PartialEq, Pod, Zeroable)]
pub struct JointSample {
    /// Joint values (rad); the first [`Self::joint_count`] are the robot's.
    pub q_rad: [f64; MAX_JOINTS],
    /// Session time of its receipt (s).
    pub time_s: f64,
    /// Joint values the telegram carried (at most [`MAX_JOINTS`]).
    pub joint_count: u64,
    /// The robot's own count of late answers (KUKA RSI `Delay`), [`LATE_UNKNOWN`] if it does
    /// not say.
    pub robot_late: u64,
    /// The TCP pose the telegram reported (robot base frame), valid when
    /// [`Self::tcp_pose_known`] is non-zero (KUKA RSI `RIst`, ABB EGM feedback).
    pub tcp_pose: Pose,
    /// 1 when the telegram carried [`Self::tcp_pose`], 0 otherwise.
    pub tcp_pose_known: u64,
}

impl JointSample {
    /// The joint values the robot reported.
    pub fn q(&self) -> &[f64] {
        &self.q_rad[..(self.joint_count as usize).min(MAX_JOINTS)]
    }

    /// The TCP pose the robot reported with these joints, when its protocol carries one.
    pub fn tcp_pose(&self) -> Option<Pose> {
        (self.tcp_pose_known != 0).then_some(self.tcp_pose)
    }
}

/// Every force/torque sample since the session started, summed, and the latest one: the control
/// thread averages the samples of its period from two snapshots (sum and count differences).
#[repr(C)]
#[derive(Clone, Copy, Debug, PartialEq, Pod, Zeroable)]
pub struct WrenchAccumulation {
    /// Sum of every raw reading so far, sensor frame (N, N·m).
    pub sum: Wrench,
    /// The latest raw reading, sensor frame (N, N·m).
    pub last: Wrench,
    /// Session time of the latest reading's receipt (s).
    pub time_s: f64,
    /// Readings summed.
    pub count: u64,
    /// The latest reading's status word (0: healthy).
    pub status: u64,
}

impl WrenchAccumulation {
    /// Adds a reading received at `time_s`.
    #[inline]
    pub fn add(&mut self, reading: &Wrench, status: u32, time_s: f64) {
        for i in 0..6 {
            self.sum[i] += reading[i];
        }
        self.last = *reading;
        self.count += 1;
        self.time_s = time_s;
        self.status = u64::from(status);
    }

    /// The wrench of a control period that began at `previous`: the mean of the readings that
    /// arrived since (`fresh`), or the latest reading again when none did.
    #[inline]
    pub fn mean_since(&self, previous: &WrenchAccumulation) -> (Wrench, bool) {
        let fresh = self.count > previous.count;
        let mut mean = self.last;
        if fresh {
            let n = (self.count - previous.count) as f64;
            for i in 0..6 {
                mean[i] = (self.sum[i] - previous.sum[i]) / n;
            }
        }
        (mean, fresh)
    }

    /// The status word.
    pub fn status_word(&self) -> u32 {
        u32::try_from(self.status).unwrap_or(u32::MAX)
    }
}

/// What the robot-link thread answers with, from one control cycle.
#[repr(C)]
#[derive(Clone, Copy, Debug, PartialEq, Pod, Zeroable)]
pub struct CorrectionCommand {
    /// The correction ξ = [δp (m); δφ (rad)], robot base axes (eq. 7).
    pub xi: Vector6<f64>,
    /// TCP orientation in base axes (a link whose correction frame follows the tool: ABB EGM).
    pub tcp_rotation: Rotation3<f64>,
    /// Δq = P ξ (links answering in joint space: KUKA RSI `AK`); zero when not needed.
    pub joint_map: JointCorrectionMap,
    /// [`LinkDirective`] code: what to do with ξ given the controller's fault.
    pub directive: u64,
}

impl CorrectionCommand {
    /// The directive.
    pub fn directive(&self) -> LinkDirective {
        LinkDirective::from_u8(u8::try_from(self.directive).unwrap_or(0))
    }
}
