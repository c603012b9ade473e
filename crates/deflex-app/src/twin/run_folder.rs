//! The output folder of a forming run (`deflex sim isf --out`, Python's `TwinRun.save`): built
//! aside and swapped in whole at the end, so that a failed or stopped run leaves the folder as it
//! was. It holds `log.csv`, `summary.json`, `profile.csv` and the run's plots
//! (`crate::report::forming_run`), the files the front end's outlets wrote into it while the run
//! went (the MCAP recording a front end attaches: [`RunFolder::record`], `run.mcap`), and the
//! `deflex plot` page of the run (`plot/`). It holds plots: a build without the `report` feature
//! refuses it ([`crate::Error::ReportsNotBuilt`]), before the run.

use crate::error::{Error, Result};
use crate::report::Drawing;
use crate::twin::TwinRun;
use deflex_record::{McapSink, RecordError, RecordOptions, RecordStats};
use deflex_sim::twin::SampleSink;
use deflex_telemetry::SessionInfo;
use std::fmt::Write as _;
use std::io::BufWriter;
use std::path::{Path, PathBuf};
use std::sync::{Arc, Mutex};

/// The `deflex plot` page's folder in the output folder.
pub const PLOT_DIR: &str = "plot";

/// The recording's file in the output folder ([`RunFolder::record`]).
pub const RECORDING: &str = "run.mcap";

/// What a run's folder is, in the words of [`crate::Error::ReportsNotBuilt`].
const RUN_FOLDER: &str =
    "a forming run's folder with its plots (`deflex sim isf --out`; Python: `TwinRun.save`)";

/// A run's output folder while it is being built.
pub struct RunFolder {
    building: deflex_files::AtomicDir,
    out: PathBuf,
    drawing: Drawing,
}

/// A run's output folder once written.
#[derive(Clone, Debug)]
pub struct WrittenRun {
    /// The folder.
    pub out: PathBuf,
    /// Every file written, in the folder.
    pub files: Vec<PathBuf>,
    /// The `deflex plot` page of the run, when it was written.
    pub plot_page: Option<PathBuf>,
}

impl RunFolder {
    /// Start building the folder `out` aside (an existing `out` is replaced only by
    /// [`RunFolder::finish`]). Needs the `report` feature (the folder holds the run's plots):
    /// refused without it, before the run.
    pub fn create(out: &Path) -> Result<RunFolder> {
        let drawing = crate::report::require(RUN_FOLDER)?;
        let building = deflex_files::AtomicDir::create(out).map_err(Error::io_on(out))?;
        Ok(RunFolder {
            building,
            out: out.to_path_buf(),
            drawing,
        })
    }

    /// The folder being built, where an outlet writes its files during the run.
    pub fn path(&self) -> &Path {
        self.building.path()
    }

    /// Start the run's MCAP recording, [`RECORDING`] in the folder being built, of the stream
    /// described by `info` (a front end attaches its [`RunRecording::sink`] to the run); errors
    /// name the file as it will be once the folder is swapped in.
    pub fn record(&self, info: &SessionInfo) -> Result<RunRecording> {
        let shown = self.out.join(RECORDING);
        let file =
            std::fs::File::create(self.path().join(RECORDING)).map_err(Error::io_on(&shown))?;
        let sink = McapSink::new(
            BufWriter::new(file),
            shown.display().to_string(),
            info,
            RecordOptions::default(),
        )?;
        Ok(RunRecording {
            state: Arc::new(Mutex::new((Some(sink), None))),
            shown,
        })
    }

    /// Write the run's files (and its `deflex plot` page with `plot_page`) into the folder and
    /// swap it in; `attached` names the files the outlets wrote into it, listed after the run's.
    pub fn finish(self, run: &TwinRun, attached: &[&str], plot_page: bool) -> Result<WrittenRun> {
        let folder = self.building.path();
        let mut names = self.drawing.forming_run_files(&run.run, folder)?;
        names.extend(attached.iter().map(|n| n.to_string()));
        if plot_page {
            names.push(write_plot_page(self.drawing, folder)?);
        }
        self.building.commit().map_err(Error::io_on(&self.out))?;
        Ok(WrittenRun {
            files: names.iter().map(|n| self.out.join(n)).collect(),
            plot_page: plot_page.then(|| self.out.join(PLOT_DIR).join("index.html")),
            out: self.out,
        })
    }
}

/// The recording's sink and the first error it met.
type SinkState = (
    Option<McapSink<BufWriter<std::fs::File>>>,
    Option<RecordError>,
);

/// A forming run's MCAP recording ([`RunFolder::record`]), written synchronously by the run's
/// loop through a sink closure (it loses nothing); the first write error stops it and is
/// reported at the end ([`RunRecording::finish`]).
pub struct RunRecording {
    state: Arc<Mutex<SinkState>>,
    shown: PathBuf,
}

impl RunRecording {
    /// The closure the run calls with every sample (`crate::twin::Outlets::sample_sink`).
    pub fn sink(&self) -> SampleSink {
        let state = self.state.clone();
        Box::new(move |s| {
            let mut guard = state.lock().unwrap_or_else(|p| p.into_inner());
            let (sink, failed) = &mut *guard;
            if failed.is_none()
                && let Some(sink) = sink.as_mut()
                && let Err(e) = sink.write(s)
            {
                *failed = Some(e);
            }
        })
    }

    /// Closes the file, synced; the first error of the run, if any.
    pub fn finish(self) -> Result<RecordStats> {
        let mut guard = self.state.lock().unwrap_or_else(|p| p.into_inner());
        if let Some(e) = guard.1.take() {
            return Err(e.into());
        }
        let io = Error::io_on(&self.shown);
        // `finish` takes the recording: the sink is there unless a write panicked with it.
        let Some(sink) = guard.0.take() else {
            return Err(io(std::io::Error::other("the recording was lost")));
        };
        let (writer, stats) = sink.finish()?;
        let file = writer.into_inner().map_err(|e| io(e.into_error()))?;
        file.sync_all().map_err(io)?;
        Ok(stats)
    }
}

impl WrittenRun {
    /// The line naming the `deflex plot` page, when it was written.
    pub fn plot_page_line(&self) -> String {
        let mut out = String::new();
        if let Some(page) = &self.plot_page {
            let _ = writeln!(out, "  plot page: {}", page.display());
        }
        out
    }
}

/// The `deflex plot` page of the run, from its `log.csv`, into `plot/` of the folder being
/// built; returns the page's name in the folder.
fn write_plot_page(drawing: Drawing, folder: &Path) -> Result<String> {
    let trace = deflex_record::trace::read_run_log(&folder.join("log.csv"), "this run", None)?;
    let dir = folder.join(PLOT_DIR);
    std::fs::create_dir_all(&dir).map_err(Error::io_on(&dir))?;
    drawing.run_figures(&dir, &[trace])?;
    Ok(format!("{PLOT_DIR}/index.html"))
}

/// The run's outputs (`log.csv`, `summary.json`, `profile.csv`, plots), written whole into
/// `dir` (Python's `TwinRun.save`). Needs the `report` feature: refused without it, nothing
/// written (the run's log, summary and profile are [`TwinRun::run`]'s, and
/// [`crate::twin::summary_json`]).
pub fn write_outputs(run: &TwinRun, dir: &Path) -> Result<Vec<PathBuf>> {
    crate::report::require(RUN_FOLDER)?.forming_run_folder(&run.run, dir)
}
