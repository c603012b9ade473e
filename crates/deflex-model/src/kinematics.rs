//! Forward kinematics (eq. 1) and the geometric Jacobian of the motorised joints.

use crate::error::QLengthError;
use crate::robot::Robot;
use crate::spatial::edof_screw;
use crate::spatial::{Pose, rot_z};
use crate::{MAX_JOINTS, robot::EdofSite};
use nalgebra::{DMatrix, Vector3, Vector6};

/// Scratch space filled by [`Robot::forward_kinematics`]: fixed-size, so the hot path never
/// touches the heap. One `Data` per thread; it is only meaningful for the robot that filled it.
#[derive(Clone, Debug)]
pub struct Data {
    /// World pose of R0 (the robot's base frame).
    pub base_frame: Pose,
    /// World pose of each joint frame R_i (i = 1..N at index i-1), joint rotation included.
    pub joint_frames: [Pose; MAX_JOINTS],
    /// World pose of the flange frame R_m (= R_N · [`Robot::flange`]).
    pub flange: Pose,
    /// World pose of the TCP frame R_t.
    pub tcp: Pose,
    /// Joint values (rad) the frames were computed for.
    pub q: [f64; MAX_JOINTS],
    /// Number of joints filled.
    pub joint_count: usize,
}

impl Default for Data {
    fn default() -> Self {
        Self::new()
    }
}

impl Data {
    /// An empty scratch space.
    pub fn new() -> Self {
        Data {
            base_frame: Pose::identity(),
            joint_frames: [Pose::identity(); MAX_JOINTS],
            flange: Pose::identity(),
            tcp: Pose::identity(),
            q: [0.0; MAX_JOINTS],
            joint_count: 0,
        }
    }

    /// World frame of link `link` (0 = base frame R0, i = joint frame R_i).
    #[inline]
    pub fn link_frame(&self, link: usize) -> &Pose {
        if link == 0 {
            &self.base_frame
        } else {
            &self.joint_frames[link - 1]
        }
    }

    /// TCP position in world coordinates (m).
    #[inline]
    pub fn tcp_position(&self) -> Vector3<f64> {
        self.tcp.translation.vector
    }

    /// World axis and centre of an eDoF (the spring's rotation axis v_{i,j} and centre O_i of
    /// eq. 13). For a joint the centre is the frame origin shifted `center_shift` along z_i; for
    /// the base it is the base pivot ([`Robot::base_pivot`], R0's origin by default).
    #[inline]
    pub fn edof_axis_center(
        &self,
        robot: &Robot,
        site: EdofSite,
        axis: crate::Axis,
    ) -> (Vector3<f64>, Vector3<f64>) {
        match site {
            EdofSite::Base => {
                let frame = &self.base_frame;
                (
                    frame.rotation.matrix().column(axis.index()).into_owned(),
                    base_pivot_world(frame, robot),
                )
            }
            EdofSite::Joint(i) => {
                let frame = &self.joint_frames[i - 1];
                (
                    frame.rotation.matrix().column(axis.index()).into_owned(),
                    edof_center(frame, robot.joints[i - 1].center_shift),
                )
            }
        }
    }
}

/// World position of the base eDoFs' centre.
#[inline]
pub(crate) fn base_pivot_world(base_frame: &Pose, robot: &Robot) -> Vector3<f64> {
    base_frame.translation.vector + base_frame.rotation * robot.base_pivot
}

impl Robot {
    /// Forward kinematics (eq. 1): fills every joint frame, the flange and the TCP of `data` for
    /// joint values `q` (rad). Allocation-free.
    pub fn forward_kinematics(&self, data: &mut Data, q: &[f64]) -> Result<(), QLengthError> {
        let n = self.joints.len();
        if q.len() != n {
            return Err(QLengthError {
                expected: n,
                got: q.len(),
            });
        }
        data.base_frame = self.base;
        let mut frame = self.base;
        for (i, (joint, &qi)) in self.joints.iter().zip(q).enumerate() {
            frame = frame * joint.placement * rot_z(qi + joint.theta_offset);
            data.joint_frames[i] = frame;
            data.q[i] = qi;
        }
        data.joint_count = n;
        data.flange = frame * self.flange;
        data.tcp = data.flange * self.tool;
        Ok(())
    }

    /// TCP pose for `q` (convenience wrapper around [`Robot::forward_kinematics`]).
    pub fn tcp_pose(&self, q: &[f64]) -> Result<Pose, QLengthError> {
        let mut data = Data::new();
        self.forward_kinematics(&mut data, q)?;
        Ok(data.tcp)
    }

    /// Columns of the geometric Jacobian of the motorised joints at a world point attached to
    /// the last link: column i is `[z_i × (p − O_i); z_i]`, mapping joint rates to
    /// `[linear velocity; angular velocity]` in world axes. The first `joint_count` entries are
    /// filled; fixed-size and allocation-free for per-cycle use.
    pub fn geometric_jacobian_columns(
        &self,
        data: &Data,
        point: &Vector3<f64>,
    ) -> [Vector6<f64>; MAX_JOINTS] {
        let mut columns = [Vector6::zeros(); MAX_JOINTS];
        for (column, frame) in columns
            .iter_mut()
            .zip(&data.joint_frames[..self.joints.len()])
        {
            let z = frame.rotation.matrix().column(2).into_owned();
            *column = edof_screw(&z, &frame.translation.vector, point);
        }
        columns
    }

    /// Geometric Jacobian (6×N) of the motorised joints at a world point attached to the last
    /// link (the TCP when `point` is `data.tcp_position()`), as a matrix (allocates; see
    /// [`Robot::geometric_jacobian_columns`] for the per-cycle form).
    pub fn geometric_jacobian(&self, data: &Data, point: &Vector3<f64>) -> DMatrix<f64> {
        let columns = self.geometric_jacobian_columns(data, point);
        DMatrix::from_fn(6, self.joints.len(), |r, c| columns[c][r])
    }
}

/// Centre O_i of the eDoFs of a joint: the frame origin shifted `center_shift` (the paper's δr)
/// along z_i.
#[inline]
pub(crate) fn edof_center(frame: &Pose, center_shift: f64) -> Vector3<f64> {
    frame.translation.vector + frame.rotation.matrix().column(2) * center_shift
}
