//! The output folder of a forming run (`deflex sim isf --out`, Python's `TwinRun.save`): built
//! aside and swapped in whole at the end, so that a failed or stopped run leaves the folder as it
//! was. It holds `log.csv`, `summary.json`, `profile.csv` and the run's plots
//! (`crate::report::forming_run`), the files the front end's outlets wrote into it while the run
//! went (a recording), and the `deflex plot` page of the run (`plot/`). It holds plots: a build
//! without the `report` feature refuses it ([`crate::Error::ReportsNotBuilt`]), before the run.

use crate::error::{Error, Result};
use crate::report::Drawing;
use crate::twin::TwinRun;
use std::fmt::Write as _;
use std::path::{Path, PathBuf};

/// The `deflex plot` page's folder in the output folder.
pub const PLOT_DIR: &str = "plot";

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

/// An error writing `path`.
fn io(path: &Path) -> impl FnOnce(std::io::Error) -> Error {
    let path = path.display().to_string();
    move |source| Error::Io { path, source }
}

impl RunFolder {
    /// Start building the folder `out` aside (an existing `out` is replaced only by
    /// [`RunFolder::finish`]). Needs the `report` feature (the folder holds the run's plots):
    /// refused without it, before the run.
    pub fn create(out: &Path) -> Result<RunFolder> {
        let drawing = crate::report::require(RUN_FOLDER)?;
        let building = deflex_files::AtomicDir::create(out).map_err(io(out))?;
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

    /// Write the run's files (and its `deflex plot` page with `plot_page`) into the folder and
    /// swap it in; `attached` names the files the outlets wrote into it, listed after the run's.
    pub fn finish(self, run: &TwinRun, attached: &[&str], plot_page: bool) -> Result<WrittenRun> {
        let folder = self.building.path();
        let mut names = self.drawing.forming_run_files(&run.run, folder)?;
        names.extend(attached.iter().map(|n| n.to_string()));
        if plot_page {
            names.push(write_plot_page(self.drawing, folder)?);
        }
        self.building.commit().map_err(io(&self.out))?;
        Ok(WrittenRun {
            files: names.iter().map(|n| self.out.join(n)).collect(),
            plot_page: plot_page.then(|| self.out.join(PLOT_DIR).join("index.html")),
            out: self.out,
        })
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
    std::fs::create_dir_all(&dir).map_err(io(&dir))?;
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
