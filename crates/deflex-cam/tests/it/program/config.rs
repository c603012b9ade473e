//! The arm configuration words (`deflex_cam::program::config`): KUKA Status and Turn, ABB
//! `robconf`, Stäubli `config`.

use deflex_cam::program::ArmConfiguration;
use deflex_cam::program::config::{abb_robconf, kuka_status_turn, staubli_config};

fn arm(q_deg: [f64; 6], behind: bool, lower: bool, stretched: bool) -> ArmConfiguration {
    ArmConfiguration {
        joints_rad: q_deg.map(f64::to_radians),
        wrist_behind_axis_1: behind,
        wrist_behind_lower_arm: lower,
        elbow_beyond_stretched: stretched,
        elbow_up: stretched,
    }
}

#[test]
fn status_turn_robconf_and_config_follow_the_definitions() {
    // KUKA's own example pose: A1..A6 = 0, −90, 90, 0, 45, 0 (basic area, A5 > 0): S 2
    // when A3 ≥ φ, T 2 (A2 negative).
    let c = arm([0.0, -90.0, 90.0, 0.0, 45.0, 0.0], false, false, true);
    assert_eq!(kuka_status_turn(&c), (0b010, 0b000010));
    let c = arm(
        [-10.0, -90.0, 90.0, -30.0, -45.0, -170.0],
        true,
        false,
        false,
    );
    assert_eq!(kuka_status_turn(&c), (0b101, 0b111011));
    // ABB: quadrants and cfx.
    let c = arm([95.0, 0.0, 0.0, -45.0, -10.0, 181.0], true, true, false);
    assert_eq!(abb_robconf(&c), [1, -1, 2, 7]);
    let c = arm([-0.5, 0.0, 0.0, 0.0, 30.0, -90.0], false, false, false);
    assert_eq!(abb_robconf(&c), [-1, 0, -1, 0]);
    assert_eq!(staubli_config(&c), ("righty", "epositive", "wpositive"));
    let c = arm([0.0, 0.0, -5.0, 0.0, -1.0, 0.0], true, false, false);
    assert_eq!(staubli_config(&c), ("lefty", "enegative", "wnegative"));
}
