//! `deflex run`'s threaded runtime (robot-link, sensor and control threads) driven against the
//! digital twin in simulated time: the twin's robot and sensor are served through in-memory
//! [`RobotLink`]/[`ForceSensorLink`] implementations and the control thread is paced by a driven
//! [`SimClock`], so the exact runtime code of the hardware path runs as fast as the CPU allows.
//! The in-process adapter itself lives in [`deflex_study::twin_controller`].

use deflex_control::runtime::{self, RunSummary, RuntimeOptions};
use deflex_control::{Clock, SimClock};
use deflex_control::{Controller, ControllerConfig};
use deflex_io::{Correction, ForceSensorLink, LinkError, RobotLink, RobotState, WrenchSample};
use deflex_model::Robot;
use deflex_sim::forming::RunningStats;
use deflex_sim::{Cell, CellConfig, CellStep, ToolPath};
use std::collections::VecDeque;
use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::{Arc, Mutex};
use std::time::{Duration, Instant};

/// The twin behind the in-memory links of [`run_runtime_in_sim_time`].
#[cfg_attr(not(test), allow(dead_code))] // entry point for tests and embedders
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
#[cfg_attr(not(test), allow(dead_code))] // entry point for tests and embedders
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
#[cfg_attr(not(test), allow(dead_code))] // entry point for tests and embedders
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
                        wrench: w,
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
/// CPU allows. Returns the run summary and the twin's ground-truth statistics.
#[cfg_attr(not(test), allow(dead_code))] // entry point for tests and embedders
pub fn run_runtime_in_sim_time(
    cell: &CellConfig,
    path: ToolPath,
    seed: u64,
    model: Robot,
    config: ControllerConfig,
) -> Result<(RunSummary, RunningStats), String> {
    let twin = Cell::new(cell, path, seed).map_err(|e| e.to_string())?;
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
    let controller = Controller::new(model, config).map_err(|e| e.to_string())?;
    let options = RuntimeOptions {
        robot_cycle_s: period_s,
        realtime: false,
        lock_memory: false,
        startup_timeout_s: 10.0,
        idle_exit_s: Some(0.2),
    };
    let runtime = runtime::spawn(
        controller,
        Box::new(robot),
        Box::new(sensor),
        clock,
        None,
        options,
    )
    .map_err(|e| format!("starting the runtime threads: {e}"))?;
    while !runtime.is_finished() {
        std::thread::sleep(Duration::from_millis(5));
    }
    let summary = runtime.join();
    let stats = shared
        .cell
        .lock()
        .map_err(|_| "twin poisoned".to_string())?
        .stats()
        .clone();
    Ok((summary, stats))
}

#[cfg(test)]
mod tests {
    use super::*;
    use deflex_study::twin_controller::{
        controller_config_for, identify_from_twin_campaign, run_closed_loop,
    };

    /// The same threads as `deflex run`, paced by a driven simulated clock against the twin,
    /// agree with the in-process run, and the run ends on the robot's silence alone (the
    /// sensor streams on). The wall time is printed, not asserted: timing belongs in benches.
    #[test]
    fn runtime_threads_in_simulated_time_agree_with_in_process() {
        let _serial = crate::realtime_test_lock();
        let cell = CellConfig::default();
        let model = identify_from_twin_campaign(&cell, 11).unwrap();
        let path = ToolPath::paper_cone().truncated(400.0);
        let config = controller_config_for(&cell);
        let wall = Instant::now();
        let (summary, stats) =
            run_runtime_in_sim_time(&cell, path.clone(), 5, model.clone(), config).unwrap();
        let wall_s = wall.elapsed().as_secs_f64();
        let inproc = run_closed_loop(&cell, path, 5, model, config, false, &mut |_| {}).unwrap();
        let (a, b) = (
            stats.max_error_norm_m * 1e3,
            inproc.forming.summary.max_error_norm_mm,
        );
        eprintln!(
            "runtime in simulated time: {} cycles in {wall_s:.2} s wall, max error {a:.4} mm \
             (in-process {b:.4} mm), max F {:.0} N, fault {:?}",
            summary.cycles, stats.max_force_norm_n, summary.fault
        );
        assert!(summary.error.is_none(), "{:?}", summary.error);
        assert!(summary.cycles > 3000);
        // Normal forming does not trip the contact-runaway guard (on by default).
        assert_eq!(summary.runaway_events, 0, "{:?}", summary.first_runaway);
        assert!((a - b).abs() <= 0.1 * b + 0.005, "{a} vs {b}");
        // The end of the robot's telegrams is the end of its program, not a fault.
        assert_eq!(summary.fault, None);
        assert_eq!(
            summary.end,
            deflex_control::runtime::SessionEnd::RobotFinished
        );
    }
}
