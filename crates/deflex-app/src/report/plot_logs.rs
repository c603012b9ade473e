//! `deflex plot LOG [LOG2] --out DIR`: the figures of a run's log (a `deflex run` CSV log, a
//! `deflex sim isf` `log.csv` or an MCAP recording), or of two logs overlaid on path position,
//! and a self-contained page, in a folder built aside and swapped in whole. It draws: a build
//! without the `report` feature refuses it ([`crate::Error::ReportsNotBuilt`]) before reading
//! a log.

use crate::error::{Error, Result};
use deflex_model::Robot;
use deflex_record::trace::{RunTrace, read_run_log};
use serde_json::json;
use std::fmt::Write as _;
use std::path::{Path, PathBuf};

/// What the figures of a run or two (`crate::report::write_run_figures`) wrote.
#[derive(Clone, Debug, PartialEq)]
pub struct RunFigures {
    /// The figures, in page order.
    pub figures: Vec<PathBuf>,
    /// The page.
    pub page: PathBuf,
    /// True when the runs are drawn against path position, false against time.
    pub by_path_position: bool,
}

/// What `deflex plot` asks for, in the words of [`crate::Error::ReportsNotBuilt`].
const LOG_FIGURES: &str = "the figures of a run log (`deflex plot`)";

/// The plot of one or two logs, written.
#[derive(Clone, Debug)]
pub struct LogPlot {
    /// The runs read, in the order given.
    pub traces: Vec<RunTrace>,
    /// The figures and page written.
    pub figures: RunFigures,
    /// The folder.
    pub out: PathBuf,
}

/// The name of log `index` of `logs` in legends: its label when given, else its file name (with
/// its folder when two logs are plotted: `open/log.csv`, `closed/log.csv`).
fn label(logs: &[PathBuf], labels: &[String], index: usize) -> String {
    if let Some(label) = labels.get(index) {
        return label.clone();
    }
    let log = &logs[index];
    let name = log.file_name().map_or_else(
        || log.display().to_string(),
        |n| n.to_string_lossy().into_owned(),
    );
    // Two logs of the same name (open/log.csv, closed/log.csv): add the folder.
    match log.parent().and_then(|p| p.file_name()) {
        Some(dir) if logs.len() > 1 => format!("{}/{name}", dir.to_string_lossy()),
        _ => name,
    }
}

/// Read `logs` (one or two) and write their figures and page into the folder `out`. `labels`
/// names the runs in legends (none: the file names); `robot` places a `deflex run` log that has
/// no path position on its path (forward kinematics of its joints), without it such a log is
/// drawn against time. Needs the `report` feature (refused without it, before a log is read).
pub fn plot_logs(
    logs: &[PathBuf],
    labels: &[String],
    robot: Option<&Robot>,
    out: &Path,
) -> Result<LogPlot> {
    let drawing = super::require(LOG_FIGURES)?;
    if !labels.is_empty() && labels.len() != logs.len() {
        return Err(Error::invalid(
            "labels",
            format!(
                "expected one name per log ({}), got {} names",
                logs.len(),
                labels.len()
            ),
        ));
    }
    let mut traces = Vec::with_capacity(logs.len());
    for (i, log) in logs.iter().enumerate() {
        traces.push(read_run_log(log, &label(logs, labels, i), robot)?);
    }
    let io = Error::io_on(out);
    let folder = deflex_files::AtomicDir::create(out).map_err(io)?;
    let figures = drawing.run_figures(folder.path(), &traces)?;
    folder.commit().map_err(io)?;
    Ok(LogPlot {
        traces,
        figures,
        out: out.to_path_buf(),
    })
}

impl LogPlot {
    /// The figures' file names, in page order.
    fn figure_names(&self) -> Vec<String> {
        self.figures
            .figures
            .iter()
            .filter_map(|p| p.file_name().map(|n| n.to_string_lossy().into_owned()))
            .collect()
    }

    /// The page in the folder.
    pub fn page(&self) -> PathBuf {
        self.out.join("index.html")
    }

    /// As JSON: the folder, the page, the figures and the runs.
    pub fn to_json(&self) -> serde_json::Value {
        json!({
            "out": self.out.display().to_string(),
            "page": self.page().display().to_string(),
            "figures": self.figure_names(),
            "by_path_position": self.figures.by_path_position,
            "simulated": self.traces.iter().any(|t| t.simulated),
            "runs": self.traces.iter().map(|t| json!({
                "label": t.label, "file": t.file, "kind": t.kind, "rows": t.time_s.len(),
            })).collect::<Vec<_>>(),
        })
    }

    /// As text: one line per run, the figures and the page.
    pub fn text(&self) -> String {
        let mut out = String::new();
        for t in &self.traces {
            let _ = writeln!(
                out,
                "{}{}: {} ({} rows) from {}",
                if t.simulated { "SIMULATED " } else { "" },
                t.label,
                t.kind,
                t.time_s.len(),
                t.file
            );
        }
        let _ = writeln!(
            out,
            "figures against {}: {}",
            if self.figures.by_path_position {
                "position along the desired path"
            } else {
                "time (a log does not give its path position; --robot places a deflex run log)"
            },
            self.figure_names().join(", ")
        );
        let _ = writeln!(out, "page: {}", self.page().display());
        out
    }
}
