//! The deflex correction controller ([`deflex_control::Controller`], eq. 5–7, 15, 17) driving the
//! digital twin in-process, in simulated time: the adapter implements the twin's
//! [`CorrectionController`], so the twin's forming run of the paper's cone (Section 4) becomes
//! closed-loop. The controller only ever sees what hardware would give it: simulated time, the
//! joint values the robot reports and the raw F/T samples of the period (averaged), plus the
//! mounting and tool data an integrator takes from drawings and datasheets. Never the plant.
//!
//! Given a telemetry publisher ([`TwinController::set_telemetry`]), the controller publishes one
//! [`CycleSample`] per control cycle, as `deflex run`'s control thread does, so the same sinks
//! (a live view, a recorder) follow a twin run.

use crate::twin::TwinError;
use crate::twin::twin_stream::SampleSink;
use crate::{CellConfig, ControllerInput, CorrectionController, FormingRun, ToolPath};
use deflex_control::{
    Controller, ControllerConfig, CycleInput, CycleOutput, Fault, FeedForward, RecordCycle,
};
use deflex_model::spatial::pose_from_xyz_rpy;
use deflex_model::{Robot, Wrench};
use deflex_runtime::telemetry::{CycleSample, Publisher, SessionInfo, StreamSource, session_info};
use deflex_telemetry::Phase;
use nalgebra::Rotation3;

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
    config.wrench.tool_in_sensor.mass_kg = s.tool_mass_kg;
    config.wrench.tool_in_sensor.centre_of_mass_m = nalgebra::Vector3::from(s.tool_com_in_sensor_m);
    config.wrench.gravity_world = [0.0, 0.0, -s.gravity_m_s2];
    config.safety.sensor_range = s.range;
    config
}

/// The telemetry of an in-process run: the publisher, the synchronous sink and the sample they
/// reuse.
struct TwinTelemetry {
    publisher: Option<Publisher<CycleSample>>,
    sink: Option<SampleSink>,
    sample: CycleSample,
    /// World → the model's base axes (the truth is in the twin's part frame, world axes).
    to_base: Rotation3<f64>,
}

/// [`Controller`] as the twin's [`CorrectionController`]. Keeps a per-cycle trace when asked.
pub struct TwinController {
    ctrl: Controller,
    started: bool,
    last_raw: Wrench,
    last_sample_s: f64,
    trace: Option<Vec<CycleOutput>>,
    max_force_n: f64,
    telemetry: Option<TwinTelemetry>,
    samples: u64,
}

impl TwinController {
    /// A controller with `model` (calibrated, never the plant) and `config`.
    pub fn new(
        model: Robot,
        config: ControllerConfig,
        keep_trace: bool,
    ) -> Result<Self, TwinError> {
        Ok(TwinController {
            ctrl: Controller::new(model, config)?,
            started: false,
            last_raw: Wrench::zeros(),
            last_sample_s: f64::NEG_INFINITY,
            trace: keep_trace.then(|| Vec::with_capacity(64 * 1024)),
            max_force_n: 0.0,
            telemetry: None,
            samples: 0,
        })
    }

    /// Publish one telemetry sample per control cycle (SIMULATED: [`StreamSource::Twin`]) into
    /// `publisher`; `None` stops publishing (and ends the stream). The samples carry the twin's
    /// path error ([`CycleSample::truth_error_m`]: true − desired TCP, turned from the twin's
    /// part frame, whose axes are the world's, into the model's base axes) from
    /// [`crate::ControllerInput::truth`]; the law itself never reads the truth.
    pub fn set_telemetry(&mut self, publisher: Option<Publisher<CycleSample>>) {
        let sink = self.telemetry.as_mut().and_then(|t| t.sink.take());
        self.set_outputs(publisher, sink);
    }

    /// Hand every telemetry sample to `sink` too, synchronously, losing none (an MCAP writer);
    /// `None` removes it.
    pub fn set_sample_sink(&mut self, sink: Option<SampleSink>) {
        let publisher = self.telemetry.as_mut().and_then(|t| t.publisher.take());
        self.set_outputs(publisher, sink);
    }

    fn set_outputs(&mut self, publisher: Option<Publisher<CycleSample>>, sink: Option<SampleSink>) {
        // The sample keeps its cycle count when the outputs change.
        let sample = self
            .telemetry
            .take()
            .map_or_else(CycleSample::default, |t| t.sample);
        let to_base = self.ctrl.robot().base.rotation.inverse();
        self.telemetry = if publisher.is_some() || sink.is_some() {
            Some(TwinTelemetry {
                publisher,
                sink,
                sample,
                to_base,
            })
        } else {
            None
        };
    }

    /// The description of a twin session of this controller, whose robot runs every
    /// `robot_cycle_s` (SIMULATED).
    pub fn session_info(&self, robot_cycle_s: f64) -> SessionInfo {
        session_info(&self.ctrl, StreamSource::Twin, "in-process", robot_cycle_s)
    }

    /// The controller.
    pub fn controller(&self) -> &Controller {
        &self.ctrl
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
            self.last_raw = period_reading(samples);
            self.last_sample_s = samples[samples.len() - 1].time_s;
            self.samples += samples.len() as u64;
        }
        let out = self.ctrl.cycle_input(&CycleInput {
            now_s: input.time_s,
            q_rad: input.q_measured_rad,
            q_age_s: 0.0,
            wrench_sensor: self.last_raw,
            wrench_age_s: input.time_s - self.last_sample_s,
            wrench_fresh: fresh,
            sensor_status: 0,
            tcp_pose: None,
        });
        let f = &out.wrench_tcp;
        self.max_force_n = self
            .max_force_n
            .max((f[0] * f[0] + f[1] * f[1] + f[2] * f[2]).sqrt());
        if let Some(trace) = self.trace.as_mut() {
            trace.push(out);
        }
        self.publish(input, &out);
        out.xi
    }
}

/// The reading the controller gets for a period: the mean of its samples; a clipped sample is
/// passed as is (at the range, which the controller treats as out of range).
fn period_reading(samples: &[crate::SensorSample]) -> Wrench {
    if let Some(clipped) = samples.iter().find(|s| s.saturated) {
        return Wrench::from(clipped.wrench_sensor);
    }
    let mut sum = [0.0; 6];
    for s in samples {
        for (acc, v) in sum.iter_mut().zip(s.wrench_sensor) {
            *acc += v;
        }
    }
    let n = samples.len() as f64;
    Wrench::from(sum.map(|v| v / n))
}

impl TwinController {
    /// One telemetry sample of the cycle just run, when publishing (allocation-free; a sink
    /// may allocate).
    fn publish(&mut self, input: &ControllerInput, out: &CycleOutput) {
        let Some(t) = self.telemetry.as_mut() else {
            return;
        };
        t.sample
            .record_cycle(&self.ctrl, input.q_measured_rad, &self.last_raw, out);
        t.sample.cycle += 1;
        t.sample.sensor_samples = self.samples;
        t.sample.truth_error_m = input.truth.map_or([f64::NAN; 3], |truth| {
            (t.to_base * truth.path_error_m()).into()
        });
        if let Some(p) = t.publisher.as_mut() {
            p.publish(&t.sample);
        }
        if let Some(sink) = t.sink.as_mut() {
            sink(&t.sample);
        }
    }
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
) -> Result<ClosedLoopRun, TwinError> {
    let twin = TwinController::new(model, config, keep_trace)?;
    run_twin_controller(
        cell,
        &TwinProgram {
            path,
            reference: None,
        },
        seed,
        twin,
        progress,
    )
}

/// What the twin's robot runs: `path`, meaning `reference` when it is a compensated program
/// (`crate::run_program_with_progress`).
#[derive(Clone, Debug)]
pub struct TwinProgram {
    /// The robot program.
    pub path: ToolPath,
    /// The path it means (`None`: itself).
    pub reference: Option<ToolPath>,
}

/// Runs `program` on the twin with `twin` (a controller set up by the caller, e.g. with a
/// feed-forward).
pub fn run_twin_controller(
    cell: &CellConfig,
    program: &TwinProgram,
    seed: u64,
    mut twin: TwinController,
    progress: &mut dyn FnMut(f64),
) -> Result<ClosedLoopRun, TwinError> {
    let forming = crate::run_program_with_progress(
        cell,
        program.path.clone(),
        program.reference.as_ref(),
        seed,
        Some(&mut twin),
        progress,
    )?;
    // The run is over: the stream ends (its sinks see it closed).
    twin.telemetry = None;
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
