//! The 6-axis force/torque sensor between flange and tool (defaults: ATI Omega160 SI-1500-240,
//! see [`crate::cell_config::SensorConfig`]).
//!
//! A reading is the sum of the loads on everything below the sensing plane, expressed in the
//! sensor frame with the moment about the sensor origin: the contact wrench of the environment on
//! the tool (the model's w) plus the tool's weight, scaled by the calibration's gain error, plus
//! a bias that drifts as the sensor warms and Gaussian noise, each channel clipped at the
//! calibrated range (the sample is then flagged `saturated`). The sensor sits at its *true*
//! mounting and carries the *true* tool (see [`crate::cell_config::SensorConfig`]), which differ from
//! the nominal ones a controller is told. A controller must therefore tare the bias and
//! compensate the tool weight, which rotates with the tool, as on hardware.

use crate::cell_config::{CellConfig, SensorConfig};
use deflex_model::{Pose, Wrench};
use nalgebra::{Rotation3, Vector3};
use rand::Rng;
use rand_chacha::ChaCha8Rng;
use rand_distr::StandardNormal;
use serde::{Deserialize, Serialize};

/// What a sensor at `sensor` (world pose) reads for a contact wrench given in world axes with
/// its moment about world point `at`: the force in sensor axes, `f_s = Rᵀ f`, and the moment
/// about the sensor origin S, `m_S = m_at + (at − S) × f`, in sensor axes. Written here, not taken
/// from deflex-model, so that the controller's wrench processing (which undoes it with the model's
/// transforms) is checked against a separate implementation.
pub fn contact_in_sensor(contact: &Wrench, at: &Vector3<f64>, sensor: &Pose) -> Wrench {
    let force = Vector3::new(contact[0], contact[1], contact[2]);
    let moment_at = Vector3::new(contact[3], contact[4], contact[5]);
    let origin = sensor.translation.vector;
    let moment_at_sensor = moment_at + (at - origin).cross(&force);
    let r_t = sensor.rotation.inverse();
    let f = r_t * force;
    let m = r_t * moment_at_sensor;
    Wrench::new(f.x, f.y, f.z, m.x, m.y, m.z)
}

/// One raw F/T sample as the sensor reports it (sensor frame, N and N·m, bias + tool gravity +
/// noise included, saturated values clipped).
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct SensorSample {
    /// Simulated time of the sample (s).
    pub time_s: f64,
    /// `[Fx, Fy, Fz, Tx, Ty, Tz]` in the sensor frame (N, N·m).
    pub wrench_sensor: [f64; 6],
    /// At least one channel hit its range and was clipped.
    pub saturated: bool,
}

/// The tool's weight as the sensor sees it: force `Rᵀ(0, 0, −m g)` and its moment about the sensor
/// origin, for a sensor with world orientation `sensor_rotation`.
pub fn tool_gravity_in_sensor(
    sensor_rotation: &Rotation3<f64>,
    mass_kg: f64,
    com_in_sensor_m: &[f64; 3],
    gravity_m_s2: f64,
) -> Wrench {
    let force = sensor_rotation.inverse() * Vector3::new(0.0, 0.0, -mass_kg * gravity_m_s2);
    let moment = Vector3::from(*com_in_sensor_m).cross(&force);
    Wrench::new(force.x, force.y, force.z, moment.x, moment.y, moment.z)
}

/// The simulated sensor: its own sample clock, true mounting and tool, gain error, drifting
/// bias, noise and saturation.
#[derive(Clone, Debug)]
pub struct ForceSensor {
    config: SensorConfig,
    sensor_in_flange: Pose,
    tool_mass_kg: f64,
    tool_com_m: [f64; 3],
    gain: [f64; 6],
    drift_per_s: [f64; 6],
    noise_sigma: [f64; 6],
    period_s: f64,
    next_sample_s: f64,
    rng: ChaCha8Rng,
}

impl ForceSensor {
    /// An ideal-mounting sensor (nominal pose given, nominal tool, no gain error, no drift) whose
    /// first sample is at t = 0.
    pub fn new(config: &SensorConfig, sensor_in_flange: Pose, rng: ChaCha8Rng) -> ForceSensor {
        ForceSensor {
            config: config.clone(),
            sensor_in_flange,
            tool_mass_kg: config.tool_mass_kg,
            tool_com_m: config.tool_com_in_sensor_m,
            gain: [1.0; 6],
            drift_per_s: [0.0; 6],
            noise_sigma: config.noise_sigma,
            period_s: 1.0 / config.rate_hz,
            next_sample_s: 0.0,
            rng,
        }
    }

    /// The sensor of a cell: true mounting and tool load, gain error, bias drift and noise as
    /// `[cell.errors]` switches them.
    pub fn for_cell(cell: &CellConfig, rng: ChaCha8Rng) -> ForceSensor {
        let s = &cell.sensor;
        let e = &cell.errors;
        let (mass, com) = cell.true_tool_load();
        ForceSensor {
            config: s.clone(),
            sensor_in_flange: cell.true_sensor_in_flange(),
            tool_mass_kg: mass,
            tool_com_m: com,
            gain: if e.sensor_gain {
                s.gain_error.map(|g| 1.0 + g)
            } else {
                [1.0; 6]
            },
            drift_per_s: if e.bias_drift {
                s.bias_drift_per_s
            } else {
                [0.0; 6]
            },
            noise_sigma: if e.sensor_noise {
                s.noise_sigma
            } else {
                [0.0; 6]
            },
            period_s: 1.0 / s.rate_hz,
            next_sample_s: 0.0,
            rng,
        }
    }

    /// World pose of the sensor frame for a (true) flange pose.
    pub fn sensor_pose(&self, flange: &Pose) -> Pose {
        flange * self.sensor_in_flange
    }

    /// Noise-free, bias-free reading: contact wrench (world axes, moment about world point `at`)
    /// plus tool weight, in the sensor frame.
    pub fn ideal_reading(&self, flange: &Pose, contact: &Wrench, at: &Vector3<f64>) -> Wrench {
        let sensor = self.sensor_pose(flange);
        contact_in_sensor(contact, at, &sensor)
            + tool_gravity_in_sensor(
                &sensor.rotation,
                self.tool_mass_kg,
                &self.tool_com_m,
                self.config.gravity_m_s2,
            )
    }

    /// One raw sample at `time_s`.
    pub fn sample(
        &mut self,
        time_s: f64,
        flange: &Pose,
        contact: &Wrench,
        at: &Vector3<f64>,
    ) -> SensorSample {
        let ideal = self.ideal_reading(flange, contact, at);
        let mut wrench_sensor = [0.0; 6];
        let mut saturated = false;
        for (i, out) in wrench_sensor.iter_mut().enumerate() {
            let noise: f64 = self.rng.sample(StandardNormal);
            let bias = self.config.bias[i] + self.drift_per_s[i] * time_s;
            let value = self.gain[i] * ideal[i] + bias + self.noise_sigma[i] * noise;
            let range = self.config.range[i];
            if value.abs() > range {
                saturated = true;
            }
            *out = value.clamp(-range, range);
        }
        SensorSample {
            time_s,
            wrench_sensor,
            saturated,
        }
    }

    /// Append every sample whose time falls before or at `until_s` (zero-order hold of the given
    /// state). Allocation-free once `out` has capacity.
    pub fn samples_until(
        &mut self,
        until_s: f64,
        flange: &Pose,
        contact: &Wrench,
        at: &Vector3<f64>,
        out: &mut Vec<SensorSample>,
    ) {
        // Tolerance against accumulated rounding of the two clocks.
        while self.next_sample_s <= until_s + 1e-9 {
            let t = self.next_sample_s;
            let sample = self.sample(t, flange, contact, at);
            out.push(sample);
            self.next_sample_s += self.period_s;
        }
    }
}
