//! `deflex plot LOG [LOG2] --out DIR`: the figures of a run's log (a `deflex run` CSV log, a
//! `deflex sim isf` log.csv or an MCAP recording), or of two logs overlaid on path position, and
//! a self-contained page. The folder is built aside and swapped in whole.

use crate::args;
use crate::error::{CliError, CommandResult, UsageError};
use clap::Args;
use std::path::PathBuf;

/// Arguments of `deflex plot`.
#[derive(Args)]
pub struct PlotArgs {
    /// The log: a `deflex run` CSV log, a `deflex sim isf` log.csv or an MCAP recording.
    log: PathBuf,
    /// A second log, overlaid on the first, aligned by position along the desired path (e.g.
    /// open and closed loop).
    log2: Option<PathBuf>,
    /// Output folder (replaced whole when the figures are done).
    #[arg(long)]
    pub out: PathBuf,
    /// Names of the runs in legends, comma-separated (default: the file names).
    #[arg(long, value_delimiter = ',')]
    labels: Vec<String>,
    /// Robot model (built-in name or file) to place a `deflex run` log that has no `path_s_m`
    /// on its path (forward kinematics of its joints); without it such a log is drawn against
    /// time.
    #[arg(long)]
    robot: Option<String>,
}

/// Runs `deflex plot`.
pub fn plot(a: PlotArgs, json: bool) -> CommandResult {
    let logs: Vec<PathBuf> = std::iter::once(a.log).chain(a.log2).collect();
    if !a.labels.is_empty() && a.labels.len() != logs.len() {
        return Err(UsageError::invalid(
            "--labels",
            format!("one name per log ({})", logs.len()),
            format!("{} names", a.labels.len()),
        )
        .into());
    }
    let robot = a.robot.as_deref().map(args::robot).transpose()?;
    let mut traces = Vec::new();
    for (i, log) in logs.iter().enumerate() {
        let label = a.labels.get(i).cloned().unwrap_or_else(|| {
            let name = log.file_name().map_or_else(
                || log.display().to_string(),
                |n| n.to_string_lossy().into_owned(),
            );
            // Two logs of the same name (open/log.csv, closed/log.csv): add the folder.
            match log.parent().and_then(|p| p.file_name()) {
                Some(dir) if logs.len() > 1 => format!("{}/{name}", dir.to_string_lossy()),
                _ => name,
            }
        });
        let trace = deflex_record::trace::read_run_log(log, &label, robot.as_ref())?;
        traces.push(trace);
    }
    let out = deflex_files::AtomicDir::create(&a.out).map_err(CliError::write(&a.out))?;
    let figures = deflex_app::report::write_run_figures(out.path(), &traces)?;
    out.commit().map_err(CliError::write(&a.out))?;
    let names: Vec<String> = figures
        .figures
        .iter()
        .filter_map(|p| p.file_name().map(|n| n.to_string_lossy().into_owned()))
        .collect();
    let page = a.out.join("index.html");
    if json {
        args::print_json(&serde_json::json!({
            "out": a.out.display().to_string(),
            "page": page.display().to_string(),
            "figures": names,
            "by_path_position": figures.by_path_position,
            "simulated": traces.iter().any(|t| t.simulated),
            "runs": traces.iter().map(|t| serde_json::json!({
                "label": t.label, "file": t.file, "kind": t.kind, "rows": t.time_s.len(),
            })).collect::<Vec<_>>(),
        }));
    } else {
        for t in &traces {
            println!(
                "{}{}: {} ({} rows) from {}",
                if t.simulated { "SIMULATED " } else { "" },
                t.label,
                t.kind,
                t.time_s.len(),
                t.file
            );
        }
        println!(
            "figures against {}: {}",
            if figures.by_path_position {
                "position along the desired path"
            } else {
                "time (a log does not give its path position; --robot places a deflex run log)"
            },
            names.join(", ")
        );
        println!("page: {}", page.display());
    }
    Ok(())
}
