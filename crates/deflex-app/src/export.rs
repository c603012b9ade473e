//! `deflex export`: a calibrated robot where controllers and ROS stacks read it — a URDF with
//! the calibrated joint origins (plus a deflex robot file beside it that reads the URDF and
//! keeps the stiffnesses), Universal Robots' calibration YAML, or a DH table with the
//! corrections against a nominal robot (`deflex_cam::export`). Each file is read back before it
//! is kept and its forward kinematics compared with the model's over
//! [`CONFIGURATIONS_CHECKED`] configurations within the joint limits: the export fails (writing
//! nothing) beyond [`READBACK_BOUND_M`].

use crate::error::{Error, Result};
use deflex_model::Robot;
use serde_json::json;
use std::path::{Path, PathBuf};

/// Configurations over which a file read back is compared with the model.
pub const CONFIGURATIONS_CHECKED: usize = 500;

/// Largest TCP position difference between the file read back and the model (m).
pub const READBACK_BOUND_M: f64 = 1e-6;

/// The export formats (`--format`).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
#[cfg_attr(feature = "clap", derive(clap::ValueEnum))]
pub enum ExportFormat {
    /// URDF (`world` → `base_link` → `link_1` … → `flange` → `tcp`) and a robot TOML reading it.
    Urdf,
    /// Universal Robots' calibration YAML (`ur_calibration` / `ur_robot_driver` layout).
    UrCalibration,
    /// DH table (CSV, units in the column names), with corrections against `--nominal`.
    DhTable,
}

impl ExportFormat {
    /// The name on the command line (`urdf`, `ur-calibration`, `dh-table`).
    pub fn name(self) -> &'static str {
        match self {
            ExportFormat::Urdf => "urdf",
            ExportFormat::UrCalibration => "ur-calibration",
            ExportFormat::DhTable => "dh-table",
        }
    }
}

/// What an export wrote and how well it read back.
#[derive(Clone, Debug)]
pub struct Exported {
    /// The robot's name.
    pub robot: String,
    /// Its geometry's fingerprint.
    pub robot_geometry: String,
    /// The format.
    pub format: ExportFormat,
    /// The files written (the URDF's robot TOML after it).
    pub files: Vec<PathBuf>,
    /// Largest TCP position difference of the file read back (m).
    pub readback_max_tcp_error_m: f64,
}

impl Exported {
    /// The result in one line (what the CLI prints).
    pub fn text(&self) -> String {
        format!(
            "{}: wrote {} (read back: forward kinematics within {:.3e} m of the model over {CONFIGURATIONS_CHECKED} configurations)",
            self.robot,
            self.shown_files().join(", "),
            self.readback_max_tcp_error_m
        )
    }

    /// The result as JSON (what the CLI prints with `--json`).
    pub fn json(&self) -> serde_json::Value {
        json!({
            "robot": self.robot,
            "robot_geometry": self.robot_geometry,
            "format": self.format.name(),
            "files": self.shown_files(),
            "readback_max_tcp_error_m": self.readback_max_tcp_error_m,
            "configurations_checked": CONFIGURATIONS_CHECKED,
        })
    }

    fn shown_files(&self) -> Vec<String> {
        self.files.iter().map(|p| p.display().to_string()).collect()
    }
}

/// Export `robot` in `format` to `out` (the URDF's robot TOML beside it, `out` with the
/// extension `toml`), the DH table's corrections against `nominal`: every file read back and
/// compared first (see the module documentation), then each written whole.
pub fn export(
    robot: &Robot,
    format: ExportFormat,
    out: &Path,
    nominal: Option<&Robot>,
) -> Result<Exported> {
    let mut files: Vec<(PathBuf, String)> = Vec::new();
    let error_m = match format {
        ExportFormat::Urdf => {
            let xml = deflex_cam::export::urdf(robot);
            let file_name = out
                .file_name()
                .map_or("robot.urdf".into(), |n| n.to_string_lossy().into_owned());
            let toml = deflex_cam::export::urdf_robot_toml(robot, &file_name);
            let back = deflex_model::robot_from_toml_and_urdf_str(&toml, &xml, "export.toml")
                .map_err(Error::UrdfReadback)?;
            let gap = largest_gap(robot, &|q| {
                back.tcp_pose(q).ok().map(|p| p.translation.vector)
            });
            files.push((out.to_path_buf(), xml));
            files.push((out.with_extension("toml"), toml));
            gap
        }
        ExportFormat::UrCalibration => {
            let mut flange = robot.clone();
            flange.tool = deflex_model::Pose::identity();
            let yaml = deflex_cam::export::ur_calibration(&flange)?;
            let segments =
                deflex_cam::export::read_ur_calibration(&yaml, &out.display().to_string())?;
            let gap = largest_gap(&flange, &|q| {
                let mut t = deflex_model::Pose::identity();
                for (s, qi) in segments.iter().zip(q) {
                    t = t * deflex_cam::export::segment_pose(s) * deflex_model::spatial::rot_z(*qi);
                }
                Some(t.translation.vector)
            });
            files.push((out.to_path_buf(), yaml));
            gap
        }
        ExportFormat::DhTable => {
            let text = deflex_cam::export::dh_table(robot, nominal)?;
            let rows = deflex_cam::export::read_dh_table(&text, &out.display().to_string())?;
            // The table's rows rebuild the robot's placements.
            let mut rebuilt = robot.clone();
            for (joint, row) in rebuilt.joints.iter_mut().zip(&rows) {
                joint.dh = Some(row.dh);
                joint.theta_offset = row.theta_offset;
            }
            rebuilt.rebuild_dh_geometry();
            let gap = largest_gap(robot, &|q| {
                rebuilt.tcp_pose(q).ok().map(|p| p.translation.vector)
            });
            files.push((out.to_path_buf(), text));
            gap
        }
    };
    if error_m.is_nan() || error_m > READBACK_BOUND_M {
        return Err(Error::ExportMismatch {
            format: format.name(),
            error_m,
        });
    }
    for (path, text) in &files {
        crate::table::write_text(path, text)?;
    }
    Ok(Exported {
        robot: robot.name.clone(),
        robot_geometry: robot.geometry_fingerprint(),
        format,
        files: files.into_iter().map(|(path, _)| path).collect(),
        readback_max_tcp_error_m: error_m,
    })
}

/// Configurations within the limits (±3 rad where there are none), deterministic.
fn configurations(robot: &Robot, count: usize) -> Vec<Vec<f64>> {
    let mut state: u64 = 0x9e37_79b9_7f4a_7c15;
    (0..count)
        .map(|_| {
            robot
                .joints
                .iter()
                .map(|j| {
                    state ^= state << 13;
                    state ^= state >> 7;
                    state ^= state << 17;
                    let u = (state >> 11) as f64 / (1u64 << 53) as f64;
                    let [lo, hi] = j.limits.unwrap_or([-3.0, 3.0]);
                    let (lo, hi) = (lo.max(-3.0), hi.min(3.0));
                    lo + (hi - lo) * u
                })
                .collect()
        })
        .collect()
}

/// The largest TCP position difference between two chains over the configurations checked.
fn largest_gap(robot: &Robot, other: &dyn Fn(&[f64]) -> Option<nalgebra::Vector3<f64>>) -> f64 {
    configurations(robot, CONFIGURATIONS_CHECKED)
        .iter()
        .map(|q| match (robot.tcp_pose(q), other(q)) {
            (Ok(a), Some(b)) => (a.translation.vector - b).norm(),
            _ => f64::INFINITY,
        })
        .fold(0.0, f64::max)
}
