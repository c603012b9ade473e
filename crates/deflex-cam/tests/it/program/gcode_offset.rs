//! The G-code program's work offset (issue 36): named with its exact values in the header, set by
//! the program itself with `gcode.set_work_offset` (`G10 L2 Pn` for the path's work offset),
//! refused for a rotated part frame or a work offset `G10 L2` cannot set, and a program in the
//! robot base frame asks for a zero offset.

use deflex_cam::program::readback::read_gcode;
use deflex_cam::program::settings::ProgramSettings;
use deflex_cam::program::{Coordinates, Format, ProgramError, ProgramInput, ProgramPoint, export};
use deflex_model::Pose;
use nalgebra::{Rotation3, Translation3, Vector3};

fn input(frame: Pose, frame_name: Option<&str>) -> ProgramInput {
    let down = Rotation3::from_axis_angle(&Vector3::x_axis(), std::f64::consts::PI);
    let points = (0..5)
        .map(|i| ProgramPoint {
            pose: Pose::from_parts(Translation3::new(0.01 * i as f64, 0.0, -0.001), down),
            speed_m_s: (i > 0).then_some(0.01),
        })
        .collect();
    let mut input = ProgramInput::new(points);
    input.frame_in_robot = frame;
    input.frame_name = frame_name.map(str::to_string);
    input.tool_in_flange = Pose::translation(0.0, 0.0, 0.123_456_78);
    input
}

fn gcode(input: &ProgramInput, set: bool) -> Result<String, ProgramError> {
    let mut settings = ProgramSettings::default();
    settings.gcode.set_work_offset = set;
    Ok(export(Format::Gcode, input, &settings)?.remove(0).contents)
}

#[test]
fn the_header_names_the_exact_offset_and_g10_sets_it() {
    let frame = Pose::translation(1.713_635_12, -0.000_049_9, 0.207_645_04);
    let text = gcode(&input(frame, Some("G56")), false).unwrap();
    assert!(
        text.contains("( work offset G56 must hold the part frame in the robot base frame [mm]: X1713.6351 Y-0.0499 Z207.6450 )"),
        "{text}"
    );
    assert!(
        text.contains("flange -> X0.0000 Y0.0000 Z123.4568 mm"),
        "{text}"
    );
    assert!(!text.contains("G10"), "{text}");
    let set = gcode(&input(frame, Some("G56")), true).unwrap();
    assert!(
        set.contains("\nG10 L2 P3 X1713.6351 Y-0.0499 Z207.6450\n"),
        "{set}"
    );
    assert!(set.find("G10 L2").unwrap() < set.find("G17 G40").unwrap());
    // Both read back to the same motions: the G10 line is a setting, not a motion.
    let a = read_gcode(&text, "a.gcode").unwrap();
    let b = read_gcode(&set, "b.gcode").unwrap();
    assert_eq!(a.len(), b.len());
    assert_eq!(a.len(), 7, "clearance, five points, retract");
    let default_offset = gcode(&input(frame, None), true).unwrap();
    assert!(default_offset.contains("\nG10 L2 P1 X"), "G54 by default");
    let last = gcode(&input(frame, Some("G59.3")), true).unwrap();
    assert!(last.contains("\nG10 L2 P9 X"), "{last}");
}

#[test]
fn a_rotated_frame_or_a_robot_frame_program_is_not_given_a_g10() {
    let rotated = Pose::from_parts(
        Translation3::new(1.0, 0.2, 0.1),
        Rotation3::from_axis_angle(&Vector3::z_axis(), 0.3),
    );
    let text = gcode(&input(rotated, None), false).unwrap();
    assert!(
        text.contains("rotated by roll-pitch-yaw 0.000000 0.000000 17.188734 deg"),
        "{text}"
    );
    let e = gcode(&input(rotated, None), true).unwrap_err().to_string();
    assert!(
        e.contains("gcode.set_work_offset") && e.contains("rotated"),
        "{e}"
    );
    let mut robot = input(Pose::identity(), None);
    robot.coordinates = Coordinates::Robot;
    for set in [false, true] {
        let text = gcode(&robot, set).unwrap();
        assert!(
            text.contains(
                "( work offset G54 must be zero: the positions are in the robot base frame )"
            ),
            "{text}"
        );
        assert!(!text.contains("G10"), "{text}");
    }
}
