//! A forming run on the twin (SIMULATED), open or closed loop: `deflex sim isf` and Python's
//! `deflex.sim.form`. [`FormingSetup::prepare`] reads the cell, builds the tool path and the
//! correction controller; [`FormingSetup::run`] runs it with the outlets a front end attaches
//! (a recording's sink, a live view's stream, real-time pacing, a stop flag, a progress bar).

use crate::OptionNames;
use crate::error::{Error, Result, bounded};
use crate::twin::path::{PathChoice, tool_path};
use crate::twin::{TwinSetupError, cell_config, load_model};
use deflex_model::Robot;
use deflex_sim::twin::{
    RunWatch, SampleSink, TwinCellStream, TwinController, controller_config_for,
    twin_cell_session_info,
};
use deflex_sim::{CellConfig, CorrectionController, CycleObserver, FormingRun, ProcessKind};
use deflex_telemetry::{CycleSample, Publisher, SessionInfo};
use std::fmt::Write as _;
use std::path::PathBuf;
use std::sync::atomic::AtomicBool;

/// The online correction of a forming run: off (open loop) or on (the deflex correction
/// controller in the loop, with the identified model).
// Plain comments on the variants: doc comments would become clap's help text and change the
// CLI's `--help`.
#[allow(missing_docs)]
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
#[cfg_attr(feature = "clap", derive(clap::ValueEnum))]
pub enum FormCorrection {
    // Open loop.
    #[default]
    Off,
    // The correction controller with the identified model.
    On,
}

impl FormCorrection {
    /// The name the CLI and Python use.
    pub fn name(self) -> &'static str {
        match self {
            FormCorrection::Off => "off",
            FormCorrection::On => "on",
        }
    }
}

impl std::str::FromStr for FormCorrection {
    type Err = Error;

    /// `off` or `on` (Python's `correction=`).
    fn from_str(text: &str) -> Result<FormCorrection> {
        match text {
            "off" => Ok(FormCorrection::Off),
            "on" => Ok(FormCorrection::On),
            other => Err(Error::invalid(
                "correction",
                format!("expected \"on\" or \"off\", got \"{other}\""),
            )),
        }
    }
}

/// Options of a forming run that do not go together. A message names the options in the words
/// of the front end ([`FormConflict::describe`]); the application's error holds both
/// ([`FormConflict::named`]).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum FormConflict {
    /// A correction model given with the correction off.
    ModelWithoutCorrection,
    /// A fixture stiffness for a path that does not plunge into the fixture.
    FixtureStiffnessWithoutPlunge,
    /// A feed for a G-code file, which sets its own.
    FeedWithGcode,
}

impl FormConflict {
    /// The conflict in the words of `names`: `--model: only used with --correction on`,
    /// `model: only used with correction="on"`.
    pub fn describe(self, names: OptionNames) -> String {
        match self {
            FormConflict::ModelWithoutCorrection => format!(
                "{}: only used with {}",
                names.name("model"),
                names.give_text("correction", FormCorrection::On.name())
            ),
            FormConflict::FixtureStiffnessWithoutPlunge => format!(
                "{}: applies to {}",
                names.name("fixture_stiffness_n_m"),
                names.give_text("path", "plunge")
            ),
            FormConflict::FeedWithGcode => format!(
                "{}: applies to the built-in paths; a G-code file sets its own F",
                names.name("feed_m_s")
            ),
        }
    }

    /// The conflict as the application's error, named in the words of `names`.
    pub fn named(self, names: OptionNames) -> Error {
        Error::FormConflict {
            conflict: self,
            names,
        }
    }
}

/// Refuse a correction model given with the correction off (the front ends ask first, before
/// reading anything), naming the options in the words of `names`.
pub fn check_correction(
    correction: FormCorrection,
    has_model: bool,
    names: OptionNames,
) -> Result<()> {
    if correction == FormCorrection::Off && has_model {
        Err(FormConflict::ModelWithoutCorrection.named(names))
    } else {
        Ok(())
    }
}

/// The identified model the correction controller uses: never the twin's plant.
#[derive(Clone, Debug)]
pub enum CorrectionModel {
    /// A model in memory.
    Robot(Box<Robot>),
    /// A robot file (or a built-in name), read when the run is set up.
    File(PathBuf),
}

/// Smallest and largest contact stiffness of the plunge's fixture (N/m).
pub const FIXTURE_STIFFNESS_RANGE_N_M: (f64, f64) = (1e4, 1e9);

/// Options of a forming run. The path's feed and length are in mm, the unit of the tool-path
/// generator ([`tool_path`]).
#[derive(Clone, Debug)]
pub struct FormOptions {
    /// The robot the twin plays (built-in name or robot file); default the twin file's, else
    /// the TX200.
    pub robot: Option<String>,
    /// Twin settings (`[cell]` TOML) over the robot's cell.
    pub config: Option<PathBuf>,
    /// The tool path.
    pub path: PathChoice,
    /// Random seed (sensor and tracker noise).
    pub seed: u64,
    /// Only the first part of the path (mm of travel).
    pub length_mm: Option<f64>,
    /// Feed of the built-in paths (mm/s).
    pub feed_mm_s: Option<f64>,
    /// Contact stiffness of the fixture for [`PathChoice::Plunge`] (N/m); default the cell's.
    pub fixture_stiffness_n_m: Option<f64>,
    /// The online correction.
    pub correction: FormCorrection,
    /// The identified model of the correction (needed with [`FormCorrection::On`]).
    pub model: Option<CorrectionModel>,
    /// The front end that asks, for the option names in its refusals.
    pub names: OptionNames,
}

impl Default for FormOptions {
    /// The open-loop run of the paper's cone on the TX200's cell, seed 0, refusals in the
    /// command line's words.
    fn default() -> FormOptions {
        FormOptions {
            robot: None,
            config: None,
            path: PathChoice::default(),
            seed: 0,
            length_mm: None,
            feed_mm_s: None,
            fixture_stiffness_n_m: None,
            correction: FormCorrection::default(),
            model: None,
            names: OptionNames::Cli,
        }
    }
}

/// What a front end attaches to a run: every one optional.
#[derive(Default)]
pub struct Outlets<'a> {
    /// Every sample of the run's stream, synchronously, losing none (a recording): in closed
    /// loop the controller's stream (with the twin's path error), in open loop the twin's own
    /// (ground truth at every log row).
    pub sample_sink: Option<SampleSink>,
    /// The same stream for a live view (it may lose samples, never blocks the run).
    pub publisher: Option<Publisher<CycleSample>>,
    /// Simulated seconds per wall-clock second, when a person watches; `None`: as fast as the
    /// CPU allows.
    pub speed: Option<f64>,
    /// Set (Ctrl-C): the run stops before its end with `deflex_sim::SimError::Stopped`.
    pub stop: Option<&'static AtomicBool>,
    /// Hears the completed fraction (0..1) about every simulated second.
    pub progress: Option<&'a mut dyn FnMut(f64)>,
}

/// A forming run set up: its cell, path and controller, before it runs.
pub struct FormingSetup {
    config: CellConfig,
    path: deflex_sim::ToolPath,
    seed: u64,
    controller: Option<TwinController>,
    nominal: Option<Robot>,
}

impl FormingSetup {
    /// Read the cell, build the tool path and, with the correction on, the controller (its
    /// model read from a file when given so).
    pub fn prepare(options: &FormOptions) -> Result<FormingSetup> {
        check_correction(options.correction, options.model.is_some(), options.names)?;
        let mut config = cell_config(options.robot.as_deref(), options.config.as_deref())?;
        let plunge = options.path == PathChoice::Plunge;
        if plunge {
            config.process.kind = ProcessKind::Fixture;
        }
        if let Some(k) = options.fixture_stiffness_n_m {
            if !plunge {
                return Err(FormConflict::FixtureStiffnessWithoutPlunge.named(options.names));
            }
            let (lo, hi) = FIXTURE_STIFFNESS_RANGE_N_M;
            config.process.fixture_stiffness_n_m =
                bounded("fixture_stiffness_n_m", k, lo, hi, "N/m")?;
        }
        let path = tool_path(
            &options.path,
            options.feed_mm_s,
            options.length_mm,
            options.names,
        )?;
        // Closed loop: the deflex correction controller in-process, in simulated time, with the
        // nominal mounting and tool of the cell (never the plant's).
        let controller = match options.correction {
            FormCorrection::Off => None,
            FormCorrection::On => {
                let model = match &options.model {
                    None => return Err(TwinSetupError::ModelRequired.into()),
                    Some(CorrectionModel::File(file)) => load_model(file)?,
                    Some(CorrectionModel::Robot(robot)) => (**robot).clone(),
                };
                Some(TwinController::new(
                    model,
                    controller_config_for(&config),
                    false,
                )?)
            }
        };
        Ok(FormingSetup {
            config,
            path,
            seed: options.seed,
            controller,
            nominal: None,
        })
    }

    /// The cell the run forms in.
    pub fn config(&self) -> &CellConfig {
        &self.config
    }

    /// True with the correction controller in the loop.
    pub fn closed_loop(&self) -> bool {
        self.controller.is_some()
    }

    /// The cell's nominal robot (the description a user would write for it).
    fn nominal(&mut self) -> Result<Robot> {
        if let Some(robot) = &self.nominal {
            return Ok(robot.clone());
        }
        let robot = self.config.nominal_robot()?;
        self.nominal = Some(robot.clone());
        Ok(robot)
    }

    /// The description of the run's stream (SIMULATED): the controller's session in closed
    /// loop, the twin cell's in open loop.
    pub fn session_info(&mut self) -> Result<SessionInfo> {
        let nominal = self.nominal()?;
        Ok(match &self.controller {
            Some(t) => t.session_info(self.config.robot_period_s()),
            None => twin_cell_session_info(&nominal, &self.config),
        })
    }

    /// Run the path with `outlets` attached; they are detached when the run ends (their
    /// streams end with it), whether it finished or not.
    pub fn run(mut self, outlets: Outlets<'_>) -> Result<TwinRun> {
        let Outlets {
            sample_sink,
            publisher,
            speed,
            stop,
            progress,
        } = outlets;
        let streams = sample_sink.is_some() || publisher.is_some();
        let stream = match self.controller.as_mut() {
            Some(t) => {
                if let Some(sink) = sample_sink {
                    t.set_sample_sink(Some(sink));
                }
                if let Some(p) = publisher {
                    t.set_telemetry(Some(p));
                }
                None
            }
            None if streams => {
                let mut stream = TwinCellStream::new(self.nominal()?);
                if let Some(sink) = sample_sink {
                    stream = stream.with_sink(sink);
                }
                if let Some(p) = publisher {
                    stream = stream.with_publisher(p);
                }
                Some(stream)
            }
            None => None,
        };
        let watched = stream.is_some() || speed.is_some() || stop.is_some();
        let mut watch = RunWatch::new(stream, speed, stop);
        let observer = watched.then_some(&mut watch as &mut dyn CycleObserver);
        let controller = self
            .controller
            .as_mut()
            .map(|t| t as &mut dyn CorrectionController);
        let mut quiet = |_: f64| {};
        let progress = progress.unwrap_or(&mut quiet);
        let path_name = self.path.name.clone();
        let run = deflex_sim::run_program_observed(
            &self.config,
            self.path,
            None,
            self.seed,
            controller,
            observer,
            progress,
        );
        // The streams end with the run.
        drop(watch);
        if let Some(t) = self.controller.as_mut() {
            t.set_telemetry(None);
            t.set_sample_sink(None);
        }
        Ok(TwinRun {
            run: run?,
            config: self.config,
            controller_status: self.controller.as_ref().map(|t| t.status_line()),
            path_name,
            seed: self.seed,
        })
    }
}

/// `deflex sim isf` without outlets (Python's `deflex.sim.form`): form the path on the twin,
/// closed loop with the correction on.
pub fn form(options: &FormOptions) -> Result<TwinRun> {
    FormingSetup::prepare(options)?.run(Outlets::default())
}

/// A finished twin run.
pub struct TwinRun {
    /// The run (log, summary, profiles).
    pub run: FormingRun,
    /// The cell it ran in.
    pub config: CellConfig,
    /// The correction controller's status line (closed loop only).
    pub controller_status: Option<String>,
    /// The tool path's name.
    pub path_name: String,
    /// The run's seed.
    pub seed: u64,
}

/// The run's summary as `summary.json`'s text.
pub fn summary_json(run: &TwinRun) -> Result<String> {
    run.run.summary_json().map_err(|e| Error::Serialise {
        what: "the run's summary.json",
        reason: e.to_string(),
    })
}

impl TwinRun {
    /// What the run did, as text (mm, N): the header, the controller's status, the errors, the
    /// forces and the part, and the folder it was written to (`written`).
    pub fn report_text(&self, written: &crate::twin::WrittenRun) -> String {
        let s = &self.run.summary;
        let mut out = String::new();
        let mode = if self.controller_status.is_some() {
            "closed-loop"
        } else {
            "open-loop"
        };
        let _ = writeln!(
            out,
            "SIMULATED {mode} run on the twin of the {}: {} (seed {})",
            s.robot, self.path_name, self.seed
        );
        let tool = self.config.part.tool_xyz_m.map(|v| v * 1e3);
        let _ = writeln!(
            out,
            "  tool (flange to TCP) at ({:.4}, {:.4}, {:.4}) mm: the cell's, as deflex compensate and model show use it",
            tool[0], tool[1], tool[2]
        );
        if let Some(status) = &self.controller_status {
            let _ = writeln!(out, "  {status}");
        }
        let _ = writeln!(
            out,
            "  {:.1} s simulated in {:.2} s ({} cycles)",
            s.duration_s, self.run.wall_time_s, s.cycles
        );
        let _ = writeln!(
            out,
            "  TCP error: max {:.3} mm, RMS {:.3} mm (max |x| {:.3}, |y| {:.3}, |z| {:.3} mm)",
            s.max_error_norm_mm,
            s.rms_error_norm_mm,
            s.max_error_abs_mm[0],
            s.max_error_abs_mm[1],
            s.max_error_abs_mm[2]
        );
        if self.config.process.kind == ProcessKind::Fixture {
            let _ = writeln!(
                out,
                "  force: max |F| {:.0} N against a {:.0e} N/m fixture, deepest penetration {:.3} mm",
                s.max_force_norm_N,
                self.config.process.fixture_stiffness_n_m,
                s.final_part_depth_mm
            );
        } else if self.config.process.kind == ProcessKind::Prescribed {
            let _ = writeln!(
                out,
                "  force: max |F| {:.0} N, set along the path: ramped to {:.0} N over {:.0} mm of travel in contact, whatever the depth",
                s.max_force_norm_N,
                self.config.process.prescribed_force_n,
                self.config.process.prescribed_ramp_mm
            );
        } else {
            let _ = writeln!(
                out,
                "  force: max |F| {:.0} N, max Fz {:.0} N, max in-plane {:.0} N (Aerens level {:.0} N)",
                s.max_force_norm_N, s.max_fz_N, s.max_fxy_N, s.aerens_steady_fz_N
            );
            let _ = writeln!(
                out,
                "  part depth {:.2} mm of {:.2} mm programmed",
                s.final_part_depth_mm, s.target_depth_mm
            );
        }
        let _ = writeln!(
            out,
            "  wrote {} files to {}",
            written.files.len(),
            written.out.display()
        );
        out
    }

    /// What the run did, as JSON: `summary.json`'s content with the robot as given
    /// (`robot_spec`) and the files written.
    pub fn report_json(&self, written: &crate::twin::WrittenRun) -> Result<serde_json::Value> {
        // The summary as written in `summary.json`, read back: the numbers printed are the
        // file's.
        let text = summary_json(self)?;
        let mut value: serde_json::Value =
            serde_json::from_str(&text).map_err(|e| Error::Serialise {
                what: "the run's summary",
                reason: e.to_string(),
            })?;
        if let Some(map) = value.as_object_mut() {
            map.insert("robot_spec".into(), self.config.part.robot.clone().into());
            map.insert(
                "files".into(),
                written
                    .files
                    .iter()
                    .map(|f| serde_json::Value::from(f.display().to_string()))
                    .collect(),
            );
        }
        Ok(value)
    }
}

/// The log as a table of SI columns ([`log_columns`]) under its title comment (SIMULATED, the
/// robot, the path, the seed): Python's `TwinRun.log`.
pub fn log_table(run: &TwinRun) -> crate::table::CsvTable {
    let columns = log_columns(run);
    crate::table::CsvTable {
        comments: vec![run.run.log.title()],
        rows: run.run.log.rows.len(),
        columns: columns
            .into_iter()
            .map(|(name, values)| (name.to_string(), crate::table::TableColumn::Number(values)))
            .collect(),
    }
}

/// The log as SI columns (part frame R_p; the wrench on the tool at the TCP; the correction
/// applied; the contact state). One row per logged cycle.
pub fn log_columns(run: &TwinRun) -> Vec<(&'static str, Vec<f64>)> {
    type Row = deflex_sim::forming::FormingLogRow;
    let rows = &run.run.log.rows;
    let mut out: Vec<(&'static str, Vec<f64>)> = Vec::new();
    // Columns `names`, the k-th one's value `value(row, k)`.
    let mut push = |names: &[&'static str], value: &dyn Fn(&Row, usize) -> f64| {
        for (k, name) in names.iter().enumerate() {
            out.push((name, rows.iter().map(|r| value(r, k)).collect()));
        }
    };
    push(&["time_s"], &|r, _| r.time_s);
    push(&["des_x_m", "des_y_m", "des_z_m"], &|r, k| {
        r.truth.desired_m[k]
    });
    push(&["cmd_x_m", "cmd_y_m", "cmd_z_m"], &|r, k| {
        r.truth.commanded_m[k]
    });
    push(&["true_x_m", "true_y_m", "true_z_m"], &|r, k| {
        r.truth.true_m[k]
    });
    push(&["tracked_x_m", "tracked_y_m", "tracked_z_m"], &|r, k| {
        r.tracked_m[k]
    });
    push(&["err_x_m", "err_y_m", "err_z_m"], &|r, k| {
        r.truth.path_error_m()[k]
    });
    push(&["err_norm_m"], &|r, _| r.truth.path_error_m().norm());
    push(
        &["fx_N", "fy_N", "fz_N", "mx_Nm", "my_Nm", "mz_Nm"],
        &|r, k| r.truth.wrench[k],
    );
    push(
        &[
            "sensor_fx_N",
            "sensor_fy_N",
            "sensor_fz_N",
            "sensor_tx_Nm",
            "sensor_ty_Nm",
            "sensor_tz_Nm",
        ],
        &|r, k| r.sensor.wrench_sensor[k],
    );
    push(&["sensor_saturated"], &|r, _| {
        if r.sensor.saturated { 1.0 } else { 0.0 }
    });
    push(
        &[
            "corr_x_m",
            "corr_y_m",
            "corr_z_m",
            "corr_rx_rad",
            "corr_ry_rad",
            "corr_rz_rad",
        ],
        &|r, k| r.truth.correction[k],
    );
    // The deflection's columns are named as the compensation's table names them.
    push(&deflex_compensate::table::DEFLECTION, &|r, k| {
        r.truth.deflection[k]
    });
    push(&["penetration_m"], &|r, _| r.truth.contact.penetration_m);
    push(&["flow_level_N"], &|r, _| r.truth.contact.flow_n);
    push(&["tool_depth_m"], &|r, _| r.truth.contact.depth_m);
    out
}
