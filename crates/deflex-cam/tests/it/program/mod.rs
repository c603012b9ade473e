//! The tests of `deflex_cam::program` (the old `deflex-program`).

mod common;
mod config;
mod fanuc;
mod gcode_offset;
mod inform;
mod names;
mod round_trip;
mod streaming;

use deflex_cam::program::{ArmConfiguration, ProgramInput, ProgramPoint};
use deflex_model::Pose;
use nalgebra::{Rotation3, Translation3, Vector3};

/// The test line of the TP and INFORM writers: `points` points along x, `step_m` apart, the tool
/// pointing down with a small tilt, at `speed_m_s`, the first point a rapid start.
fn tilted_line(points: usize, step_m: f64, speed_m_s: f64) -> Vec<ProgramPoint> {
    let down = Rotation3::from_axis_angle(&Vector3::y_axis(), std::f64::consts::PI);
    (0..points)
        .map(|i| ProgramPoint {
            pose: Pose::from_parts(
                Translation3::new(0.4 + step_m * i as f64, -0.1, 0.3),
                Rotation3::from_scaled_axis(Vector3::new(0.0, 1e-3 * (i % 7) as f64, 0.0)) * down,
            ),
            speed_m_s: (i > 0).then_some(speed_m_s),
        })
        .collect()
}

/// `points` described as a SIMULATED test line for `writer`, with a 200 mm tool and a 2.5 kg
/// tool load.
fn tool_input(points: Vec<ProgramPoint>, writer: &str) -> ProgramInput {
    let mut input = ProgramInput::new(points);
    input.description = vec![format!("SIMULATED test line for the {writer} writer")];
    input.tool_load_in_flange = Some(deflex_model::ToolLoad {
        mass_kg: 2.5,
        centre_of_mass_m: Vector3::new(0.0, 0.0, 0.08),
    });
    input.tool_load_source = "test".into();
    input.tool_in_flange = Pose::translation(0.0, 0.0, 0.2);
    input
}

/// An arm configuration with joints `q`, the wrist behind axis 1 or not, the elbow up (above
/// the line from axis 2 to the wrist, and beyond the stretched axis 3) or not.
fn arm(q: [f64; 6], behind: bool, elbow_up: bool) -> ArmConfiguration {
    ArmConfiguration {
        joints_rad: q,
        wrist_behind_axis_1: behind,
        wrist_behind_lower_arm: false,
        elbow_beyond_stretched: elbow_up,
        elbow_up,
    }
}
