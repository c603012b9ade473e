//! Wrench transport between points and frames ([`deflex_model::wrench_transport`]).

use deflex_model::Wrench;
use deflex_model::spatial::pose_from_xyz_rpy;
use deflex_model::wrench_transport::*;
use nalgebra::Vector3;

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
    assert!((world.fixed_rows::<3>(0).norm() - reading.fixed_rows::<3>(0).norm()).abs() < 1e-10);
}
