//! `deflex export`: a calibrated robot where controllers and ROS stacks read it — a URDF with
//! the calibrated joint origins (plus a deflex robot file beside it that reads the URDF and
//! keeps the stiffnesses), Universal Robots' calibration YAML, or a DH table with the
//! corrections against a nominal robot. Flags and printing only: the export, its read-back
//! check (forward kinematics over 500 configurations within the joint limits, the command fails
//! writing nothing beyond 1 µm) and the writing are `deflex_app::export`.

use crate::args::print_json;
use crate::error::{CommandResult, UsageError};
use clap::Args;
use deflex_app::compensate::robot_from_spec;
use deflex_app::export::{ExportFormat, export as export_robot};
use std::path::PathBuf;

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

/// Runs `deflex export`.
pub fn export(args: ExportArgs, json: bool) -> CommandResult {
    let robot = robot_from_spec("--robot", &args.robot)?;
    if args.nominal.is_some() && args.format != ExportFormat::DhTable {
        return Err(UsageError::OnlyWith {
            flag: "--nominal",
            with: "--format dh-table",
        }
        .into());
    }
    let nominal = match (&args.nominal, args.format) {
        (Some(spec), ExportFormat::DhTable) => Some(robot_from_spec("--nominal", spec)?),
        _ => None,
    };
    let exported = export_robot(&robot, args.format, &args.out, nominal.as_ref())?;
    if json {
        print_json(&exported.json());
    } else {
        println!("{}", exported.text());
    }
    Ok(())
}
