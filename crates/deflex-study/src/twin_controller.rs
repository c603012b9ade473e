//! The deflex correction controller ([`deflex_control::Controller`], eq. 5–7, 15, 17) driving the
//! digital twin in-process, in simulated time: the adapter implements the twin's
//! [`CorrectionController`], so the twin's forming run of the paper's cone (Section 4) becomes
//! closed-loop. The controller only ever sees what hardware would give it: simulated time, the
//! joint values the robot reports and the raw F/T samples of the period (averaged), plus the
//! mounting and tool data an integrator takes from drawings and datasheets. Never the plant.

use deflex_control::{
    Controller, ControllerConfig, CycleInput, CycleOutput, Fault, FeedForward, Phase,
};
use deflex_model::Robot;
use deflex_model::spatial::pose_from_xyz_rpy;
use deflex_sim::{CellConfig, ControllerInput, CorrectionController, FormingRun, ToolPath};
use std::path::Path;

/// The controller configuration for the twin's cell: the paper's gains and the default limits,
/// with the sensor mounting, tool, gravity and sensor range of the cell as an integrator knows
/// them: the **nominal** mounting and tool of the drawings and datasheets, not the twin's true
/// ones (which differ by the documented mounting and tool-load errors). The force limit is twice
/// the cell's forming force level, capped at the controller's default 2500 N (the TX200 cell
/// keeps 2500 N; the UR10e cell gets about 340 N, well inside what its arm and sensor carry).
pub fn controller_config_for(cell: &CellConfig) -> ControllerConfig {
    let mut config = ControllerConfig::default();
    config.safety.max_force_n = config
        .safety
        .max_force_n
        .min((2.0 * cell.forming_force_level_n() / 10.0).round() * 10.0);
    let s = &cell.sensor;
    config.wrench.sensor_in_flange =
        pose_from_xyz_rpy(s.sensor_in_flange_xyz_m, s.sensor_in_flange_rpy);
    config.wrench.tool.mass_kg = s.tool_mass_kg;
    config.wrench.tool.com_in_sensor_m = s.tool_com_in_sensor_m;
    config.wrench.gravity_world = [0.0, 0.0, -s.gravity_m_s2];
    config.safety.sensor_range = s.range;
    config
}

/// [`Controller`] as the twin's [`CorrectionController`]. Keeps a per-cycle trace when asked.
pub struct TwinController {
    ctrl: Controller,
    started: bool,
    last_raw: [f64; 6],
    last_sample_s: f64,
    trace: Option<Vec<CycleOutput>>,
    max_force_n: f64,
}

impl TwinController {
    /// A controller with `model` (calibrated, never the plant) and `config`.
    pub fn new(model: Robot, config: ControllerConfig, keep_trace: bool) -> Result<Self, String> {
        Ok(TwinController {
            ctrl: Controller::new(model, config).map_err(|e| e.to_string())?,
            started: false,
            last_raw: [0.0; 6],
            last_sample_s: f64::NEG_INFINITY,
            trace: keep_trace.then(|| Vec::with_capacity(64 * 1024)),
            max_force_n: 0.0,
        })
    }

    /// Feed-forward plus feedback (`deflex_control::feedforward`): the table of an offline
    /// compensation in the model's world frame, as `deflex run` takes it from `[feedforward]`.
    pub fn set_feedforward(&mut self, feedforward: Option<FeedForward>) {
        self.ctrl.set_feedforward(feedforward);
    }
}

impl CorrectionController for TwinController {
    fn period_s(&self) -> f64 {
        self.ctrl.config().period_s
    }

    fn step(&mut self, input: &ControllerInput) -> [f64; 6] {
        if !self.started {
            self.ctrl.start(input.time_s);
            self.started = true;
        }
        let samples = input.wrench_samples;
        let fresh = !samples.is_empty();
        if fresh {
            // Mean of the period's samples; a clipped sample is passed as is (at the range, which
            // the controller treats as out of range).
            let mut sum = [0.0; 6];
            for s in samples {
                for (acc, v) in sum.iter_mut().zip(s.wrench_sensor) {
                    *acc += v;
                }
            }
            let n = samples.len() as f64;
            self.last_raw = sum.map(|v| v / n);
            if samples.iter().any(|s| s.saturated) {
                let first = samples
                    .iter()
                    .find(|s| s.saturated)
                    .map(|s| s.wrench_sensor);
                if let Some(w) = first {
                    self.last_raw = w;
                }
            }
            self.last_sample_s = samples[samples.len() - 1].time_s;
        }
        let out = self.ctrl.cycle_input(&CycleInput {
            now_s: input.time_s,
            q_rad: input.q_measured_rad,
            q_age_s: 0.0,
            wrench_sensor: &self.last_raw,
            wrench_age_s: input.time_s - self.last_sample_s,
            wrench_fresh: fresh,
            sensor_status: 0,
        });
        let f = &out.wrench_tcp;
        self.max_force_n = self
            .max_force_n
            .max((f[0] * f[0] + f[1] * f[1] + f[2] * f[2]).sqrt());
        if let Some(trace) = self.trace.as_mut() {
            trace.push(out);
        }
        out.xi
    }
}

/// The controller for `deflex sim isf --correction on --model MODEL.toml`: `model` is the
/// identified robot (a `deflex calibrate` output, never the plant); the mounting, tool and
/// sensor range come from the twin's cell settings.
pub fn twin_controller(cell: &CellConfig, model: Option<&Path>) -> Result<TwinController, String> {
    let path =
        model.ok_or("--correction on needs --model MODEL.toml (the identified robot model)")?;
    let robot = deflex_model::load_robot(&path.display().to_string())
        .map_err(|e| format!("--model {}: {e}", path.display()))?;
    TwinController::new(robot, controller_config_for(cell), false)
}

impl TwinController {
    /// One line for the operator: phase, latched fault, largest measured force.
    pub fn status_line(&self) -> String {
        let fault = match self.ctrl.fault() {
            Some(f) => format!("fault {f}"),
            None => "no fault".into(),
        };
        format!(
            "correction controller (eq. 17, Kc {}, Ti {} s, Td {} s, {} Hz): {}, {fault}, max measured |F| {:.0} N",
            self.ctrl.config().gains.kc,
            self.ctrl.config().gains.ti_s,
            self.ctrl.config().gains.td_s,
            1.0 / self.ctrl.config().period_s,
            self.ctrl.phase().name(),
            self.max_force_n
        )
    }
}

/// A closed-loop forming run.
pub struct ClosedLoopRun {
    /// The twin's run (ground truth, summary).
    pub forming: FormingRun,
    /// Final controller phase.
    pub phase: Phase,
    /// Latched fault, if any.
    pub fault: Option<Fault>,
    /// Largest force norm the controller measured at the TCP (N).
    pub max_force_n: f64,
    /// Per-cycle outputs (when kept).
    pub trace: Vec<CycleOutput>,
    /// The controller's status line at the end of the run.
    pub status: String,
    /// Times the contact-runaway guard acted (warnings `contact_runaway`, or the fault).
    pub runaway_events: u64,
    /// The first runaway the guard acted on (a warning record unless the action is `fault`).
    pub first_runaway: Option<Fault>,
}

/// Runs `path` on the twin with the correction on (simulated time, as fast as the CPU allows).
pub fn run_closed_loop(
    cell: &CellConfig,
    path: ToolPath,
    seed: u64,
    model: Robot,
    config: ControllerConfig,
    keep_trace: bool,
    progress: &mut dyn FnMut(f64),
) -> Result<ClosedLoopRun, String> {
    let twin = TwinController::new(model, config, keep_trace)?;
    run_twin_controller(
        cell,
        &Program {
            path,
            reference: None,
        },
        seed,
        twin,
        progress,
    )
}

/// What the twin's robot runs: `path`, meaning `reference` when it is a compensated program
/// (`deflex_sim::run_program_with_progress`).
#[derive(Clone, Debug)]
pub struct Program {
    /// The robot program.
    pub path: ToolPath,
    /// The path it means (`None`: itself).
    pub reference: Option<ToolPath>,
}

/// Runs `program` on the twin with `twin` (a controller set up by the caller, e.g. with a
/// feed-forward).
pub fn run_twin_controller(
    cell: &CellConfig,
    program: &Program,
    seed: u64,
    mut twin: TwinController,
    progress: &mut dyn FnMut(f64),
) -> Result<ClosedLoopRun, String> {
    let forming = deflex_sim::run_program_with_progress(
        cell,
        program.path.clone(),
        program.reference.as_ref(),
        seed,
        Some(&mut twin),
        progress,
    )
    .map_err(|e| e.to_string())?;
    Ok(ClosedLoopRun {
        forming,
        phase: twin.ctrl.phase(),
        fault: twin.ctrl.fault(),
        max_force_n: twin.max_force_n,
        trace: twin.trace.take().unwrap_or_default(),
        status: twin.status_line(),
        runaway_events: twin.ctrl.runaway_events(),
        first_runaway: twin.ctrl.first_runaway(),
    })
}

/// A model identified from the twin's own calibration campaign, the way a user would do it on
/// hardware (plan for the full eDoF family → laser-tracker campaign on the twin → structure
/// search from the nominal model). Never reads the plant. Used by tests and embedders; the demo
/// runs the same steps with its reporting around them.
pub fn identify_from_twin_campaign(cell: &CellConfig, seed: u64) -> Result<Robot, String> {
    let nominal = cell.nominal_robot().map_err(|e| e.to_string())?;
    let options = deflex_stiffness::plan::PlanOptions {
        full_family: true,
        ..deflex_stiffness::plan::PlanOptions::for_a_real_cell()
    };
    let plan =
        deflex_stiffness::plan::plan_experiments(&nominal, &options).map_err(|e| e.to_string())?;
    let rows =
        deflex_sim::campaign::run_campaign(cell, &plan.rows, seed).map_err(|e| e.to_string())?;
    let result = deflex_stiffness::search_structure(
        &nominal,
        &rows,
        &deflex_stiffness::SearchOptions::default(),
        &mut |_, _, _| {},
    )
    .map_err(|e| e.to_string())?;
    Ok(result.calibration.to_robot(&nominal))
}

#[cfg(test)]
mod tests {
    use super::*;

    fn calibrated_model(cell: &CellConfig) -> Robot {
        identify_from_twin_campaign(cell, 11).unwrap()
    }

    fn norm3(v: &[f64]) -> f64 {
        (v[0] * v[0] + v[1] * v[1] + v[2] * v[2]).sqrt()
    }

    /// Mean vertical contact force over the cycles in contact (N).
    fn mean_fz(run: &FormingRun) -> f64 {
        let fz: Vec<f64> = run
            .log
            .rows
            .iter()
            .map(|r| r.truth.wrench[2])
            .filter(|f| *f > 0.0)
            .collect();
        fz.iter().sum::<f64>() / fz.len().max(1) as f64
    }

    struct Comparison {
        open: FormingRun,
        closed: ClosedLoopRun,
    }

    fn compare(path: ToolPath, model: Robot, seed: u64) -> Comparison {
        let cell = CellConfig::default();
        let open = deflex_sim::run_forming(&cell, path.clone(), seed, None).unwrap();
        let config = controller_config_for(&cell);
        let closed = run_closed_loop(&cell, path, seed, model, config, true, &mut |_| {}).unwrap();
        Comparison { open, closed }
    }

    /// The acceptance run: the paper's cone on the twin with every error source on, closed loop
    /// with a model calibrated from the twin's campaign: the maximum error norm improves by ≥ 70 %
    /// (the paper's figure; measured 83 %), without fault, overshoot or instability, and the
    /// process force rises with the correction as in Figs. 18–19 (force norm 1320 → 1472 N
    /// measured, the paper's ≈ 1300 → 1500 N).
    #[test]
    fn paper_cone_closed_loop_with_calibrated_model() {
        let cell = CellConfig::default();
        let c = compare(ToolPath::paper_cone(), calibrated_model(&cell), 1);
        let (o, k) = (&c.open.summary, &c.closed.forming.summary);
        let improvement = 1.0 - k.max_error_norm_mm / o.max_error_norm_mm;
        let trace = &c.closed.trace;
        let max_eps = trace.iter().map(|t| norm3(&t.epsilon)).fold(0.0, f64::max);
        let max_xi = trace.iter().map(|t| norm3(&t.xi)).fold(0.0, f64::max);
        let max_ds = trace
            .iter()
            .map(|t| norm3(&t.delta_s_hat))
            .fold(0.0, f64::max);
        let (fz_open, fz_closed) = (mean_fz(&c.open), mean_fz(&c.closed.forming));
        eprintln!(
            "paper cone: open max {:.3} mm (rms {:.3}), closed max {:.3} mm (rms {:.3}): \
             improvement {:.1} %; max |ε_p| {:.3} mm, max |ξ_p| {:.3} mm, max |δŝ_p| {:.3} mm; \
             mean Fz open {:.0} N, closed {:.0} N; max Fz open {:.0} N, closed {:.0} N; \
             controller max |F| {:.0} N, phase {:?}",
            o.max_error_norm_mm,
            o.rms_error_norm_mm,
            k.max_error_norm_mm,
            k.rms_error_norm_mm,
            improvement * 100.0,
            max_eps * 1e3,
            max_xi * 1e3,
            max_ds * 1e3,
            fz_open,
            fz_closed,
            o.max_fz_N,
            k.max_fz_N,
            c.closed.max_force_n,
            c.closed.phase,
        );
        assert!(
            improvement >= 0.70,
            "improvement {:.1} %",
            improvement * 100.0
        );
        assert!(c.closed.fault.is_none(), "{:?}", c.closed.fault);
        assert_eq!(c.closed.phase, Phase::Running);
        // No overshoot: the correction never exceeds the deflection it cancels.
        assert!(max_xi <= 1.02 * max_ds, "ξ {max_xi} vs δŝ {max_ds}");
        // No instability: the loop error stays a small fraction of the deflection.
        assert!(max_eps <= 0.1 * max_ds, "ε {max_eps} vs δŝ {max_ds}");
        assert!(trace.iter().all(|t| t.xi.iter().all(|v| v.is_finite())));
        // Forces rise with the correction (Fig. 18): the corrected tool reaches the programmed
        // depth and wall angle, where the process pushes back harder.
        assert!(
            fz_closed >= fz_open,
            "mean Fz closed {fz_closed} < open {fz_open}"
        );
        let rise = k.max_force_norm_N / o.max_force_norm_N;
        assert!(
            (1.08..1.30).contains(&rise),
            "max |F| open {} N, closed {} N",
            o.max_force_norm_N,
            k.max_force_norm_N
        );
        // The uncorrected cone reproduces the paper's levels: 3.84 mm ± 25 %, Fz 1.2–1.3 kN.
        assert!((2.88..=4.80).contains(&o.max_error_norm_mm));
        assert!((1150.0..=1350.0).contains(&o.max_fz_N));
    }

    /// With the paper's Table 1 model (stiffer than the twin's robot) the loop still helps.
    #[test]
    fn table1_model_still_improves_a_short_run() {
        let model = deflex_model::load_robot("tx200").unwrap();
        let c = compare(ToolPath::paper_cone().truncated(600.0), model, 2);
        let (o, k) = (&c.open.summary, &c.closed.forming.summary);
        assert!(k.max_error_norm_mm < 0.9 * o.max_error_norm_mm);
        assert!(c.closed.fault.is_none());
    }

    /// The `deflex sim isf --correction on --model MODEL.toml` path: the model is read from a
    /// file written by `deflex calibrate` (here: the calibrated model saved as TOML).
    #[test]
    fn twin_controller_from_a_model_file() {
        let cell = CellConfig::default();
        let missing = twin_controller(&cell, None).err().unwrap_or_default();
        assert!(missing.contains("--model"), "{missing}");
        let dir = std::env::temp_dir().join(format!("deflex-model-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        let file = dir.join("model.toml");
        std::fs::write(&file, deflex_model::robot_to_toml(&calibrated_model(&cell))).unwrap();
        let mut twin = twin_controller(&cell, Some(&file)).unwrap();
        let path = ToolPath::paper_cone().truncated(300.0);
        let run = deflex_sim::run_forming(&cell, path, 4, Some(&mut twin)).unwrap();
        assert!(run.summary.correction);
        let line = twin.status_line();
        assert!(
            line.contains("running") && line.contains("no fault"),
            "{line}"
        );
        let _ = std::fs::remove_dir_all(&dir);
    }
}
