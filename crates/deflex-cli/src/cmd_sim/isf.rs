//! `deflex sim isf`: forming (or a plunge into a fixture) on the twin, open or closed loop
//! (SIMULATED), with its outputs, its MCAP recording (`run.mcap`), the `deflex plot` page of the
//! run (`plot/`) and, with `--view`, a live page paced at real time.
//!
//! The recording is written synchronously in the run's own loop (it loses nothing): in closed
//! loop the controller's stream (`deflex run`'s channels, with the twin's path error), in open
//! loop the twin's own stream (`deflex_sim::twin::twin_stream`: ground truth at every log row).

use super::{TwinArgs, load_config};
use crate::args::{bounded, print_json};
use crate::error::{CliError, CommandResult, UsageError};
use clap::{Args, ValueEnum};
use deflex_app::load::gcode_file::read_gcode;
use deflex_record::{McapSink, RecordError, RecordOptions, RecordStats};
use deflex_sim::twin::{RunWatch, SampleSink, TwinCellStream, twin_cell_session_info};
use deflex_sim::{ConeParams, PlungeParams, ProcessKind, PyramidParams, ToolPath};
use deflex_telemetry::{CycleSample, SessionInfo, broadcast};
use serde_json::json;
use std::io::BufWriter;
use std::path::{Path, PathBuf};
use std::sync::{Arc, Mutex};

/// The recording's file in the output folder.
pub const RECORDING: &str = "run.mcap";
/// The `deflex plot` page's folder in the output folder.
pub const PLOT_DIR: &str = "plot";

#[derive(Args)]
pub struct IsfArgs {
    /// Tool path: `cone` (the paper's helical cone), `cone-contour`, `pyramid`, `plunge` (1 mm
    /// into a stiff fixture, then 20 mm along x), or a G-code file.
    #[arg(long, default_value = "cone", value_parser = parse_path_choice)]
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
    pub correction: Correction,
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

/// `--correction`: the online correction off or on.
#[derive(Clone, Copy, Debug, PartialEq, Eq, ValueEnum)]
pub enum Correction {
    // Open loop (plain comments: doc comments would change `--help`).
    Off,
    // The correction controller with `--model`.
    On,
}

/// `--path`: a built-in tool path or a G-code file.
#[derive(Clone, Debug, PartialEq, Eq)]
pub enum PathChoice {
    /// The paper's helical cone.
    Cone,
    /// The cone in contours.
    ConeContour,
    /// The pyramid.
    Pyramid,
    /// 1 mm into a stiff fixture, then 20 mm along x.
    Plunge,
    /// A G-code file.
    Gcode(PathBuf),
}

/// `cone`, `cone-contour`, `pyramid`, `plunge`, or a G-code file.
fn parse_path_choice(text: &str) -> Result<PathChoice, std::convert::Infallible> {
    Ok(match text {
        "cone" => PathChoice::Cone,
        "cone-contour" => PathChoice::ConeContour,
        "pyramid" => PathChoice::Pyramid,
        "plunge" => PathChoice::Plunge,
        file => PathChoice::Gcode(PathBuf::from(file)),
    })
}

fn tool_path(args: &IsfArgs) -> Result<ToolPath, CliError> {
    let feed = match args.feed_mm_s {
        Some(f) => Some(bounded("--feed-mm-s", f, 0.1, 1000.0, "mm/s")?),
        None => None,
    };
    let path = match &args.path {
        PathChoice::Cone | PathChoice::ConeContour => {
            let mut p = ConeParams {
                helical: args.path == PathChoice::Cone,
                ..ConeParams::default()
            };
            if let Some(f) = feed {
                p.feed_mm_s = f;
            }
            ToolPath::cone(&p)?
        }
        PathChoice::Pyramid => {
            let mut p = PyramidParams::default();
            if let Some(f) = feed {
                p.feed_mm_s = f;
            }
            ToolPath::pyramid(&p)?
        }
        PathChoice::Plunge => {
            let mut p = PlungeParams::default();
            if let Some(f) = feed {
                p.traverse_feed_mm_s = f;
            }
            ToolPath::plunge(&p)?
        }
        PathChoice::Gcode(file) => {
            if feed.is_some() {
                return Err(UsageError::DoesNotApply {
                    flag: "--feed-mm-s",
                    applies: "applies to the built-in paths; a G-code file sets its own F",
                }
                .into());
            }
            read_gcode(file)?
        }
    };
    Ok(match args.length_mm {
        Some(l) => path.truncated(bounded("--length-mm", l, 1e-3, 1e6, "mm")?),
        None => path,
    })
}

pub fn isf(args: IsfArgs, json: bool) -> CommandResult {
    if args.correction == Correction::Off && args.model.is_some() {
        return Err(UsageError::DoesNotApply {
            flag: "--model",
            applies: "only used with --correction on",
        }
        .into());
    }
    let mut config = load_config(&args.twin)?;
    if args.path == PathChoice::Plunge {
        config.process.kind = ProcessKind::Fixture;
    }
    if let Some(k) = args.fixture_stiffness_n_m {
        if args.path != PathChoice::Plunge {
            return Err(UsageError::DoesNotApply {
                flag: "--fixture-stiffness-n-m",
                applies: "applies to --path plunge",
            }
            .into());
        }
        config.process.fixture_stiffness_n_m =
            bounded("--fixture-stiffness-n-m", k, 1e4, 1e9, "N/m")?;
    }
    let path = tool_path(&args)?;
    // Closed loop: the deflex correction controller in-process, in simulated time.
    let mut twin = match args.correction {
        Correction::On => Some(deflex_app::twin::twin_controller(
            &config,
            args.model.as_deref(),
        )?),
        Correction::Off => None,
    };
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
    let building =
        deflex_files::AtomicDir::create(&args.out).map_err(CliError::write(&args.out))?;
    let recording_path = building.path().join(RECORDING);
    let nominal = config.nominal_robot()?;
    let info = match &twin {
        Some(t) => t.session_info(config.robot_period_s()),
        None => twin_cell_session_info(&nominal, &config),
    };
    let recorder = Recording::create(&recording_path, &args.out.join(RECORDING), &info)?;
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
    let publisher = view.is_some().then_some(publisher);
    let stream = match twin.as_mut() {
        Some(t) => {
            t.set_sample_sink(Some(recorder.sink()));
            if let Some(p) = publisher {
                t.set_telemetry(Some(p));
            }
            None
        }
        None => {
            let stream = TwinCellStream::new(nominal).with_sink(recorder.sink());
            Some(match publisher {
                Some(p) => stream.with_publisher(p),
                None => stream,
            })
        }
    };
    let stop = view.is_some().then(deflex_runtime::rt::interrupt_flag);
    let mut watch = RunWatch::new(stream, speed, stop);
    let controller = twin
        .as_mut()
        .map(|t| t as &mut dyn deflex_sim::CorrectionController);
    let run = deflex_sim::run_program_observed(
        &config,
        path,
        None,
        args.seed,
        controller,
        Some(&mut watch),
        &mut |f| bar.set_position((f * 1000.0) as u64),
    );
    bar.finish_and_clear();
    // The streams end with the run.
    drop(watch);
    if let Some(t) = twin.as_mut() {
        t.set_telemetry(None);
        t.set_sample_sink(None);
    }
    let view_stats = view.map(|v| {
        let stats = v.stats();
        v.shutdown();
        stats
    });
    let run = run.map_err(|e| match e {
        e @ deflex_sim::SimError::Stopped { .. } => CliError::Stopped {
            out: args.out.clone(),
            source: Box::new(e),
        },
        e => e.into(),
    })?;
    let record_stats = recorder.finish(&args.out.join(RECORDING))?;
    let mut names = run_files(&run, building.path())?;
    names.push(RECORDING.into());
    if !args.no_plot {
        names.push(plot_page(building.path())?);
    }
    building.commit().map_err(CliError::write(&args.out))?;
    let files: Vec<PathBuf> = names.iter().map(|n| args.out.join(n)).collect();
    print_result(&RunResult {
        args: &args,
        config: &config,
        twin: twin.as_ref(),
        run: &run,
        name: &name,
        files: &files,
        record_stats: &record_stats,
        view_stats: view_stats.as_ref(),
        json,
    });
    Ok(())
}

/// What `deflex sim isf` ran and wrote, for its report.
struct RunResult<'a> {
    args: &'a IsfArgs,
    config: &'a deflex_sim::CellConfig,
    twin: Option<&'a deflex_sim::twin::TwinController>,
    run: &'a deflex_sim::FormingRun,
    name: &'a str,
    files: &'a [PathBuf],
    record_stats: &'a RecordStats,
    view_stats: Option<&'a deflex_view::ViewStats>,
    json: bool,
}

/// The run's report: its summary as JSON (with the recording and the files), or as text.
fn print_result(r: &RunResult<'_>) {
    let RunResult {
        args,
        config,
        twin,
        run,
        name,
        files,
        record_stats,
        view_stats,
        json,
    } = *r;
    let s = &run.summary;
    if json {
        let mut value: serde_json::Value =
            serde_json::from_str(&run.summary_json()).unwrap_or_default();
        if let Some(map) = value.as_object_mut() {
            map.insert("robot_spec".into(), json!(config.part.robot));
            map.insert(
                "mcap".into(),
                json!({
                    "path": args.out.join(RECORDING),
                    "source": info_key(twin.is_some()),
                    "cycles": record_stats.recorded,
                    "messages": record_stats.messages,
                    "bytes": record_stats.bytes,
                }),
            );
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
        println!(
            "SIMULATED {mode} run on the twin of the {}: {name} (seed {})",
            s.robot, args.seed
        );
        if let Some(t) = twin {
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
        if config.process.kind == ProcessKind::Fixture {
            println!(
                "  force: max |F| {:.0} N against a {:.0e} N/m fixture, deepest penetration {:.3} mm",
                s.max_force_norm_N, config.process.fixture_stiffness_n_m, s.final_part_depth_mm
            );
        } else {
            println!(
                "  force: max |F| {:.0} N, max Fz {:.0} N, max in-plane {:.0} N (Aerens level {:.0} N)",
                s.max_force_norm_N, s.max_fz_N, s.max_fxy_N, s.aerens_steady_fz_N
            );
            println!(
                "  part depth {:.2} mm of {:.2} mm programmed",
                s.final_part_depth_mm, s.target_depth_mm
            );
        }
        println!("  wrote {} files to {}", files.len(), args.out.display());
        println!(
            "  recording: {} (MCAP, {}: {} samples, {:.1} MB)",
            args.out.join(RECORDING).display(),
            if twin.is_some() {
                "the controller's stream with the twin's path error"
            } else {
                "the twin's own stream, ground truth"
            },
            record_stats.recorded,
            record_stats.bytes as f64 / 1e6
        );
        if !args.no_plot {
            println!(
                "  plot page: {}",
                args.out.join(PLOT_DIR).join("index.html").display()
            );
        }
        if let Some(v) = view_stats {
            println!(
                "  live view: {} (the page keeps the run's data after this process ends)",
                crate::live::view_line(v)
            );
        }
    }
}

/// The key of the recorded stream's source.
fn info_key(closed_loop: bool) -> &'static str {
    if closed_loop {
        deflex_telemetry::Source::Twin.key()
    } else {
        deflex_telemetry::Source::TwinCell.key()
    }
}

/// `log.csv`, `summary.json`, `profile.csv` and the run's PNG plots
/// (`deflex_app::report::forming_run`) written into the folder being built; returns their names.
fn run_files(run: &deflex_sim::FormingRun, folder: &Path) -> Result<Vec<String>, CliError> {
    let mut names = Vec::new();
    for (name, text) in [
        ("log.csv", run.log.to_csv()),
        ("summary.json", run.summary_json()),
        ("profile.csv", run.profile_csv()),
    ] {
        let path = folder.join(name);
        deflex_files::write_atomic(&path, text).map_err(CliError::write(&path))?;
        names.push(name.to_string());
    }
    for plot in deflex_app::report::forming_run::forming_plots(run, folder)? {
        if let Some(name) = plot.file_name() {
            names.push(name.to_string_lossy().into_owned());
        }
    }
    Ok(names)
}

/// The `deflex plot` page of the run, from its `log.csv`, into `plot/` of the folder being
/// built; returns the page's name in the folder.
fn plot_page(folder: &Path) -> Result<String, CliError> {
    let trace = deflex_record::trace::read_run_log(&folder.join("log.csv"), "this run", None)?;
    let dir = folder.join(PLOT_DIR);
    std::fs::create_dir_all(&dir).map_err(CliError::write(&dir))?;
    deflex_app::report::write_run_figures(&dir, &[trace])?;
    Ok(format!("{PLOT_DIR}/index.html"))
}

type SinkState = (
    Option<McapSink<BufWriter<std::fs::File>>>,
    Option<RecordError>,
);

/// The run's MCAP recording, written synchronously by the run's loop through a sink closure;
/// the first write error stops it and is reported at the end.
struct Recording {
    state: Arc<Mutex<SinkState>>,
}

impl Recording {
    /// A recording into `path` (in the folder being built), named `shown` in errors.
    fn create(path: &Path, shown: &Path, info: &SessionInfo) -> Result<Recording, CliError> {
        let file = std::fs::File::create(path).map_err(CliError::write(shown))?;
        let sink = McapSink::new(
            BufWriter::new(file),
            shown.display().to_string(),
            info,
            RecordOptions::default(),
        )?;
        Ok(Recording {
            state: Arc::new(Mutex::new((Some(sink), None))),
        })
    }

    /// The closure the run calls with every sample.
    fn sink(&self) -> SampleSink {
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

    /// Closes the file; the first error of the run, if any.
    fn finish(self, shown: &Path) -> Result<RecordStats, CliError> {
        let mut guard = self.state.lock().unwrap_or_else(|p| p.into_inner());
        if let Some(e) = guard.1.take() {
            return Err(e.into());
        }
        // `finish` takes the recording: the sink is there unless a write panicked with it.
        let Some(sink) = guard.0.take() else {
            return Err(CliError::write(shown)(std::io::Error::other(
                "the recording was lost",
            )));
        };
        let (writer, stats) = sink.finish()?;
        let file = writer
            .into_inner()
            .map_err(|e| CliError::write(shown)(e.into_error()))?;
        file.sync_all().map_err(CliError::write(shown))?;
        Ok(stats)
    }
}
