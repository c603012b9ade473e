//! `deflex export`: a calibrated robot where controllers and ROS stacks read it — a URDF with
//! the calibrated joint origins (plus a deflex robot file beside it that reads the URDF and
//! keeps the stiffnesses), Universal Robots' calibration YAML, or a DH table with the
//! corrections against a nominal robot. Each file is read back before it is kept and its
//! forward kinematics compared with the model's over 500 configurations within the joint
//! limits: the command fails (writing nothing) beyond 1 µm.

use crate::args::print_json;
use crate::error::CommandResult;
use clap::{Args, ValueEnum};
use deflex_model::Robot;
use serde_json::json;
use std::path::PathBuf;

/// The export formats.
#[derive(Clone, Copy, Debug, PartialEq, Eq, ValueEnum)]
pub enum ExportFormat {
    /// URDF (`world` → `base_link` → `link_1` … → `flange` → `tcp`) and a robot TOML reading it.
    Urdf,
    /// Universal Robots' calibration YAML (`ur_calibration` / `ur_robot_driver` layout).
    UrCalibration,
    /// DH table (CSV, units in the column names), with corrections against `--nominal`.
    DhTable,
}

#[derive(Args)]
pub struct ExportArgs {
    /// The (calibrated) robot: a robot TOML or a built-in name.
    #[arg(long)]
    pub robot: String,
    /// What to write.
    #[arg(long, value_enum)]
    pub format: ExportFormat,
    /// Output file (`.urdf`, `.yaml`, `.csv`).
    #[arg(long)]
    pub out: PathBuf,
    /// Nominal robot for the DH corrections (`dh-table`).
    #[arg(long)]
    pub nominal: Option<String>,
}

/// Why `deflex export` stops.
#[derive(Debug, thiserror::Error)]
pub enum ExportCommandError {
    /// A robot file.
    #[error("{flag} {spec}: {source}")]
    Robot {
        /// The flag.
        flag: &'static str,
        /// As given.
        spec: String,
        /// Why.
        source: deflex_model::ModelError,
    },
    /// The format cannot hold the robot, or the file did not read back.
    #[error(transparent)]
    Export(#[from] deflex_cam::export::ExportError),
    /// The URDF did not load.
    #[error("the written URDF does not read back: {0}")]
    Readback(deflex_model::ModelError),
    /// The read-back kinematics differ.
    #[error(
        "{format}: the file read back is {error_m:.3e} m from the model (bound 1e-6 m); nothing written"
    )]
    Mismatch {
        /// The format.
        format: &'static str,
        /// Largest TCP position difference (m).
        error_m: f64,
    },
    /// `--nominal` for another format.
    #[error("--nominal is only used with --format dh-table")]
    Nominal,
    /// Writing.
    #[error("{path}: {source}")]
    Output {
        /// The file.
        path: String,
        /// Why.
        source: std::io::Error,
    },
}

fn load(flag: &'static str, spec: &str) -> Result<Robot, ExportCommandError> {
    deflex_app::load::load_robot(spec).map_err(|source| ExportCommandError::Robot {
        flag,
        spec: spec.to_string(),
        source,
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

/// The largest TCP position difference between two chains over `configurations`.
fn largest_gap(robot: &Robot, other: &dyn Fn(&[f64]) -> Option<nalgebra::Vector3<f64>>) -> f64 {
    configurations(robot, 500)
        .iter()
        .map(|q| match (robot.tcp_pose(q), other(q)) {
            (Ok(a), Some(b)) => (a.translation.vector - b).norm(),
            _ => f64::INFINITY,
        })
        .fold(0.0, f64::max)
}

/// Runs `deflex export`.
pub fn export(args: ExportArgs, json: bool) -> CommandResult {
    Ok(run(args, json)?)
}

pub fn run(args: ExportArgs, json: bool) -> Result<(), ExportCommandError> {
    let robot = load("--robot", &args.robot)?;
    if args.nominal.is_some() && args.format != ExportFormat::DhTable {
        return Err(ExportCommandError::Nominal);
    }
    let out_error = |path: &std::path::Path| {
        let path = path.display().to_string();
        move |source| ExportCommandError::Output {
            path: path.clone(),
            source,
        }
    };
    let mut files: Vec<(PathBuf, String)> = Vec::new();
    let (format, error_m) = match args.format {
        ExportFormat::Urdf => {
            let xml = deflex_cam::export::urdf(&robot);
            let file_name = args
                .out
                .file_name()
                .map_or("robot.urdf".into(), |n| n.to_string_lossy().into_owned());
            let toml = deflex_cam::export::urdf_robot_toml(&robot, &file_name);
            let back = deflex_model::robot_from_toml_and_urdf_str(&toml, &xml, "export.toml")
                .map_err(ExportCommandError::Readback)?;
            let gap = largest_gap(&robot, &|q| {
                back.tcp_pose(q).ok().map(|p| p.translation.vector)
            });
            files.push((args.out.clone(), xml));
            files.push((args.out.with_extension("toml"), toml));
            ("urdf", gap)
        }
        ExportFormat::UrCalibration => {
            let mut flange = robot.clone();
            flange.tool = deflex_model::Pose::identity();
            let yaml = deflex_cam::export::ur_calibration(&flange)?;
            let segments =
                deflex_cam::export::read_ur_calibration(&yaml, &args.out.display().to_string())?;
            let gap = largest_gap(&flange, &|q| {
                let mut t = deflex_model::Pose::identity();
                for (s, qi) in segments.iter().zip(q) {
                    t = t * deflex_cam::export::segment_pose(s) * deflex_model::spatial::rot_z(*qi);
                }
                Some(t.translation.vector)
            });
            files.push((args.out.clone(), yaml));
            ("ur-calibration", gap)
        }
        ExportFormat::DhTable => {
            let nominal = args
                .nominal
                .as_deref()
                .map(|spec| load("--nominal", spec))
                .transpose()?;
            let text = deflex_cam::export::dh_table(&robot, nominal.as_ref())?;
            let rows = deflex_cam::export::read_dh_table(&text, &args.out.display().to_string())?;
            // The table's rows rebuild the robot's placements.
            let mut rebuilt = robot.clone();
            for (joint, row) in rebuilt.joints.iter_mut().zip(&rows) {
                joint.dh = Some(row.dh);
                joint.theta_offset = row.theta_offset;
            }
            rebuilt.rebuild_dh_geometry();
            let gap = largest_gap(&robot, &|q| {
                rebuilt.tcp_pose(q).ok().map(|p| p.translation.vector)
            });
            files.push((args.out.clone(), text));
            ("dh-table", gap)
        }
    };
    if error_m.is_nan() || error_m > 1e-6 {
        return Err(ExportCommandError::Mismatch { format, error_m });
    }
    for (path, text) in &files {
        deflex_files::write_atomic(path, text).map_err(out_error(path))?;
    }
    let written: Vec<String> = files.iter().map(|(p, _)| p.display().to_string()).collect();
    if json {
        print_json(&json!({
            "robot": robot.name,
            "robot_geometry": robot.geometry_fingerprint(),
            "format": format,
            "files": written,
            "readback_max_tcp_error_m": error_m,
            "configurations_checked": 500,
        }));
    } else {
        println!(
            "{}: wrote {} (read back: forward kinematics within {:.3e} m of the model over 500 configurations)",
            robot.name,
            written.join(", "),
            error_m
        );
    }
    Ok(())
}
