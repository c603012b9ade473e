//! Fuzzing deflex's model parsers, the robot TOML and URDF readers: random and mutated inputs
//! must give `Ok` or an error, never a panic or a hang. A quick count here; ≥ 10⁶ with
//! `DEFLEX_FUZZ_COUNT=1000000 cargo test --release -p deflex --test it fuzz::model -- --nocapture`.

use crate::fuzz::engine::{count_from_env, fuzz};
use deflex_model::{BUILTIN_ROBOTS, Data, robot_from_toml_and_urdf_str, robot_from_toml_str};

/// A robot that parsed must be usable: FK and the deflection do not panic either.
fn exercise(robot: &deflex_model::Robot) {
    let mut data = Data::new();
    let q = vec![0.3; robot.joint_count()];
    robot.forward_kinematics(&mut data, &q).unwrap();
    let _ = robot.tcp_deflection(
        &data,
        &deflex_model::Wrench::new(1.0, 2.0, 3.0, 0.1, 0.2, 0.3),
    );
    let _ = robot.gravity_displacement(&data, &data.tcp_position(), robot.joint_count());
}

#[test]
fn robot_toml_reader_never_panics() {
    let corpus: Vec<&[u8]> = BUILTIN_ROBOTS.iter().map(|(_, t)| t.as_bytes()).collect();
    let count = count_from_env(20_000);
    let report = fuzz(&corpus, count, 8192, |input| {
        let text = String::from_utf8_lossy(input);
        if let Ok(robot) = robot_from_toml_str(&text, "fuzz.toml", None) {
            exercise(&robot);
        }
    });
    report.assert_no_panic("robot TOML");
    println!("robot TOML: {} inputs, no panic", report.inputs);
}

const URDF: &str = r#"<?xml version="1.0"?>
<robot name="arm">
  <link name="base_link"/>
  <link name="link_1"><inertial><origin xyz="0.1 0 0.2" rpy="0 0 0"/><mass value="12.5"/></inertial></link>
  <link name="link_2"><inertial><origin xyz="0.3 0 0"/><mass value="8"/></inertial></link>
  <link name="tool0"/>
  <joint name="joint_1" type="revolute"><origin xyz="0 0 0.4" rpy="0 0 0"/><parent link="base_link"/>
    <child link="link_1"/><axis xyz="0 0 1"/><limit lower="-3.14" upper="3.14" effort="0" velocity="1"/></joint>
  <joint name="joint_2" type="continuous"><origin xyz="0.2 0 0" rpy="1.5708 0 0"/><parent link="link_1"/>
    <child link="link_2"/><axis xyz="0 1 0"/></joint>
  <joint name="flange" type="fixed"><origin xyz="0.5 0 0" rpy="0 1.5708 0"/><parent link="link_2"/><child link="tool0"/></joint>
  <!-- a comment <joint> -->
</robot>
"#;

const URDF_TOML: &str = "name = \"fuzz\"\nurdf = \"arm.urdf\"\n[[joint]]\nname = \"joint_1\"\nstiffness = { z = 1e6 }\n[[joint]]\nname = \"joint_2\"\n";

#[test]
fn urdf_reader_never_panics() {
    let corpus: &[&[u8]] = &[URDF.as_bytes()];
    robot_from_toml_and_urdf_str(URDF_TOML, URDF, "fuzz").expect("the corpus entry is valid");
    let count = count_from_env(20_000);
    let report = fuzz(corpus, count, 8192, |input| {
        let xml = String::from_utf8_lossy(input);
        if let Ok(robot) = robot_from_toml_and_urdf_str(URDF_TOML, &xml, "fuzz") {
            exercise(&robot);
        }
    });
    report.assert_no_panic("URDF");
    println!("URDF: {} inputs, no panic", report.inputs);
}
