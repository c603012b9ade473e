//! `deflex register`: a new measuring session (where the tracker stands) and, optionally, a new
//! target (probe) registered from a handful of readings with the calibrated robot frozen. The
//! workflow is `deflex_app::calibrate_geometry::register`'s (shared with the Python package);
//! here the flags, their checks and conversions (mm → m), and the printing.

use crate::args::{check_flag, print_json};
use crate::error::CommandResult;
use clap::Args;
use deflex_app::calibrate::MeasurementSource;
use deflex_app::calibrate_geometry::{
    self as app, DEFAULT_ORIENTATION_SIGMA_RAD, OptionNames, RegisterRequest,
};
use std::path::PathBuf;

#[derive(Args)]
pub struct RegisterArgs {
    /// Calibrated robot file (from calibrate-geometry; its NAME.terms.json is used when present).
    #[arg(long)]
    pub robot: String,
    /// A few absolute readings of the new session (30 recommended, spread over the workspace
    /// and the wrist orientations).
    #[arg(long)]
    pub data: PathBuf,
    /// Set-up to register (default: the one set-up the data names). A new name is registered
    /// from scratch; a known one is re-registered (same tracker place, new session).
    #[arg(long)]
    pub setup: Option<String>,
    /// Target whose offset on the flange is fitted too (a new probe, or one remounted): 3
    /// parameters, 6 with --orientations.
    #[arg(long)]
    pub target: Option<String>,
    /// Fit the measured orientations (rx_rad…) too.
    #[arg(long)]
    pub orientations: bool,
    /// Standard deviation of an orientation component for rows without sigma_rad (rad).
    #[arg(long, default_value_t = DEFAULT_ORIENTATION_SIGMA_RAD)]
    pub sigma_rad: f64,
    /// Residual RMS (mm) above which the robot is deemed changed (default: 1.5 × the
    /// calibration's held-out RMS from the terms file).
    #[arg(long)]
    pub recalibrate_above_mm: Option<f64>,
    /// Updated robot file (the new set-up and target added; everything else as it was).
    #[arg(long)]
    pub out: PathBuf,
    /// A column of the measurement file(s) that deflex does not read, kept knowingly
    /// (repeatable). Without it an unknown column is an error naming the closest known one.
    #[arg(long = "ignore-column", value_name = "NAME")]
    pub ignore_column: Vec<String>,
    /// Write a registration that moves a known set-up by more than the arm's size, or puts the
    /// target further from the flange than half of it (refused without it).
    #[arg(long)]
    pub allow_large_changes: bool,
}

/// Runs `deflex register`.
pub fn register(args: RegisterArgs, json_output: bool) -> CommandResult {
    check_flag(
        "--sigma-rad",
        args.sigma_rad,
        1e-9,
        app::MAX_SIGMA_RAD,
        "rad",
    )?;
    if let Some(mm) = args.recalibrate_above_mm {
        check_flag("--recalibrate-above-mm", mm, 1e-3, 1e3, "mm")?;
    }
    let model = app::load_calibrated(&args.robot)?;
    let request = RegisterRequest {
        setup: args.setup,
        target: args.target,
        orientations: args.orientations.then_some(args.sigma_rad),
        recalibrate_above_m: args.recalibrate_above_mm.map(|mm| mm * 1e-3),
        ignored_columns: args.ignore_column,
        allow_large_changes: args.allow_large_changes,
        names: OptionNames::Cli,
    };
    let registration = app::register(model, &MeasurementSource::File(args.data), &request)?;
    app::save_registration(&registration, &args.out)?;
    if json_output {
        print_json(&app::registration_json(&registration, Some(&args.out)));
    } else {
        print!("{}", app::saved_registration_text(&registration, &args.out));
    }
    Ok(())
}
