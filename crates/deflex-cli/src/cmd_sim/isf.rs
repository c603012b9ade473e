//! `deflex sim isf`: forming (or a plunge into a fixture) on the twin, open or closed loop
//! (SIMULATED), with its outputs, its MCAP recording (`run.mcap`), the `deflex plot` page of the
//! run (`plot/`) and, with `--view`, a live page paced at real time.
//!
//! The recording (`deflex_app::twin::RunFolder::record`) is written synchronously in the run's
//! own loop (it loses nothing): in closed loop the controller's stream (`deflex run`'s channels,
//! with the twin's path error), in open loop the twin's own stream (ground truth at every log
//! row).

use super::TwinArgs;
use crate::args::{bounded, print_json};
use crate::error::{CliError, CommandResult};
use clap::Args;
use deflex_app::OptionNames;
use deflex_app::twin::form::{
    CorrectionModel, FIXTURE_STIFFNESS_RANGE_N_M, FormOptions, FormingSetup, Outlets,
};
use deflex_app::twin::path::{FEED_RANGE_MM_S, LENGTH_RANGE_MM};
use deflex_app::twin::{
    FormCorrection, PathChoice, RECORDING, RunFolder, TwinRun, WrittenRun, check_correction,
};
use deflex_record::RecordStats;
use deflex_telemetry::{CycleSample, broadcast};
use serde_json::json;
use std::path::PathBuf;
use std::str::FromStr;
use std::sync::Arc;

#[derive(Args)]
pub struct IsfArgs {
    /// Tool path: `cone` (the paper's helical cone), `cone-contour`, `pyramid`, `plunge` (1 mm
    /// into a stiff fixture, then 20 mm along x), or a G-code file.
    #[arg(long, default_value = "cone", value_parser = PathChoice::from_str)]
    pub path: PathChoice,
    /// Output folder (log.csv, summary.json, plots), swapped in whole at the end.
    #[arg(long)]
    pub out: PathBuf,
    /// Random seed (sensor and tracker noise).
    #[arg(long, default_value_t = 1)]
    pub seed: u64,
    #[command(flatten)]
    pub twin: TwinArgs,
    /// Only the first part of the path (mm of travel, within (0, 10⁶]).
    #[arg(long)]
    pub length_mm: Option<f64>,
    /// Feed rate for the built-in paths (mm/s, 0.1–1000).
    #[arg(long)]
    pub feed_mm_s: Option<f64>,
    /// Contact stiffness of the fixture for `--path plunge` (N/m, 10⁴–10⁹; default the twin's
    /// `[cell.process] fixture_stiffness_n_m`, 10⁷).
    #[arg(long)]
    pub fixture_stiffness_n_m: Option<f64>,
    /// Online correction: `off` (default) or `on` (needs --model).
    #[arg(long, value_enum, default_value = "off", hide_possible_values = true)]
    pub correction: FormCorrection,
    /// Identified model used by the correction controller (robot TOML).
    #[arg(long)]
    pub model: Option<PathBuf>,
    /// Do not write the `deflex plot` page of the run (`plot/` in the output folder).
    #[arg(long)]
    pub no_plot: bool,
    /// Serve the live view on ADDR (127.0.0.1:8767 when no address is given) and run at real
    /// time (× `--speed`) so it can be watched; Ctrl-C stops the run and writes nothing. Closed
    /// loop: the controller's page (with the path error); open loop: the twin's own page.
    #[arg(long, value_name = "ADDR", num_args = 0..=1, default_missing_value = crate::live::SIM_VIEW)]
    pub view: Option<String>,
    /// With `--view`: simulated seconds per second of wall time (0.1–1000).
    #[arg(long, requires = "view")]
    pub speed: Option<f64>,
}

/// The run's options, every numeric flag checked in its unit.
fn form_options(args: &IsfArgs) -> Result<FormOptions, CliError> {
    let fixture_stiffness_n_m = match args.fixture_stiffness_n_m {
        Some(k) => {
            let (lo, hi) = FIXTURE_STIFFNESS_RANGE_N_M;
            Some(bounded("--fixture-stiffness-n-m", k, lo, hi, "N/m")?)
        }
        None => None,
    };
    let feed_mm_s = match args.feed_mm_s {
        Some(f) => Some(bounded(
            "--feed-mm-s",
            f,
            FEED_RANGE_MM_S.0,
            FEED_RANGE_MM_S.1,
            "mm/s",
        )?),
        None => None,
    };
    let length_mm = match args.length_mm {
        Some(l) => Some(bounded(
            "--length-mm",
            l,
            LENGTH_RANGE_MM.0,
            LENGTH_RANGE_MM.1,
            "mm",
        )?),
        None => None,
    };
    Ok(FormOptions {
        robot: args.twin.robot.clone(),
        config: args.twin.config.clone(),
        path: args.path.clone(),
        seed: args.seed,
        length_mm,
        feed_mm_s,
        fixture_stiffness_n_m,
        correction: args.correction,
        model: args.model.clone().map(CorrectionModel::File),
        names: OptionNames::Cli,
    })
}

pub fn isf(args: IsfArgs, json: bool) -> CommandResult {
    check_correction(args.correction, args.model.is_some(), OptionNames::Cli)?;
    let options = form_options(&args)?;
    let mut setup = FormingSetup::prepare(&options)?;
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
    let speed = match (&args.view, args.speed) {
        (_, Some(v)) => Some(bounded("--speed", v, 0.1, 1000.0, "")?),
        (Some(_), None) => Some(1.0),
        (None, None) => None,
    };
    let view_addr = args
        .view
        .as_deref()
        .map(crate::live::view_address)
        .transpose()?;
    // Built aside, swapped in whole at the end: a failed or stopped run leaves `--out` whole.
    let folder = RunFolder::create(&args.out)?;
    let info = setup.session_info()?;
    let recording = folder.record(&info)?;
    let (publisher, ring) = broadcast::<CycleSample>(1 << 14);
    let view = match view_addr {
        Some(addr) => Some(crate::live::start_view(
            addr,
            ring,
            Arc::new(info),
            None,
            json,
        )?),
        None => None,
    };
    let closed_loop = setup.closed_loop();
    let run = setup.run(Outlets {
        sample_sink: Some(recording.sink()),
        publisher: view.is_some().then_some(publisher),
        speed,
        stop: view.is_some().then(deflex_runtime::rt::interrupt_flag),
        progress: Some(&mut |f| bar.set_position((f * 1000.0) as u64)),
    });
    bar.finish_and_clear();
    let view_stats = view.map(|v| {
        let stats = v.stats();
        v.shutdown();
        stats
    });
    let run = run.map_err(|e| match e {
        deflex_app::Error::Sim(e @ deflex_sim::SimError::Stopped { .. }) => CliError::Stopped {
            out: args.out.clone(),
            source: Box::new(e),
        },
        e => e.into(),
    })?;
    let record_stats = recording.finish()?;
    let written = folder.finish(&run, &[RECORDING], !args.no_plot)?;
    let report = RunReport {
        args: &args,
        run: &run,
        written: &written,
        closed_loop,
        record_stats: &record_stats,
        view_stats: view_stats.as_ref(),
    };
    if json {
        print_json(&report.json()?);
    } else {
        print!("{}", report.text());
    }
    Ok(())
}

/// What `deflex sim isf` ran, wrote and attached, for its report.
struct RunReport<'a> {
    args: &'a IsfArgs,
    run: &'a TwinRun,
    written: &'a WrittenRun,
    closed_loop: bool,
    record_stats: &'a RecordStats,
    view_stats: Option<&'a deflex_view::ViewStats>,
}

impl RunReport<'_> {
    /// The run's report as JSON, with the recording.
    fn json(&self) -> Result<serde_json::Value, CliError> {
        let mut value = self.run.report_json(self.written)?;
        if let Some(map) = value.as_object_mut() {
            map.insert(
                "mcap".into(),
                json!({
                    "path": self.args.out.join(RECORDING),
                    "source": info_key(self.closed_loop),
                    "cycles": self.record_stats.recorded,
                    "messages": self.record_stats.messages,
                    "bytes": self.record_stats.bytes,
                }),
            );
        }
        Ok(value)
    }

    /// The run's report as text: the run's, the recording's line, the plot page's and the live
    /// view's.
    fn text(&self) -> String {
        let recording = format!(
            "  recording: {} (MCAP, {}: {} samples, {:.1} MB)\n",
            self.args.out.join(RECORDING).display(),
            if self.closed_loop {
                "the controller's stream with the twin's path error"
            } else {
                "the twin's own stream, ground truth"
            },
            self.record_stats.recorded,
            self.record_stats.bytes as f64 / 1e6
        );
        let mut text = self.run.report_text(self.written) + &recording;
        text += &self.written.plot_page_line();
        if let Some(v) = self.view_stats {
            text += &format!(
                "  live view: {} (the page keeps the run's data after this process ends)\n",
                crate::live::view_line(v)
            );
        }
        text
    }
}

/// The key of the recorded stream's source.
fn info_key(closed_loop: bool) -> &'static str {
    if closed_loop {
        deflex_telemetry::StreamSource::Twin.key()
    } else {
        deflex_telemetry::StreamSource::TwinCell.key()
    }
}
