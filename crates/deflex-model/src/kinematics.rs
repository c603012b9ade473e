//! Forward kinematics (eq. 1) and the geometric Jacobian of the motorised joints.

use crate::error::QLengthError;
use crate::robot::Robot;
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
    /// World pose of the flange frame R_m (= R_N).
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
    /// the base it is R0's origin.
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
                    frame.translation.vector,
                )
            }
            EdofSite::Joint(i) => {
                let frame = &self.joint_frames[i - 1];
                let rotation = frame.rotation.matrix();
                let z = rotation.column(2);
                (
                    rotation.column(axis.index()).into_owned(),
                    frame.translation.vector + z * robot.joints[i - 1].center_shift,
                )
            }
        }
    }
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
        data.flange = frame;
        data.tcp = frame * self.tool;
        Ok(())
    }

    /// TCP pose for `q` (convenience wrapper around [`Robot::forward_kinematics`]).
    pub fn tcp_pose(&self, q: &[f64]) -> Result<Pose, QLengthError> {
        let mut data = Data::new();
        self.forward_kinematics(&mut data, q)?;
        Ok(data.tcp)
    }

    /// Geometric Jacobian (6×N) of the motorised joints at a world point attached to the last
    /// link (the TCP when `point` is `data.tcp_position()`): column i is `[z_i × (p − O_i); z_i]`,
    /// mapping joint rates to `[linear velocity; angular velocity]` in world axes.
    pub fn geometric_jacobian(&self, data: &Data, point: &Vector3<f64>) -> DMatrix<f64> {
        let n = self.joints.len();
        let mut jacobian = DMatrix::zeros(6, n);
        for i in 0..n {
            let column = joint_screw(&data.joint_frames[i], point);
            jacobian.column_mut(i).copy_from(&column);
        }
        jacobian
    }
}

/// `[z × (p − O); z]` for a joint frame.
#[inline]
fn joint_screw(frame: &Pose, point: &Vector3<f64>) -> Vector6<f64> {
    let z = frame.rotation.matrix().column(2).into_owned();
    let lever = point - frame.translation.vector;
    let linear = z.cross(&lever);
    Vector6::new(linear.x, linear.y, linear.z, z.x, z.y, z.z)
}
