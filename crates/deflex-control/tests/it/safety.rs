//! Latched faults and the safe value ([`deflex_control::safety`]).

use deflex_control::safety::*;
use deflex_telemetry::{FaultKind, Flags};

#[test]
fn fault_texts_name_check_channel_value_and_limit() {
    let f = Fault::new(FaultKind::JointOutOfLimits, 1.23, 3.2, std::f64::consts::PI)
        .on(Channel::Joint(2));
    assert_eq!(
        f.to_string(),
        "joint_out_of_limits: joint 3 value 3.2000 rad limit 3.1416 rad (183.35° vs 180.00°) at t = 1.230 s"
    );
    let f = Fault::new(FaultKind::SensorOverRange, 0.5, -2600.0, 2500.0).on(Channel::Sensor(2));
    assert_eq!(
        f.to_string(),
        "sensor_over_range: sensor fz value -2600.0000 N limit 2500.0000 N at t = 0.500 s"
    );
    let f = Fault::new(FaultKind::SensorStatus, 2.0, f64::from(0x8000_0001u32), 0.0);
    assert!(
        f.to_string()
            .starts_with("sensor_status: status word 0x80000001"),
        "{f}"
    );
    let f = Fault::new(FaultKind::ForceOverLimit, 2.0, 2600.0, 2500.0);
    assert_eq!(
        f.to_string(),
        "force_over_limit: value 2600.0000 N limit 2500.0000 N at t = 2.000 s"
    );
}

#[test]
fn every_kind_has_its_own_bit_below_the_state_bits() {
    let mut all = 0u32;
    for k in FaultKind::ALL {
        assert_eq!(all & k.flag(), 0, "{k}");
        all |= k.flag();
        assert!(k.flag() < Flags::LATCHED);
        assert_eq!(Flags(k.flag()).describe(), k.name());
    }
    assert_eq!(Flags::CONTACT_RUNAWAY, FaultKind::ContactRunaway.flag());
    assert_eq!(Flags::ROBOT_LINK_LOST, FaultKind::RobotLinkLost.flag());
    assert_eq!(Flags::MODEL_MISMATCH, FaultKind::ModelMismatch.flag());
}
