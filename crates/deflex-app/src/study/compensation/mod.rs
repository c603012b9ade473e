//! Compensation without a real-time option, in the twin (SIMULATED): on the paper's cone and on
//! a CAM part (`docs/parts/pyramid-pocket.gcode`), the path error of
//!
//! 1. the uncorrected program;
//! 2. **offline only**, forces from the process model: `deflex compensate --wrench process`
//!    (the twin's forming law with the identified robot model, iterated to convergence), the
//!    compensated program run by the robot;
//! 3. **offline only**, forces from the uncorrected run's log (`--wrench log:…`, one pass);
//! 4. **online only**: the correction controller of `deflex run` (eq. 17);
//! 5. **offline + online, feed-forward**: the original program, the controller given the
//!    process-model table as feed-forward (`[feedforward] mode = "feed-forward"`, with a lead
//!    of the twin controller's correction delay);
//! 6. **offline + online, pre-compensated**: the compensated program of 2, the controller told
//!    (`mode = "precompensated"`);
//! 7. (CAM part) the compensated program with the controller *not* told: the double correction
//!    that mode 6 prevents.
//!
//! The independent runs go to [`CompensationPlan::threads`] threads (each run is
//! deterministic: the numbers do not depend on the threads).
//!
//! with the max and RMS path error and the lag at the force ramps ([`lag`]). The robot model is
//! the one the study identified from its twin campaign; the twin's robot is the independent
//! plant with every error source on. The compensations are position only: the twin holds the
//! tool orientation along its paths.

pub mod lag;

use crate::load::parse_wrench_log;
use crate::study::DemoError;
use deflex_compensate::log::{ResampleOptions, resample_on_path};
use deflex_compensate::table::{read_csv, write_csv};
use deflex_compensate::{
    Compensation, CompensationOptions, TcpPath, WrenchSource, commanded_pose, compensate,
};
use deflex_control::{FeedForward, FeedForwardConfig, FeedForwardMode};
use deflex_model::Robot;
use deflex_sim::twin::{
    ClosedLoopRun, TwinController, TwinProgram, controller_config_for, run_twin_controller,
};
use deflex_sim::{CellConfig, FormingProcess, FormingRun, ToolPath, compensated_tool_path};
use lag::ErrorNumbers;
use serde::Serialize;

/// The CAM part of the study, shipped in the repository.
pub const GCODE_PART_FILE: &str = "docs/parts/pyramid-pocket.gcode";
const GCODE_PART: &str = include_str!("../../../../../docs/parts/pyramid-pocket.gcode");

/// The CAM part as a tool path.
pub fn gcode_part() -> Result<ToolPath, DemoError> {
    Ok(deflex_sim::gcode::parse_gcode(GCODE_PART, GCODE_PART_FILE)?)
}

/// The ways of the comparison, in table order (labels of the report and `summary.json`).
pub const UNCORRECTED: &str = "uncorrected";
/// See [`UNCORRECTED`].
pub const OFFLINE_PROCESS: &str = "offline only, forces from the process model";
/// See [`UNCORRECTED`].
pub const OFFLINE_LOG: &str = "offline only, forces of the uncorrected run's log";
/// See [`UNCORRECTED`].
pub const ONLINE: &str = "online only";
/// See [`UNCORRECTED`].
pub const FEED_FORWARD: &str = "offline + online: feed-forward (process-model table)";
/// See [`UNCORRECTED`].
pub const PRECOMPENSATED: &str = "offline + online: pre-compensated program, controller told";
/// See [`UNCORRECTED`].
pub const ONLINE_UNGUARDED: &str = "online only, contact-runaway guard off";
/// See [`UNCORRECTED`].
pub const DOUBLE: &str =
    "pre-compensated program + online, controller NOT told (double correction)";

/// Settings of the comparison.
#[derive(Clone, Debug, PartialEq)]
pub struct CompensationPlan {
    /// Lead of the feed-forward (s): the twin controller's correction delay (transport delay,
    /// interpolator filter and servo lag).
    pub lead_s: f64,
    /// Worker threads for the independent runs.
    pub threads: usize,
    /// Shorten the CAM part to this length (mm), for tests.
    pub gcode_length_mm: Option<f64>,
    /// Also run the double-correction case on the CAM part.
    pub double_correction: bool,
    /// Also run the online correction with the contact-runaway guard off (on the CAM part its
    /// plunges' elastic onset trips the guard).
    pub online_unguarded: bool,
}

impl Default for CompensationPlan {
    fn default() -> Self {
        CompensationPlan {
            lead_s: 0.04,
            threads: 2,
            gcode_length_mm: None,
            double_correction: true,
            online_unguarded: true,
        }
    }
}

/// One way on one part.
#[derive(Clone, Debug, Serialize)]
pub struct WayNumbers {
    /// Which way ([`UNCORRECTED`] …).
    pub way: String,
    /// Error and lag numbers.
    #[serde(flatten)]
    pub numbers: ErrorNumbers,
}

/// How an offline compensation went.
#[derive(Clone, Debug, Serialize)]
#[allow(non_snake_case)]
pub struct OfflineNumbers {
    /// The wrench source.
    pub source: String,
    /// Iterations run.
    pub iterations: usize,
    /// Converged within the tolerance.
    pub converged: bool,
    /// Largest path error the model predicts for the uncompensated and the compensated
    /// program (mm).
    pub predicted_error_before_mm: f64,
    /// See `predicted_error_before_mm`.
    pub predicted_error_after_mm: f64,
    /// Largest compensation (mm).
    pub max_compensation_mm: f64,
    /// Largest force the source gives at the compensated program (N).
    pub max_force_N: f64,
    /// Wall time of the compensation (s).
    pub seconds: f64,
}

/// The comparison on one part.
#[derive(Clone, Debug, Serialize)]
pub struct PartComparison {
    /// The part (path name).
    pub part: String,
    /// Path points.
    pub points: usize,
    /// Path length (mm).
    pub length_mm: f64,
    /// Force ramps found on the uncorrected run ([`lag`]).
    pub ramps: usize,
    /// The process-model compensation.
    pub offline_process: OfflineNumbers,
    /// The log compensation.
    pub offline_log: OfflineNumbers,
    /// One row per way.
    pub ways: Vec<WayNumbers>,
}

impl PartComparison {
    /// The numbers of one way.
    pub fn way(&self, way: &str) -> Option<&ErrorNumbers> {
        self.ways.iter().find(|w| w.way == way).map(|w| &w.numbers)
    }
}

/// The whole comparison (`summary.json`'s `compensation`).
#[derive(Clone, Debug, Serialize)]
pub struct CompensationStudy {
    /// Always true.
    pub simulated: bool,
    /// Lead of the feed-forward (s).
    pub lead_s: f64,
    /// How the lag is measured.
    pub lag_definition: String,
    /// The paper's cone and the CAM part.
    pub parts: Vec<PartComparison>,
}

/// The runs behind a part's numbers (for figures and CSV files).
pub struct PartRuns {
    /// `(way, run)` in table order.
    pub runs: Vec<(String, FormingRun)>,
    /// Ramps (reference arc lengths, m).
    pub ramps: Vec<f64>,
    /// The process-model table (`compensated_path.csv` text).
    pub table_csv: String,
}

fn offline_numbers(c: &Compensation, seconds: f64) -> OfflineNumbers {
    OfflineNumbers {
        source: c.source.clone(),
        iterations: c.iterations.len(),
        converged: c.converged,
        predicted_error_before_mm: c
            .iterations
            .first()
            .map_or(0.0, |i| i.max_predicted_error_m * 1e3),
        predicted_error_after_mm: c.final_max_error_m * 1e3,
        max_compensation_mm: c.max_compensation_m * 1e3,
        max_force_N: c.final_max_force_n,
        seconds,
    }
}

/// One independent run of a comparison.
type Job<'a, T> = Box<dyn FnOnce() -> Result<T, DemoError> + Send + 'a>;

/// Runs `jobs` on up to `threads` threads; results in job order.
fn parallel<'a, T: Send>(threads: usize, jobs: Vec<Job<'a, T>>) -> Result<Vec<T>, DemoError> {
    let count = jobs.len();
    let queue = std::sync::Mutex::new(jobs.into_iter().enumerate().collect::<Vec<_>>());
    let results: std::sync::Mutex<Vec<Option<Result<T, DemoError>>>> =
        std::sync::Mutex::new((0..count).map(|_| None).collect());
    std::thread::scope(|scope| {
        for _ in 0..threads.clamp(1, count.max(1)) {
            scope.spawn(|| {
                loop {
                    let job = queue.lock().ok().and_then(|mut q| q.pop());
                    let Some((i, job)) = job else { break };
                    let result = job();
                    if let Ok(mut r) = results.lock() {
                        r[i] = Some(result);
                    }
                }
            });
        }
    });
    results
        .into_inner()
        .map_err(|_| DemoError::Worker {
            what: "a comparison thread failed",
        })?
        .into_iter()
        .map(|r| {
            r.unwrap_or(Err(DemoError::Worker {
                what: "a comparison run did not finish",
            }))
        })
        .collect()
}

/// The CAM part's moves are split to at most this length (mm) for every way: a compensation
/// moves the program's waypoints, and a plunge written as one 2.4 mm move would be compensated
/// at its ends only (`deflex compensate --max-segment-mm`).
pub const MAX_SEGMENT_MM: f64 = 0.5;

/// Convergence tolerance of the demo's compensations (m): the twin's forming law remembers the
/// last pass per 1° sector, and the fixed point dithers by a few µm once within 5 µm (measured
/// on the cone: 3.8 → 0.60 → 0.12 → 0.027 → 0.005 mm of change, then 3–8 µm for another dozen
/// iterations); 10 µm is 70 times below the smallest path error the study reports.
pub const TOLERANCE_M: f64 = 10e-6;

/// The compensation of `tcp` by `model` against `source`, position only, timed.
fn offline(
    model: &Robot,
    tcp: &TcpPath,
    seed_q: &[f64],
    source: WrenchSource,
) -> Result<(Compensation, f64), DemoError> {
    let clock = std::time::Instant::now();
    let options = CompensationOptions {
        orientation: false,
        tolerance_m: TOLERANCE_M,
        ..CompensationOptions::default()
    };
    let c = compensate(model, tcp, seed_q, source, &options, &mut |_| {})?;
    if let Some((first, failure)) = c.failures().next() {
        return Err(DemoError::Uncompensated {
            path: tcp.name().to_string(),
            count: c.failure_count(),
            first,
            code: failure.code(),
        });
    }
    Ok((c, clock.elapsed().as_secs_f64()))
}

/// The robot program of a compensation (part frame, for the twin).
fn program(
    cell: &CellConfig,
    path: &ToolPath,
    tcp: &TcpPath,
    c: &Compensation,
) -> Result<TwinProgram, DemoError> {
    let commanded: Vec<_> = tcp
        .points()
        .iter()
        .zip(&c.points)
        .map(|(p, r)| commanded_pose(&p.pose, &r.compensation).translation.vector)
        .collect();
    Ok(TwinProgram {
        path: compensated_tool_path(path, &commanded, &cell.part_frame())?,
        reference: Some(path.clone()),
    })
}

fn controlled(
    cell: &CellConfig,
    model: &Robot,
    program: &TwinProgram,
    seed: u64,
    feedforward: Option<FeedForward>,
    guard: bool,
) -> Result<ClosedLoopRun, DemoError> {
    let mut config = controller_config_for(cell);
    config.runaway.enabled = guard;
    let mut twin = TwinController::new(model.clone(), config, false).map_err(DemoError::from)?;
    twin.set_feedforward(feedforward);
    let run =
        run_twin_controller(cell, program, seed, twin, &mut |_| {}).map_err(DemoError::from)?;
    if let Some(fault) = run.fault {
        return Err(DemoError::ControllerFault {
            path: program.path.name.clone(),
            fault,
        });
    }
    Ok(run)
}

/// A timed compensation and the run of its program.
type LogCompensation = (Compensation, f64, FormingRun);

/// What stage 1 of a comparison gives: the uncorrected and online runs when they were not
/// given, and the timed process-model compensation.
struct StageOne {
    open: Option<FormingRun>,
    online: Option<FormingRun>,
    process: (Compensation, f64),
    /// The log compensation, when the uncorrected run was given (it then joins stage 1).
    log: Option<LogCompensation>,
}

/// One part of the comparison: the cell, the controller's model, the path and its TCP path.
struct PartSetup<'a> {
    cell: &'a CellConfig,
    model: &'a Robot,
    path: &'a ToolPath,
    tcp: TcpPath,
    seed_q: [f64; 6],
    seed: u64,
}

impl PartSetup<'_> {
    /// The log compensation (forces of the uncorrected run's log, one pass) and its run.
    fn log_compensation(&self, open: &FormingRun) -> Result<LogCompensation, DemoError> {
        let text = open.log.to_csv();
        let log = parse_wrench_log(
            &text,
            "forming_open/log.csv",
            self.model,
            &self.cell.part_frame(),
        )?;
        let resampled = resample_on_path(&log, &self.tcp, &ResampleOptions::default())?;
        let (c, seconds) = offline(
            self.model,
            &self.tcp,
            &self.seed_q,
            WrenchSource::Fixed {
                label: "forces of the uncorrected run's log (SIMULATED)".into(),
                simulated: true,
                wrenches: &resampled.wrenches,
            },
        )?;
        let run = self.run_program(&program(self.cell, self.path, &self.tcp, &c)?)?;
        Ok((c, seconds, run))
    }

    /// A compensated program run open loop, meaning the part's path.
    fn run_program(&self, program: &TwinProgram) -> Result<FormingRun, DemoError> {
        Ok(deflex_sim::run_program_with_progress(
            self.cell,
            program.path.clone(),
            Some(self.path),
            self.seed,
            None,
            &mut |_| {},
        )?)
    }

    /// The part's own path, as a program.
    fn original(&self) -> TwinProgram {
        TwinProgram {
            path: self.path.clone(),
            reference: None,
        }
    }

    /// Stage 1, independent runs: the process-model compensation, the uncorrected run (the
    /// previous run of the log compensation) and the online run unless given; with a given
    /// uncorrected run, the log compensation too.
    fn stage_one(
        &self,
        threads: usize,
        uncorrected: Option<&FormingRun>,
        online_given: bool,
    ) -> Result<StageOne, DemoError> {
        type Stage1 = (
            Option<FormingRun>,
            Option<FormingRun>,
            Option<(Compensation, f64)>,
            Option<LogCompensation>,
        );
        let mut jobs: Vec<Job<'_, Stage1>> = vec![Box::new(|| {
            let mut process = FormingProcess::from_cell(self.cell, self.path)?;
            let c = offline(
                self.model,
                &self.tcp,
                &self.seed_q,
                WrenchSource::Process(&mut process),
            )?;
            Ok((None, None, Some(c), None))
        })];
        if uncorrected.is_none() {
            jobs.push(Box::new(|| {
                let run = deflex_sim::run_forming(self.cell, self.path.clone(), self.seed, None)?;
                Ok((Some(run), None, None, None))
            }));
        }
        if !online_given {
            jobs.push(Box::new(|| {
                let run = controlled(
                    self.cell,
                    self.model,
                    &self.original(),
                    self.seed,
                    None,
                    true,
                )?;
                Ok((None, Some(run.forming), None, None))
            }));
        }
        if let Some(open) = uncorrected {
            jobs.push(Box::new(|| {
                Ok((None, None, None, Some(self.log_compensation(open)?)))
            }));
        }
        let (mut open, mut online, mut process, mut log) = (None, None, None, None);
        for (a, b, c, d) in parallel(threads, jobs)? {
            open = open.or(a);
            online = online.or(b);
            process = process.or(c);
            log = log.or(d);
        }
        Ok(StageOne {
            open,
            online,
            process: process.ok_or(DemoError::Worker {
                what: "no process-model compensation",
            })?,
            log,
        })
    }

    /// The process-model compensation as the controller's table (`compensated_path.csv`), and
    /// the feed-forward (with `lead_s`) and pre-compensated controllers' feed-forward from it.
    fn feed_forwards(
        &self,
        process: &Compensation,
        lead_s: f64,
    ) -> Result<(String, FeedForward, FeedForward), DemoError> {
        let table_csv = write_csv(
            &self.tcp,
            process,
            self.model.joint_count(),
            &["SIMULATED: forces from the twin's forming model".to_string()],
        );
        let rows = read_csv(&table_csv, "compensated_path.csv")?;
        let table = crate::cell::feedforward::table_of(&rows, self.model, "compensated_path.csv")?;
        let feedforward = |mode, lead_s| {
            FeedForward::new(
                table.clone(),
                FeedForwardConfig {
                    mode,
                    lead_s,
                    ..FeedForwardConfig::default()
                },
            )
            .map_err(DemoError::from)
        };
        let ff = feedforward(FeedForwardMode::FeedForward, lead_s)?;
        let pre = feedforward(FeedForwardMode::Precompensated, 0.0)?;
        Ok((table_csv, ff, pre))
    }

    /// Stage 2, independent runs: the offline program, the feed-forward and pre-compensated
    /// controllers, the double correction and the unguarded online run when planned, and the
    /// log compensation when stage 1 could not make it. Returns the ways' runs in table order
    /// after the uncorrected, offline-log and online ones, and the log compensation.
    fn stage_two(
        &self,
        plan: &CompensationPlan,
        process: &Compensation,
        (ff, pre): (FeedForward, FeedForward),
        open: &FormingRun,
        log: Option<LogCompensation>,
    ) -> Result<(Vec<FormingRun>, LogCompensation), DemoError> {
        let process_program = program(self.cell, self.path, &self.tcp, process)?;
        let original = self.original();
        type Stage2 = (Option<FormingRun>, Option<LogCompensation>);
        let closed = |program: &TwinProgram, feedforward: Option<FeedForward>, guard: bool| {
            controlled(
                self.cell,
                self.model,
                program,
                self.seed,
                feedforward,
                guard,
            )
            .map(|run| (Some(run.forming), None))
        };
        let mut jobs: Vec<Job<'_, Stage2>> = vec![
            Box::new(|| Ok((Some(self.run_program(&process_program)?), None))),
            Box::new(|| closed(&original, Some(ff), true)),
            Box::new(|| closed(&process_program, Some(pre), true)),
        ];
        if plan.double_correction {
            jobs.push(Box::new(|| closed(&process_program, None, true)));
        }
        if plan.online_unguarded {
            jobs.push(Box::new(|| closed(&original, None, false)));
        }
        let given_log = log.is_some();
        if !given_log {
            jobs.push(Box::new(|| Ok((None, Some(self.log_compensation(open)?)))));
        }
        let mut results = parallel(plan.threads, jobs)?;
        let log = match log {
            Some(done) => done,
            None => results
                .pop()
                .and_then(|(_, log)| log)
                .ok_or(DemoError::Worker {
                    what: "no log compensation",
                })?,
        };
        Ok((
            results.into_iter().filter_map(|(run, _)| run).collect(),
            log,
        ))
    }
}

/// The comparison on one part. `uncorrected` and `online` are reused when the study already
/// ran them on this path with this seed.
pub fn compare_part(
    cell: &CellConfig,
    model: &Robot,
    path: &ToolPath,
    seed: u64,
    plan: &CompensationPlan,
    uncorrected: Option<&FormingRun>,
    online: Option<&FormingRun>,
) -> Result<(PartComparison, PartRuns), DemoError> {
    let seed_q = cell.seed_q_rad();
    let rotation = model
        .tcp_pose(&seed_q)
        .map_err(deflex_model::ModelError::from)?
        .rotation;
    let tcp = deflex_sim::tcp_path(
        path,
        &cell.part_frame(),
        &rotation,
        cell.controller.rapid_feed_mm_s,
    )?;
    let part = PartSetup {
        cell,
        model,
        path,
        tcp,
        seed_q,
        seed,
    };
    let first = part.stage_one(plan.threads, uncorrected, online.is_some())?;
    let missing = |what| DemoError::Worker { what };
    let open = match uncorrected {
        Some(run) => run,
        None => first.open.as_ref().ok_or(missing("no uncorrected run"))?,
    };
    let online = match online {
        Some(run) => run,
        None => first.online.as_ref().ok_or(missing("no online run"))?,
    };
    let (process_c, process_s) = first.process;
    let (table_csv, ff, pre) = part.feed_forwards(&process_c, plan.lead_s)?;
    let (second, (log_c, log_s, offline_log_run)) =
        part.stage_two(plan, &process_c, (ff, pre), open, first.log)?;
    let mut results = second.into_iter();
    let mut next = || results.next().ok_or(missing("a comparison run is missing"));
    let mut runs: Vec<(String, FormingRun)> = vec![(UNCORRECTED.into(), open.clone())];
    runs.push((OFFLINE_PROCESS.into(), next()?));
    runs.push((OFFLINE_LOG.into(), offline_log_run));
    runs.push((ONLINE.into(), online.clone()));
    runs.push((FEED_FORWARD.into(), next()?));
    runs.push((PRECOMPENSATED.into(), next()?));
    if plan.double_correction {
        runs.push((DOUBLE.into(), next()?));
    }
    if plan.online_unguarded {
        runs.push((ONLINE_UNGUARDED.into(), next()?));
    }
    let ramps = lag::ramps(open);
    let ways = runs
        .iter()
        .map(|(way, run)| WayNumbers {
            way: way.clone(),
            numbers: lag::error_numbers(run, &ramps),
        })
        .collect();
    Ok((
        PartComparison {
            part: path.name.clone(),
            points: part.tcp.len(),
            length_mm: part.tcp.length_m() * 1e3,
            ramps: ramps.len(),
            offline_process: offline_numbers(&process_c, process_s),
            offline_log: offline_numbers(&log_c, log_s),
            ways,
        },
        PartRuns {
            runs,
            ramps,
            table_csv,
        },
    ))
}

/// The lag definition, for the report and `summary.json`.
pub fn lag_definition() -> String {
    format!(
        "force ramps: on the uncorrected run, where Fz rises through 5 % of its maximum after \
         {} s below it to a step (the largest Fz within {} s) of at least {} % of the maximum; \
         each ramp's reference point is where Fz first reaches 50 % of its step, by arc length \
         of the desired path. ramp_error_integral: \
         ∫|e|dt over {} s from that point (mm·s, mean over the ramps); ramp_settle: time from it \
         until |e| falls below {} mm and stays below for {} s (mean; {} s when not within {} s)",
        lag::QUIET_S,
        lag::STEP_WINDOW_S,
        lag::MIN_STEP_FRACTION * 100.0,
        lag::INTEGRAL_WINDOW_S,
        lag::SETTLE_THRESHOLD_MM,
        lag::SETTLE_HOLD_S,
        lag::SETTLE_WINDOW_S,
        lag::SETTLE_WINDOW_S
    )
}

/// The demo's stage: the comparison on the study's cone (reusing its uncorrected and online
/// runs) and on the CAM part, with the runs behind it (cone first: its CSV files and figures are
/// `crate::report::study`'s). `quick` shortens the CAM part to its first levels.
pub fn study(
    cell: &CellConfig,
    model: &Robot,
    seed: u64,
    quick: bool,
    cone: (&ToolPath, &FormingRun, &FormingRun),
) -> Result<(CompensationStudy, [PartRuns; 2]), DemoError> {
    let plan = CompensationPlan {
        gcode_length_mm: quick.then_some(400.0),
        ..CompensationPlan::default()
    };
    let (cone_path, open, online) = cone;
    // The double correction is shown on the CAM part only (one run fewer on the long cone).
    let cone_plan = CompensationPlan {
        double_correction: false,
        online_unguarded: false,
        ..plan.clone()
    };
    let (cone_numbers, cone_runs) = compare_part(
        cell,
        model,
        cone_path,
        seed,
        &cone_plan,
        Some(open),
        Some(online),
    )?;
    let mut part = gcode_part()?;
    if let Some(length) = plan.gcode_length_mm {
        part = part.truncated(length);
    }
    // `deflex compensate --max-segment-mm`: the plunges are single moves.
    let part = part.subdivided(MAX_SEGMENT_MM)?;
    let (part_numbers, part_runs) = compare_part(cell, model, &part, seed, &plan, None, None)?;
    let study = CompensationStudy {
        simulated: true,
        lead_s: plan.lead_s,
        lag_definition: lag_definition(),
        parts: vec![cone_numbers, part_numbers],
    };
    Ok((study, [cone_runs, part_runs]))
}

/// One line for the terminal: the max error of each way on each part.
pub fn one_line(study: &CompensationStudy) -> String {
    study
        .parts
        .iter()
        .map(|p| {
            let get = |way| p.way(way).map_or(f64::NAN, |n| n.max_error_mm);
            format!(
                "{}: max |e| {:.2} / offline {:.2} (log {:.2}) / online {:.2} / both {:.2} mm",
                if p.part.starts_with("cone") {
                    "cone"
                } else {
                    "part"
                },
                get(UNCORRECTED),
                get(OFFLINE_PROCESS),
                get(OFFLINE_LOG),
                get(ONLINE),
                get(FEED_FORWARD).min(get(PRECOMPENSATED)),
            )
        })
        .collect::<Vec<_>>()
        .join("; ")
}
