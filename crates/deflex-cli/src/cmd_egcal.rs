//! `deflex import ur10-tracker`, `deflex calibrate-geometry`, `deflex predict`: elasto-geometric
//! calibration from absolute tracker readings. The workflows are
//! `deflex_app::calibrate_geometry`'s (shared with the Python package); here the flags, their
//! checks and conversions, and the printing.

use crate::args::{check_flag, print_json};
use crate::error::{CommandResult, UsageError};
use clap::{Args, Subcommand};
use deflex_app::calibrate::MeasurementSource;
use deflex_app::calibrate_geometry::{
    self as app, CvBy, DEFAULT_ORIENTATION_SIGMA_RAD, GeometryOptions, HeldOutProtocol,
    ImportRequest, OptionNames,
};
use std::path::PathBuf;

#[derive(Subcommand)]
pub enum ImportCommand {
    /// The public UR10 laser-tracker data set (Landgraf et al., CASE 2021) → absolute CSV.
    Ur10Tracker(Ur10TrackerArgs),
}

#[derive(Args)]
pub struct Ur10TrackerArgs {
    /// A series folder (holding one measurements_*.csv) or the file itself.
    #[arg(long)]
    pub series: PathBuf,
    /// Set-up label written on every row (one per tracker placement).
    #[arg(long)]
    pub setup: String,
    /// Target label written on every row.
    #[arg(long, default_value = "tmac")]
    pub target: String,
    /// Write the tracker's per-reading standard deviation into sigma_m (default: none, so
    /// every reading weighs the same).
    #[arg(long)]
    pub tracker_sigma: bool,
    /// Keep every n-th reading only (decimation for small test sets).
    #[arg(long, default_value_t = 1)]
    pub every: usize,
    /// Output CSV (absolute measurement format).
    #[arg(long)]
    pub out: PathBuf,
}

#[derive(Args)]
pub struct CalibrateGeometryArgs {
    /// Starting robot: built-in name or TOML file (a DH robot).
    #[arg(long)]
    pub robot: String,
    /// Absolute measurement CSV (repeat for several files).
    #[arg(long, required = true)]
    pub data: Vec<PathBuf>,
    /// Loaded-displacement measurement CSV (the `deflex calibrate` format) fitted together.
    #[arg(long)]
    pub loaded: Vec<PathBuf>,
    /// A column of the --data, --test-data or --loaded files that deflex does not read, kept
    /// knowingly (repeatable). Without it an unknown column is an error naming the closest known
    /// one.
    #[arg(long = "ignore-column", value_name = "NAME")]
    pub ignore_column: Vec<String>,
    /// Absolute CSV never fitted: set-ups the fit knows are scored as they are; new set-ups get
    /// their registration fitted on half their configurations and are scored on the rest.
    #[arg(long)]
    pub test_data: Vec<PathBuf>,
    /// Model steps, comma-separated, each adding to the previous: registration, geometry,
    /// compliance, and opt-in masses, harmonics:N (N ≤ 4), periodic:N (N cycles per joint
    /// turn, a gear's ratio), backlash, torsion:cubic / torsion:soft:T (a strain-wave gear's
    /// nonlinear torsion on the free eDoFs: hardening, or a soft zone below T N·m), residual (a
    /// residual model on the joint angles), joint-maps (each joint's angle error as a smooth
    /// function of its angle). Opt-in steps are kept only when they improve the held-out groups
    /// (--test-data, --cv-by). Default: registration,geometry,compliance, and joint-maps when
    /// --cv-by gives groups to vote with.
    #[arg(long)]
    pub steps: Option<String>,
    /// Fit the measured orientations (rx_rad…) with the positions.
    #[arg(long)]
    pub orientations: bool,
    /// Standard deviation of an orientation component for rows without sigma_rad (rad).
    #[arg(long, default_value_t = DEFAULT_ORIENTATION_SIGMA_RAD)]
    pub sigma_rad: f64,
    /// Leave out each session, set-up or series of the fit data in turn: refit without it,
    /// register it by the protocol, score it (and judge opt-in steps by it).
    #[arg(long, value_enum)]
    pub cv_by: Option<CvBy>,
    /// Readings drawn at random to register each held-out series or group (0: every other
    /// configuration registers, the rest score).
    #[arg(long, default_value_t = 0)]
    pub register_readings: usize,
    /// Random draws of those readings.
    #[arg(long, default_value_t = 1)]
    pub register_draws: usize,
    /// Register the target offset too (a new probe), not only the set-up.
    #[arg(long)]
    pub register_target: bool,
    /// Write a fit that moves the geometry further than a calibration does (lengths, angles,
    /// set-ups, targets beyond the bounds of the calibration chapter): only for a robot file
    /// that is a rough first guess. Without it such a fit is refused.
    #[arg(long)]
    pub allow_large_changes: bool,
    /// eDoFs whose compliance is fitted (e.g. J2.z,J3.z); default: all of the robot's.
    #[arg(long)]
    pub elastic: Option<String>,
    /// Robust loss: huber, cauchy or none; huber:K / cauchy:K set the threshold.
    #[arg(long, default_value = "huber")]
    pub loss: String,
    /// Cross-validation folds by configuration (0 = none).
    #[arg(long, default_value_t = 5)]
    pub folds: usize,
    /// Bootstrap replicates by configuration (0 = none).
    #[arg(long, default_value_t = 0)]
    pub bootstrap: usize,
    /// Fraction of the configurations held out as a test set, never fitted.
    #[arg(long, default_value_t = 0.0)]
    pub test_fraction: f64,
    /// Seed of the splits and the bootstrap.
    #[arg(long, default_value_t = 1)]
    pub seed: u64,
    /// Calibrated robot file (DH rows, stiffness, masses, set-ups, targets); the joint terms,
    /// residual model and the calibration's accuracy go beside it as NAME.terms.json.
    #[arg(long)]
    pub out: PathBuf,
    /// Report folder (text, JSON, CSV, plots, HTML).
    #[arg(long)]
    pub report: Option<PathBuf>,
}

#[derive(Args)]
pub struct PredictArgs {
    /// Calibrated robot file (its [[setup]] and [[target]] name the rows' set-ups and targets).
    #[arg(long)]
    pub robot: String,
    /// Absolute measurement CSV; position columns may be left empty in a plan-like file.
    #[arg(long)]
    pub data: PathBuf,
    /// Fit the registration of the rows' set-ups on all the rows before predicting (optimistic;
    /// `deflex register` registers from a few readings instead).
    #[arg(long)]
    pub fit_setup: bool,
    /// Output CSV: each row with predicted_x_m … and, when measured, the error.
    #[arg(long)]
    pub out: PathBuf,
    /// A column of the measurement file(s) that deflex does not read, kept knowingly
    /// (repeatable). Without it an unknown column is an error naming the closest known one.
    #[arg(long = "ignore-column", value_name = "NAME")]
    pub ignore_column: Vec<String>,
}

/// Runs `deflex import`.
pub fn import(command: ImportCommand, json_output: bool) -> CommandResult {
    let ImportCommand::Ur10Tracker(args) = command;
    if args.every == 0 || args.every > 1_000_000 {
        return Err(UsageError::invalid("--every", "1…1000000", args.every).into());
    }
    let request = ImportRequest {
        setup: args.setup,
        target: args.target,
        tracker_sigma: args.tracker_sigma,
        every: args.every,
        names: OptionNames::Cli,
    };
    let imported = app::import_ur10_tracker(&args.series, &request)?;
    imported.save(&args.out)?;
    if json_output {
        print_json(&imported.summary_json(Some(&args.out)));
    } else {
        print!("{}", imported.saved_text(&args.out));
    }
    Ok(())
}

/// The files of a repeatable flag as the workflow takes them.
fn files(paths: Vec<PathBuf>) -> Vec<MeasurementSource> {
    paths.into_iter().map(MeasurementSource::File).collect()
}

/// Runs `deflex calibrate-geometry`.
pub fn calibrate_geometry(args: CalibrateGeometryArgs, json_output: bool) -> CommandResult {
    let steps = match &args.steps {
        Some(text) => {
            let names: Vec<String> = text.split(',').map(String::from).collect();
            Some(app::parse_steps(&names, OptionNames::Cli)?)
        }
        None => None,
    };
    let loss = app::parse_loss(&args.loss, OptionNames::Cli)?;
    check_flag(
        "--sigma-rad",
        args.sigma_rad,
        1e-9,
        app::MAX_SIGMA_RAD,
        "rad",
    )?;
    let start = crate::args::robot(&args.robot)?;
    let options = GeometryOptions {
        steps,
        loss,
        folds: args.folds,
        bootstrap: args.bootstrap,
        test_fraction: args.test_fraction,
        seed: args.seed,
        elastic: args
            .elastic
            .as_deref()
            .map(|t| t.split(',').map(|s| s.trim().to_string()).collect())
            .unwrap_or_default(),
        orientations: args.orientations.then_some(args.sigma_rad),
        cv_by: args.cv_by,
        protocol: HeldOutProtocol {
            register_readings: args.register_readings,
            draws: args.register_draws,
            register_target: args.register_target,
        },
        ignored_columns: args.ignore_column,
        allow_large_changes: args.allow_large_changes,
        names: OptionNames::Cli,
    };
    let cal = app::calibrate_geometry(
        &start,
        &files(args.data),
        &files(args.loaded),
        &files(args.test_data),
        &options,
    )?;
    let saved = app::save(&cal, &args.out, args.report.as_deref())?;
    if json_output {
        print_json(&app::saved_json(&cal, &saved));
    } else {
        print!("{}", app::saved_text(&cal, &saved));
    }
    Ok(())
}

/// Runs `deflex predict`.
pub fn predict(args: PredictArgs, json_output: bool) -> CommandResult {
    let model = app::load_calibrated(&args.robot)?;
    let prediction = app::predict(
        &model,
        &MeasurementSource::File(args.data),
        args.fit_setup,
        &args.ignore_column,
    )?;
    prediction.save(&args.out)?;
    if json_output {
        print_json(&prediction.json);
    } else {
        print!("{}", prediction.saved_text(&args.out));
    }
    Ok(())
}
