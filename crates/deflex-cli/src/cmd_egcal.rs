//! `deflex import ur10-tracker`, `deflex calibrate-geometry`, `deflex predict`: elasto-geometric
//! calibration from absolute tracker readings (maths in `deflex-absolute`; the report, plots and
//! prediction tables in `deflex_app::report::absolute_report`, shared with the Python package; the
//! files here).

use crate::args::{print_json, robot};
use crate::error::{CliError, CommandResult, UsageError};
use clap::{Args, Subcommand, ValueEnum};
use deflex_app::report::absolute_report as report;
use deflex_calibrate::geometry::campaign::Campaign;
use deflex_calibrate::geometry::data::{
    AbsoluteRow, DEFAULT_ORIENTATION_SIGMA_RAD, format_absolute, limits, parse_absolute_ignoring,
};
use deflex_calibrate::geometry::fit::{
    ChoiceError, FitOptions, HeldOutProtocol, Step, fit, session_groups,
};
use deflex_calibrate::geometry::params::EgModel;
use deflex_calibrate::geometry::predict;
use deflex_calibrate::geometry::solve::Loss;
use deflex_calibrate::geometry::terms::CalibrationTerms;
use deflex_calibrate::geometry::ur10_tracker::{ImportOptions, MAX_SERIES_BYTES, parse_series};
use std::path::{Path, PathBuf};

/// Gap between time stamps that starts a new measuring session (`--cv-by session`).
pub const SESSION_GAP_S: f64 = 3600.0;
/// Largest terms file read (bytes).
const MAX_TERMS_BYTES: u64 = 64 << 20;

/// Read a text file of at most `limit` bytes (a regular file, counted while reading), naming
/// it in errors.
pub fn read_bounded(path: &Path, limit: u64) -> Result<String, CliError> {
    Ok(deflex_files::read_bounded(path, limit)?)
}

/// Readings that differ in set-up, target, configuration or measured position (bit for bit):
/// a repeated reading is not a new equation.
fn distinct_readings(rows: &[AbsoluteRow]) -> usize {
    let mut keys: Vec<(String, String, Vec<u64>)> = rows
        .iter()
        .map(|r| {
            let mut k: Vec<u64> = r.q_rad.iter().map(|v| v.to_bits()).collect();
            k.extend(r.position_m.iter().map(|v| v.to_bits()));
            (r.setup.clone(), r.target.clone(), k)
        })
        .collect();
    keys.sort_unstable();
    keys.dedup();
    keys.len()
}

/// Largest RMS of the fitted readings' residuals a calibration may end with (m). A calibrated
/// arm fits its tracker readings to a fraction of a millimetre; readings of another robot, or
/// of another tool on an unknown target, leave residuals of centimetres to metres.
pub const MAX_PLAUSIBLE_RMS_M: f64 = 0.02;

/// Refuse a fit whose readings the calibrated robot still misses by more than
/// [`MAX_PLAUSIBLE_RMS_M`] RMS (data of another robot given with `--robot`): nothing is written.
fn check_plausible_fit(
    result: &deflex_calibrate::geometry::fit::FitResult,
    robot: &str,
    data: &[PathBuf],
) -> Result<(), CliError> {
    let fitted: Vec<f64> = result
        .residuals
        .iter()
        .filter(|r| r.role == deflex_calibrate::geometry::fit::Role::Fit)
        .map(|r| r.residual.norm_squared())
        .collect();
    if fitted.is_empty() {
        return Ok(());
    }
    let rms = (fitted.iter().sum::<f64>() / fitted.len() as f64).sqrt();
    if rms.is_finite() && rms <= MAX_PLAUSIBLE_RMS_M {
        return Ok(());
    }
    Err(CliError::ImplausibleFit {
        files: shown_paths(data),
        robot: robot.to_string(),
        rms_mm: rms * 1e3,
        limit_mm: MAX_PLAUSIBLE_RMS_M * 1e3,
    })
}

/// Read an absolute measurement file, skipping the columns named in `ignored` (unknown to the
/// format, kept knowingly: `--ignore-column`).
pub fn read_absolute(
    path: &Path,
    joints: usize,
    ignored: &[String],
) -> Result<Vec<AbsoluteRow>, CliError> {
    let text = read_bounded(path, limits::MAX_FILE_BYTES)?;
    Ok(parse_absolute_ignoring(
        &text,
        &path.display().to_string(),
        joints,
        ignored,
    )?)
}

/// Files as the messages show them, comma-separated.
fn shown_paths(paths: &[PathBuf]) -> String {
    paths
        .iter()
        .map(|p| deflex_files::shown_path(p))
        .collect::<Vec<_>>()
        .join(", ")
}

/// The single `measurements_*.csv` of a series folder (or the file itself).
fn series_file(path: &Path) -> Result<PathBuf, CliError> {
    if path.is_file() {
        return Ok(path.to_path_buf());
    }
    let entries = std::fs::read_dir(path).map_err(|source| CliError::Read {
        path: path.to_path_buf(),
        source,
    })?;
    let mut found: Vec<PathBuf> = entries
        .filter_map(|e| e.ok().map(|e| e.path()))
        .filter(|p| {
            p.file_name()
                .and_then(|n| n.to_str())
                .is_some_and(|n| n.starts_with("measurements") && n.ends_with(".csv"))
        })
        .collect();
    found.sort();
    match found.len() {
        1 => Ok(found.remove(0)),
        found => Err(CliError::SeriesFiles {
            folder: path.to_path_buf(),
            found,
        }),
    }
}

/// The terms file written beside a calibrated robot file: `NAME.toml` → `NAME.terms.json`.
pub fn terms_path(robot_file: &Path) -> PathBuf {
    robot_file.with_extension("terms.json")
}

/// A calibrated model: the robot (built-in name or file) and, for a file with a terms file
/// beside it, the joint terms and residual model it keeps.
pub fn load_model(spec: &str) -> Result<(EgModel, Option<CalibrationTerms>), CliError> {
    let robot = robot(spec)?;
    let mut model = EgModel::from_robot(&robot);
    let path = Path::new(spec);
    let terms_file = terms_path(path);
    if !path.is_file() || !terms_file.is_file() {
        return Ok((model, None));
    }
    let text = read_bounded(&terms_file, MAX_TERMS_BYTES)?;
    let in_terms = |e: deflex_calibrate::geometry::terms::TermsError| {
        CliError::in_context(terms_file.display().to_string())(e.into())
    };
    let terms = CalibrationTerms::from_json(&text).map_err(in_terms)?;
    terms.apply(&mut model).map_err(in_terms)?;
    Ok((model, Some(terms)))
}

/// Groups of `--cv-by`.
#[derive(Clone, Copy, Debug, PartialEq, Eq, ValueEnum)]
pub enum CvBy {
    /// Measuring sessions (time stamps more than an hour apart; one per set-up without them).
    Session,
    /// Tracker set-ups.
    Setup,
    /// Data files (`--data`), one series each.
    Series,
}

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
    /// function of its angle). Opt-in steps are kept only when they improve the held-out groups (--test-data,
    /// --cv-by).
    #[arg(long, default_value = "registration,geometry,compliance")]
    pub steps: String,
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
    // Import writes only labels its readers read back the same: a label they would not is
    // refused, not rewritten (a silently changed set-up name would no longer match the robot
    // file's [[setup]]).
    for (flag, label) in [("--setup", &args.setup), ("--target", &args.target)] {
        deflex_calibrate::geometry::data::check_label(label).map_err(|problem| {
            CliError::ImportLabel {
                flag,
                label: deflex_files::shown(label).to_string(),
                problem,
                max_bytes: limits::MAX_LABEL_BYTES,
            }
        })?;
    }
    let options = ImportOptions {
        setup: args.setup.clone(),
        target: args.target.clone(),
        tracker_sigma: args.tracker_sigma,
    };
    let file = series_file(&args.series)?;
    let text = read_bounded(&file, MAX_SERIES_BYTES)?;
    let (rows, mut summary) = parse_series(&text, &file.display().to_string(), &options)?;
    summary.file = file;
    let kept: Vec<AbsoluteRow> = rows.into_iter().step_by(args.every).collect();
    let comments = vec![
        "UR10 laser-tracker data: Landgraf, Ernst, Schleth, Fabritius, Huber, IEEE CASE 2021 (MIT licence)".to_string(),
        format!(
            "imported by deflex from {} (every {} reading(s); approach_q*_rad from the whole time-ordered series); T-Mac probe in the tracker frame",
            summary.file.display(),
            args.every
        ),
    ];
    let text = format_absolute(&kept, &comments);
    deflex_files::write_atomic(&args.out, text).map_err(CliError::write(&args.out))?;
    if json_output {
        print_json(&serde_json::json!({
            "file": summary.file.display().to_string(),
            "rows_read": summary.rows,
            "rows_written": kept.len(),
            "rows_without_time": summary.rows_without_time,
            "median_tracker_std_m": summary.median_tracker_std_m,
            "temperature_range_C": summary.temperature_range_c,
            "out": args.out.display().to_string(),
        }));
    } else {
        println!(
            "{}: {} readings, {} written to {} (set-up {}, target {})",
            summary.file.display(),
            summary.rows,
            kept.len(),
            args.out.display(),
            args.setup,
            args.target
        );
        if let Some(s) = summary.median_tracker_std_m {
            println!(
                "tracker standard deviation per reading: median {:.1} µm",
                s * 1e6
            );
        }
        if let Some([lo, hi]) = summary.temperature_range_c {
            println!("temperature {lo:.2} … {hi:.2} °C");
        }
        if summary.rows_without_time > 0 {
            println!(
                "{} time stamps unreadable (left out of time_s)",
                summary.rows_without_time
            );
        }
    }
    Ok(())
}

fn parse_steps(text: &str) -> Result<Vec<Step>, CliError> {
    text.split(',')
        .map(|item| {
            item.parse()
                .map_err(|e: ChoiceError| CliError::in_context("--steps")(e.into()))
        })
        .collect()
}

fn parse_loss(text: &str) -> Result<Loss, CliError> {
    text.parse()
        .map_err(|e: ChoiceError| CliError::in_context("--loss")(e.into()))
}

fn read_all(
    paths: &[PathBuf],
    joints: usize,
    ignored: &[String],
) -> Result<Vec<Vec<AbsoluteRow>>, CliError> {
    paths
        .iter()
        .map(|p| read_absolute(p, joints, ignored))
        .collect()
}

/// Runs `deflex calibrate-geometry`.
pub fn calibrate_geometry(args: CalibrateGeometryArgs, json_output: bool) -> CommandResult {
    let steps = parse_steps(&args.steps)?;
    let loss = parse_loss(&args.loss)?;
    crate::args::check_flag(
        "--sigma-rad",
        args.sigma_rad,
        1e-9,
        deflex_calibrate::measurements::MAX_SIGMA_RAD,
        "rad",
    )?;
    let start_robot = robot(&args.robot)?;
    let n = start_robot.joint_count();
    let series = read_all(&args.data, n, &args.ignore_column)?;
    let test = read_all(&args.test_data, n, &args.ignore_column)?;
    let mut loaded = Vec::new();
    for path in &args.loaded {
        // Loaded readings are in the robot's world: checked against its forward kinematics
        // as `deflex calibrate` checks them (another robot's campaign is refused).
        let file = deflex_app::load::read_file_ignoring(path, Some(n), true, &args.ignore_column)?;
        let origin = deflex_files::shown_path(path);
        let check = deflex_calibrate::stiffness::consistency::check_geometry(
            &start_robot,
            &file.rows,
            Some(&file.lines),
            Some(&file.header),
            deflex_calibrate::stiffness::consistency::DEFAULT_FK_TOLERANCE_M,
        )
        .map_err(|e| CliError::in_context(origin.clone())(e.into()))?;
        deflex_calibrate::stiffness::consistency::enforce(
            &check,
            &origin,
            false,
            "Is this the robot the loaded campaign was measured on? Give the robot with --robot.",
        )?;
        loaded.extend(file.rows);
    }
    let series_of: Vec<usize> = series
        .iter()
        .enumerate()
        .flat_map(|(k, rows)| std::iter::repeat_n(k, rows.len()))
        .collect();
    let fit_count = series_of.len();
    let mut all: Vec<AbsoluteRow> = series.into_iter().flatten().collect();
    let distinct = distinct_readings(&all);
    // Test readings go after the fitted ones and are held out by index.
    let test_count: usize = test.iter().map(Vec::len).sum();
    all.extend(test.into_iter().flatten());
    let mut model = EgModel::from_robot(&start_robot);
    let mut campaign = Campaign::new(&mut model, all, loaded)?;
    if args.orientations {
        campaign.use_orientations(args.sigma_rad);
        if campaign.orientation_rows.is_empty() {
            return Err(UsageError::Missing {
                what: "--orientations",
                give: "no row of the data has rx_rad, ry_rad, rz_rad",
            }
            .into());
        }
    }
    let groups = args.cv_by.map(|by| {
        let mut g: Vec<usize> = match by {
            CvBy::Session => session_groups(&campaign, SESSION_GAP_S),
            CvBy::Setup => campaign.setup_of.clone(),
            CvBy::Series => series_of.clone(),
        };
        // Test rows are never fitted: their group does not matter.
        g.resize(fit_count + test_count, usize::MAX);
        g
    });
    let options = FitOptions {
        steps,
        loss,
        folds: args.folds,
        bootstrap: args.bootstrap,
        test_fraction: args.test_fraction,
        seed: args.seed,
        elastic_edofs: args
            .elastic
            .as_deref()
            .map(|t| t.split(',').map(|s| s.trim().to_string()).collect())
            .unwrap_or_default(),
        held_out_readings: (fit_count..campaign.absolute.len()).collect(),
        groups,
        protocol: HeldOutProtocol {
            register_readings: args.register_readings,
            draws: args.register_draws,
            register_target: args.register_target,
        },
        ..FitOptions::default()
    };
    let started = std::time::Instant::now();
    let result = fit(&model, &campaign, &options)?;
    let elapsed = started.elapsed().as_secs_f64();
    // As many independent equations as parameters at least (3 per distinct reading): fewer,
    // and the standard errors and χ² of 0 would claim what the data cannot give.
    if 3 * distinct <= result.estimates.len() {
        return Err(CliError::TooFewReadings {
            files: shown_paths(&args.data),
            distinct,
            readings: fit_count,
            equations: 3 * distinct,
            parameters: result.estimates.len(),
        });
    }
    check_plausible_fit(&result, &start_robot.name, &args.data)?;
    let robot_out = result.model.to_robot();
    let toml = deflex_app::load::robot_to_toml_for(&robot_out, &args.out);
    let terms = CalibrationTerms::of(&result);
    let terms_file = terms_path(&args.out);
    // Model, terms and report are one unit: the model and terms are written aside first, the
    // report folder swapped in, and only then the model and terms renamed in. A report that
    // fails (a full disk) leaves the earlier model, terms and report as they were.
    use std::io::Write as _;
    let staged = |path: &Path, text: String| -> Result<deflex_files::AtomicFile, CliError> {
        let mut file = deflex_files::AtomicFile::create(path).map_err(CliError::write(path))?;
        file.write_all(text.as_bytes())
            .and_then(|()| file.flush())
            .map_err(CliError::write(path))?;
        Ok(file)
    };
    let terms_staged = staged(&terms_file, terms.to_json())?;
    let model_staged = staged(&args.out, toml)?;
    let files = match &args.report {
        Some(dir) => report::write_report(&result, &campaign, dir)?,
        None => Vec::new(),
    };
    terms_staged
        .commit()
        .map_err(CliError::write(&terms_file))?;
    model_staged.commit().map_err(CliError::write(&args.out))?;
    if json_output {
        let mut value = report::json(&result, &campaign);
        value["elapsed_s"] = serde_json::json!(elapsed);
        value["out"] = serde_json::json!(args.out.display().to_string());
        value["terms"] = serde_json::json!(terms_file.display().to_string());
        value["report_files"] = serde_json::json!(
            files
                .iter()
                .map(|f| f.display().to_string())
                .collect::<Vec<_>>()
        );
        print_json(&value);
    } else {
        print!("{}", report::text(&result, &campaign));
        println!(
            "fit time {elapsed:.2} s; calibrated robot written to {} (terms: {})",
            args.out.display(),
            terms_file.display()
        );
        if let Some(dir) = &args.report {
            println!("report: {}", dir.join("index.html").display());
        }
    }
    Ok(())
}

/// Runs `deflex predict`.
pub fn predict(args: PredictArgs, json_output: bool) -> CommandResult {
    let (model, _) = load_model(&args.robot)?;
    let rows = read_absolute(&args.data, model.robot.joint_count(), &args.ignore_column)?;
    let prediction = predict::predict_rows(&model, rows, args.fit_setup)?;
    deflex_files::write_atomic(&args.out, report::prediction::prediction_csv(&prediction))
        .map_err(CliError::write(&args.out))?;
    if json_output {
        print_json(&report::prediction::prediction_json(&prediction));
    } else {
        print!("{}", report::prediction::prediction_text(&prediction));
        println!("predictions written to {}", args.out.display());
    }
    Ok(())
}
