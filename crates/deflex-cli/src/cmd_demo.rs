//! `deflex demo`: the paper's whole study on the SIMULATED cell of the TX200 or another robot
//! (`--robot`), with progress bars and a summary table; the work is done by `deflex-study`.

use crate::error::CommandResult;
use clap::Args;
use deflex_app::study::{DemoOptions, run_study};
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
    let cell = deflex_app::cell::twin_cell_file::cell_for_robot(&options.robot)?;
    let study = run_study(&options, cell, &mut |p| bars.show(p))?;
    deflex_app::report::study::write_study(&study, &args.out)?;
    let summary = study.summary;
    if json {
        println!(
            "{}",
            serde_json::to_string_pretty(&summary).unwrap_or_default()
        );
        return Ok(());
    }
    println!();
    println!(
        "deflex demo — SIMULATED cell of the {} (seed {}){}",
        summary.robot,
        summary.seed,
        if summary.quick { ", quick" } else { "" }
    );
    if summary.paper_comparison {
        println!("{:<52} {:>10} {:>12}", "quantity", "paper", "deflex (sim)");
        for (quantity, paper, ours, unit) in deflex_app::study::paper_vs_deflex_rows(&summary) {
            println!(
                "{:<52} {:>7.3} {unit:<2} {:>9.3} {unit}",
                quantity, paper, ours
            );
        }
    } else {
        for v in &summary.validation {
            if v.model.starts_with("identified") {
                println!(
                    "identified model, {}: RMS / max δz error {:.3} / {:.3} mm",
                    v.data, v.rms_z_mm, v.max_z_mm
                );
            }
        }
    }
    let (o, c) = (&summary.forming_open, &summary.forming_closed);
    println!(
        "cone, every error source on: max |error| {:.3} → {:.3} mm ({:.1} % better), RMS {:.3} → {:.3} mm, \
         max |F| {:.0} → {:.0} N",
        o.max_error_norm_mm,
        c.max_error_norm_mm,
        summary.improvement_percent,
        o.rms_error_norm_mm,
        c.rms_error_norm_mm,
        o.max_force_norm_N,
        c.max_force_norm_N
    );
    let sc = &summary.stiff_contact;
    let outcome =
        |l: &deflex_app::study::contact::ContactLoopNumbers| match (&l.fault, l.runaway_warnings) {
            (Some(f), _) => format!(" ({f})"),
            (None, 0) => String::new(),
            (None, n) => format!(
                " ({n} contact_runaway warning{})",
                if n == 1 { "" } else { "s" }
            ),
        };
    println!(
        "plunge into a {:.0e} N/m fixture: max |F| {:.0} N without correction, {:.0} N with \
         correction and no runaway guard{}, {:.0} N with the guard{}",
        sc.stiffness_n_m,
        sc.open_max_force_N,
        sc.unguarded.max_force_N,
        outcome(&sc.unguarded),
        sc.guarded.max_force_N,
        outcome(&sc.guarded)
    );
    if let Some(s) = &summary.sensitivity {
        let worst = s
            .rows
            .iter()
            .min_by(|a, b| a.improvement_percent.total_cmp(&b.improvement_percent));
        if let Some(w) = worst {
            println!(
                "sensitivity: {} runs, worst improvement {:.1} % ({}: {})",
                s.runs, w.improvement_percent, w.factor, w.condition
            );
        }
    }
    println!("identified structure: {}", summary.identified_structure);
    println!(
        "report: {} ({:.1} s)",
        args.out.join("index.html").display(),
        started.elapsed().as_secs_f64()
    );
    Ok(())
}
