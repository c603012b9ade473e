//! The model checked against the robot ([`deflex_control::model_check`]): the TCP pose a robot
//! reports against the model's forward kinematics at the same joints — nothing at its own pose,
//! a wrong tool's length in millimetres, and a jump of the reported pose during a run latches
//! `model_mismatch` and ramps the correction out.

use crate::common;
use deflex_control::controller::{CycleInput, CycleOutput};
use deflex_control::{Controller, ModelCheckConfig, tcp_pose_mismatch};
use deflex_model::{Data, Pose, Wrench};
use deflex_telemetry::{FaultKind, Flags, Phase};
use nalgebra::{Rotation3, Translation3, Vector3};

/// The TCP pose `robot` reports at `q` in its base frame (its own forward kinematics).
fn reported(robot: &deflex_model::Robot, q: &[f64]) -> Pose {
    robot.base.inverse() * robot.tcp_pose(q).unwrap()
}

#[test]
fn a_wrong_tool_shows_as_its_length() {
    let model = common::robot();
    let q = common::q0();
    let mut data = Data::new();
    let own = tcp_pose_mismatch(&model, &mut data, &q, &reported(&model, &q)).unwrap();
    assert!(
        own.position_m < 1e-12 && own.orientation_rad < 1e-7,
        "{own:?}"
    );
    // The controller's tool is 60 mm longer along its z than the model's.
    let mut robot = model.clone();
    robot.tool *= Translation3::new(0.0, 0.0, 0.06);
    let m = tcp_pose_mismatch(&model, &mut data, &q, &reported(&robot, &q)).unwrap();
    assert!((m.position_m - 0.06).abs() < 1e-9, "{m:?}");
    assert!(m.orientation_rad < 1e-7, "{m:?}");
    assert!(m.exceeds(&ModelCheckConfig::default()));
    // Turned by 20 mrad about the tool's z: the orientation alone.
    let mut turned = model.clone();
    turned.tool *= Rotation3::from_axis_angle(&Vector3::z_axis(), 0.02);
    let m = tcp_pose_mismatch(&model, &mut data, &q, &reported(&turned, &q)).unwrap();
    assert!(
        m.position_m < 1e-9 && (m.orientation_rad - 0.02).abs() < 1e-9,
        "{m:?}"
    );
    assert!(m.exceeds(&ModelCheckConfig::default()));
    // A calibration's difference passes.
    let mut calibrated = model.clone();
    calibrated.tool *= Translation3::new(0.0002, -0.0001, 0.0003);
    let m = tcp_pose_mismatch(&model, &mut data, &q, &reported(&calibrated, &q)).unwrap();
    assert!(!m.exceeds(&ModelCheckConfig::default()), "{m:?}");
    // Another joint count is not compared.
    assert!(tcp_pose_mismatch(&model, &mut data, &q[..5], &reported(&model, &q)).is_err());
}

/// One cycle with the reported pose `pose`.
fn cycle(ctrl: &mut Controller, t: f64, q: &[f64], raw: &Wrench, pose: Pose) -> CycleOutput {
    ctrl.cycle_input(&CycleInput {
        now_s: t,
        q_rad: q,
        q_age_s: 0.0,
        wrench_sensor: *raw,
        wrench_age_s: 0.0,
        wrench_fresh: true,
        sensor_status: 0,
        tcp_pose: Some(pose),
    })
}

#[test]
fn a_jump_of_the_reported_pose_latches_a_fault_and_ramps_out() {
    let config = common::config();
    let mut ctrl = common::controller(config);
    let q = common::q0();
    let raw = common::raw_reading(&config, &q, [300.0, -250.0, 1000.0, 0.0, 0.0, 0.0]);
    let pose = reported(&common::robot(), &q);
    ctrl.start(0.0);
    let mut t = 0.0;
    for _ in 0..300 {
        t += 0.01;
        let out = cycle(&mut ctrl, t, &q, &raw, pose);
        assert!(!out.flags.has(Flags::MODEL_MISMATCH));
    }
    assert_eq!(ctrl.phase(), Phase::Running);
    let before = ctrl.last_output().xi;
    assert!(before[2].abs() > 5e-4, "{before:?}");
    let m = ctrl.pose_mismatch_max().unwrap();
    assert!(m.position_m < 1e-12, "{m:?}");
    // The controller reports its TCP 8 mm off (its tool or base changed mid-session).
    let mut jumped = pose;
    jumped.translation.vector += Vector3::new(0.0, 0.008, 0.0);
    let mut previous = before;
    for _ in 0..200 {
        t += 0.01;
        let out = cycle(&mut ctrl, t, &q, &raw, jumped);
        assert!(out.flags.has(Flags::LATCHED) && out.flags.has(Flags::MODEL_MISMATCH));
        for i in 0..6 {
            assert!(
                out.xi[i].abs() <= previous[i].abs() + 1e-15,
                "ξ grew on axis {i}"
            );
        }
        previous = out.xi;
    }
    assert_eq!(ctrl.last_output().xi, [0.0; 6], "not ramped out");
    let fault = ctrl.fault().unwrap();
    assert_eq!(fault.kind, FaultKind::ModelMismatch);
    assert_eq!(fault.unit(), "m");
    assert!((fault.value - 0.008).abs() < 1e-9, "{fault}");
    let text = fault.to_string();
    assert!(
        text.starts_with(
            "model_mismatch: TCP position reported 8.00 mm from the model's at the same joints, \
             limit 5.00 mm"
        ),
        "{text}"
    );
    assert!((ctrl.pose_mismatch_max().unwrap().position_m - 0.008).abs() < 1e-9);
}

#[test]
fn the_orientation_is_checked_and_the_check_can_be_off() {
    let mut config = common::config();
    let q = common::q0();
    let raw = common::raw_reading(&config, &q, [0.0; 6]);
    let mut turned = reported(&common::robot(), &q);
    turned.rotation *= Rotation3::from_axis_angle(&Vector3::x_axis(), 0.015);
    let mut ctrl = common::controller(config);
    ctrl.start(0.0);
    cycle(&mut ctrl, 0.01, &q, &raw, turned);
    let fault = ctrl.fault().unwrap();
    assert_eq!(
        (fault.kind, fault.unit()),
        (FaultKind::ModelMismatch, "rad")
    );
    assert!(
        fault
            .to_string()
            .starts_with("model_mismatch: TCP orientation reported 15.00 mrad"),
        "{fault}"
    );
    config.model_check.enabled = false;
    let mut off = common::controller(config);
    off.start(0.0);
    for k in 1..50 {
        cycle(&mut off, 0.01 * f64::from(k), &q, &raw, turned);
    }
    assert!(off.fault().is_none() && off.pose_mismatch_max().is_none());
    // Without a reported pose (Stäubli, the simple line links) nothing is compared.
    let mut none = common::controller(common::config());
    none.start(0.0);
    none.cycle(0.01, &q, &raw);
    assert!(none.pose_mismatch_max().is_none());
}
