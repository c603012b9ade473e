//! `deflex import ur10-tracker`, `deflex calibrate-geometry`, `deflex predict`: elasto-geometric
//! calibration from absolute tracker readings (logic in `deflex-absolute`).

use crate::args::{CliResult, print_json, robot};
use clap::{Args, Subcommand};
use deflex_absolute::campaign::Campaign;
use deflex_absolute::data::{AbsoluteRow, format_absolute, read_absolute};
use deflex_absolute::fit::{FitOptions, Step, fit};
use deflex_absolute::params::EgModel;
use deflex_absolute::solve::Loss;
use deflex_absolute::ur10_tracker::{ImportOptions, import_series};
use deflex_absolute::{predict, report};
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
    /// Absolute CSV never fitted: set-ups the fit knows are scored as they are; new set-ups get
    /// their registration fitted on half their configurations and are scored on the rest.
    #[arg(long)]
    pub test_data: Vec<PathBuf>,
    /// Model steps, comma-separated, each adding to the previous: registration, geometry,
    /// compliance, masses, harmonics:N.
    #[arg(long, default_value = "registration,geometry,compliance")]
    pub steps: String,
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
    /// Calibrated robot file (DH rows, stiffness, masses, set-ups, targets).
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
    /// Fit the registration of the rows' set-ups (all rows) before predicting: for a set-up
    /// the model does not know, or a tracker that was moved.
    #[arg(long)]
    pub fit_setup: bool,
    /// Output CSV: each row with predicted_x_m … and, when measured, the error.
    #[arg(long)]
    pub out: PathBuf,
}

pub fn import(command: ImportCommand, json_output: bool) -> CliResult {
    let ImportCommand::Ur10Tracker(args) = command;
    if args.every == 0 || args.every > 1_000_000 {
        return Err(format!("--every: expected 1…1000000, got {}", args.every));
    }
    let options = ImportOptions {
        setup: args.setup.clone(),
        target: args.target.clone(),
        tracker_sigma: args.tracker_sigma,
    };
    let (rows, summary) = import_series(&args.series, &options).map_err(|e| e.to_string())?;
    let kept: Vec<AbsoluteRow> = rows.into_iter().step_by(args.every).collect();
    let comments = vec![
        "UR10 laser-tracker data: Landgraf, Ernst, Schleth, Fabritius, Huber, IEEE CASE 2021 (MIT licence)".to_string(),
        format!(
            "imported by deflex from {} (every {} reading(s)); T-Mac probe in the tracker frame",
            summary.file.display(),
            args.every
        ),
    ];
    let text = format_absolute(&kept, &comments);
    deflex_files::write_atomic(&args.out, text)
        .map_err(|e| format!("{}: {e}", args.out.display()))?;
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

fn parse_steps(text: &str) -> Result<Vec<Step>, String> {
    text.split(',')
        .map(|item| match item.trim() {
            "registration" => Ok(Step::Registration),
            "geometry" => Ok(Step::Geometry),
            "compliance" | "gravity" => Ok(Step::Compliance),
            "masses" => Ok(Step::Masses),
            other => match other.strip_prefix("harmonics:").map(str::parse::<u8>) {
                Some(Ok(n)) if (1..=4).contains(&n) => Ok(Step::Harmonics(n)),
                _ => Err(format!(
                    "--steps: unknown step \"{other}\" (registration, geometry, compliance, masses, harmonics:N with N 1…4)"
                )),
            },
        })
        .collect()
}

fn parse_loss(text: &str) -> Result<Loss, String> {
    let (name, k) = match text.split_once(':') {
        Some((n, k)) => (
            n,
            Some(
                k.parse::<f64>()
                    .ok()
                    .filter(|k| k.is_finite() && (0.1..=100.0).contains(k))
                    .ok_or_else(|| {
                        format!("--loss: threshold \"{k}\" must be a number in 0.1…100")
                    })?,
            ),
        ),
        None => (text, None),
    };
    match name {
        "huber" => Ok(Loss::Huber(k.unwrap_or(3.0))),
        "cauchy" => Ok(Loss::Cauchy(k.unwrap_or(2.4))),
        "none" | "squared" => Ok(Loss::Squared),
        other => Err(format!(
            "--loss: expected huber, cauchy or none, got \"{other}\""
        )),
    }
}

fn read_all(paths: &[PathBuf], joints: usize) -> Result<Vec<AbsoluteRow>, String> {
    let mut rows = Vec::new();
    for path in paths {
        rows.extend(read_absolute(path, joints).map_err(|e| e.to_string())?);
    }
    Ok(rows)
}

pub fn calibrate_geometry(args: CalibrateGeometryArgs, json_output: bool) -> CliResult {
    let steps = parse_steps(&args.steps)?;
    let loss = parse_loss(&args.loss)?;
    let start_robot = robot(&args.robot)?;
    let n = start_robot.joint_count();
    let absolute = read_all(&args.data, n)?;
    let test = read_all(&args.test_data, n)?;
    let mut loaded = Vec::new();
    for path in &args.loaded {
        loaded.extend(deflex_stiffness::read_for_robot(path, n, true).map_err(|e| e.to_string())?);
    }
    let fit_count = absolute.len();
    let mut all = absolute;
    // Test readings go after the fitted ones and are held out by index.
    all.extend(test);
    let mut model = EgModel::from_robot(&start_robot);
    let campaign = Campaign::new(&mut model, all, loaded).map_err(|e| e.to_string())?;
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
        ..FitOptions::default()
    };
    let started = std::time::Instant::now();
    let result = fit(&model, &campaign, &options).map_err(|e| e.to_string())?;
    let elapsed = started.elapsed().as_secs_f64();
    let robot_out = result.model.to_robot();
    let toml = deflex_model::robot_to_toml_for(&robot_out, &args.out);
    deflex_files::write_atomic(&args.out, toml)
        .map_err(|e| format!("{}: {e}", args.out.display()))?;
    let files = match &args.report {
        Some(dir) => report::write_report(&result, &campaign, dir).map_err(|e| e.to_string())?,
        None => Vec::new(),
    };
    if json_output {
        let mut value = report::json(&result, &campaign);
        value["elapsed_s"] = serde_json::json!(elapsed);
        value["out"] = serde_json::json!(args.out.display().to_string());
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
            "fit time {elapsed:.2} s; calibrated robot written to {}",
            args.out.display()
        );
        if let Some(dir) = &args.report {
            println!("report: {}", dir.join("index.html").display());
        }
    }
    Ok(())
}

pub fn predict(args: PredictArgs, json_output: bool) -> CliResult {
    let robot = robot(&args.robot)?;
    let rows = read_absolute(&args.data, robot.joint_count()).map_err(|e| e.to_string())?;
    let prediction =
        predict::predict_rows(&robot, rows, args.fit_setup).map_err(|e| e.to_string())?;
    deflex_files::write_atomic(&args.out, &prediction.csv)
        .map_err(|e| format!("{}: {e}", args.out.display()))?;
    if json_output {
        print_json(&prediction.json);
    } else {
        print!("{}", prediction.text);
        println!("predictions written to {}", args.out.display());
    }
    Ok(())
}
