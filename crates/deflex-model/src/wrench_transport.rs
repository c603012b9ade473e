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

#[cfg(test)]
mod tests {
    use super::*;
    use crate::spatial::pose_from_xyz_rpy;

    #[test]
    fn shifting_preserves_power_for_any_rigid_motion() {
        // Virtual power f·v_A + m_A·ω is independent of the reference point when v_B = v_A + ω × (B − A).
        let wrench = Wrench::new(10.0, -3.0, 7.0, 1.0, 2.0, -0.5);
        let a = Vector3::new(0.3, -0.2, 1.1);
        let b = Vector3::new(-1.0, 0.4, 0.2);
        let v_a = Vector3::new(0.1, 0.2, -0.3);
        let omega = Vector3::new(0.05, -0.07, 0.02);
        let v_b = v_a + omega.cross(&(b - a));
        let at_b = shift_wrench(&wrench, &a, &b);
        let power_a = wrench.fixed_rows::<3>(0).dot(&v_a) + wrench.fixed_rows::<3>(3).dot(&omega);
        let power_b = at_b.fixed_rows::<3>(0).dot(&v_b) + at_b.fixed_rows::<3>(3).dot(&omega);
        assert!((power_a - power_b).abs() < 1e-12);
    }

    #[test]
    fn pure_force_offset_gives_lever_moment() {
        // 100 N along z applied 0.2 m along x from the reference point: moment −20 N·m about y.
        let wrench = Wrench::new(0.0, 0.0, 100.0, 0.0, 0.0, 0.0);
        let shifted = shift_wrench(&wrench, &Vector3::new(0.2, 0.0, 0.0), &Vector3::zeros());
        assert!((shifted[4] + 20.0).abs() < 1e-12);
        assert!(shifted[3].abs() < 1e-12 && shifted[5].abs() < 1e-12);
    }

    #[test]
    fn sensor_round_trip() {
        let sensor = pose_from_xyz_rpy([1.2, 0.1, -0.3], [0.3, -1.0, 2.0]);
        let reading = Wrench::new(5.0, -20.0, 300.0, 1.5, -2.0, 0.25);
        let tcp = Vector3::new(1.25, 0.05, -0.5);
        let world = sensor_wrench_at_point(&reading, &sensor, &tcp);
        let back = world_wrench_in_sensor(&world, &tcp, &sensor);
        assert!((back - reading).norm() < 1e-10);
        // Force magnitude is frame independent.
        assert!(
            (world.fixed_rows::<3>(0).norm() - reading.fixed_rows::<3>(0).norm()).abs() < 1e-10
        );
    }
}
