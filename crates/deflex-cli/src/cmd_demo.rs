//! `deflex demo`: the paper's whole study on the SIMULATED cell of the TX200 or another robot
//! (`--robot`), with progress bars and a summary table; the work is done by
//! `deflex_app::study::demo`.

use crate::error::CommandResult;
use clap::Args;
use deflex_app::study::{DemoOptions, summary_json, summary_text};
use deflex_telemetry::Progress;
use indicatif::{ProgressBar, ProgressStyle};
use std::path::PathBuf;

#[derive(Args)]
pub struct DemoArgs {
    /// Output folder for the report, figures and data.
    #[arg(long, default_value = "deflex-report")]
    pub out: PathBuf,
    /// Seed of every random draw (deterministic under a seed).
    #[arg(long, default_value_t = 1)]
    pub seed: u64,
    /// Shortened study (fewer load cases, short spiral, first part of the cone): for tests.
    #[arg(long)]
    pub quick: bool,
    /// The robot the twin plays: a built-in name (`tx200`, `ur10e`, …) or a robot file. The
    /// paper's comparisons are shown for the TX200 only.
    #[arg(long, default_value = "tx200")]
    pub robot: String,
    /// Leave out the sensitivity section (about half the run time).
    #[arg(long)]
    pub no_sensitivity: bool,
}

struct Bars {
    bar: Option<ProgressBar>,
    quiet: bool,
}

impl Bars {
    /// Shows one report of the study: a bar per stage, its work in per mille of the bar.
    fn show(&mut self, progress: Progress<'_>) {
        match progress {
            Progress::Stage { index, count, name } => {
                if self.quiet {
                    return;
                }
                let bar = ProgressBar::new(1000);
                bar.set_style(
                    ProgressStyle::with_template("{prefix:>5} {msg:<48} [{bar:30}] {elapsed:>4}")
                        .unwrap_or_else(|_| ProgressStyle::default_bar())
                        .progress_chars("=> "),
                );
                bar.set_prefix(match count {
                    Some(count) => format!("{index}/{count}"),
                    None => index.to_string(),
                });
                bar.set_message(name.to_string());
                self.bar = Some(bar);
            }
            Progress::Work { done, total } => {
                if let (Some(bar), true) = (&self.bar, total > 0) {
                    bar.set_position((done.min(total) * 1000 / total) as u64);
                }
            }
            Progress::Done { note } => {
                if let Some(bar) = self.bar.take() {
                    bar.set_position(1000);
                    bar.finish_with_message(format!("{} — {note}", bar.message()));
                }
            }
        }
    }
}

pub fn demo(args: DemoArgs, json: bool) -> CommandResult {
    let options = DemoOptions {
        seed: args.seed,
        quick: args.quick,
        robot: args.robot.clone(),
        sensitivity: !args.no_sensitivity,
    };
    let started = std::time::Instant::now();
    let mut bars = Bars {
        bar: None,
        quiet: json,
    };
    let summary = deflex_app::study::demo(&options, &args.out, &mut |p| bars.show(p))?;
    if json {
        println!("{}", summary_json(&summary)?);
    } else {
        print!(
            "{}",
            summary_text(&summary, &args.out, started.elapsed().as_secs_f64())
        );
    }
    Ok(())
}
