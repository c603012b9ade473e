//! The steppable twin of the robotised ISF cell (SIMULATED).
//!
//! Each robot-controller cycle: the emulated controller interpolates the joints and adds the
//! (delayed, filtered, bounded) external correction; the plant (true robot) and the sheet are
//! brought to quasi-static equilibrium — the true TCP is the commanded pose plus the plant's
//! deflection under the contact wrench, and the contact wrench depends on the true TCP — by a
//! bracketed 1-D root find on the vertical contact force (allocation-free); the sheet flows
//! plastically where the tool pushes past its flow level; the F/T sensor produces its samples
//! for the cycle; the ground truth goes to the [`FormingLog`].
//!
//! A correction controller only ever sees [`ControllerInput`]: time, measured joints and raw F/T
//! samples.

use crate::config::CellConfig;
use crate::controller_emulation::{ControllerCycle, ControllerEmulation};
use crate::error::SimError;
use crate::forming::{FormingLog, LogRow, RunningStats};
use crate::plant::{Plant, apply_displacement};
use crate::sensor::ForceSensor;
use crate::sheet::{ContactState, Sheet};
use crate::toolpath::ToolPath;
use crate::tracker::LaserTracker;
use deflex_model::{Displacement, Pose, Wrench};
use nalgebra::Vector3;
use rand::SeedableRng;
use rand_chacha::ChaCha8Rng;

pub use crate::sensor::SensorSample;

/// What an external correction controller sees each cycle: only sensor data, never the plant.
#[derive(Clone, Copy, Debug)]
pub struct ControllerInput<'a> {
    /// Simulated time (s).
    pub time_s: f64,
    /// Joint values reported by the robot (motor encoders: the commanded joints; the elastic
    /// deflection is invisible to them) (rad).
    pub q_measured_rad: &'a [f64],
    /// Raw F/T samples received since the previous controller call, oldest first.
    pub wrench_samples: &'a [SensorSample],
}

/// An external correction controller (like a CompactRIO running the paper's loop).
pub trait CorrectionController {
    /// Controller period (s), e.g. 0.01.
    fn period_s(&self) -> f64;
    /// One control cycle: the Cartesian correction ξ = [δp (m); δφ (rad)], robot base axes;
    /// s_com = s_des + ξ (eq. 7).
    fn step(&mut self, input: &ControllerInput) -> [f64; 6];
}

/// What the robot and the sensor report in one robot-controller cycle.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct CellStep {
    /// Simulated time at the end of the cycle (s).
    pub time_s: f64,
    /// Cycle index (0-based).
    pub cycle: u64,
    /// Joint values reported by the robot (rad).
    pub q_measured_rad: [f64; 6],
    /// F/T samples taken during this cycle (sensor clock), oldest first.
    pub sensor_samples: Vec<SensorSample>,
    /// The path is complete (this was the last cycle).
    pub finished: bool,
}

/// Ground-truth state of the last cycle (evaluation only).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct TruthState {
    /// Desired TCP in R_p (m).
    pub desired_m: Vector3<f64>,
    /// Commanded (undeformed) TCP in R_p (m).
    pub commanded_m: Vector3<f64>,
    /// True TCP in R_p (m).
    pub true_m: Vector3<f64>,
    /// Contact wrench on the tool at the TCP, world axes (N, N·m).
    pub wrench: Wrench,
    /// TCP deflection [δp; δφ] (m, rad).
    pub deflection: Displacement,
    /// Contact state.
    pub contact: ContactState,
    /// Correction applied (m, rad).
    pub correction: [f64; 6],
}

/// The steppable twin: the same object serves the in-process run and the loopback protocol
/// server.
#[derive(Clone, Debug)]
pub struct Cell {
    config: CellConfig,
    controller: ControllerEmulation,
    plant: Plant,
    sheet: Sheet,
    sensor: ForceSensor,
    tracker: LaserTracker,
    origin: Vector3<f64>,
    tool_inverse: Pose,
    feed_ratio: f64,
    log: FormingLog,
    stats: RunningStats,
    log_every: u64,
    last_force: f64,
    truth: Option<TruthState>,
    cycle: u64,
    finished: bool,
}

impl Cell {
    /// Build the cell for a path: plans the joint trajectory (IK of every waypoint), sets up the
    /// plant, the flat sheet and the sensors. All randomness comes from `seed`.
    pub fn new(config: &CellConfig, path: ToolPath, seed: u64) -> Result<Cell, SimError> {
        config.validate()?;
        let nominal = config.nominal_robot()?;
        let plant = Plant::new(&config.plant, &nominal)?;
        let part = config.part_frame();
        let controller = ControllerEmulation::new(
            &nominal,
            &config.controller,
            &path,
            &part,
            &config.seed_q_rad(),
        )?;
        let sheet = Sheet::new(
            &config.sheet,
            path.step_down_mm
                .unwrap_or(config.sheet.default_step_down_mm),
            path.wall_angle_deg
                .unwrap_or(config.sheet.default_wall_angle_deg),
        )?;
        let mut sensor_rng = ChaCha8Rng::seed_from_u64(seed);
        sensor_rng.set_stream(1);
        let mut tracker_rng = ChaCha8Rng::seed_from_u64(seed);
        tracker_rng.set_stream(2);
        let sensor = ForceSensor::new(&config.sensor, config.sensor_in_flange(), sensor_rng);
        let tracker = LaserTracker::new(&config.tracker, tracker_rng);
        let log_every = ((config.controller.rate_hz / config.log.rate_hz).round() as u64).max(1);
        let expected_rows = (controller.duration_s() * config.log.rate_hz) as usize + 16;
        Ok(Cell {
            config: config.clone(),
            origin: part.translation.vector,
            tool_inverse: nominal.tool.inverse(),
            feed_ratio: config.sheet.feed_ratio,
            log: FormingLog::with_capacity(&path.name, seed, expected_rows),
            stats: RunningStats::default(),
            log_every,
            last_force: 0.0,
            truth: None,
            cycle: 0,
            finished: false,
            controller,
            plant,
            sheet,
            sensor,
            tracker,
        })
    }

    /// Robot controller period (s).
    pub fn robot_period_s(&self) -> f64 {
        self.controller.period_s()
    }

    /// The path is complete.
    pub fn is_finished(&self) -> bool {
        self.finished
    }

    /// Duration of the programmed path (s).
    pub fn path_duration_s(&self) -> f64 {
        self.controller.duration_s()
    }

    /// The cell configuration.
    pub fn config(&self) -> &CellConfig {
        &self.config
    }

    /// Ground truth (evaluation only; never for a controller).
    pub fn log(&self) -> &FormingLog {
        &self.log
    }

    /// Running statistics over every cycle so far (evaluation only).
    pub fn stats(&self) -> &RunningStats {
        &self.stats
    }

    /// Ground truth of the last cycle (evaluation only).
    pub fn truth(&self) -> Option<&TruthState> {
        self.truth.as_ref()
    }

    /// The sheet (evaluation only).
    pub fn sheet(&self) -> &Sheet {
        &self.sheet
    }

    /// The external correction input (like Alter/RSI), m and rad, robot base axes; applied after
    /// the transport delay and first-order filter, bounded in size and rate.
    pub fn set_correction(&mut self, xi: [f64; 6]) {
        self.controller.set_correction(xi);
    }

    /// Advance one robot-controller cycle (1/250 s by default); returns what the robot and the
    /// sensor report in that cycle.
    pub fn step(&mut self) -> CellStep {
        let mut out = CellStep::default();
        self.step_into(&mut out);
        out
    }

    /// [`Cell::step`] reusing the caller's buffers (no allocation once warmed up).
    pub fn step_into(&mut self, out: &mut CellStep) {
        let cycle = self.controller.advance();
        self.plant.set_configuration(&cycle.q_command);
        let tcp_cmd = self.plant.tcp_pose();
        let p_cmd = tcp_cmd.translation.vector - self.origin;
        let (wrench, deflection, contact) = self.equilibrium(&cycle, &p_cmd);
        let tcp_true = apply_displacement(&tcp_cmd, &deflection);
        let p_true = tcp_true.translation.vector - self.origin;
        self.sheet.form(&p_true, &contact);
        self.plant.commit_tcp_wrench(&wrench);
        self.last_force = wrench[2];
        let flange_true = tcp_true * self.tool_inverse;
        out.sensor_samples.clear();
        self.sensor.samples_until(
            cycle.time_s,
            &flange_true,
            &wrench,
            &tcp_true.translation.vector,
            &mut out.sensor_samples,
        );
        out.time_s = cycle.time_s;
        out.cycle = self.cycle;
        out.q_measured_rad = cycle.q_command;
        out.finished = cycle.finished;
        let truth = TruthState {
            desired_m: cycle.desired_m - self.origin,
            commanded_m: p_cmd,
            true_m: p_true,
            wrench,
            deflection,
            contact,
            correction: cycle.correction,
        };
        self.stats.add(&truth);
        if self.cycle.is_multiple_of(self.log_every) || cycle.finished {
            let tracked = self.tracker.measure(&tcp_true.translation.vector) - self.origin;
            let raw = out.sensor_samples.last().copied().unwrap_or(SensorSample {
                time_s: cycle.time_s,
                wrench_sensor: [0.0; 6],
                saturated: false,
            });
            self.log.push(LogRow {
                time_s: cycle.time_s,
                truth,
                tracked_m: tracked,
                sensor: raw,
            });
        }
        self.truth = Some(truth);
        self.cycle += 1;
        self.finished = cycle.finished;
    }

    /// Quasi-static equilibrium of the plant and the sheet for this cycle: find the vertical
    /// contact force F with F = min(k δ(p(F)), F_flow(p(F))), p(F) = p_cmd + δp(w(F)).
    fn equilibrium(
        &mut self,
        cycle: &ControllerCycle,
        p_cmd: &Vector3<f64>,
    ) -> (Wrench, Displacement, ContactState) {
        let free = self.sheet.contact(p_cmd);
        if free.force_n <= 0.0 {
            return (Wrench::zeros(), Displacement::zeros(), free);
        }
        // Unit wrench per newton of vertical force (direction fixed within the cycle).
        let force = self
            .sheet
            .force_vector(p_cmd, 1.0, &cycle.feed_dir, free.depth_m);
        let friction = -cycle.feed_dir * self.feed_ratio;
        let moment = Vector3::new(0.0, 0.0, -self.sheet.tool_radius_m()).cross(&friction);
        let unit = Wrench::new(force.x, force.y, force.z, moment.x, moment.y, moment.z);
        let plant = &self.plant;
        let sheet = &self.sheet;
        let eval = |f: f64| -> (f64, Displacement, ContactState) {
            let d = plant.tcp_deflection(&(unit * f));
            let p = p_cmd + Vector3::new(d[0], d[1], d[2]);
            let c = sheet.contact(&p);
            (f - c.force_n, d, c)
        };
        // g(F) = F − force(p(F)) is increasing; g(0) < 0, g(F_hi) ≥ 0.
        let (mut a, mut ga) = (0.0, -free.force_n);
        let mut b = free.force_n;
        let (mut gb, mut db, mut cb) = eval(b);
        if gb <= 0.0 {
            return (unit * b, db, cb);
        }
        // Warm start from the previous cycle's force.
        let guess = self.last_force;
        if guess > a && guess < b {
            let (g, d, c) = eval(guess);
            if g.abs() < 1e-3 {
                return (unit * guess, d, c);
            }
            if g < 0.0 {
                a = guess;
                ga = g;
            } else {
                b = guess;
                gb = g;
                db = d;
                cb = c;
            }
        }
        // Illinois regula falsi.
        let mut side = 0i8;
        for _ in 0..60 {
            let x = (a * gb - b * ga) / (gb - ga);
            let (g, d, c) = eval(x);
            if g.abs() < 1e-3 || (b - a) < 1e-6 {
                return (unit * x, d, c);
            }
            if g < 0.0 {
                a = x;
                ga = g;
                if side == -1 {
                    gb *= 0.5;
                }
                side = -1;
            } else {
                b = x;
                gb = g;
                db = d;
                cb = c;
                if side == 1 {
                    ga *= 0.5;
                }
                side = 1;
            }
        }
        (unit * b, db, cb)
    }
}
