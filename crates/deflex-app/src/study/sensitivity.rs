//! Sensitivity of the closed loop to what a real cell gets wrong (issue 11, item 5): the
//! correction's delay, the model's compliance scale, the F/T gain error, the drift of its bias
//! and the contact stiffness, each varied around the cell's own values with everything else on.
//!
//! The runs use the **sensitivity cone**: the paper's cone (Ø40 mm, 45°, 15 mm deep) with a 1 mm
//! step-down instead of 0.24 mm (≈ 120 s instead of 494 s) and the sheet's strength scaled so
//! that its Aerens force level equals the paper cone's (the level grows as Δh^0.09 with the
//! scallop height of the larger step). Each condition is one open-loop and one closed-loop run;
//! the improvement is that of the maximum path error norm. Runs are independent and seeded, so
//! they are spread over threads without changing a number.

use crate::study::DemoError;
use deflex_model::{Axis, EdofSite, Robot};
use deflex_sim::sheet::{aerens_fz, scallop_height_mm};
use deflex_sim::twin::{controller_config_for, run_closed_loop};
use deflex_sim::{CellConfig, ConeParams, ToolPath};
use serde::Serialize;

/// What to vary. Empty lists leave a factor out.
#[derive(Clone, Debug, Serialize)]
pub struct SensitivityPlan {
    /// Correction delays of the robot controller (s), 0–1.
    pub delays_s: Vec<f64>,
    /// Compliance scale of the controller's model (1.3 = a model 30 % too soft), 0.1–10.
    pub model_scales: Vec<f64>,
    /// F/T gain errors applied to every channel (relative, ±0.5).
    pub gain_errors: Vec<f64>,
    /// Bias drift as a multiple of the cell's documented drift, 0–1000.
    pub drift_factors: Vec<f64>,
    /// Contact stiffness of the sheet under the tool (N/m), 10⁴–10⁹.
    pub contact_stiffness_n_m: Vec<f64>,
    /// Threads (1–64).
    pub threads: usize,
    /// Only the first part of the sensitivity cone (mm of travel), for tests.
    pub length_mm: Option<f64>,
}

impl SensitivityPlan {
    /// The full study of `deflex sim sensitivity`: delay 8/20/40/60 ms × model scale
    /// 0.7/0.85/1/1.15/1.3 as a heatmap, gain −5/0/+5 %, drift 0/1/10×, contact stiffness
    /// 10⁵/10⁶/10⁷/10⁸ N/m.
    pub fn full() -> SensitivityPlan {
        SensitivityPlan {
            delays_s: vec![0.008, 0.020, 0.040, 0.060],
            model_scales: vec![0.7, 0.85, 1.0, 1.15, 1.3],
            gain_errors: vec![-0.05, 0.0, 0.05],
            drift_factors: vec![0.0, 1.0, 10.0],
            contact_stiffness_n_m: vec![1e5, 1e6, 1e7, 1e8],
            threads: 2,
            length_mm: None,
        }
    }

    /// The demo's section: delay 8/30/60 ms × scale 0.7/1/1.3, gain ±5 %, drift 0/10×,
    /// contact 10⁵/10⁶/10⁸ N/m.
    pub fn demo() -> SensitivityPlan {
        SensitivityPlan {
            delays_s: vec![0.008, 0.030, 0.060],
            model_scales: vec![0.7, 1.0, 1.3],
            gain_errors: vec![-0.05, 0.05],
            drift_factors: vec![0.0, 10.0],
            contact_stiffness_n_m: vec![1e5, 1e6, 1e8],
            threads: 2,
            length_mm: None,
        }
    }

    /// Check every value; messages name the option.
    pub fn validate(&self) -> Result<(), SensitivityPlanError> {
        use SensitivityPlanError as E;
        let check = |option: &'static str, values: &[f64], lo: f64, hi: f64| {
            if values.len() > MAX_VALUES {
                return Err(E::TooManyValues {
                    option,
                    count: values.len(),
                });
            }
            match values
                .iter()
                .find(|v| !(v.is_finite() && **v >= lo && **v <= hi))
            {
                Some(&value) => Err(E::OutOfRange {
                    option,
                    value,
                    lo,
                    hi,
                }),
                None => Ok(()),
            }
        };
        check("--delays-ms (s)", &self.delays_s, 0.0, 1.0)?;
        check("--model-scales", &self.model_scales, 0.1, 10.0)?;
        for (option, values) in [
            ("--delays-ms", &self.delays_s),
            ("--model-scales", &self.model_scales),
        ] {
            if values.windows(2).any(|w| w[1] <= w[0]) {
                return Err(E::NotIncreasing { option });
            }
        }
        check("--gain-errors", &self.gain_errors, -0.5, 0.5)?;
        check("--drift-factors", &self.drift_factors, 0.0, 1000.0)?;
        check(
            "--contact-stiffness-n-m",
            &self.contact_stiffness_n_m,
            1e4,
            1e9,
        )?;
        if !(1..=64).contains(&self.threads) {
            return Err(E::Threads { got: self.threads });
        }
        if let Some(l) = self.length_mm
            && !(l.is_finite() && l > 0.0 && l <= 1e5)
        {
            return Err(E::Length { got: l });
        }
        Ok(())
    }
}

/// Most values per factor.
pub const MAX_VALUES: usize = 20;

/// A sensitivity plan outside its ranges; the message names the `deflex sim sensitivity` option.
#[derive(Clone, Debug, PartialEq, thiserror::Error)]
pub enum SensitivityPlanError {
    /// More than [`MAX_VALUES`] values.
    #[error("{option}: at most 20 values, got {count}")]
    TooManyValues {
        /// The option.
        option: &'static str,
        /// Values given.
        count: usize,
    },
    /// A value outside its range (or not finite).
    #[error("{option}: {value} is outside {lo}..{hi}")]
    OutOfRange {
        /// The option.
        option: &'static str,
        /// The value.
        value: f64,
        /// Smallest allowed.
        lo: f64,
        /// Largest allowed.
        hi: f64,
    },
    /// Values that do not increase.
    #[error("{option}: give increasing values")]
    NotIncreasing {
        /// The option.
        option: &'static str,
    },
    /// Threads outside 1–64.
    #[error("--threads: 1..64, got {got}")]
    Threads {
        /// Threads asked for.
        got: usize,
    },
    /// A path length outside (0, 100 000] mm.
    #[error("--length-mm: within (0, 100000], got {got}")]
    Length {
        /// The length given (mm).
        got: f64,
    },
}

/// One condition of the study.
#[derive(Clone, Debug, Serialize)]
#[allow(non_snake_case)]
pub struct SensitivityRow {
    /// Factor varied (`delay`, `model scale`, `gain error`, `bias drift`, `contact stiffness`,
    /// or `delay × model scale` for the heatmap cells).
    pub factor: String,
    /// Condition, human readable (`40 ms, ×1.30`).
    pub condition: String,
    /// The same condition as table columns, one unit per column: `(header with unit, value)`,
    /// e.g. `("delay [ms]", "40")`, `("model compliance scale [×]", "1.30")`.
    pub condition_columns: Vec<(String, String)>,
    /// Max path error norm without correction (mm).
    pub open_max_mm: f64,
    /// Max path error norm with correction (mm).
    pub closed_max_mm: f64,
    /// RMS path error norm with correction (mm).
    pub closed_rms_mm: f64,
    /// `100 (1 − closed/open)` of the max error norm (%).
    pub improvement_percent: f64,
    /// Largest contact force norm with correction (N).
    pub closed_max_force_N: f64,
    /// Latched controller fault, if any.
    pub fault: Option<String>,
}

/// The study's result.
#[derive(Clone, Debug, Serialize)]
pub struct SensitivityResult {
    /// The robot the twin played.
    pub robot: String,
    /// Every condition, the heatmap cells first.
    pub rows: Vec<SensitivityRow>,
    /// Heatmap axes: delays (s) and model scales, and the improvement (%) per cell, row-major
    /// with the scale outer.
    pub heatmap_delays_s: Vec<f64>,
    /// See `heatmap_delays_s`.
    pub heatmap_scales: Vec<f64>,
    /// See `heatmap_delays_s`.
    pub heatmap_improvement_percent: Vec<f64>,
    /// Runs made.
    pub runs: usize,
}

/// The sensitivity cone for a cell and the cell with its sheet strength scaled so that the
/// Aerens level of the 1 mm step-down equals that of the paper's 0.24 mm.
pub fn sensitivity_cone(cell: &CellConfig) -> Result<(ToolPath, CellConfig), DemoError> {
    let paper = ConeParams::default();
    let fast = ConeParams {
        step_down_mm: 1.0,
        ..ConeParams::default()
    };
    let s = &cell.sheet;
    let r = s.tool_diameter_mm / 2.0;
    let level = |step: f64| {
        aerens_fz(
            s.rm_mpa,
            s.thickness_mm,
            s.tool_diameter_mm,
            scallop_height_mm(r, step, paper.wall_angle_deg),
            paper.wall_angle_deg,
        )
    };
    let mut scaled = cell.clone();
    scaled.sheet.rm_mpa *= level(paper.step_down_mm) / level(fast.step_down_mm);
    let mut path = ToolPath::cone(&fast)?;
    path.name = format!("sensitivity cone ({})", path.name);
    Ok((path, scaled))
}

/// The model with every compliance multiplied by `scale` (stiffnesses divided by it).
pub fn scaled_model(model: &Robot, scale: f64) -> Robot {
    let mut out = model.clone();
    for axis in Axis::ALL {
        if let Some(k) = out.base_stiffness.get(axis) {
            out.base_stiffness.set(axis, Some(k / scale));
        }
    }
    for i in 1..=out.joint_count() {
        for axis in Axis::ALL {
            if let Some(k) = out.stiffness(EdofSite::Joint(i), axis) {
                out.set_stiffness(EdofSite::Joint(i), axis, Some(k / scale));
            }
        }
    }
    out
}

/// One run to make: a cell, a model scale, whether closed loop.
struct Job {
    factor: String,
    condition: String,
    columns: Vec<(String, String)>,
    cell: CellConfig,
    scale: f64,
}

struct Outcome {
    max_mm: f64,
    rms_mm: f64,
    force_n: f64,
    fault: Option<String>,
}

fn run_job(
    job: &Job,
    path: &ToolPath,
    model: &Robot,
    seed: u64,
    closed: bool,
) -> Result<Outcome, DemoError> {
    if closed {
        let run = run_closed_loop(
            &job.cell,
            path.clone(),
            seed,
            scaled_model(model, job.scale),
            controller_config_for(&job.cell),
            false,
            &mut |_| {},
        )
        .map_err(DemoError::from)?;
        let s = &run.forming.summary;
        Ok(Outcome {
            max_mm: s.max_error_norm_mm,
            rms_mm: s.rms_error_norm_mm,
            force_n: s.max_force_norm_N,
            fault: run.fault.map(|f| f.to_string()),
        })
    } else {
        let run = deflex_sim::run_forming(&job.cell, path.clone(), seed, None)?;
        let s = &run.summary;
        Ok(Outcome {
            max_mm: s.max_error_norm_mm,
            rms_mm: s.rms_error_norm_mm,
            force_n: s.max_force_norm_N,
            fault: None,
        })
    }
}

/// One closed-loop job per condition of `plan`, on the sensitivity cell `base` and `path`: the
/// delay × model-scale cells first, then gain, drift and contact stiffness.
fn sensitivity_jobs(plan: &SensitivityPlan, base: &CellConfig, path: &ToolPath) -> Vec<Job> {
    let mut jobs: Vec<Job> = Vec::new();
    let with = |f: &dyn Fn(&mut CellConfig)| {
        let mut c = base.clone();
        f(&mut c);
        c
    };
    for &scale in &plan.model_scales {
        for &delay in &plan.delays_s {
            jobs.push(Job {
                factor: "delay × model scale".into(),
                condition: format!("{:.0} ms, ×{scale:.2}", delay * 1e3),
                columns: vec![
                    ("delay [ms]".into(), format!("{:.0}", delay * 1e3)),
                    ("model compliance scale [×]".into(), format!("{scale:.2}")),
                ],
                cell: with(&|c| c.controller.correction_delay_s = delay),
                scale,
            });
        }
    }
    for &g in &plan.gain_errors {
        jobs.push(Job {
            factor: "gain error".into(),
            condition: format!("{:+.1} %", g * 100.0),
            columns: vec![("F/T gain error [%]".into(), format!("{:+.1}", g * 100.0))],
            cell: with(&|c| {
                c.errors.sensor_gain = true;
                c.sensor.gain_error = [g; 6];
            }),
            scale: 1.0,
        });
    }
    for &d in &plan.drift_factors {
        let drift_n =
            d * base.sensor.bias_drift_per_s[2] * path.duration_s(base.controller.rapid_feed_mm_s);
        jobs.push(Job {
            factor: "bias drift".into(),
            condition: format!("×{d} ({drift_n:.1} N of Fz over the run)"),
            columns: vec![
                ("bias drift [× the cell's]".into(), format!("{d}")),
                ("Fz drift over the run [N]".into(), format!("{drift_n:.1}")),
            ],
            cell: with(&|c| {
                c.errors.bias_drift = true;
                c.sensor.bias_drift_per_s = c.sensor.bias_drift_per_s.map(|v| v * d);
            }),
            scale: 1.0,
        });
    }
    for &k in &plan.contact_stiffness_n_m {
        jobs.push(Job {
            factor: "contact stiffness".into(),
            condition: format!("{k:.0e} N/m"),
            columns: vec![("contact stiffness [N/m]".into(), format!("{k:.0e}"))],
            cell: with(&|c| c.sheet.contact_stiffness_n_mm = k * 1e-3),
            scale: 1.0,
        });
    }
    jobs
}

/// Run the study for `cell` with the controller's (identified) `model`; `progress` receives the
/// fraction of runs done.
pub fn run_sensitivity(
    cell: &CellConfig,
    model: &Robot,
    plan: &SensitivityPlan,
    seed: u64,
    progress: &(dyn Fn(f64) + Sync),
) -> Result<SensitivityResult, DemoError> {
    plan.validate()?;
    let (mut path, base) = sensitivity_cone(cell)?;
    if let Some(l) = plan.length_mm {
        path = path.truncated(l);
    }
    let jobs = sensitivity_jobs(plan, &base, &path);
    // Open loop depends on the cell's plant and process only: one run per distinct process.
    let open_key = |c: &CellConfig| c.sheet.contact_stiffness_n_mm.to_bits();
    let mut open_cells: Vec<(u64, CellConfig)> = Vec::new();
    for job in &jobs {
        if !open_cells.iter().any(|(k, _)| *k == open_key(&job.cell)) {
            let mut c = job.cell.clone();
            c.controller = base.controller.clone();
            c.sensor = base.sensor.clone();
            c.errors = base.errors.clone();
            open_cells.push((open_key(&job.cell), c));
        }
    }
    let total = jobs.len() + open_cells.len();
    let done = std::sync::atomic::AtomicUsize::new(0);
    let work: Vec<(usize, bool)> = (0..open_cells.len())
        .map(|i| (i, false))
        .chain((0..jobs.len()).map(|i| (i, true)))
        .collect();
    let next = std::sync::atomic::AtomicUsize::new(0);
    let results: std::sync::Mutex<Vec<Option<Result<Outcome, DemoError>>>> =
        std::sync::Mutex::new((0..work.len()).map(|_| None).collect());
    std::thread::scope(|scope| {
        for _ in 0..plan.threads.min(work.len()).max(1) {
            scope.spawn(|| {
                loop {
                    let w = next.fetch_add(1, std::sync::atomic::Ordering::Relaxed);
                    let Some(&(i, closed)) = work.get(w) else {
                        break;
                    };
                    let outcome = if closed {
                        run_job(&jobs[i], &path, model, seed, true)
                    } else {
                        let job = Job {
                            factor: String::new(),
                            condition: String::new(),
                            columns: Vec::new(),
                            cell: open_cells[i].1.clone(),
                            scale: 1.0,
                        };
                        run_job(&job, &path, model, seed, false)
                    };
                    if let Ok(mut r) = results.lock() {
                        r[w] = Some(outcome);
                    }
                    let n = done.fetch_add(1, std::sync::atomic::Ordering::Relaxed) + 1;
                    progress(n as f64 / total as f64);
                }
            });
        }
    });
    let results = results.into_inner().map_err(|_| DemoError::Worker {
        what: "a sensitivity run panicked",
    })?;
    let mut outcomes = Vec::with_capacity(results.len());
    for r in results {
        outcomes.push(r.ok_or(DemoError::Worker {
            what: "a sensitivity run did not finish",
        })??);
    }
    let (open, closed) = outcomes.split_at(open_cells.len());
    let mut rows = Vec::with_capacity(jobs.len());
    for (job, c) in jobs.iter().zip(closed) {
        let o = open_cells
            .iter()
            .position(|(k, _)| *k == open_key(&job.cell))
            .map(|i| &open[i])
            .ok_or(DemoError::Worker {
                what: "missing open-loop run",
            })?;
        rows.push(SensitivityRow {
            factor: job.factor.clone(),
            condition: job.condition.clone(),
            condition_columns: job.columns.clone(),
            open_max_mm: o.max_mm,
            closed_max_mm: c.max_mm,
            closed_rms_mm: c.rms_mm,
            improvement_percent: 100.0 * (1.0 - c.max_mm / o.max_mm),
            closed_max_force_N: c.force_n,
            fault: c.fault.clone(),
        });
    }
    let cells = plan.delays_s.len() * plan.model_scales.len();
    Ok(SensitivityResult {
        robot: crate::twin::robot_name(cell),
        heatmap_improvement_percent: rows[..cells]
            .iter()
            .map(|r| r.improvement_percent)
            .collect(),
        heatmap_delays_s: plan.delays_s.clone(),
        heatmap_scales: plan.model_scales.clone(),
        rows,
        runs: total,
    })
}
