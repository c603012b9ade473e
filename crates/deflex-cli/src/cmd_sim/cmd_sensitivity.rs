//! `deflex sim sensitivity`: the closed loop across delay, model scale, sensor gain, bias drift
//! and contact stiffness (the work is `deflex_app::twin::sensitivity`): the flags in their units
//! (ms, %), the progress bar and the printing.

use super::{TwinArgs, load_config};
use crate::args::{parse_list, print_json};
use crate::error::{CommandResult, UsageError};
use clap::Args;
use deflex_app::study::sensitivity::SensitivityPlan;
use deflex_app::twin::sensitivity::{sweep, sweep_model};
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
        .map_err(|e| deflex_app::Error::from(deflex_app::study::DemoError::from(e)))?;
    if plan.delays_s.is_empty() || plan.model_scales.is_empty() {
        return Err(UsageError::Missing {
            what: "--delays-ms and --model-scales",
            give: "need at least one value each",
        }
        .into());
    }
    if args.model.is_none() && !json {
        eprintln!("identifying the controller's model from a campaign on the twin …");
    }
    let model = sweep_model(&config, args.model.as_deref(), args.seed)?;
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
    let done = sweep(&config, &model, &plan, args.seed, &|f| {
        bar.set_position((f * 1000.0) as u64)
    })?;
    bar.finish_and_clear();
    done.write(&args.out)?;
    if json {
        print_json(&done.summary_value()?);
    } else {
        print!("{}", done.text(&args.out));
    }
    Ok(())
}
