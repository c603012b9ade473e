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
pub(crate) mod page;

use crate::twin_controller::{
    ClosedLoopRun, Program, TwinController, controller_config_for, run_twin_controller,
};
use deflex_compensate::log::{ResampleOptions, parse_log, resample_on_path};
use deflex_compensate::table::{read_csv, write_csv};
use deflex_compensate::{
    Compensation, CompensationOptions, TcpPath, WrenchSource, commanded_pose, compensate,
};
use deflex_control::{FeedForward, FeedForwardConfig, FeedForwardMode, FeedForwardTable};
use deflex_model::Robot;
use deflex_sim::{CellConfig, FormingProcess, FormingRun, ToolPath, compensated_tool_path};
use lag::ErrorNumbers;
use serde::Serialize;

/// The CAM part of the study, shipped in the repository.
pub const GCODE_PART_FILE: &str = "docs/parts/pyramid-pocket.gcode";
const GCODE_PART: &str = include_str!("../../../../docs/parts/pyramid-pocket.gcode");

/// The CAM part as a tool path.
pub fn gcode_part() -> Result<ToolPath, String> {
    deflex_sim::gcode::parse_gcode(GCODE_PART, GCODE_PART_FILE).map_err(|e| e.to_string())
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

/// Runs `jobs` on up to `threads` threads; results in job order.
fn parallel<'a, T: Send>(
    threads: usize,
    jobs: Vec<Box<dyn FnOnce() -> Result<T, String> + Send + 'a>>,
) -> Result<Vec<T>, String> {
    let count = jobs.len();
    let queue = std::sync::Mutex::new(jobs.into_iter().enumerate().collect::<Vec<_>>());
    let results: std::sync::Mutex<Vec<Option<Result<T, String>>>> =
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
        .map_err(|_| "a comparison thread failed".to_string())?
        .into_iter()
        .map(|r| r.unwrap_or_else(|| Err("a comparison run did not finish".into())))
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
) -> Result<(Compensation, f64), String> {
    let clock = std::time::Instant::now();
    let options = CompensationOptions {
        orientation: false,
        tolerance_m: TOLERANCE_M,
        ..CompensationOptions::default()
    };
    let c =
        compensate(model, tcp, seed_q, source, &options, &mut |_| {}).map_err(|e| e.to_string())?;
    if c.failure_count() > 0 {
        let (i, f) = c
            .failures()
            .next()
            .map(|(i, f)| (i, f.code()))
            .unwrap_or_default();
        return Err(format!(
            "{}: {} point(s) could not be compensated (first: point {i}, {f})",
            tcp.name(),
            c.failure_count()
        ));
    }
    Ok((c, clock.elapsed().as_secs_f64()))
}

/// The robot program of a compensation (part frame, for the twin).
fn program(
    cell: &CellConfig,
    path: &ToolPath,
    tcp: &TcpPath,
    c: &Compensation,
) -> Result<Program, String> {
    let commanded: Vec<_> = tcp
        .points()
        .iter()
        .zip(&c.points)
        .map(|(p, r)| commanded_pose(&p.pose, &r.compensation).translation.vector)
        .collect();
    Ok(Program {
        path: compensated_tool_path(path, &commanded, &cell.part_frame())
            .map_err(|e| e.to_string())?,
        reference: Some(path.clone()),
    })
}

fn controlled(
    cell: &CellConfig,
    model: &Robot,
    program: &Program,
    seed: u64,
    feedforward: Option<FeedForward>,
    guard: bool,
) -> Result<ClosedLoopRun, String> {
    let mut config = controller_config_for(cell);
    config.runaway.enabled = guard;
    let mut twin = TwinController::new(model.clone(), config, false)?;
    twin.set_feedforward(feedforward);
    let run = run_twin_controller(cell, program, seed, twin, &mut |_| {})?;
    if let Some(fault) = run.fault {
        return Err(format!(
            "{}: the controller faulted: {fault}",
            program.path.name
        ));
    }
    Ok(run)
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
) -> Result<(PartComparison, PartRuns), String> {
    let seed_q = cell.seed_q_rad();
    let rotation = model.tcp_pose(&seed_q).map_err(|e| e.to_string())?.rotation;
    let tcp = deflex_sim::tcp_path(
        path,
        &cell.part_frame(),
        &rotation,
        cell.controller.rapid_feed_mm_s,
    )
    .map_err(|e| e.to_string())?;
    // The log compensation and its run need only the uncorrected run: with a given one they
    // join stage 1.
    let log_job = |open: &FormingRun| -> Result<(Compensation, f64, FormingRun), String> {
        let text = open.log.to_csv();
        let log = parse_log(&text, "forming_open/log.csv", model, &cell.part_frame())
            .map_err(|e| e.to_string())?;
        let resampled =
            resample_on_path(&log, &tcp, &ResampleOptions::default()).map_err(|e| e.to_string())?;
        let (c, seconds) = offline(
            model,
            &tcp,
            &seed_q,
            WrenchSource::Fixed {
                label: "forces of the uncorrected run's log (SIMULATED)".into(),
                simulated: true,
                wrenches: &resampled.wrenches,
            },
        )?;
        let p = program(cell, path, &tcp, &c)?;
        let run = deflex_sim::run_program_with_progress(
            cell,
            p.path,
            Some(path),
            seed,
            None,
            &mut |_| {},
        )
        .map_err(|e| e.to_string())?;
        Ok((c, seconds, run))
    };
    let log_slot = std::sync::Mutex::new(None);
    // Stage 1, independent: the uncorrected run (its log is the previous run of the log
    // compensation) and the online run unless given, and the process-model compensation.
    type Stage1 = (
        Option<FormingRun>,
        Option<FormingRun>,
        Option<(Compensation, f64)>,
    );
    let mut first: Vec<Box<dyn FnOnce() -> Result<Stage1, String> + Send + '_>> = Vec::new();
    first.push(Box::new(|| {
        let mut process = FormingProcess::from_cell(cell, path).map_err(|e| e.to_string())?;
        let c = offline(model, &tcp, &seed_q, WrenchSource::Process(&mut process))?;
        Ok((None, None, Some(c)))
    }));
    if uncorrected.is_none() {
        first.push(Box::new(|| {
            let run = deflex_sim::run_forming(cell, path.clone(), seed, None)
                .map_err(|e| e.to_string())?;
            Ok((Some(run), None, None))
        }));
    }
    if online.is_none() {
        first.push(Box::new(|| {
            let p = Program {
                path: path.clone(),
                reference: None,
            };
            Ok((
                None,
                Some(controlled(cell, model, &p, seed, None, true)?.forming),
                None,
            ))
        }));
    }
    if let Some(open) = uncorrected {
        first.push(Box::new(|| {
            let result = log_job(open)?;
            if let Ok(mut slot) = log_slot.lock() {
                *slot = Some(result);
            }
            Ok((None, None, None))
        }));
    }
    let (mut open_run, mut online_run, mut process_c) = (None, None, None);
    for (a, b, c) in parallel(plan.threads, first)? {
        open_run = open_run.or(a);
        online_run = online_run.or(b);
        process_c = process_c.or(c);
    }
    let open = match uncorrected {
        Some(run) => run,
        None => open_run.as_ref().ok_or("no uncorrected run")?,
    };
    let online = match online {
        Some(run) => run,
        None => online_run.as_ref().ok_or("no online run")?,
    };
    let (process_c, process_s) = process_c.ok_or("no process-model compensation")?;
    let given_log = log_slot.into_inner().ok().flatten();
    let process_program = program(cell, path, &tcp, &process_c)?;
    let table_csv = write_csv(
        &tcp,
        &process_c,
        model.joint_count(),
        &["SIMULATED: forces from the twin's forming model".to_string()],
    );
    let rows = read_csv(&table_csv, "compensated_path.csv").map_err(|e| e.to_string())?;
    let table = FeedForwardTable::from_rows(&rows, model, "compensated_path.csv")
        .map_err(|e| e.to_string())?;
    let feedforward = |mode, lead_s| {
        FeedForward::new(
            table.clone(),
            FeedForwardConfig {
                mode,
                lead_s,
                ..FeedForwardConfig::default()
            },
        )
        .map_err(|e| e.to_string())
    };
    let ff = feedforward(FeedForwardMode::FeedForward, plan.lead_s)?;
    let pre = feedforward(FeedForwardMode::Precompensated, 0.0)?;
    let original = Program {
        path: path.clone(),
        reference: None,
    };
    // Stage 2, independent runs (and the log compensation when the uncorrected run was made
    // in stage 1).
    type Stage2 = (Option<FormingRun>, Option<(Compensation, f64, FormingRun)>);
    let simple = |run: Result<FormingRun, String>| run.map(|r| (Some(r), None));
    let mut second: Vec<Box<dyn FnOnce() -> Result<Stage2, String> + Send + '_>> = vec![
        Box::new(|| {
            simple(
                deflex_sim::run_program_with_progress(
                    cell,
                    process_program.path.clone(),
                    Some(path),
                    seed,
                    None,
                    &mut |_| {},
                )
                .map_err(|e| e.to_string()),
            )
        }),
        Box::new(|| {
            simple(Ok(controlled(
                cell,
                model,
                &original,
                seed,
                Some(ff),
                true,
            )?
            .forming))
        }),
        Box::new(|| {
            simple(Ok(controlled(
                cell,
                model,
                &process_program,
                seed,
                Some(pre),
                true,
            )?
            .forming))
        }),
    ];
    if plan.double_correction {
        second.push(Box::new(|| {
            simple(Ok(controlled(
                cell,
                model,
                &process_program,
                seed,
                None,
                true,
            )?
            .forming))
        }));
    }
    if plan.online_unguarded {
        second.push(Box::new(|| {
            simple(Ok(
                controlled(cell, model, &original, seed, None, false)?.forming
            ))
        }));
    }
    if given_log.is_none() {
        second.push(Box::new(|| Ok((None, Some(log_job(open)?)))));
    }
    let mut stage2 = parallel(plan.threads, second)?;
    let (log_c, log_s, offline_log_run) = match given_log {
        Some(done) => done,
        None => stage2
            .pop()
            .and_then(|(_, log)| log)
            .ok_or("no log compensation")?,
    };
    let mut results = stage2.into_iter().filter_map(|(run, _)| run);
    let mut next = || {
        results
            .next()
            .ok_or("a comparison run is missing".to_string())
    };
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
            points: tcp.len(),
            length_mm: tcp.length_m() * 1e3,
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
/// runs) and on the CAM part, with the CSV files and figures in `out`. `quick` shortens the CAM
/// part to its first levels.
pub(crate) fn study(
    cell: &CellConfig,
    model: &Robot,
    seed: u64,
    quick: bool,
    cone: (&ToolPath, &FormingRun, &FormingRun),
    out: &std::path::Path,
) -> Result<(CompensationStudy, Vec<crate::figures::Figure>), String> {
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
    let part = part.subdivided(MAX_SEGMENT_MM).map_err(|e| e.to_string())?;
    let (part_numbers, part_runs) = compare_part(cell, model, &part, seed, &plan, None, None)?;
    let study = CompensationStudy {
        simulated: true,
        lead_s: plan.lead_s,
        lag_definition: lag_definition(),
        parts: vec![cone_numbers, part_numbers],
    };
    let runs = [cone_runs, part_runs];
    page::write_files(out, &study, &runs)?;
    let figures = page::figures(out, &runs)?;
    Ok((study, figures))
}

/// One line for the terminal: the max error of each way on each part.
pub(crate) fn one_line(study: &CompensationStudy) -> String {
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
