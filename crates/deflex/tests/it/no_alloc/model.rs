//! No allocation on deflex-model's per-cycle path: the hot path (FK, eDoF screws, deflection,
//! compliance and gravity) performs zero heap allocations, checked with this binary's counting
//! global allocator, which counts only the allocations of the thread under test (the test
//! harness's own threads allocate whenever they like).

use super::allocations;
use deflex_model::{Axis, Data, EdofSite, Wrench, builtin};

#[test]
fn hot_path_allocates_nothing() {
    let mut robot = builtin("tx200").unwrap();
    for i in 1..=6 {
        for axis in Axis::ALL {
            robot.set_stiffness(EdofSite::Joint(i), axis, Some(3.0e6));
        }
    }
    robot.set_stiffness(EdofSite::Base, Axis::X, Some(5.0e7));
    robot.set_stiffness(EdofSite::Base, Axis::Y, Some(5.0e7));
    // An off-diagonal compliance is part of the hot path too.
    robot.couplings = vec![deflex_model::ComplianceCoupling {
        a: (EdofSite::Joint(2), Axis::Z),
        b: (EdofSite::Joint(3), Axis::Z),
        compliance: 0.1 / 3.0e6,
    }];
    let mut data = Data::new();
    let q = [0.1, 0.8, 1.5, 0.05, 0.7, -0.1];
    let wrench = Wrench::new(100.0, -300.0, 1200.0, 1.0, 2.0, 3.0);
    let mut sink = 0.0;
    let ur10 = builtin("ur10").unwrap();
    let mut ur_data = Data::new();
    let before = allocations();
    for k in 0..1000 {
        let mut qk = q;
        qk[0] += k as f64 * 1e-4;
        robot.forward_kinematics(&mut data, &qk).unwrap();
        sink += robot.tcp_deflection(&data, &wrench)[2];
        sink += robot.compliance_matrix(&data)[(2, 2)];
        let columns = robot.edof_columns(&data, &data.tcp_position(), 6);
        sink += columns.columns[0][0];
        sink += robot.gravity_edof_torques(&data)[0];
        sink += robot.gravity_displacement(&data, &data.tcp_position(), 6)[2];
        ur10.forward_kinematics(&mut ur_data, &qk).unwrap();
        sink += ur10.gravity_displacement(&ur_data, &ur_data.tcp_position(), 6)[2];
    }
    let after = allocations();
    assert!(sink.is_finite());
    assert_eq!(
        after - before,
        0,
        "the hot path allocated {} times",
        after - before
    );
}
