//! The robot programs of a compensation: the commanded poses in the program frame with the
//! arm's configuration at every point (joint values from the compensation, the wrist centre's
//! side from the model's forward kinematics), the clearance points' joint values by inverse
//! kinematics, written per format and read back: every path point within 1 µm (and 2 µrad for
//! the formats with an orientation), the first and last motions at the clearance points,
//! outside the part. The output folder's programs are written to disk part by part and read
//! back from disk line by line, so a million-point program is never held in memory (only the
//! program input is); Python's are made and read back in memory.

use super::Setup;
use super::setup::check_program_points;
use crate::error::{Error, Result};
use deflex_cam::program::readback::{
    DirectorySource, MemorySource, ProgramSource, ReadPoint, read_program,
};
use deflex_cam::program::{
    ArmConfiguration, DirectorySink, Format, MemorySink, ProgramFile, ProgramInput,
    ProgramSettings, export_to,
};
use deflex_compensate::Compensation;
use deflex_model::{Data, IkOptions, Pose, Robot};
use serde_json::json;
use std::path::Path;

/// Largest distance of a program's motion from the path's point (m).
const READBACK_POSITION_BOUND_M: f64 = 1e-6;
/// Largest angle of a program's motion from the path's orientation (rad).
const READBACK_ROTATION_BOUND_RAD: f64 = 2e-6;

/// What was checked of one format's program.
#[derive(Clone, Debug)]
pub struct ProgramCheck {
    /// The format.
    pub format: Format,
    /// The files, relative to the programs' folder, the main program first.
    pub files: Vec<String>,
    /// Bytes written.
    pub bytes: usize,
    /// Part files (1 for a program in one file).
    pub parts: usize,
    /// Largest distance of a motion read back from its point (m).
    pub max_position_error_m: f64,
    /// Largest angle of a motion read back from its orientation (rad).
    pub max_rotation_error_rad: f64,
    /// Height of the first and last motions above the path's highest point (m, program frame).
    pub first_last_height_m: [f64; 2],
}

impl ProgramCheck {
    /// The check in one line (the summary's text).
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

    /// The check for `summary.json`.
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

/// The programs' input of a compensation: the commanded poses in the program frame, the arm's
/// configurations and the clearance points, ready to write in any format.
pub struct ProgramPlan {
    input: ProgramInput,
    clear: [Pose; 2],
    /// The path's highest point (program frame, m).
    top: f64,
}

impl ProgramPlan {
    /// The input of the programs of `result` (the compensation of `setup`'s path) with the
    /// template `settings` and the header lines `description`. The compensation may be freed
    /// once this returns.
    pub fn new(
        setup: &Setup,
        result: &Compensation,
        description: Vec<String>,
        settings: &ProgramSettings,
    ) -> Result<ProgramPlan> {
        let names = setup.front;
        check_program_points(setup.path.len(), settings, names)?;
        let robot = &setup.robot;
        let n = robot.joint_count();
        let (first, last) = match (result.points.first(), result.points.last()) {
            (Some(first), Some(last)) => (first.q, last.q),
            _ => return Err(Error::invalid(names.name("path"), "the path has no point")),
        };
        let mut data = Data::new();
        let six = n == 6;
        let phi = if six {
            stretched_q3(robot, &first[..6], &mut data)
        } else {
            0.0
        };
        let mut input = ProgramInput::from_world_poses(
            setup
                .path
                .points()
                .iter()
                .zip(&result.points)
                .map(|(p, c)| (c.commanded(&p.pose), p.feed_m_s)),
            &robot.base,
            &setup.part_frame,
            settings.program.coordinates,
            &robot.tool,
            description,
        );
        input.frame_name = setup.frame_name.clone();
        input.tool_load_in_flange = setup.tool_load_in_flange;
        input.tool_load_source = setup.tool_load_source.into();
        if six {
            input.configurations = result
                .points
                .iter()
                .map(|c| arm_configuration(robot, &c.q[..6], phi, &mut data))
                .collect();
        }
        // The clearance points in the world, their joint values from the path's ends.
        let clear = input
            .clearance_poses(settings)
            .ok_or_else(|| Error::invalid(names.name("path"), "the path has no point"))?;
        let frame_in_world = robot.base * input.frame_in_robot;
        if six {
            let mut configs = Vec::with_capacity(2);
            for (k, (pose, q)) in [(clear[0], first), (clear[1], last)].iter().enumerate() {
                let world: Pose = frame_in_world * pose;
                let options = IkOptions {
                    position_tolerance_m: 1e-9,
                    orientation_tolerance_rad: 1e-9,
                    ..IkOptions::default()
                };
                let solution = robot
                    .inverse_kinematics(&world, &q[..n], &options)
                    .map_err(|source| Error::Clearance {
                        which: if k == 0 { "start" } else { "end" },
                        names,
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
        Ok(ProgramPlan { input, clear, top })
    }

    /// Write the program in `format` under `dir` (which must exist), part by part, and read it
    /// back from disk (see the module documentation).
    pub fn write_checked(
        &self,
        format: Format,
        settings: &ProgramSettings,
        dir: &Path,
    ) -> Result<ProgramCheck> {
        let mut sink = DirectorySink::new(dir);
        let files = export_to(format, &self.input, settings, &mut sink)?;
        let check = self.read_back(format, &DirectorySource::new(dir), &files)?;
        Ok(ProgramCheck {
            bytes: sink.bytes as usize,
            parts: files.iter().filter(|f| is_part_file(f)).count().max(1),
            files,
            ..check
        })
    }

    /// The program in `format` in memory, read back (see the module documentation): its files,
    /// the main program first.
    pub fn export_checked(
        &self,
        format: Format,
        settings: &ProgramSettings,
    ) -> Result<Vec<ProgramFile>> {
        let mut sink = MemorySink::default();
        let order = export_to(format, &self.input, settings, &mut sink)?;
        let mut files = sink.files;
        files.sort_by_key(|f| order.iter().position(|p| *p == f.path));
        self.read_back(format, &MemorySource(&files), &order)?;
        Ok(files)
    }

    /// Read the program back from `source` and compare it with the input.
    fn read_back(
        &self,
        format: Format,
        source: &dyn ProgramSource,
        files: &[String],
    ) -> Result<ProgramCheck> {
        let mut compare = Compare::new(format, &self.input, &self.clear, self.top);
        read_program(format, source, files, &mut |p| {
            compare.point(&p);
            Ok(())
        })?;
        compare.finish()
    }
}

/// A part file: `NAME_p01.src` …, `NAME_P01.ls` (FANUC) … or `NAME/part1.pgx` ….
pub fn is_part_file(path: &str) -> bool {
    let stem = path.rsplit('/').next().unwrap_or(path);
    let stem = stem.split('.').next().unwrap_or(stem);
    let digits = |s: &str| !s.is_empty() && s.chars().all(|c| c.is_ascii_digit());
    stem.rsplit_once("_p").is_some_and(|(_, n)| digits(n))
        || stem.rsplit_once("_P").is_some_and(|(_, n)| digits(n))
        || stem.strip_prefix("part").is_some_and(digits)
}

/// The axis-3 value at which the arm is stretched (the wrist centre farthest from the axis-2
/// origin), with the other joints at `q`: KUKA Status bit 1's φ. A scan of one degree, then
/// golden-section refinement.
fn stretched_q3(robot: &Robot, q: &[f64], data: &mut Data) -> f64 {
    let mut joints = q.to_vec();
    let distance = |q3: f64, joints: &mut Vec<f64>, data: &mut Data| {
        joints[2] = q3;
        // A 6-joint arm's joint values: the forward kinematics cannot fail on their count.
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
    // A 6-joint arm's joint values: the forward kinematics cannot fail on their count.
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
    // The elbow above the line from axis 2 to the wrist: the part of (axis 3 − axis 2) across
    // that line points up along R0's z (world vectors).
    let up = robot.base.rotation * nalgebra::Vector3::z();
    let (p2w, p3w, ww) = (
        data.link_frame(2).translation.vector,
        data.link_frame(3).translation.vector,
        data.link_frame(5).translation.vector,
    );
    let (d, e) = (ww - p2w, p3w - p2w);
    let across = e - d * (d.dot(&e) / d.norm_squared().max(f64::MIN_POSITIVE));
    let mut joints_rad = [0.0; 6];
    joints_rad.copy_from_slice(&q[..6]);
    ArmConfiguration {
        joints_rad,
        wrist_behind_axis_1: wrist.x < 0.0,
        wrist_behind_lower_arm: cross > 0.0,
        elbow_beyond_stretched: q[2] >= phi,
        elbow_up: across.dot(&up) > 0.0,
    }
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

    fn error(&self, what: String) -> Error {
        Error::Readback {
            format: self.format.name(),
            what,
        }
    }

    fn point(&mut self, r: &ReadPoint) {
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
    }

    fn finish(self) -> Result<ProgramCheck> {
        let n = self.input.points.len();
        if self.read != n + 2 {
            return Err(self.error(format!("{} motions, expected {}", self.read, n + 2)));
        }
        if self.position > READBACK_POSITION_BOUND_M || self.rotation > READBACK_ROTATION_BOUND_RAD
        {
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
