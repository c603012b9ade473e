//! `deflex calibrate`, `validate` (and `plan`, in `cmd_plan`): identification of the
//! elasto-geometrical model (Johra et al. 2022, Section 3) from laser-tracker measurements. The
//! workflows are `deflex_app::calibrate`'s; here the flags are checked in their units, converted
//! and the results printed.

use crate::args::{check_range, print_json, robot};
use crate::error::{CliError, CommandResult, UsageError};
use clap::Args;
use deflex_app::OptionNames;
use deflex_app::calibrate::{
    self, CalibrateOptions, CriterionChoice, DataCheck, MAX_FK_TOLERANCE_M, MIN_FK_TOLERANCE_M,
    MeasurementSource, StructureChoice,
};
use std::path::PathBuf;

mod couplings;

#[derive(Args)]
pub struct CalibrateArgs {
    /// Start model: built-in name (tx200, tx200-1edof, …) or TOML file. Gives the geometry; with
    /// --structure fixed also the eDoFs and centre shifts.
    #[arg(long)]
    pub robot: String,
    /// Measurement CSV (see `deflex plan` for the columns).
    #[arg(long)]
    pub data: PathBuf,
    /// auto: structure search from one z-eDoF per joint (see --criterion); fixed: the start
    /// model's eDoFs and centre shifts as given.
    #[arg(long, value_enum, default_value = "auto")]
    pub structure: StructureChoice,
    /// Stop the search once the RMS residual (all components) is at most this (mm, 0 to 1000).
    #[arg(long)]
    pub target_rms_mm: Option<f64>,
    /// With --structure fixed: also fit the centre shift of every joint with an x or y eDoF.
    #[arg(long)]
    pub fit_shifts: bool,
    /// Do not consider base tilt eDoFs in the search.
    #[arg(long)]
    pub no_base: bool,
    /// Smallest BIC decrease for the search to accept a refinement (0 to 1e6).
    #[arg(long, default_value_t = 10.0)]
    pub min_bic_gain: f64,
    /// How the search ranks structures: bic, or cv (held-out χ² of k-fold cross-validation by
    /// load case). The iteration table shows the cross-validated RMS either way.
    #[arg(long, value_enum, default_value = "bic")]
    pub criterion: CriterionChoice,
    /// Folds of the cross-validation (by load case; 2 to 100, at most one per load case).
    #[arg(long, default_value_t = 5)]
    pub folds: usize,
    /// With --criterion cv: smallest relative decrease of the held-out χ² for the search to
    /// accept a refinement (%, 0 to 100).
    #[arg(long, default_value_t = 2.0)]
    pub min_cv_gain_percent: f64,
    /// Largest distance between a row's point coordinates and the robot's forward kinematics of
    /// its joint values (mm, 0.001 to 1000): more refuses the file.
    #[arg(long, default_value_t = 1.0)]
    pub fk_tolerance_mm: f64,
    /// Use the file even when its coordinates disagree with the robot's forward kinematics
    /// (the disagreement is printed as a warning).
    #[arg(long)]
    pub ignore_fk_check: bool,
    /// A column of the measurement file that deflex does not read, kept knowingly (repeatable).
    /// Without it an unknown column is an error naming the closest known one (a typo such as
    /// `sigma_mm` would otherwise drop the σ it meant).
    #[arg(long = "ignore-column", value_name = "NAME")]
    pub ignore_column: Vec<String>,
    /// Off-diagonal joint compliances to fit once the structure is identified, together with
    /// the eDoF compliances (weighted least squares, standard errors as the stiffnesses'):
    /// pairs of eDoFs of the identified structure, e.g. `J2.z:J3.z` (a shared counterbalance or
    /// casting), separated by commas, at most 8. Written into the output model as
    /// `[[coupling]]`, with the stiffnesses refitted with them.
    #[arg(long, value_name = "A:B[,A:B…]")]
    pub couplings: Option<String>,
    /// Output robot TOML (a drop-in for every other command).
    #[arg(long)]
    pub out: PathBuf,
    /// Folder for an HTML report with plots and CSV tables (replaced whole).
    #[arg(long)]
    pub report: Option<PathBuf>,
}

#[derive(Args)]
pub struct ValidateArgs {
    /// Model to validate: built-in name or TOML file.
    #[arg(long)]
    pub robot: String,
    /// Measurement CSV.
    #[arg(long)]
    pub data: PathBuf,
    /// Baseline model shown side by side (e.g. tx200-1edof).
    #[arg(long)]
    pub baseline: Option<String>,
    /// Largest distance between a row's point coordinates and the model's forward kinematics
    /// of its joint values (mm, 0.001 to 1000): more refuses the file.
    #[arg(long, default_value_t = 1.0)]
    pub fk_tolerance_mm: f64,
    /// Use the file even when its coordinates disagree with the model's forward kinematics.
    #[arg(long)]
    pub ignore_fk_check: bool,
    /// A column of the measurement file that deflex does not read, kept knowingly (repeatable).
    /// Without it an unknown column is an error naming the closest known one (a typo such as
    /// `sigma_mm` would otherwise drop the σ it meant).
    #[arg(long = "ignore-column", value_name = "NAME")]
    pub ignore_column: Vec<String>,
    /// Folder for PNG plots and validation.html (replaced whole, or left as it was on error).
    #[arg(long)]
    pub out: Option<PathBuf>,
}
/// The data check from `--fk-tolerance-mm` (checked in mm, named), `--ignore-fk-check` and
/// `--ignore-column`.
fn data_check(
    tolerance_mm: f64,
    ignore_fk_check: bool,
    ignore_columns: &[String],
) -> Result<DataCheck, CliError> {
    if !(tolerance_mm.is_finite()
        && (MIN_FK_TOLERANCE_M * 1e3..=MAX_FK_TOLERANCE_M * 1e3).contains(&tolerance_mm))
    {
        return Err(UsageError::invalid(
            "--fk-tolerance-mm",
            format!(
                "{} to {} mm",
                MIN_FK_TOLERANCE_M * 1e3,
                MAX_FK_TOLERANCE_M * 1e3
            ),
            tolerance_mm,
        )
        .into());
    }
    Ok(DataCheck {
        fk_tolerance_m: tolerance_mm * 1e-3,
        ignore_fk_check,
        ignore_columns: ignore_columns.to_vec(),
    })
}

pub fn calibrate(args: CalibrateArgs, json_output: bool) -> CommandResult {
    if let Some(t) = args.target_rms_mm {
        check_range("--target-rms-mm", t, 0.0, 1000.0)?;
    }
    check_range("--min-bic-gain", args.min_bic_gain, 0.0, 1e6)?;
    check_range(
        "--min-cv-gain-percent",
        args.min_cv_gain_percent,
        0.0,
        99.999,
    )?;
    if !(2..=100).contains(&args.folds) {
        return Err(UsageError::invalid("--folds", "2 to 100", args.folds).into());
    }
    let couplings = args
        .couplings
        .as_deref()
        .map(couplings::parse)
        .transpose()?
        .unwrap_or_default();
    let start = robot(&args.robot)?;
    let check = data_check(
        args.fk_tolerance_mm,
        args.ignore_fk_check,
        &args.ignore_column,
    )?;
    let options = CalibrateOptions {
        structure: args.structure,
        fit_shifts: args.fit_shifts,
        criterion: args.criterion,
        folds: args.folds,
        min_cv_gain: args.min_cv_gain_percent / 100.0,
        target_rms_m: args.target_rms_mm.map(|v| v * 1e-3),
        min_bic_gain: args.min_bic_gain,
        allow_base: !args.no_base,
        check,
        couplings,
    };
    // A progress bar for the structure search, on the terminal only (hidden with --json).
    let bar = (args.structure == StructureChoice::Auto).then(|| search_bar(json_output));
    let mut progress = |p: deflex_telemetry::Progress<'_>| {
        if let Some(bar) = &bar {
            match p {
                deflex_telemetry::Progress::Stage { name, .. } => bar.set_message(name.to_string()),
                deflex_telemetry::Progress::Work { done, total } => {
                    bar.set_length(total as u64);
                    bar.set_position(done as u64);
                }
                deflex_telemetry::Progress::Done { .. } => {}
            }
        }
    };
    let source = MeasurementSource::File(args.data.clone());
    let result = calibrate::calibrate(&start, &source, &options, OptionNames::Cli, &mut progress);
    if let Some(bar) = &bar {
        bar.finish_and_clear();
    }
    let cal = result?;
    calibrate::save(&cal, &args.out, args.report.as_deref())?;
    if json_output {
        print_json(&calibrate::summary_json(&cal, Some(&args.out)));
        return Ok(());
    }
    print!("{}", calibrate::report_text(&cal));
    print!(
        "{}",
        calibrate::written_text(&args.out, args.report.as_deref())
    );
    Ok(())
}

/// The structure search's progress bar (hidden for JSON output).
fn search_bar(json_output: bool) -> indicatif::ProgressBar {
    let bar = if json_output {
        indicatif::ProgressBar::hidden()
    } else {
        indicatif::ProgressBar::new(1)
    };
    bar.set_style(
        indicatif::ProgressStyle::with_template(
            "structure search {msg} [{bar:30}] {pos}/{len} candidates",
        )
        .unwrap_or_else(|_| indicatif::ProgressStyle::default_bar()),
    );
    bar
}

pub fn validate(args: ValidateArgs, json_output: bool) -> CommandResult {
    let model = robot(&args.robot)?;
    let baseline = args.baseline.as_deref().map(robot).transpose()?;
    let check = data_check(
        args.fk_tolerance_mm,
        args.ignore_fk_check,
        &args.ignore_column,
    )?;
    let source = MeasurementSource::File(args.data.clone());
    let v = calibrate::validate(&model, baseline.as_ref(), &source, &check, OptionNames::Cli)?;
    let files = match &args.out {
        Some(dir) => calibrate::write_validation_report(&v, dir)?,
        None => Vec::new(),
    };
    if json_output {
        print_json(&calibrate::validation_json(&v, Some(&files)));
        return Ok(());
    }
    print!("{}", calibrate::validation_text(&v));
    if let Some(dir) = &args.out {
        print!("{}", calibrate::validation_written_text(&files, dir));
    }
    Ok(())
}
