//! `deflex sim ...`: the digital twin of the robotised ISF cell (SIMULATED).
//!
//! * `deflex sim campaign --plan PLAN.csv --out MEAS.csv [--seed N]`: measure a calibration plan
//!   on the twin's true robot with the simulated laser tracker and load cell;
//! * `deflex sim campaign --grid paper --out GRID.csv`: the paper's validation grid (200 poses,
//!   600 N and 1100 N, Figs. 10–13);
//! * `deflex sim campaign --spiral --out SPIRAL.csv`: the spiral of Fig. 14;
//! * `deflex sim isf --path cone|cone-contour|pyramid|FILE.gcode --out DIR [--seed N]`: the
//!   forming run without correction, with its log, summary and plots (Figs. 17–19, A1).

use crate::args::{CliResult, print_json};
use clap::{Args, Subcommand};
use deflex_sim::campaign::{SpiralParams, run_campaign, spiral, validation_grid};
use deflex_sim::gcode::read_gcode;
use deflex_sim::{CellConfig, ConeParams, PyramidParams, ToolPath, run_forming_with_progress};
use serde_json::json;
use std::path::{Path, PathBuf};

#[derive(Subcommand)]
pub enum SimCommand {
    /// Measure a calibration plan, the paper's validation grid or its spiral on the twin.
    Campaign(CampaignArgs),
    /// Form a part on the twin (open loop) and write its log, summary and plots.
    Isf(IsfArgs),
}

#[derive(Args)]
pub struct CampaignArgs {
    /// Plan file (the measurement format without displacement columns), e.g. from `deflex plan`.
    #[arg(long, conflicts_with_all = ["grid", "spiral"])]
    pub plan: Option<PathBuf>,
    /// The paper's validation grid: `paper` (200 poses, 600 N and 1100 N dead weights).
    #[arg(long, conflicts_with = "spiral")]
    pub grid: Option<String>,
    /// The paper's spiral (Fig. 14): 600 N dead weight, tracked at 50 Hz.
    #[arg(long)]
    pub spiral: bool,
    /// Output measurement file (CSV).
    #[arg(long)]
    pub out: PathBuf,
    /// Random seed (tracker and load-cell noise).
    #[arg(long, default_value_t = 1)]
    pub seed: u64,
    /// Twin settings (`[cell]` TOML); default: the paper's cell.
    #[arg(long)]
    pub config: Option<PathBuf>,
}

#[derive(Args)]
pub struct IsfArgs {
    /// Tool path: `cone` (the paper's helical cone), `cone-contour`, `pyramid`, or a G-code file.
    #[arg(long, default_value = "cone")]
    pub path: String,
    /// Output folder (log.csv, summary.json, plots).
    #[arg(long)]
    pub out: PathBuf,
    /// Random seed (sensor and tracker noise).
    #[arg(long, default_value_t = 1)]
    pub seed: u64,
    /// Twin settings (`[cell]` TOML); default: the paper's cell.
    #[arg(long)]
    pub config: Option<PathBuf>,
    /// Only the first part of the path (mm of travel).
    #[arg(long)]
    pub length_mm: Option<f64>,
    /// Feed rate for the built-in paths (mm/s).
    #[arg(long)]
    pub feed_mm_s: Option<f64>,
    /// Online correction: `off` (default) or `on` (needs --model).
    #[arg(long, default_value = "off")]
    pub correction: String,
    /// Identified model used by the correction controller (robot TOML).
    #[arg(long)]
    pub model: Option<PathBuf>,
}

pub fn sim(command: SimCommand, json: bool) -> CliResult {
    match command {
        SimCommand::Campaign(args) => campaign(args, json),
        SimCommand::Isf(args) => isf(args, json),
    }
}

fn load_config(path: Option<&Path>) -> Result<CellConfig, String> {
    match path {
        Some(p) => CellConfig::load(p).map_err(|e| e.to_string()),
        None => Ok(CellConfig::default()),
    }
}

fn campaign(args: CampaignArgs, json: bool) -> CliResult {
    let config = load_config(args.config.as_deref())?;
    let (kind, rows) = match (&args.plan, &args.grid, args.spiral) {
        (Some(plan), None, false) => {
            let plan_rows = deflex_calib::read_plan(plan).map_err(|e| e.to_string())?;
            let rows = run_campaign(&config, &plan_rows, args.seed).map_err(|e| e.to_string())?;
            (format!("plan {}", plan.display()), rows)
        }
        (None, Some(grid), false) => {
            if grid != "paper" {
                return Err(format!("--grid: only `paper` is known, got \"{grid}\""));
            }
            let params =
                deflex_sim::campaign::GridParams::for_cell(&config).map_err(|e| e.to_string())?;
            let plan = validation_grid(&config, &params).map_err(|e| e.to_string())?;
            let rows = run_campaign(&config, &plan, args.seed).map_err(|e| e.to_string())?;
            (
                "validation grid (paper, 600 N and 1100 N)".to_string(),
                rows,
            )
        }
        (None, None, true) => {
            let rows =
                spiral(&config, &SpiralParams::default(), args.seed).map_err(|e| e.to_string())?;
            ("spiral (paper Fig. 14, 600 N)".to_string(), rows)
        }
        _ => return Err("give one of --plan PLAN.csv, --grid paper or --spiral".into()),
    };
    let mut text = format!(
        "# SIMULATED deflex digital-twin campaign ({kind}), seed {}: not a measurement\n",
        args.seed
    );
    text.push_str(&deflex_calib::data::format_rows(&rows));
    std::fs::write(&args.out, text).map_err(|e| format!("{}: {e}", args.out.display()))?;
    let cases = deflex_calib::data::load_case_count(&rows);
    let max_disp = rows
        .iter()
        .filter_map(|r| r.displacement_m)
        .map(|d| (d[0] * d[0] + d[1] * d[1] + d[2] * d[2]).sqrt())
        .fold(0.0, f64::max);
    if json {
        print_json(&json!({
            "simulated": true,
            "campaign": kind,
            "seed": args.seed,
            "rows": rows.len(),
            "load_cases": cases,
            "max_displacement_mm": max_disp * 1e3,
            "out": args.out.display().to_string(),
        }));
    } else {
        println!("SIMULATED campaign: {kind}");
        println!(
            "  {} rows in {} load cases, largest displacement {:.3} mm → {}",
            rows.len(),
            cases,
            max_disp * 1e3,
            args.out.display()
        );
    }
    Ok(())
}

fn tool_path(args: &IsfArgs) -> Result<ToolPath, String> {
    let path = match args.path.as_str() {
        "cone" | "cone-contour" => {
            let mut p = ConeParams {
                helical: args.path == "cone",
                ..ConeParams::default()
            };
            if let Some(f) = args.feed_mm_s {
                p.feed_mm_s = f;
            }
            ToolPath::cone(&p).map_err(|e| e.to_string())?
        }
        "pyramid" => {
            let mut p = PyramidParams::default();
            if let Some(f) = args.feed_mm_s {
                p.feed_mm_s = f;
            }
            ToolPath::pyramid(&p).map_err(|e| e.to_string())?
        }
        file => {
            if args.feed_mm_s.is_some() {
                return Err(
                    "--feed-mm-s applies to the built-in paths; a G-code file sets its own F"
                        .into(),
                );
            }
            read_gcode(Path::new(file)).map_err(|e| e.to_string())?
        }
    };
    Ok(match args.length_mm {
        Some(l) if l > 0.0 => path.truncated(l),
        Some(l) => return Err(format!("--length-mm must be positive, got {l}")),
        None => path,
    })
}

fn isf(args: IsfArgs, json: bool) -> CliResult {
    match args.correction.as_str() {
        "off" => {
            if args.model.is_some() {
                return Err("--model is only used with --correction on".into());
            }
        }
        "on" => {}
        other => return Err(format!("--correction: expected on or off, got \"{other}\"")),
    }
    let config = load_config(args.config.as_deref())?;
    // Closed loop: the deflex correction controller in-process, in simulated time.
    let mut twin = match args.correction.as_str() {
        "on" => Some(deflex_demo::twin_controller::twin_controller(
            &config,
            args.model.as_deref(),
        )?),
        _ => None,
    };
    let path = tool_path(&args)?;
    let name = path.name.clone();
    let bar = if json {
        indicatif::ProgressBar::hidden()
    } else {
        indicatif::ProgressBar::new(1000)
    };
    bar.set_style(
        indicatif::ProgressStyle::with_template(
            "SIMULATED forming {bar:40} {percent:>3}% {elapsed}",
        )
        .unwrap_or_else(|_| indicatif::ProgressStyle::default_bar()),
    );
    let controller = twin
        .as_mut()
        .map(|t| t as &mut dyn deflex_sim::CorrectionController);
    let run = run_forming_with_progress(&config, path, args.seed, controller, &mut |f| {
        bar.set_position((f * 1000.0) as u64)
    })
    .map_err(|e| e.to_string())?;
    bar.finish_and_clear();
    let files = run.write_outputs(&args.out).map_err(|e| e.to_string())?;
    let s = &run.summary;
    if json {
        let mut value: serde_json::Value =
            serde_json::from_str(&run.summary_json()).unwrap_or_default();
        if let Some(map) = value.as_object_mut() {
            map.insert(
                "files".into(),
                json!(
                    files
                        .iter()
                        .map(|f| f.display().to_string())
                        .collect::<Vec<_>>()
                ),
            );
        }
        print_json(&value);
    } else {
        let mode = if twin.is_some() {
            "closed-loop"
        } else {
            "open-loop"
        };
        println!("SIMULATED {mode} forming: {name} (seed {})", args.seed);
        if let Some(t) = &twin {
            println!("  {}", t.status_line());
        }
        println!(
            "  {:.1} s simulated in {:.2} s ({} cycles)",
            s.duration_s, run.wall_time_s, s.cycles
        );
        println!(
            "  TCP error: max {:.3} mm, RMS {:.3} mm (max |x| {:.3}, |y| {:.3}, |z| {:.3} mm)",
            s.max_error_norm_mm,
            s.rms_error_norm_mm,
            s.max_error_abs_mm[0],
            s.max_error_abs_mm[1],
            s.max_error_abs_mm[2]
        );
        println!(
            "  force: max |F| {:.0} N, max Fz {:.0} N, max in-plane {:.0} N (Aerens level {:.0} N)",
            s.max_force_norm_N, s.max_fz_N, s.max_fxy_N, s.aerens_steady_fz_N
        );
        println!(
            "  part depth {:.2} mm of {:.2} mm programmed",
            s.final_part_depth_mm, s.target_depth_mm
        );
        println!("  wrote {} files to {}", files.len(), args.out.display());
    }
    Ok(())
}
