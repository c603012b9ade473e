//! `deflex sim sensitivity`: the closed loop across delay, model scale, sensor gain, bias drift
//! and contact stiffness (the work is `deflex_app::study::sensitivity`).

use super::{TwinArgs, load_config, robot_name};
use crate::args::{parse_list, print_json};
use crate::error::{CliError, CommandResult, UsageError};
use clap::Args;
use serde_json::json;
use std::path::PathBuf;

#[derive(Args)]
pub struct SensitivityArgs {
    /// Output folder (sensitivity.csv, sensitivity_heatmap.png, summary.json).
    #[arg(long)]
    pub out: PathBuf,
    #[command(flatten)]
    pub twin: TwinArgs,
    /// The controller's model (robot TOML, e.g. from `deflex calibrate`); default: identified
    /// from a calibration campaign on the twin, as a user would.
    #[arg(long)]
    pub model: Option<PathBuf>,
    /// Random seed.
    #[arg(long, default_value_t = 1)]
    pub seed: u64,
    /// Correction delays (ms, increasing, 0–1000).
    #[arg(long, default_value = "8,20,40,60")]
    pub delays_ms: String,
    /// Compliance scales of the model (increasing, 0.1–10; 1.3 = a model 30 % too soft).
    #[arg(long, default_value = "0.7,0.85,1,1.15,1.3")]
    pub model_scales: String,
    /// F/T gain errors on every channel (%, ±50; empty to skip).
    #[arg(long, default_value = "-5,0,5")]
    pub gain_errors_percent: String,
    /// Bias drift as multiples of the cell's documented drift (0–1000).
    #[arg(long, default_value = "0,1,10")]
    pub drift_factors: String,
    /// Contact stiffness of the sheet (N/m, 10⁴–10⁹).
    #[arg(long, default_value = "1e5,1e6,1e7,1e8")]
    pub contact_stiffness_n_m: String,
    /// Threads (1–64).
    #[arg(long, default_value_t = 2)]
    pub threads: usize,
    /// Only the first part of the sensitivity cone (mm, within (0, 10⁵]).
    #[arg(long)]
    pub length_mm: Option<f64>,
}

pub(super) fn sensitivity(args: SensitivityArgs, json: bool) -> CommandResult {
    use deflex_app::study::sensitivity::{SensitivityPlan, run_sensitivity};
    let config = load_config(&args.twin)?;
    let list = |text: &str, name: &str, scale: f64| -> Result<Vec<f64>, UsageError> {
        if text.trim().is_empty() {
            return Ok(Vec::new());
        }
        Ok(parse_list(text, name)?
            .into_iter()
            .map(|v| v * scale)
            .collect())
    };
    let plan = SensitivityPlan {
        delays_s: list(&args.delays_ms, "--delays-ms", 1e-3)?,
        model_scales: list(&args.model_scales, "--model-scales", 1.0)?,
        gain_errors: list(&args.gain_errors_percent, "--gain-errors-percent", 0.01)?,
        drift_factors: list(&args.drift_factors, "--drift-factors", 1.0)?,
        contact_stiffness_n_m: list(&args.contact_stiffness_n_m, "--contact-stiffness-n-m", 1.0)?,
        threads: args.threads,
        length_mm: args.length_mm,
    };
    plan.validate()
        .map_err(deflex_app::study::DemoError::from)?;
    if plan.delays_s.is_empty() || plan.model_scales.is_empty() {
        return Err(UsageError::Missing {
            what: "--delays-ms and --model-scales",
            give: "need at least one value each",
        }
        .into());
    }
    let model = match &args.model {
        Some(path) => deflex_app::load::load_robot(&path.display().to_string())
            .map_err(|e| CliError::in_context(format!("--model {}", path.display()))(e.into()))?,
        None => {
            if !json {
                eprintln!("identifying the controller's model from a campaign on the twin …");
            }
            deflex_app::twin::identify_from_twin_campaign(&config, args.seed)?
        }
    };
    let bar = if json {
        indicatif::ProgressBar::hidden()
    } else {
        indicatif::ProgressBar::new(1000)
    };
    bar.set_style(
        indicatif::ProgressStyle::with_template(
            "SIMULATED sensitivity runs {bar:40} {percent:>3}% {elapsed}",
        )
        .unwrap_or_else(|_| indicatif::ProgressStyle::default_bar()),
    );
    let result = run_sensitivity(&config, &model, &plan, args.seed, &|f| {
        bar.set_position((f * 1000.0) as u64)
    })?;
    bar.finish_and_clear();
    let building =
        deflex_files::AtomicDir::create(&args.out).map_err(CliError::write(&args.out))?;
    let dir = building.path();
    let write = |name: &str, text: String| {
        deflex_files::write_atomic(dir.join(name), text)
            .map_err(CliError::write(args.out.join(name)))
    };
    write(
        "sensitivity.csv",
        deflex_app::report::study::csv_files::sensitivity_csv(&result),
    )?;
    let robot = robot_name(&config);
    let summary = json!({
        "simulated": true,
        "robot": robot,
        "robot_spec": config.part.robot,
        "model": model.name,
        "seed": args.seed,
        "plan": plan,
        "result": result,
    });
    write(
        "summary.json",
        serde_json::to_string_pretty(&summary).unwrap_or_default(),
    )?;
    deflex_app::report::study::figures::sensitivity_heatmap(
        &result,
        &dir.join("sensitivity_heatmap.png"),
    )?;
    building.commit().map_err(CliError::write(&args.out))?;
    if json {
        print_json(&summary);
        return Ok(());
    }
    println!(
        "SIMULATED closed-loop sensitivity on the twin of the {robot} ({} runs, sensitivity cone, every error source on)",
        result.runs
    );
    println!(
        "{:<22} {:<34} {:>9} {:>9} {:>8} {:>8}  fault",
        "factor", "condition", "open mm", "closed mm", "improv %", "max |F| N"
    );
    for r in &result.rows {
        println!(
            "{:<22} {:<34} {:>9.3} {:>9.3} {:>8.1} {:>8.0}  {}",
            r.factor,
            r.condition,
            r.open_max_mm,
            r.closed_max_mm,
            r.improvement_percent,
            r.closed_max_force_N,
            r.fault.as_deref().unwrap_or("–")
        );
    }
    println!(
        "wrote sensitivity.csv, sensitivity_heatmap.png, summary.json to {}",
        args.out.display()
    );
    Ok(())
}
