//! The wrench path of the controller (Section 4.2): raw sensor reading → bias (tare taken out of
//! contact) → tool-gravity compensation for the current orientation → optional first-order
//! low-pass → the environment wrench `w` of eq. 2 at the TCP, in world (base) axes, which is what
//! eq. 15 needs. [`WrenchProcessor::raw_reading`] goes the other way: the reading for a known
//! environment wrench.
//!
//! Conventions: the sensor reports, in its own axes and about its own origin, the wrench that
//! acts on the part of the tool beyond it (the environment's push plus the tool's weight). The
//! sensor pose is `flange × sensor_in_flange`, with the flange from forward kinematics (eq. 1).
//! Everything here is allocation-free.

use deflex_model::wrench_transport::{sensor_wrench_at_point, world_wrench_in_sensor};
use deflex_model::{Data, Pose, ToolLoad, Wrench};
use nalgebra::Vector3;

/// Standard gravity (m/s²), pointing along −z of the world frame by default.
pub const STANDARD_GRAVITY: f64 = 9.806_65;

/// Static configuration of the wrench path.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct WrenchConfig {
    /// Sensor frame in the flange frame (mounting).
    pub sensor_in_flange: Pose,
    /// The tool carried by the sensor, for gravity compensation (its weight is taken out of
    /// every reading): the mass beyond the sensor's measuring plane, the centre of mass in the
    /// sensor frame.
    pub tool_in_sensor: ToolLoad,
    /// Gravity acceleration in world axes (m/s²).
    pub gravity_world: [f64; 3],
    /// Cut-off of the first-order low-pass (Hz); `None` disables it.
    pub lowpass_hz: Option<f64>,
}

impl Default for WrenchConfig {
    fn default() -> Self {
        WrenchConfig {
            sensor_in_flange: Pose::identity(),
            tool_in_sensor: ToolLoad::NONE,
            gravity_world: [0.0, 0.0, -STANDARD_GRAVITY],
            lowpass_hz: None,
        }
    }
}

/// The result of one pass through the wrench path.
#[derive(Clone, Copy, Debug, PartialEq, Default)]
pub struct ProcessedWrench {
    /// Bias- and gravity-compensated, filtered reading in the sensor frame.
    pub sensor: Wrench,
    /// Environment wrench `w` (eq. 2) at the TCP in world axes, moment about the TCP.
    pub tcp_world: Wrench,
}

/// Stateful wrench processing: bias, tare accumulation and low-pass state.
#[derive(Clone, Debug)]
pub struct WrenchProcessor {
    config: WrenchConfig,
    bias: Wrench,
    tare_sum: Wrench,
    tare_count: u32,
    filtered: Wrench,
    filter_primed: bool,
    /// Cached (dt, α) of the low-pass: `exp` only when the sample time changes.
    alpha_cache: (f64, f64),
}

impl WrenchProcessor {
    /// A processor with zero bias.
    pub fn new(config: WrenchConfig) -> Self {
        WrenchProcessor {
            config,
            bias: Wrench::zeros(),
            tare_sum: Wrench::zeros(),
            tare_count: 0,
            filtered: Wrench::zeros(),
            filter_primed: false,
            alpha_cache: (f64::NAN, 0.0),
        }
    }

    /// The configuration.
    pub fn config(&self) -> &WrenchConfig {
        &self.config
    }

    /// World pose of the sensor frame: `flange × sensor_in_flange` (forward kinematics, eq. 1).
    #[inline]
    pub fn sensor_pose(&self, data: &Data) -> Pose {
        data.flange * self.config.sensor_in_flange
    }

    /// What the sensor reads from the tool's weight alone at `sensor_pose`: force `Rᵀ m g`, moment
    /// `c × f` about the sensor origin (sensor axes).
    #[inline]
    pub fn gravity_in_sensor(&self, sensor_pose: &Pose) -> Wrench {
        let tool = &self.config.tool_in_sensor;
        let g = Vector3::from(self.config.gravity_world) * tool.mass_kg;
        let f = sensor_pose.rotation.matrix().transpose() * g;
        let m = tool.centre_of_mass_m.cross(&f);
        Wrench::new(f.x, f.y, f.z, m.x, m.y, m.z)
    }

    /// Current bias (sensor frame, gravity excluded).
    pub fn bias(&self) -> Wrench {
        self.bias
    }

    /// Sets the bias directly (e.g. from a configuration file).
    pub fn set_bias(&mut self, bias: Wrench) {
        self.bias = bias;
    }

    /// Adds one out-of-contact reading to the tare: its gravity part for the current orientation
    /// is removed first, so the tool may move during the tare.
    pub fn tare_add(&mut self, raw: &Wrench, sensor_pose: &Pose) {
        let g = self.gravity_in_sensor(sensor_pose);
        for i in 0..6 {
            self.tare_sum[i] += raw[i] - g[i];
        }
        self.tare_count += 1;
    }

    /// Number of readings accumulated by [`Self::tare_add`] since the last [`Self::tare_finish`].
    pub fn tare_count(&self) -> u32 {
        self.tare_count
    }

    /// Ends the tare: the bias becomes the mean of the accumulated readings. Returns false (bias
    /// unchanged) when nothing was accumulated.
    pub fn tare_finish(&mut self) -> bool {
        if self.tare_count == 0 {
            return false;
        }
        let n = f64::from(self.tare_count);
        for i in 0..6 {
            self.bias[i] = self.tare_sum[i] / n;
        }
        self.tare_sum = Wrench::zeros();
        self.tare_count = 0;
        true
    }

    /// Bias and gravity compensation of one raw reading (sensor frame).
    #[inline]
    pub fn compensate(&self, raw: &Wrench, sensor_pose: &Pose) -> Wrench {
        let g = self.gravity_in_sensor(sensor_pose);
        let mut out = Wrench::zeros();
        for i in 0..6 {
            out[i] = raw[i] - self.bias[i] - g[i];
        }
        out
    }

    /// First-order low-pass with cut-off `lowpass_hz`, sampled every `dt_s`; the identity when the
    /// filter is off. The first sample primes the state.
    #[inline]
    pub fn filter(&mut self, wrench: &Wrench, dt_s: f64) -> Wrench {
        let Some(fc) = self.config.lowpass_hz.filter(|f| *f > 0.0) else {
            return *wrench;
        };
        if !self.filter_primed {
            self.filtered = *wrench;
            self.filter_primed = true;
            return *wrench;
        }
        let dt = dt_s.max(0.0);
        if dt != self.alpha_cache.0 {
            self.alpha_cache = (dt, 1.0 - (-2.0 * std::f64::consts::PI * fc * dt).exp());
        }
        let alpha = self.alpha_cache.1;
        for i in 0..6 {
            self.filtered[i] += alpha * (wrench[i] - self.filtered[i]);
        }
        self.filtered
    }

    /// Forgets the filter state (the next sample primes it).
    pub fn reset_filter(&mut self) {
        self.filter_primed = false;
    }

    /// The raw reading that this path turns into the environment wrench `tcp_world` (eq. 2:
    /// world axes, moment about the TCP), with `data` filled by forward kinematics: the inverse
    /// of [`Self::process`] once the low-pass has settled,
    ///
    /// `raw = b + g_S + [Rᵀ f ; Rᵀ (m + (p_tcp − p_S) × f)]`,
    ///
    /// with `b` the bias ([`Self::bias`]), `g_S` the tool's weight as the sensor sees it
    /// ([`Self::gravity_in_sensor`]), `R` and `p_S` the sensor frame's world rotation and origin
    /// (`flange × sensor_in_flange`, [`Self::sensor_pose`]), `f` and `m` the force and the moment
    /// of `tcp_world`, `p_tcp` the TCP position. It is what the sensor must read for a given
    /// contact under this mounting, tool and bias: readings synthesised for a known contact (a
    /// test, a bench, a what-if), or the expected reading to compare a real one with.
    #[inline]
    pub fn raw_reading(&self, tcp_world: &Wrench, data: &Data) -> Wrench {
        let sensor_pose = self.sensor_pose(data);
        let gravity = self.gravity_in_sensor(&sensor_pose);
        let contact = world_wrench_in_sensor(tcp_world, &data.tcp_position(), &sensor_pose);
        Wrench::from_fn(|i, _| self.bias[i] + gravity[i] + contact[i])
    }

    /// The full path for one reading with `data` filled by forward kinematics at the robot's
    /// reported joint values: compensated, filtered, and moved to the TCP in world axes.
    #[inline]
    pub fn process(&mut self, raw: &Wrench, data: &Data, dt_s: f64) -> ProcessedWrench {
        let sensor_pose = self.sensor_pose(data);
        let compensated = self.compensate(raw, &sensor_pose);
        let filtered = self.filter(&compensated, dt_s);
        let at_tcp = sensor_wrench_at_point(&filtered, &sensor_pose, &data.tcp_position());
        ProcessedWrench {
            sensor: filtered,
            tcp_world: at_tcp,
        }
    }
}
