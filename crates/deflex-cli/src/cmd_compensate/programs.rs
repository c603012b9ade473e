//! The robot programs of a compensation: the commanded poses in the program frame with the
//! arm's configuration at every point (joint values from the compensation, the wrist centre's
//! side from the model's forward kinematics), the clearance points' joint values by inverse
//! kinematics, written per format and read back: every path point within 1 µm (and 2 µrad for
//! the formats with an orientation), the first and last motions at the clearance points,
//! outside the part. Each format is written to disk part by part and read back from disk line
//! by line, so a million-point program is never held in memory (only the program input is).

use super::setup::Setup;
use deflex_cam::program::readback::{DirectorySource, ReadPoint, read_program};
use deflex_cam::program::{ArmConfiguration, DirectorySink, Format, ProgramInput, export_to};
use deflex_compensate::Compensation;
use deflex_model::{Data, IkOptions, Pose, Robot};
use serde_json::json;
use std::path::Path;

/// A program that could not be written or that did not read back as the path.
#[derive(Debug, thiserror::Error)]
pub enum ProgramCheckError {
    /// Writing failed.
    #[error(transparent)]
    Program(#[from] deflex_cam::program::ProgramError),
    /// The clearance point's joint values.
    #[error(
        "the clearance point above the {which} of the path is not reachable ({source}): lower program.clearance_mm in --program-config or move the part with --part-xyz-mm"
    )]
    Clearance {
        /// `start` or `end`.
        which: &'static str,
        /// Why.
        source: deflex_model::ModelError,
    },
    /// The program read back differs from the path (a bug: nothing is written then).
    #[error("{format}: read back {what}")]
    Readback {
        /// The format.
        format: &'static str,
        /// What differs.
        what: String,
    },
}

/// What was checked of one format's program.
pub struct ProgramCheck {
    pub format: Format,
    pub files: Vec<String>,
    pub bytes: usize,
    pub parts: usize,
    pub max_position_error_m: f64,
    pub max_rotation_error_rad: f64,
    /// Height of the first and last motions above the path's highest point (m, program frame).
    pub first_last_height_m: [f64; 2],
}

impl ProgramCheck {
    pub fn line(&self) -> String {
        format!(
            "{}: {} file(s), {} part(s), {:.0} kB; read back within {:.2} µm, {:.2} µrad; first and last motions {:.1} / {:.1} mm above the part's highest point",
            self.format.name(),
            self.files.len(),
            self.parts,
            self.bytes as f64 / 1024.0,
            self.max_position_error_m * 1e6,
            self.max_rotation_error_rad * 1e6,
            self.first_last_height_m[0] * 1e3,
            self.first_last_height_m[1] * 1e3
        )
    }

    pub fn json(&self) -> serde_json::Value {
        json!({
            "format": self.format.name(),
            "files": self.files,
            "bytes": self.bytes,
            "parts": self.parts,
            "readback_max_position_error_m": self.max_position_error_m,
            "readback_max_rotation_error_rad": self.max_rotation_error_rad,
            "first_last_motion_height_above_part_m": self.first_last_height_m,
        })
    }
}

/// The axis-3 value at which the arm is stretched (the wrist centre farthest from the axis-2
/// origin), with the other joints at `q`: KUKA Status bit 1's φ. A scan of one degree, then
/// golden-section refinement.
fn stretched_q3(robot: &Robot, q: &[f64], data: &mut Data) -> f64 {
    let mut joints = q.to_vec();
    let distance = |q3: f64, joints: &mut Vec<f64>, data: &mut Data| {
        joints[2] = q3;
        let _ = robot.forward_kinematics(data, joints);
        (data.link_frame(5).translation.vector - data.link_frame(2).translation.vector).norm()
    };
    let (mut best, mut best_d) = (0.0, f64::MIN);
    for k in -180..180 {
        let q3 = f64::from(k).to_radians();
        let d = distance(q3, &mut joints, data);
        if d > best_d {
            (best, best_d) = (q3, d);
        }
    }
    let (mut a, mut b) = (best - 1f64.to_radians(), best + 1f64.to_radians());
    let ratio = 0.5 * (5f64.sqrt() - 1.0);
    for _ in 0..40 {
        let c = b - ratio * (b - a);
        let d = a + ratio * (b - a);
        if distance(c, &mut joints, data) > distance(d, &mut joints, data) {
            b = d;
        } else {
            a = c;
        }
    }
    0.5 * (a + b)
}

/// The arm's configuration at `q` (see [`ArmConfiguration`]); `phi` is [`stretched_q3`].
fn arm_configuration(robot: &Robot, q: &[f64], phi: f64, data: &mut Data) -> ArmConfiguration {
    let _ = robot.forward_kinematics(data, q);
    let a1 = data.link_frame(1).inverse();
    let wrist = a1 * nalgebra::Point3::from(data.link_frame(5).translation.vector);
    let p2 = a1 * nalgebra::Point3::from(data.link_frame(2).translation.vector);
    let p3 = a1 * nalgebra::Point3::from(data.link_frame(3).translation.vector);
    // In the arm's plane (x, z of the A1 frame): the wrist in front of the lower arm when it
    // lies on the forward side of the line from axis 2 to axis 3 (for an upright lower arm, at
    // positive x): u × v < 0.
    let (u, v) = (p3 - p2, wrist - p2);
    let cross = u.x * v.z - u.z * v.x;
    let mut joints_rad = [0.0; 6];
    joints_rad.copy_from_slice(&q[..6]);
    ArmConfiguration {
        joints_rad,
        wrist_behind_axis_1: wrist.x < 0.0,
        wrist_behind_lower_arm: cross > 0.0,
        elbow_beyond_stretched: q[2] >= phi,
    }
}

/// Write every format's program under `dir` and read each back (see the module documentation).
pub fn write_programs(
    s: &Setup,
    result: Compensation,
    description: Vec<String>,
    dir: &Path,
    _json: bool,
) -> Result<Vec<ProgramCheck>, ProgramCheckError> {
    let robot = &s.robot;
    let n = robot.joint_count();
    let mut data = Data::new();
    let six = n == 6;
    let phi = if six {
        stretched_q3(robot, &result.points[0].q[..6], &mut data)
    } else {
        0.0
    };
    let mut input = ProgramInput::from_world_poses(
        s.path
            .points()
            .iter()
            .zip(&result.points)
            .map(|(p, c)| (c.commanded(&p.pose), p.feed_m_s)),
        &robot.base,
        &s.part_frame,
        s.settings.program.coordinates,
        &robot.tool,
        description,
    );
    input.frame_name = s.frame_name.clone();
    input.tool_load_in_flange = s.tool_load_in_flange;
    input.tool_load_source = s.tool_load_source.into();
    if six {
        input.configurations = result
            .points
            .iter()
            .map(|c| arm_configuration(robot, &c.q[..6], phi, &mut data))
            .collect();
    }
    let first_q = result.points[0].q;
    let last_q = result.points[result.points.len() - 1].q;
    drop(result);
    // The clearance points in the world, their joint values from the path's ends.
    let clear = input
        .clearance_poses(&s.settings)
        .expect("the path has points");
    let frame_in_world = robot.base * input.frame_in_robot;
    if six {
        let mut configs = Vec::with_capacity(2);
        for (k, (pose, q)) in [(clear[0], first_q), (clear[1], last_q)].iter().enumerate() {
            let world: Pose = frame_in_world * pose;
            let options = IkOptions {
                position_tolerance_m: 1e-9,
                orientation_tolerance_rad: 1e-9,
                ..IkOptions::default()
            };
            let solution = robot
                .inverse_kinematics(&world, &q[..n], &options)
                .map_err(|source| ProgramCheckError::Clearance {
                    which: if k == 0 { "start" } else { "end" },
                    source,
                })?;
            configs.push(arm_configuration(robot, &solution.q, phi, &mut data));
        }
        input.clearance_configurations = Some([configs[0], configs[1]]);
    }
    let top = input
        .points
        .iter()
        .map(|p| p.pose.translation.vector.z)
        .fold(f64::MIN, f64::max);
    let mut checks = Vec::new();
    for format in &s.formats {
        let mut sink = DirectorySink::new(dir);
        let files = export_to(*format, &input, &s.settings, &mut sink)?;
        let mut compare = Compare::new(*format, &input, &clear, top);
        read_program(*format, &DirectorySource::new(dir), &files, &mut |p| {
            compare.point(&p)
        })?;
        let check = compare.finish()?;
        checks.push(ProgramCheck {
            format: *format,
            bytes: sink.bytes as usize,
            parts: files.iter().filter(|f| is_part(f)).count().max(1),
            files,
            ..check
        });
    }
    Ok(checks)
}

/// A part file: `NAME_p01.src` … or `NAME/part1.pgx` ….
fn is_part(path: &str) -> bool {
    let stem = path.rsplit('/').next().unwrap_or(path);
    let stem = stem.split('.').next().unwrap_or(stem);
    let digits = |s: &str| !s.is_empty() && s.chars().all(|c| c.is_ascii_digit());
    stem.rsplit_once("_p").is_some_and(|(_, n)| digits(n))
        || stem.strip_prefix("part").is_some_and(digits)
}

/// The program read back against the input, motion by motion as it is read: the clearance
/// point, the path points, the clearance point.
struct Compare<'a> {
    format: Format,
    input: &'a ProgramInput,
    clear: &'a [Pose; 2],
    top: f64,
    read: usize,
    position: f64,
    rotation: f64,
    heights: [f64; 2],
}

impl<'a> Compare<'a> {
    fn new(format: Format, input: &'a ProgramInput, clear: &'a [Pose; 2], top: f64) -> Self {
        Compare {
            format,
            input,
            clear,
            top,
            read: 0,
            position: 0.0,
            rotation: 0.0,
            heights: [0.0; 2],
        }
    }

    fn error(&self, what: String) -> ProgramCheckError {
        ProgramCheckError::Readback {
            format: self.format.name(),
            what,
        }
    }

    fn point(&mut self, r: &ReadPoint) -> Result<(), deflex_cam::program::ProgramError> {
        let n = self.input.points.len();
        let k = self.read;
        self.read += 1;
        if k == 0 || k == n + 1 {
            let c = &self.clear[usize::from(k != 0)];
            self.position = self
                .position
                .max((c.translation.vector - r.position_m).norm());
            self.heights[usize::from(k != 0)] = r.position_m.z - self.top;
        } else if let Some(p) = self.input.points.get(k - 1) {
            self.position = self
                .position
                .max((p.pose.translation.vector - r.position_m).norm());
            if let Some(back) = r.rotation {
                self.rotation = self
                    .rotation
                    .max(deflex_model::conventions::rotation_distance(
                        &p.pose.rotation,
                        &back,
                    ));
            }
        }
        Ok(())
    }

    fn finish(self) -> Result<ProgramCheck, ProgramCheckError> {
        let n = self.input.points.len();
        if self.read != n + 2 {
            return Err(self.error(format!("{} motions, expected {}", self.read, n + 2)));
        }
        if self.position > 1e-6 || self.rotation > 2e-6 {
            return Err(self.error(format!(
                "{:.3e} m and {:.3e} rad from the path (bound 1 µm, 2 µrad)",
                self.position, self.rotation
            )));
        }
        Ok(ProgramCheck {
            format: self.format,
            files: Vec::new(),
            bytes: 0,
            parts: 0,
            max_position_error_m: self.position,
            max_rotation_error_rad: self.rotation,
            first_last_height_m: self.heights,
        })
    }
}
