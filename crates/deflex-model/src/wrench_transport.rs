//! Wrench utilities: moving a wrench between points and frames. A force/torque sensor measures
//! in its own frame, about its own origin; the model wants the wrench at the TCP in world axes.

use crate::spatial::{Pose, Wrench};
use nalgebra::Vector3;

/// The same wrench with its moment taken about `to` instead of `from` (both in the wrench's axes):
/// `m_to = m_from + (from − to) × f`.
#[inline]
pub fn shift_wrench(wrench: &Wrench, from: &Vector3<f64>, to: &Vector3<f64>) -> Wrench {
    let force = wrench.fixed_rows::<3>(0).into_owned();
    let moment = wrench.fixed_rows::<3>(3).into_owned() + (from - to).cross(&force);
    Wrench::new(force.x, force.y, force.z, moment.x, moment.y, moment.z)
}

/// Express a wrench given in the axes of `frame` (moment about the frame origin) in the parent's
/// axes, moment still about the frame origin.
#[inline]
pub fn rotate_wrench_to_parent(wrench: &Wrench, frame: &Pose) -> Wrench {
    let rotation = frame.rotation.matrix();
    let force = rotation * wrench.fixed_rows::<3>(0);
    let moment = rotation * wrench.fixed_rows::<3>(3);
    Wrench::new(force.x, force.y, force.z, moment.x, moment.y, moment.z)
}

/// Express a wrench given in world axes in the axes of `frame` (moment point unchanged).
#[inline]
pub fn rotate_wrench_to_local(wrench: &Wrench, frame: &Pose) -> Wrench {
    let rotation_t = frame.rotation.matrix().transpose();
    let force = rotation_t * wrench.fixed_rows::<3>(0);
    let moment = rotation_t * wrench.fixed_rows::<3>(3);
    Wrench::new(force.x, force.y, force.z, moment.x, moment.y, moment.z)
}

/// A wrench measured in a sensor frame (axes and moment about the sensor origin, `sensor_pose`
/// in world) expressed in world axes with the moment about world point `point`.
#[inline]
pub fn sensor_wrench_at_point(
    sensor_wrench: &Wrench,
    sensor_pose: &Pose,
    point: &Vector3<f64>,
) -> Wrench {
    let world = rotate_wrench_to_parent(sensor_wrench, sensor_pose);
    shift_wrench(&world, &sensor_pose.translation.vector, point)
}

/// Inverse of [`sensor_wrench_at_point`]: what a sensor at `sensor_pose` reads for a wrench given
/// in world axes about world point `point`.
#[inline]
pub fn world_wrench_in_sensor(wrench: &Wrench, point: &Vector3<f64>, sensor_pose: &Pose) -> Wrench {
    let shifted = shift_wrench(wrench, point, &sensor_pose.translation.vector);
    rotate_wrench_to_local(&shifted, sensor_pose)
}
