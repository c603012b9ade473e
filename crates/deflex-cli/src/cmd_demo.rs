//! `deflex demo`: the paper's whole study on the built-in SIMULATED cell, with progress bars and
//! a summary table; the work is done by `deflex-demo`.

use crate::args::CliResult;
use clap::Args;
use deflex_demo::{DemoOptions, Progress, run_demo};
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
}

struct Bars {
    bar: Option<ProgressBar>,
    quiet: bool,
}

impl Progress for Bars {
    fn stage(&mut self, index: usize, total: usize, name: &str) {
        if self.quiet {
            return;
        }
        let bar = ProgressBar::new(1000);
        bar.set_style(
            ProgressStyle::with_template("{prefix:>5} {msg:<48} [{bar:30}] {elapsed:>4}")
                .unwrap_or_else(|_| ProgressStyle::default_bar())
                .progress_chars("=> "),
        );
        bar.set_prefix(format!("{index}/{total}"));
        bar.set_message(name.to_string());
        self.bar = Some(bar);
    }
    fn fraction(&mut self, fraction: f64) {
        if let Some(bar) = &self.bar {
            bar.set_position((fraction.clamp(0.0, 1.0) * 1000.0) as u64);
        }
    }
    fn done(&mut self, note: &str) {
        if let Some(bar) = self.bar.take() {
            bar.set_position(1000);
            bar.finish_with_message(format!("{} — {note}", bar.message()));
        }
    }
}

pub fn demo(args: DemoArgs, json: bool) -> CliResult {
    let options = DemoOptions {
        out_dir: args.out.clone(),
        seed: args.seed,
        quick: args.quick,
    };
    let started = std::time::Instant::now();
    let mut bars = Bars {
        bar: None,
        quiet: json,
    };
    let summary = run_demo(&options, &mut bars)?;
    if json {
        println!(
            "{}",
            serde_json::to_string_pretty(&summary).unwrap_or_default()
        );
        return Ok(());
    }
    println!();
    println!(
        "deflex demo — SIMULATED TX200 cell (seed {}){}",
        summary.seed,
        if summary.quick { ", quick" } else { "" }
    );
    println!("{:<52} {:>10} {:>12}", "quantity", "paper", "deflex (sim)");
    for (quantity, paper, ours, unit) in deflex_demo::paper_vs_deflex_rows(&summary) {
        println!(
            "{:<52} {:>7.3} {unit:<2} {:>9.3} {unit}",
            quantity, paper, ours
        );
    }
    println!("identified structure: {}", summary.identified_structure);
    println!(
        "report: {} ({:.1} s)",
        args.out.join("index.html").display(),
        started.elapsed().as_secs_f64()
    );
    Ok(())
}
