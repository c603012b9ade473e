//! The digital twin's own telemetry stream ([`StreamSource::TwinCell`], SIMULATED): what the robot
//! reports and the plant's ground truth, as [`CycleSample`]s, with no controller in them. It is
//! what `deflex cell --sim` shows and records (its controller is another process, `deflex run`,
//! with its own stream) and what an open-loop `deflex sim isf` shows and records.
//!
//! One sample per row of the twin's forming log (every `controller.rate_hz / log.rate_hz` robot
//! cycles, 50 Hz by default, and the last cycle), at exactly the instants of the log's rows, so
//! a recording and the CSV log can be compared row by row. The fields mean (base axes, SI):
//!
//! * `q_rad`: the joints the robot reports; `tcp_position_m`/`tcp_rotation`: their forward
//!   kinematics with the robot controller's own (nominal) model — the commanded TCP, correction
//!   included, as `deflex run` computes it from the same joints;
//! * `wrench_raw`: the last raw F/T sample of the cycle (sensor frame), as in the log;
//! * `wrench_tcp`: the **true** contact wrench on the tool at the TCP;
//! * `deflection`: the arm's **true** TCP deflection under it [δp; δφ];
//! * `correction`: the correction the robot **applies** (after its transport delay, filter and
//!   bounds), so the sample's program position (TCP − ξ) is the program's;
//! * `truth_error_m`: true − desired TCP;
//! * `cycle_time_s`: the largest round trip of the controller's answers since the previous
//!   sample (`cell --sim`), NaN in-process; `robot_telegrams`, `late_answers`, `robot_late`:
//!   robot cycles served and answers late by the robot's count;
//! * `phase_code`: the cell's [`CellState`];
//! * what only a controller knows (the processed reading, ε, the feed-forward, the arc length,
//!   the loop gain) is NaN, flags and fault are zero.
//!
//! The twin holds positions in its part frame R_p, whose axes are the world's; they are turned
//! into the robot's base axes with the nominal robot's base orientation.

use crate::{Cell, CellStep, CycleObserver};
use deflex_model::{Data, Robot};
use deflex_runtime::telemetry::{CycleSample, Publisher, SessionInfo, StreamSource};
use deflex_telemetry::CellState;
use nalgebra::{Rotation3, Vector3};
use std::sync::atomic::{AtomicBool, Ordering};
use std::time::Instant;

/// A consumer of every sample, called synchronously (e.g. an MCAP writer that must lose
/// nothing).
pub type SampleSink = Box<dyn FnMut(&CycleSample) + Send>;

/// Turns the twin's cycles into [`StreamSource::TwinCell`] samples and hands them to a telemetry
/// publisher (a live view reads it) and/or a synchronous sink (a recording).
pub struct TwinCellStream {
    publisher: Option<Publisher<CycleSample>>,
    sink: Option<SampleSink>,
    robot: Robot,
    data: Data,
    /// World → base axes.
    to_base: Rotation3<f64>,
    sample: CycleSample,
    sensor_samples: u64,
    round_trip_max_s: f64,
    published: u64,
}

/// The description of a twin-cell session of the robot `nominal` (what its controller
/// believes) in the cell `cell`.
pub fn twin_cell_session_info(nominal: &Robot, cell: &crate::CellConfig) -> SessionInfo {
    let mut info = SessionInfo::new(
        StreamSource::TwinCell,
        nominal.name.clone(),
        nominal.joints.iter().map(|j| j.name.clone()).collect(),
    );
    let c = &cell.controller;
    info.protocol = "twin".into();
    info.control_period_s = 1.0 / cell.log.rate_hz;
    info.robot_cycle_s = cell.robot_period_s();
    info.correction_limit = [
        c.max_correction_m,
        c.max_correction_m,
        c.max_correction_m,
        c.max_correction_rad,
        c.max_correction_rad,
        c.max_correction_rad,
    ];
    info.correction_rate_limit = [
        c.max_correction_speed_m_s,
        c.max_correction_speed_m_s,
        c.max_correction_speed_m_s,
        c.max_correction_speed_rad_s,
        c.max_correction_speed_rad_s,
        c.max_correction_speed_rad_s,
    ];
    info
}

impl TwinCellStream {
    /// A stream of the twin whose robot controller's model is `nominal` (the cell's nominal
    /// robot, [`crate::CellConfig::nominal_robot`]).
    pub fn new(nominal: Robot) -> TwinCellStream {
        let mut sample = CycleSample::default();
        for v in [
            &mut sample.wrench_sensor,
            &mut sample.error,
            &mut sample.feedforward,
        ] {
            *v = [f64::NAN; 6];
        }
        sample.cycle_time_s = f64::NAN;
        TwinCellStream {
            publisher: None,
            sink: None,
            to_base: nominal.base.rotation.inverse(),
            robot: nominal,
            data: Data::new(),
            sample,
            sensor_samples: 0,
            round_trip_max_s: f64::NAN,
            published: 0,
        }
    }

    /// Publishes every sample into `publisher` (a live view subscribes to its ring).
    pub fn with_publisher(mut self, publisher: Publisher<CycleSample>) -> Self {
        self.publisher = Some(publisher);
        self
    }

    /// Hands every sample to `sink`, synchronously.
    pub fn with_sink(mut self, sink: SampleSink) -> Self {
        self.sink = Some(sink);
        self
    }

    /// Samples made so far.
    pub fn samples(&self) -> u64 {
        self.published
    }

    /// A round trip of the controller's answer (s), reported with the next sample (its
    /// maximum since the previous sample).
    pub fn note_round_trip(&mut self, seconds: f64) {
        // NaN (none yet since the last sample) is replaced.
        if self.round_trip_max_s.is_nan() || seconds > self.round_trip_max_s {
            self.round_trip_max_s = seconds;
        }
    }

    /// The robot's counts: cycles served and answers late by its count.
    pub fn set_robot_counts(&mut self, cycles: u64, late: u64) {
        self.sample.robot_telegrams = cycles;
        self.sample.late_answers = late;
        self.sample.robot_late = late;
    }

    /// Counts the F/T samples of a cycle (also while the twin holds its start pose).
    pub fn count_sensor_samples(&mut self, n: usize) {
        self.sensor_samples += n as u64;
    }

    /// A sample of the cell's last cycle `step` in state `state`.
    pub fn record(&mut self, cell: &Cell, step: &CellStep, state: CellState) {
        let s = &mut self.sample;
        s.time_s = step.time_s;
        s.cycle = step.cycle + 1;
        s.set_q(&step.q_measured_rad);
        s.wrench_raw = step
            .sensor_samples
            .last()
            .map_or([0.0; 6], |x| x.wrench_sensor);
        s.sensor_samples = self.sensor_samples;
        s.phase_code = state.code();
        s.cycle_time_s = self.round_trip_max_s;
        self.round_trip_max_s = f64::NAN;
        if let Some(t) = cell.truth() {
            let r = &self.to_base;
            let v = |x: Vector3<f64>| -> [f64; 3] { (r * x).into() };
            let w = &t.wrench;
            let f = v(Vector3::new(w[0], w[1], w[2]));
            let m = v(Vector3::new(w[3], w[4], w[5]));
            s.wrench_tcp = [f[0], f[1], f[2], m[0], m[1], m[2]];
            let d = &t.deflection;
            let dp = v(Vector3::new(d[0], d[1], d[2]));
            let dr = v(Vector3::new(d[3], d[4], d[5]));
            s.deflection = [dp[0], dp[1], dp[2], dr[0], dr[1], dr[2]];
            s.correction = t.correction;
            s.truth_error_m = v(t.path_error_m());
        }
        if self
            .robot
            .forward_kinematics(&mut self.data, &step.q_measured_rad)
            .is_ok()
        {
            let base = &self.robot.base;
            let p = base.rotation.inverse() * (self.data.tcp_position() - base.translation.vector);
            s.tcp_position_m = p.into();
            s.set_tcp_rotation(&(base.rotation.inverse() * self.data.tcp.rotation));
        }
        self.emit();
    }

    /// A sample that only changes the state (waiting, dwelling: the twin holds its start pose
    /// and its time does not advance).
    pub fn record_state(&mut self, state: CellState) {
        self.sample.phase_code = state.code();
        self.sample.sensor_samples = self.sensor_samples;
        self.emit();
    }

    fn emit(&mut self) {
        if let Some(p) = self.publisher.as_mut() {
            p.publish(&self.sample);
        }
        if let Some(sink) = self.sink.as_mut() {
            sink(&self.sample);
        }
        self.published += 1;
    }
}

/// What watches an in-process run (`deflex sim isf`): the twin's stream (open loop), the pace of
/// a live view, and a stop flag.
#[derive(Default)]
pub struct RunWatch {
    /// The twin's own stream, fed at every log row.
    pub stream: Option<TwinCellStream>,
    /// Simulated seconds per wall-clock second when a person watches (`None`: as fast as the
    /// CPU allows).
    pub speed: Option<f64>,
    /// Set (Ctrl-C): the run stops before the end.
    pub stop: Option<&'static AtomicBool>,
    started: Option<Instant>,
}

impl RunWatch {
    /// A watch with `stream`, pacing at `speed` × real time when given, stopped by `stop`.
    pub fn new(
        stream: Option<TwinCellStream>,
        speed: Option<f64>,
        stop: Option<&'static AtomicBool>,
    ) -> RunWatch {
        RunWatch {
            stream,
            speed,
            stop,
            started: None,
        }
    }
}

impl CycleObserver for RunWatch {
    fn observe(&mut self, cell: &Cell, step: &CellStep) -> bool {
        if let Some(stream) = self.stream.as_mut() {
            stream.count_sensor_samples(step.sensor_samples.len());
            if step.logged {
                let state = if step.finished {
                    CellState::Finished
                } else {
                    CellState::Forming
                };
                stream.record(cell, step, state);
            }
        }
        if let Some(speed) = self.speed {
            let started = *self.started.get_or_insert_with(Instant::now);
            let due = step.time_s / speed;
            let now = started.elapsed().as_secs_f64();
            if due > now {
                std::thread::sleep(std::time::Duration::from_secs_f64(due - now));
            }
        }
        !self.stop.is_some_and(|s| s.load(Ordering::SeqCst))
    }
}
