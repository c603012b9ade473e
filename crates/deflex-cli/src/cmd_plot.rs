//! `deflex plot LOG [LOG2] --out DIR`: the figures of a run's log (a `deflex run` CSV log, a
//! `deflex sim isf` log.csv or an MCAP recording), or of two logs overlaid on path position, and
//! a self-contained page, written by `deflex_app::report::plot_logs`.

use crate::args;
use crate::error::{CommandResult, UsageError};
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
    let plot = deflex_app::report::plot_logs(&logs, &a.labels, robot.as_ref(), &a.out)?;
    args::print_report(json, || plot.text(), || plot.to_json());
    Ok(())
}
