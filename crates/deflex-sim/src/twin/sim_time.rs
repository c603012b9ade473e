//! `deflex run`'s threaded runtime (robot-link, sensor and control threads) driven against the
//! digital twin in simulated time: the twin's robot and sensor are served through in-memory
//! [`RobotLink`]/[`ForceSensorLink`] implementations and the control thread is paced by a driven
//! [`SimClock`], so the exact runtime code of the hardware path runs as fast as the CPU allows
//! (SIMULATED). The in-process adapter, without the threads, is [`crate::twin::closed_loop`].

use crate::forming::RunningStats;
use crate::twin::TwinError;
use crate::{Cell, CellConfig, CellStep, ToolPath};
use deflex_control::{Controller, ControllerConfig};
use deflex_io::{Correction, ForceSensorLink, LinkError, RobotLink, RobotState, WrenchSample};
use deflex_model::{Robot, Wrench};
use deflex_runtime::session::{self, RunSummary, RuntimeOptions};
use deflex_runtime::telemetry::{StreamSource, Telemetry, session_info};
use deflex_runtime::{Clock, SimClock};
use std::collections::VecDeque;
use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::{Arc, Mutex};
use std::time::{Duration, Instant};

/// The twin behind the in-memory links of [`run_runtime_in_sim_time`].
struct TwinShared {
    cell: Mutex<Cell>,
    /// Samples waiting for the sensor thread, and whether that thread found the queue empty
    /// since the last push (then everything pushed before has been published).
    samples: Mutex<(VecDeque<[f64; 6]>, bool)>,
    /// Set when the sensor thread has stopped its link: nobody publishes samples any more.
    sensor_stopped: AtomicBool,
}

/// The twin's robot as a [`RobotLink`]: each `receive` advances the driven simulated clock by
/// one robot cycle (running every control cycle due first, in lockstep), steps the twin, hands
/// the cycle's F/T samples to [`TwinSensorLink`] and waits until they are published.
struct TwinRobotLink {
    shared: Arc<TwinShared>,
    clock: SimClock,
    step: CellStep,
    period_s: f64,
    calls: u64,
    /// Simulated time at which the path ended (s); `None` while it runs.
    ended_at_s: Option<f64>,
    /// The latest F/T sample (a robot cycle may carry none when the sensor is slower), repeated
    /// while the robot is silent after the end.
    last_sample: [f64; 6],
}

/// How long (simulated seconds) the twin keeps time and sensor running after the path ends:
/// the robot's telegrams stop, the F/T sensor streams on, as in a real cell.
const AFTER_END_S: f64 = 2.0;

impl TwinRobotLink {
    /// Hands samples to the sensor thread and waits (wall time, bounded) until it has published
    /// all of them, so the control cycles of the next robot period see them.
    fn publish_samples(&self, samples: impl IntoIterator<Item = [f64; 6]>) {
        if let Ok(mut q) = self.shared.samples.lock() {
            q.0.extend(samples);
            q.1 = false;
        }
        let waiting = Instant::now();
        while waiting.elapsed() < Duration::from_secs(2)
            && !self.shared.sensor_stopped.load(Ordering::Acquire)
        {
            match self.shared.samples.lock() {
                Ok(q) if q.0.is_empty() && q.1 => break,
                _ => std::thread::yield_now(),
            }
        }
    }

    /// One robot period after the end of the path (at `ended_at_s`), in lockstep: the robot is
    /// silent (no telegram), the sensor keeps reporting its latest wrench. After
    /// [`AFTER_END_S`] the clock is released to run free.
    fn silent_cycle(&mut self, ended_at_s: f64, timeout: Duration) -> Option<RobotState> {
        let now = self.clock.now();
        if now - ended_at_s > AFTER_END_S {
            self.clock.finish();
            std::thread::sleep(timeout);
            return None;
        }
        self.clock.advance_to(now + self.period_s);
        let per_cycle = self.step.sensor_samples.len().max(1);
        self.publish_samples(std::iter::repeat_n(self.last_sample, per_cycle));
        None
    }
}

impl RobotLink for TwinRobotLink {
    fn receive(&mut self, timeout: Duration) -> Result<Option<RobotState>, LinkError> {
        if let Some(ended_at_s) = self.ended_at_s {
            return Ok(self.silent_cycle(ended_at_s, timeout));
        }
        if self.calls == 1 {
            // The first state and samples are out: start the lockstep with the control loop.
            self.clock.wait_for_follower(Duration::from_secs(10));
        }
        self.calls += 1;
        self.clock.advance_to(self.step.time_s + self.period_s);
        {
            let mut cell = self.shared.cell.lock().map_err(|_| LinkError::NoPeer {
                protocol: deflex_io::Protocol::Rsi,
            })?;
            cell.step_into(&mut self.step);
        }
        self.clock.advance_to(self.step.time_s);
        if let Some(last) = self.step.sensor_samples.last() {
            self.last_sample = last.wrench_sensor;
        }
        self.publish_samples(self.step.sensor_samples.iter().map(|s| s.wrench_sensor));
        if self.step.finished {
            self.ended_at_s = Some(self.step.time_s);
        }
        Ok(Some(RobotState {
            cycle_id: self.calls,
            ..RobotState::with_joints(&self.step.q_measured_rad)
        }))
    }

    fn send_correction(&mut self, c: &Correction) -> Result<(), LinkError> {
        if let Ok(mut cell) = self.shared.cell.lock() {
            cell.set_correction(c.to_array());
        }
        Ok(())
    }

    fn protocol(&self) -> deflex_io::Protocol {
        deflex_io::Protocol::SimpleLine
    }
}

/// The twin's F/T sensor as a [`ForceSensorLink`] fed by [`TwinRobotLink`].
struct TwinSensorLink {
    shared: Arc<TwinShared>,
}

impl ForceSensorLink for TwinSensorLink {
    fn start(&mut self) -> Result<(), LinkError> {
        Ok(())
    }
    fn bias(&mut self) -> Result<(), LinkError> {
        Ok(())
    }
    fn receive(&mut self, timeout: Duration) -> Result<Option<WrenchSample>, LinkError> {
        let start = Instant::now();
        loop {
            if let Ok(mut q) = self.shared.samples.lock() {
                if let Some(w) = q.0.pop_front() {
                    return Ok(Some(WrenchSample {
                        wrench: Wrench::from(w),
                        ..WrenchSample::default()
                    }));
                }
                q.1 = true;
            }
            if start.elapsed() >= timeout {
                return Ok(None);
            }
            std::thread::yield_now();
        }
    }
    fn stop(&mut self) -> Result<(), LinkError> {
        self.shared.sensor_stopped.store(true, Ordering::Release);
        Ok(())
    }
}

/// The threaded runtime of `deflex run` (robot-link, sensor and control threads, the control
/// thread paced by a driven [`SimClock`]) against the twin in simulated time, as fast as the
/// CPU allows. `telemetry`, when given, receives the session's samples (subscribe its sinks
/// first); otherwise a small ring nobody reads is used. Returns the run summary and the twin's
/// ground-truth statistics.
pub fn run_runtime_in_sim_time(
    cell: &CellConfig,
    path: ToolPath,
    seed: u64,
    model: Robot,
    config: ControllerConfig,
    telemetry: Option<Telemetry>,
) -> Result<(RunSummary, RunningStats), TwinError> {
    let twin = Cell::new(cell, path, seed)?;
    let period_s = twin.robot_period_s();
    let shared = Arc::new(TwinShared {
        cell: Mutex::new(twin),
        samples: Mutex::new((VecDeque::new(), false)),
        sensor_stopped: AtomicBool::new(false),
    });
    let clock = SimClock::driven();
    let robot = TwinRobotLink {
        shared: shared.clone(),
        clock: clock.clone(),
        step: CellStep::default(),
        period_s,
        calls: 0,
        ended_at_s: None,
        last_sample: [0.0; 6],
    };
    let sensor = TwinSensorLink {
        shared: shared.clone(),
    };
    let controller = Controller::new(model, config)?;
    let telemetry = telemetry.unwrap_or_else(|| {
        let mut info = session_info(&controller, StreamSource::Runtime, "in-memory", period_s);
        info.simulated = true;
        Telemetry::new(info, 16)
    });
    let options = RuntimeOptions {
        robot_cycle_s: period_s,
        realtime: false,
        lock_memory: false,
        startup_timeout_s: 10.0,
        idle_exit_s: Some(0.2),
    };
    let runtime = session::spawn(
        controller,
        Box::new(robot),
        Box::new(sensor),
        clock,
        telemetry,
        options,
    )
    .map_err(TwinError::Threads)?;
    while !runtime.is_finished() {
        std::thread::sleep(Duration::from_millis(5));
    }
    let summary = runtime.join();
    let stats = shared
        .cell
        .lock()
        .map_err(|_| TwinError::Poisoned)?
        .stats()
        .clone();
    Ok((summary, stats))
}
