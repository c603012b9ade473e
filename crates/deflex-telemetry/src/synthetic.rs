//! A SIMULATED telemetry stream for examples, tests and benches: a tool on a descending helix
//! (a forming pass) that comes into contact after one second, the contact force rising towards
//! about 1 kN, a diagonal compliance turning it into a deflection of a few millimetres, and a
//! correction following it with a first-order lag, bounded in size and rate. It is **not** the
//! digital twin (`deflex-sim`) and not the controller: only signals of the right shape and
//! size, deterministic for a given seed, so that a page, a recording or a plot has something
//! realistic to show. Every [`SessionInfo`] it makes says SIMULATED.

use crate::{CycleSample, SessionInfo, StreamSource};
use crate::{Flags, Phase};
use nalgebra::{Rotation3, Vector3};

/// The stream's generator; [`SyntheticCell::next_sample`] gives one control cycle.
#[derive(Clone, Debug)]
pub struct SyntheticCell {
    period_s: f64,
    cycle: u64,
    state: u64,
    xi: [f64; 6],
    late: u64,
    twin: bool,
}

/// Correction bound per axis of the synthetic session (m, rad).
pub const LIMIT: [f64; 6] = [0.01, 0.01, 0.01, 0.02, 0.02, 0.02];
/// Correction rate bound (m/s, rad/s).
pub const RATE_LIMIT: [f64; 6] = [0.05, 0.05, 0.05, 0.1, 0.1, 0.1];

impl SyntheticCell {
    /// A stream at `period_s` per cycle; `twin`: the truth (path error) is known.
    pub fn new(period_s: f64, seed: u64, twin: bool) -> SyntheticCell {
        SyntheticCell {
            period_s,
            cycle: 0,
            state: seed.wrapping_mul(0x9E37_79B9_7F4A_7C15) | 1,
            xi: [0.0; 6],
            late: 0,
            twin,
        }
    }

    /// The session description of this stream (labelled SIMULATED).
    pub fn session_info(&self) -> SessionInfo {
        let source = if self.twin {
            StreamSource::Twin
        } else {
            StreamSource::Runtime
        };
        let mut info = SessionInfo::new(
            source,
            "SIMULATED synthetic stream (tx200 joint names)",
            (1..=6).map(|i| format!("joint_{i}")).collect(),
        );
        info.simulated = true;
        info.protocol = "synthetic".into();
        info.control_period_s = self.period_s;
        info.correction_limit = LIMIT;
        info.correction_rate_limit = RATE_LIMIT;
        info.force_limit_n = 2000.0;
        info
    }

    /// Uniform in [0, 1) (xorshift64).
    fn uniform(&mut self) -> f64 {
        self.state ^= self.state << 13;
        self.state ^= self.state >> 7;
        self.state ^= self.state << 17;
        (self.state >> 11) as f64 / (1u64 << 53) as f64
    }

    /// Bell-shaped noise in [−1, 1] (mean of three uniforms).
    fn noise(&mut self) -> f64 {
        let sum = self.uniform() + self.uniform() + self.uniform();
        (sum / 3.0 - 0.5) * 2.0
    }

    /// The next control cycle.
    pub fn next_sample(&mut self) -> CycleSample {
        self.cycle += 1;
        let t = self.cycle as f64 * self.period_s;
        let mut s = CycleSample {
            time_s: t,
            cycle: self.cycle,
            ..CycleSample::default()
        };
        // Program: a descending helix, 40 mm radius, 1 rad/s, 0.5 mm down per turn.
        let angle = t;
        let radius = 0.04;
        let centre = Vector3::new(1.5, 0.0, 0.2);
        let program = centre
            + Vector3::new(
                radius * angle.cos(),
                radius * angle.sin(),
                -0.0005 * angle / std::f64::consts::TAU,
            );
        // Contact after 1 s; Fz towards −1 kN, in-plane 0.36 Fz radial and 0.12 Fz against feed.
        let contact = if t > 1.0 {
            1.0 - (-(t - 1.0) / 1.5).exp()
        } else {
            0.0
        };
        let fz = -(600.0 + 400.0 * (1.0 - (-t / 30.0).exp())) * contact + 8.0 * self.noise();
        let radial = Vector3::new(angle.cos(), angle.sin(), 0.0);
        let feed = Vector3::new(-angle.sin(), angle.cos(), 0.0);
        let f = radial * (0.36 * fz.abs()) - feed * (0.12 * fz.abs()) + Vector3::new(0.0, 0.0, fz);
        let m = Vector3::new(0.02 * f.y, -0.02 * f.x, 0.5 * self.noise());
        s.wrench_tcp = [f.x, f.y, f.z, m.x, m.y, m.z];
        // The sensor sees the same wrench in its own frame (tool pointing down: x, −y, −z).
        s.wrench_sensor = [f.x, -f.y, -f.z, m.x, -m.y, -m.z];
        let bias = [3.0, -2.0, 12.0, 0.1, 0.05, -0.02];
        for (i, b) in bias.iter().enumerate() {
            s.wrench_raw[i] = s.wrench_sensor[i] + b + 2.0 * self.noise();
        }
        // δŝ = C w with a diagonal compliance (m/N, rad/(N·m)).
        let c = [2.0e-6, 2.5e-6, 3.0e-6, 1.0e-6, 1.0e-6, 2.0e-6];
        for (i, c) in c.iter().enumerate() {
            s.deflection[i] = c * s.wrench_tcp[i];
        }
        // ξ follows −δŝ (time constant 0.4 s) within its size and rate bounds.
        let running = t > 0.5;
        let mut saturated = false;
        for i in 0..6 {
            let target = if running { -s.deflection[i] } else { 0.0 };
            let step = (target - self.xi[i]) * (self.period_s / 0.4).min(1.0);
            let max_step = RATE_LIMIT[i] * self.period_s;
            if step.abs() > max_step {
                saturated = true;
            }
            self.xi[i] = (self.xi[i] + step.clamp(-max_step, max_step)).clamp(-LIMIT[i], LIMIT[i]);
            s.correction[i] = self.xi[i];
            s.error[i] = -self.xi[i] - s.deflection[i];
        }
        s.tcp_position_m = (program + Vector3::from_column_slice(&self.xi[..3])).into();
        let down = Rotation3::from_euler_angles(std::f64::consts::PI, 0.0, angle * 0.1);
        s.set_tcp_rotation(
            &(Rotation3::from_scaled_axis(Vector3::from_column_slice(&self.xi[3..])) * down),
        );
        if self.twin {
            let e: Vector3<f64> = Vector3::from_column_slice(&s.error[..3]) * 0.4
                + Vector3::new(self.noise(), self.noise(), self.noise()) * 2e-5;
            s.truth_error_m = e.into();
        }
        s.path_s_m = radius * angle;
        s.loop_gain = if contact > 0.0 {
            0.05 + 0.01 * self.noise()
        } else {
            f64::NAN
        };
        s.set_q(&[
            0.1 * angle.sin(),
            0.6 + 0.05 * angle.cos(),
            -0.9 + 0.03 * angle.sin(),
            0.01,
            1.2 - 0.02 * angle.cos(),
            angle * 0.1,
        ]);
        // A scheduling hiccup now and then (0.3 % of the cycles): a slow cycle and a late answer.
        let spike = self.uniform() < 0.003;
        s.cycle_time_s = 350e-6 + 60e-6 * self.noise() + if spike { 1.5e-3 } else { 0.0 };
        if spike {
            self.late += 1;
        }
        s.late_answers = self.late;
        s.robot_telegrams = (t / 0.004) as u64;
        s.robot_late = self.late / 2;
        s.sensor_samples = (t * 1000.0) as u64;
        let phase = if running {
            Phase::Running
        } else {
            Phase::Taring
        };
        s.phase_code = CycleSample::phase_to_code(phase);
        let mut flags = Flags(if running {
            Flags::ACTIVE
        } else {
            Flags::TARING
        });
        if saturated {
            flags.set(Flags::SATURATED_RATE);
        }
        s.flags = flags.0;
        s
    }
}
