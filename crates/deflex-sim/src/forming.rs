//! The forming run: ground-truth log, running statistics, summary, outputs (CSV log,
//! `summary.json`, PNG plots), and [`run_forming`] which drives a [`Cell`] with an optional
//! correction controller.

use crate::cell::{
    Cell, CellStep, ControllerInput, CorrectionController, SensorSample, TruthState,
};
use crate::config::CellConfig;
use crate::error::SimError;
use crate::toolpath::ToolPath;
use nalgebra::Vector3;
use serde::Serialize;
use std::fmt::Write as _;
use std::path::Path;

/// One logged row (ground truth plus what the sensors reported).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct LogRow {
    /// Simulated time (s).
    pub time_s: f64,
    /// Ground truth of the cycle.
    pub truth: TruthState,
    /// Laser-tracker reading of the TCP, R_p (m).
    pub tracked_m: Vector3<f64>,
    /// Last raw F/T sample of the cycle.
    pub sensor: SensorSample,
}

/// The ground-truth log of a run, at the configured log rate (evaluation only).
#[derive(Clone, Debug, Default, PartialEq)]
pub struct FormingLog {
    /// Path name.
    pub path_name: String,
    /// The robot the twin played.
    pub robot: String,
    /// Seed of the run.
    pub seed: u64,
    /// Rows, in time order.
    pub rows: Vec<LogRow>,
}

impl FormingLog {
    pub(crate) fn with_capacity(
        path_name: &str,
        robot: &str,
        seed: u64,
        rows: usize,
    ) -> FormingLog {
        FormingLog {
            path_name: path_name.to_string(),
            robot: robot.to_string(),
            seed,
            rows: Vec::with_capacity(rows),
        }
    }

    pub(crate) fn push(&mut self, row: LogRow) {
        self.rows.push(row);
    }

    /// The log as CSV text (mm, N, N·m, mrad), with a `# SIMULATED` header comment.
    pub fn to_csv(&self) -> String {
        let mut s = String::with_capacity(self.rows.len() * 400 + 512);
        let _ = writeln!(
            s,
            "# SIMULATED deflex digital twin forming log (not a measurement). robot: {}; path: {}; seed: {}",
            self.robot, self.path_name, self.seed
        );
        let _ = writeln!(
            s,
            "# positions in the part frame R_p (mm); wrench on the tool at the TCP, R_p axes (N, N·m); \
             sensor = last raw F/T sample of the cycle, sensor frame; error = true − desired"
        );
        s.push_str(
            "time_s,des_x_mm,des_y_mm,des_z_mm,cmd_x_mm,cmd_y_mm,cmd_z_mm,true_x_mm,true_y_mm,true_z_mm,\
             tracked_x_mm,tracked_y_mm,tracked_z_mm,err_x_mm,err_y_mm,err_z_mm,err_norm_mm,\
             fx_N,fy_N,fz_N,mx_Nm,my_Nm,mz_Nm,sensor_fx_N,sensor_fy_N,sensor_fz_N,sensor_tx_Nm,\
             sensor_ty_Nm,sensor_tz_Nm,sensor_saturated,corr_x_mm,corr_y_mm,corr_z_mm,corr_rx_mrad,\
             corr_ry_mrad,corr_rz_mrad,penetration_mm,flow_level_N,tool_depth_mm\n",
        );
        for r in &self.rows {
            let t = &r.truth;
            let e = t.path_error_m();
            let _ = write!(s, "{:.4}", r.time_s);
            for v in [t.desired_m, t.commanded_m, t.true_m, r.tracked_m, e] {
                let _ = write!(s, ",{:.5},{:.5},{:.5}", v.x * 1e3, v.y * 1e3, v.z * 1e3);
            }
            let _ = write!(s, ",{:.5}", e.norm() * 1e3);
            for v in t.wrench.iter() {
                let _ = write!(s, ",{v:.3}");
            }
            for v in r.sensor.wrench_sensor {
                let _ = write!(s, ",{v:.3}");
            }
            let _ = write!(s, ",{}", r.sensor.saturated as u8);
            // m → mm and rad → mrad.
            for v in t.correction.iter() {
                let _ = write!(s, ",{:.5}", v * 1e3);
            }
            let _ = writeln!(
                s,
                ",{:.5},{:.2},{:.4}",
                t.contact.penetration_m * 1e3,
                t.contact.flow_n,
                t.contact.depth_m * 1e3
            );
        }
        s
    }

    /// Column of a per-row quantity.
    pub fn column(&self, f: impl Fn(&LogRow) -> f64) -> Vec<f64> {
        self.rows.iter().map(f).collect()
    }
}

/// Statistics over every controller cycle.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct RunningStats {
    /// Cycles counted.
    pub cycles: u64,
    /// Cycles with the tool in contact.
    pub contact_cycles: u64,
    sum_sq_error: f64,
    /// Largest error norm (m).
    pub max_error_norm_m: f64,
    /// Largest |error| per axis (m).
    pub max_error_abs_m: [f64; 3],
    /// Largest force norm (N).
    pub max_force_norm_n: f64,
    /// Largest vertical force (N).
    pub max_fz_n: f64,
    /// Largest in-plane force norm (N).
    pub max_fxy_n: f64,
    /// Largest correction norm (m).
    pub max_correction_m: f64,
}

impl RunningStats {
    pub(crate) fn add(&mut self, t: &TruthState) {
        let e = t.path_error_m();
        let n = e.norm();
        self.cycles += 1;
        if t.wrench[2] > 0.0 {
            self.contact_cycles += 1;
        }
        self.sum_sq_error += n * n;
        self.max_error_norm_m = self.max_error_norm_m.max(n);
        for i in 0..3 {
            self.max_error_abs_m[i] = self.max_error_abs_m[i].max(e[i].abs());
        }
        let f = t.wrench.fixed_rows::<3>(0);
        self.max_force_norm_n = self.max_force_norm_n.max(f.norm());
        self.max_fz_n = self.max_fz_n.max(f[2]);
        self.max_fxy_n = self.max_fxy_n.max(f[0].hypot(f[1]));
        let c = &t.correction;
        self.max_correction_m = self
            .max_correction_m
            .max((c[0] * c[0] + c[1] * c[1] + c[2] * c[2]).sqrt());
    }

    /// RMS of the error norm over all cycles (m).
    pub fn rms_error_norm_m(&self) -> f64 {
        if self.cycles == 0 {
            0.0
        } else {
            (self.sum_sq_error / self.cycles as f64).sqrt()
        }
    }
}

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
    /// `summary.json` text (with `"simulated": true` and the wall time).
    pub fn summary_json(&self) -> String {
        let mut value = serde_json::to_value(&self.summary).unwrap_or_default();
        if let Some(map) = value.as_object_mut() {
            map.insert("wall_time_s".into(), serde_json::json!(self.wall_time_s));
        }
        serde_json::to_string_pretty(&value).unwrap_or_default()
    }

    /// Write `log.csv`, `summary.json`, `profile.csv` and the PNG plots into the folder `dir`,
    /// whole or not at all: the folder is built aside and swapped in at the end (an existing
    /// `dir` is replaced only then). Returns the files written.
    pub fn write_outputs(&self, dir: &Path) -> Result<Vec<std::path::PathBuf>, SimError> {
        let building =
            deflex_files::AtomicDir::create(dir).map_err(|e| SimError::output(dir, e))?;
        let names = self.write_outputs_into(building.path())?;
        building.commit().map_err(|e| SimError::output(dir, e))?;
        Ok(names.into_iter().map(|n| dir.join(n)).collect())
    }

    /// The files of [`Self::write_outputs`] written into an existing folder `temporary` (one
    /// being built aside by the caller, who adds its own files and swaps it in); returns their
    /// names.
    pub fn write_outputs_into(&self, temporary: &Path) -> Result<Vec<String>, SimError> {
        let mut names = Vec::new();
        let mut write = |name: &str, text: String| -> Result<(), SimError> {
            let path = temporary.join(name);
            deflex_files::write_atomic(&path, text).map_err(|e| SimError::output(&path, e))?;
            names.push(name.to_string());
            Ok(())
        };
        write("log.csv", self.log.to_csv())?;
        write("summary.json", self.summary_json())?;
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
        write("profile.csv", profile)?;
        for plot in crate::plots::forming_plots(self, temporary)? {
            if let Some(name) = plot.file_name() {
                names.push(name.to_string_lossy().into_owned());
            }
        }
        Ok(names)
    }
}
