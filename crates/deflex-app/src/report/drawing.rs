//! Leave to draw: a workflow that writes a report or a figure first asks [`require`] for a
//! [`Drawing`], and draws only through it. With the `report` feature `require` always gives
//! one; without it `require` refuses (the error names what was asked for and the feature) and
//! `Drawing` has no value at all, so no drawing step can be reached in such a build: a workflow
//! asked for a report refuses, before it computes or writes anything, and never skips the
//! report silently.
//!
//! The methods of [`Drawing`] are every report and figure a workflow writes, one per thing:
//! with the feature they call the pages ([`crate::report`]'s drawing modules), without it they
//! do not exist in any reachable form.

use crate::error::{Error, Result};
#[cfg(feature = "report")]
use crate::report::PageError;
use crate::report::RunFigures;
use deflex_calibrate::geometry::campaign::Campaign;
use deflex_calibrate::geometry::fit::FitResult;
use deflex_record::trace::RunTrace;
use deflex_sim::FormingRun;
use std::path::{Path, PathBuf};

/// Leave to draw reports and figures: given by [`require`] in a build with the `report` feature
/// (a value of no size), and never in a build without it (a type with no value).
#[cfg(feature = "report")]
#[derive(Clone, Copy, Debug)]
pub struct Drawing(());

/// Leave to draw reports and figures: given by [`require`] in a build with the `report` feature
/// (a value of no size), and never in a build without it (a type with no value).
#[cfg(not(feature = "report"))]
#[derive(Clone, Copy, Debug)]
pub enum Drawing {}

/// Leave to draw `what` (a report or figure as the user asked for it, e.g. "the calibration
/// report (`deflex calibrate --report`; Python: `StiffnessCalibration.save(report=…)`)"), or, in
/// a build without the `report` feature, [`Error::ReportsNotBuilt`] naming it. A workflow asks
/// first, before it computes or writes anything.
// `what` names the refusal, which a build with reports never makes.
#[cfg_attr(feature = "report", allow(unused_variables))]
pub fn require(what: &'static str) -> Result<Drawing> {
    #[cfg(feature = "report")]
    return Ok(Drawing(()));
    #[cfg(not(feature = "report"))]
    Err(Error::ReportsNotBuilt { what })
}

#[cfg(feature = "report")]
impl Drawing {
    /// The calibration report (`calibration.html`, plots, CSV tables) of `cal`, whose model was
    /// written to `output_name`, into the existing folder `dir`.
    pub(crate) fn calibration_report(
        self,
        cal: &crate::calibrate::StiffnessCalibration,
        dir: &Path,
        output_name: &str,
    ) -> Result<()> {
        use crate::report::calibration_report::{
            CalibrationReport, CouplingSection, write_calibration_report,
        };
        let report = CalibrationReport {
            start_name: &cal.start.name,
            data_name: &cal.data_name,
            output_name,
            calibration: &cal.calibration,
            predicted: &cal.predicted,
            steps: &cal.steps,
            stop_reason: cal.stop_reason.as_deref(),
            rows: &cal.rows,
            warnings: &cal.data_warnings,
            data_notes: &cal.notes,
            couplings: cal.couplings.as_ref().map(|fit| CouplingSection {
                diagonal: &cal.diagonal,
                fit,
            }),
        };
        write_calibration_report(dir, &report)?;
        Ok(())
    }

    /// The validation's plots and `validation.html` into the folder `dir`, replaced whole.
    pub(crate) fn validation_report(
        self,
        validation: &deflex_calibrate::stiffness::validation::Validation,
        dir: &Path,
    ) -> Result<Vec<PathBuf>> {
        Ok(crate::report::validation_report::write_validation_report(
            validation, dir,
        )?)
    }

    /// The elasto-geometric calibration's report folder (text, JSON, CSV, plots, page), whole.
    pub(crate) fn geometry_report(
        self,
        result: &FitResult,
        campaign: &Campaign,
        summary: &str,
        summary_json: &serde_json::Value,
        dir: &Path,
    ) -> Result<Vec<PathBuf>> {
        Ok(crate::report::absolute_report::write_report(
            result,
            campaign,
            summary,
            summary_json,
            dir,
        )?)
    }

    /// A forming run's `log.csv`, `summary.json`, `profile.csv` and plots into the existing
    /// folder `dir`; their names.
    pub(crate) fn forming_run_files(self, run: &FormingRun, dir: &Path) -> Result<Vec<String>> {
        Ok(crate::report::forming_run::write_run_files(run, dir)?)
    }

    /// A forming run's files and plots into the folder `dir`, whole; the files.
    pub(crate) fn forming_run_folder(self, run: &FormingRun, dir: &Path) -> Result<Vec<PathBuf>> {
        crate::report::forming_run::write_forming_run(run, dir).map_err(|source| {
            Error::Report(PageError {
                report: "forming run",
                source,
            })
        })
    }

    /// The figures and page of one run or two overlaid (`deflex plot`) into the existing
    /// folder `dir`.
    pub(crate) fn run_figures(self, dir: &Path, traces: &[RunTrace]) -> Result<RunFigures> {
        Ok(crate::report::write_run_figures(dir, traces)?)
    }

    /// The sensitivity sweep's heatmap, written to `path`.
    pub(crate) fn sensitivity_heatmap(
        self,
        result: &crate::study::sensitivity::SensitivityResult,
        path: &Path,
    ) -> Result<()> {
        Ok(crate::report::study::figures::sensitivity_heatmap(
            result, path,
        )?)
    }

    /// The study's folder (`deflex demo`), whole.
    pub(crate) fn study(self, study: &crate::study::Study, out: &Path) -> Result<()> {
        Ok(crate::report::study::write_study(study, out)?)
    }

    /// The deflection map's heatmaps into the existing folder `out`; the files.
    pub(crate) fn map_plots(
        self,
        out: &Path,
        nodes: &[crate::robot::map::MapNode],
        robot_name: &str,
        wrench: &[f64; 6],
    ) -> Result<Vec<PathBuf>> {
        Ok(crate::robot::map::map_plots(
            out, nodes, robot_name, wrench,
        )?)
    }
}

/// Without the `report` feature there is no [`Drawing`]: each method is the same as with it and
/// cannot be called.
#[cfg(not(feature = "report"))]
#[allow(missing_docs)]
impl Drawing {
    pub(crate) fn calibration_report(
        self,
        _cal: &crate::calibrate::StiffnessCalibration,
        _dir: &Path,
        _output_name: &str,
    ) -> Result<()> {
        match self {}
    }

    pub(crate) fn validation_report(
        self,
        _validation: &deflex_calibrate::stiffness::validation::Validation,
        _dir: &Path,
    ) -> Result<Vec<PathBuf>> {
        match self {}
    }

    pub(crate) fn geometry_report(
        self,
        _result: &FitResult,
        _campaign: &Campaign,
        _summary: &str,
        _summary_json: &serde_json::Value,
        _dir: &Path,
    ) -> Result<Vec<PathBuf>> {
        match self {}
    }

    pub(crate) fn forming_run_files(self, _run: &FormingRun, _dir: &Path) -> Result<Vec<String>> {
        match self {}
    }

    pub(crate) fn forming_run_folder(self, _run: &FormingRun, _dir: &Path) -> Result<Vec<PathBuf>> {
        match self {}
    }

    pub(crate) fn run_figures(self, _dir: &Path, _traces: &[RunTrace]) -> Result<RunFigures> {
        match self {}
    }

    pub(crate) fn sensitivity_heatmap(
        self,
        _result: &crate::study::sensitivity::SensitivityResult,
        _path: &Path,
    ) -> Result<()> {
        match self {}
    }

    pub(crate) fn study(self, _study: &crate::study::Study, _out: &Path) -> Result<()> {
        match self {}
    }

    pub(crate) fn map_plots(
        self,
        _out: &Path,
        _nodes: &[crate::robot::map::MapNode],
        _robot_name: &str,
        _wrench: &[f64; 6],
    ) -> Result<Vec<PathBuf>> {
        match self {}
    }
}
