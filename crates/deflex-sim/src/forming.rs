//! The forming run: its summary (`summary.json`) and profiles, and [`run_forming`] which drives a
//! [`Cell`] with an optional correction controller. The ground-truth log and the running
//! statistics are [`crate::forming_log`]'s (re-exported here); the run's folder and plots are
//! `deflex_app::report::forming_run`'s.

use crate::cell::{Cell, CellStep, ControllerInput, CorrectionController, SensorSample};
use crate::cell_config::CellConfig;
use crate::error::SimError;
pub use crate::forming_log::{FormingLog, FormingLogRow, RunningStats};
use crate::toolpath::ToolPath;
use nalgebra::Vector3;
use serde::Serialize;
use std::fmt::Write as _;

/// Summary of a forming run (`summary.json`).
#[derive(Clone, Debug, PartialEq, Serialize)]
#[allow(non_snake_case)]
pub struct FormingSummary {
    /// Always true: this is the digital twin.
    pub simulated: bool,
    /// The robot the twin played.
    pub robot: String,
    /// Path name.
    pub path: String,
    /// Seed.
    pub seed: u64,
    /// Whether a correction controller ran.
    pub correction: bool,
    /// Simulated duration (s).
    pub duration_s: f64,
    /// Controller cycles.
    pub cycles: u64,
    /// Largest TCP error norm, true − desired (mm).
    pub max_error_norm_mm: f64,
    /// RMS TCP error norm over the run (mm).
    pub rms_error_norm_mm: f64,
    /// Largest |error| along x_p, y_p, z_p (mm).
    pub max_error_abs_mm: [f64; 3],
    /// Largest contact force norm (N).
    pub max_force_norm_N: f64,
    /// Largest vertical contact force (N).
    pub max_fz_N: f64,
    /// Largest in-plane contact force (N).
    pub max_fxy_N: f64,
    /// Largest correction applied (mm).
    pub max_correction_mm: f64,
    /// Aerens steady-state level for this path at the programmed step-down and wall angle (N;
    /// 0 against a fixture).
    pub aerens_steady_fz_N: f64,
    /// Aerens level at the actual step-down and wall angle at the end of the run (N; 0 against a
    /// fixture).
    pub aerens_actual_fz_N: f64,
    /// Smoothed actual step-down (mm) and wall angle (deg) at the end of the run (0 against a
    /// fixture).
    pub actual_step_down_mm: f64,
    /// See `actual_step_down_mm`.
    pub actual_wall_angle_deg: f64,
    /// Programmed depth (mm).
    pub target_depth_mm: f64,
    /// Deepest point of the formed part (mm below the undeformed sheet); against a fixture, the
    /// deepest penetration.
    pub final_part_depth_mm: f64,
    /// F/T samples clipped at the sensor range.
    pub saturated_samples: u64,
}

/// A finished run: log, summary, formed profile and the wall time.
#[derive(Clone, Debug)]
pub struct FormingRun {
    /// Ground-truth log.
    pub log: FormingLog,
    /// Summary.
    pub summary: FormingSummary,
    /// Formed profile along the ray at θ = 0: (r mm, depth mm).
    pub profile_mm: Vec<(f64, f64)>,
    /// Programmed profile along the same ray, on the same radii: what a rigid robot following
    /// the desired path exactly would have formed ([`crate::sheet::Sheet::programmed_profile`]);
    /// empty against a fixture.
    pub programmed_profile_mm: Vec<(f64, f64)>,
    /// Wall-clock time of the simulation (s), not part of the deterministic output.
    pub wall_time_s: f64,
}

/// Runs the forming (open loop when `controller` is `None`) in simulated time, calling the
/// controller every `period_s`.
pub fn run_forming(
    config: &CellConfig,
    path: ToolPath,
    seed: u64,
    controller: Option<&mut dyn CorrectionController>,
) -> Result<FormingRun, SimError> {
    run_forming_with_progress(config, path, seed, controller, &mut |_| {})
}

/// [`run_forming`] with a progress callback receiving the completed fraction (0..1) about every
/// simulated second.
pub fn run_forming_with_progress(
    config: &CellConfig,
    path: ToolPath,
    seed: u64,
    controller: Option<&mut dyn CorrectionController>,
    progress: &mut dyn FnMut(f64),
) -> Result<FormingRun, SimError> {
    run_program_with_progress(config, path, None, seed, controller, progress)
}

/// [`run_forming_with_progress`] for a robot program `program` that means the path
/// `reference` (an offline-compensated program, one waypoint per reference waypoint; see
/// [`Cell::with_reference`]): the errors, the log's desired positions and the summary's target
/// depth are the reference's. `None`: the program is its own reference.
pub fn run_program_with_progress(
    config: &CellConfig,
    program: ToolPath,
    reference: Option<&ToolPath>,
    seed: u64,
    controller: Option<&mut dyn CorrectionController>,
    progress: &mut dyn FnMut(f64),
) -> Result<FormingRun, SimError> {
    run_program_observed(config, program, reference, seed, controller, None, progress)
}

/// Watches a run cycle by cycle, after the controller (if any) was called: a telemetry stream
/// of the twin's truth, a live view's pacing. It sees the ground truth; it never changes the
/// run, but it may end it early.
pub trait CycleObserver {
    /// Called after every robot cycle with the cell and what the cycle reported. Returning
    /// `false` stops the run ([`SimError::Stopped`]).
    fn observe(&mut self, cell: &Cell, step: &CellStep) -> bool;
}

/// [`run_program_with_progress`] with an `observer` called after every robot cycle.
pub fn run_program_observed(
    config: &CellConfig,
    program: ToolPath,
    reference: Option<&ToolPath>,
    seed: u64,
    mut controller: Option<&mut dyn CorrectionController>,
    mut observer: Option<&mut dyn CycleObserver>,
    progress: &mut dyn FnMut(f64),
) -> Result<FormingRun, SimError> {
    let start = std::time::Instant::now();
    let target_depth_mm = reference
        .unwrap_or(&program)
        .waypoints
        .iter()
        .map(|w| -w.p_mm[2])
        .fold(0.0, f64::max);
    let mut cell = Cell::with_reference(config, program, reference, seed)?;
    let duration = cell.path_duration_s().max(1e-9);
    let period = match controller.as_ref() {
        Some(c) => {
            let p = c.period_s();
            if !(p.is_finite() && p > 0.0) {
                return Err(SimError::config(
                    "controller.period_s",
                    format!("must be positive, got {p}"),
                ));
            }
            p
        }
        None => f64::INFINITY,
    };
    let mut step = CellStep::default();
    let mut pending: Vec<SensorSample> = Vec::with_capacity(1024);
    let mut next_call = 0.0;
    let mut saturated = 0u64;
    let per_second = (1.0 / cell.robot_period_s()).round().max(1.0) as u64;
    loop {
        cell.step_into(&mut step);
        saturated += step.sensor_samples.iter().filter(|s| s.saturated).count() as u64;
        if let Some(ctrl) = controller.as_mut() {
            pending.extend_from_slice(&step.sensor_samples);
            if step.time_s + 1e-9 >= next_call {
                let xi = ctrl.step(&ControllerInput {
                    time_s: step.time_s,
                    q_measured_rad: &step.q_measured_rad,
                    wrench_samples: &pending,
                    truth: cell.truth(),
                });
                cell.set_correction(xi);
                pending.clear();
                while next_call <= step.time_s + 1e-9 {
                    next_call += period;
                }
            }
        }
        if let Some(obs) = observer.as_mut()
            && !obs.observe(&cell, &step)
        {
            return Err(SimError::Stopped {
                time_s: step.time_s,
            });
        }
        if step.cycle % per_second == 0 {
            progress((step.time_s / duration).min(1.0));
        }
        if step.finished {
            break;
        }
    }
    progress(1.0);
    let stats = cell.stats().clone();
    let to_mm = |profile: Vec<(f64, f64)>| -> Vec<(f64, f64)> {
        profile
            .into_iter()
            .map(|(r, d)| (r * 1e3, d * 1e3))
            .collect()
    };
    let (aerens, actual, (step_mm, angle), depth, profile_mm, programmed_profile_mm) =
        match cell.workpiece() {
            crate::cell::Workpiece::Sheet(sheet) => {
                let desired: Vec<Vector3<f64>> =
                    cell.log().rows.iter().map(|r| r.truth.desired_m).collect();
                (
                    sheet.steady_force_n(),
                    sheet.level_force_n(),
                    sheet.actual_step_and_angle(),
                    sheet.max_depth_m(),
                    to_mm(sheet.profile(0.0)),
                    to_mm(sheet.programmed_profile(&desired)),
                )
            }
            crate::cell::Workpiece::Fixture(f) => {
                (0.0, 0.0, (0.0, 0.0), f.deepest_m(), Vec::new(), Vec::new())
            }
            crate::cell::Workpiece::Prescribed(f) => {
                (0.0, 0.0, (0.0, 0.0), f.deepest_m(), Vec::new(), Vec::new())
            }
        };
    let summary = FormingSummary {
        simulated: true,
        robot: cell.robot_name().to_string(),
        path: cell.log().path_name.clone(),
        seed,
        correction: controller.is_some(),
        duration_s: step.time_s,
        cycles: stats.cycles,
        max_error_norm_mm: stats.max_error_norm_m * 1e3,
        rms_error_norm_mm: stats.rms_error_norm_m() * 1e3,
        max_error_abs_mm: stats.max_error_abs_m.map(|v| v * 1e3),
        max_force_norm_N: stats.max_force_norm_n,
        max_fz_N: stats.max_fz_n,
        max_fxy_N: stats.max_fxy_n,
        max_correction_mm: stats.max_correction_m * 1e3,
        aerens_steady_fz_N: aerens,
        aerens_actual_fz_N: actual,
        actual_step_down_mm: step_mm,
        actual_wall_angle_deg: angle,
        target_depth_mm,
        final_part_depth_mm: depth * 1e3,
        saturated_samples: saturated,
    };
    Ok(FormingRun {
        log: cell.log().clone(),
        summary,
        profile_mm,
        programmed_profile_mm,
        wall_time_s: start.elapsed().as_secs_f64(),
    })
}

impl FormingRun {
    /// `summary.json` text (with `"simulated": true` and the wall time), pretty-printed. A
    /// serialisation failure is returned, never written as an empty file.
    pub fn summary_json(&self) -> Result<String, serde_json::Error> {
        let mut value = serde_json::to_value(&self.summary)?;
        if let Some(map) = value.as_object_mut() {
            map.insert("wall_time_s".into(), serde_json::json!(self.wall_time_s));
        }
        serde_json::to_string_pretty(&value)
    }

    /// `profile.csv` text: the formed profile along θ = 0 beside the programmed one (mm), with
    /// a SIMULATED header line. (The run's folder, with its plots, is written by
    /// `deflex_app::report::forming`.)
    pub fn profile_csv(&self) -> String {
        let mut profile = format!(
            "# SIMULATED formed profile along θ = 0 (depth below the undeformed sheet) beside the \
             programmed one (a rigid robot on the desired path, no springback); robot: {}\n\
             r_mm,depth_mm,programmed_depth_mm\n",
            self.summary.robot
        );
        for (k, (r, d)) in self.profile_mm.iter().enumerate() {
            match self.programmed_profile_mm.get(k) {
                Some((_, p)) => {
                    let _ = writeln!(profile, "{r:.3},{d:.5},{p:.5}");
                }
                None => {
                    let _ = writeln!(profile, "{r:.3},{d:.5},");
                }
            }
        }
        profile
    }
}
