//! Robot controller emulation (a Stäubli CS8 with the Alter pack, or a KUKA KRC with RSI).
//!
//! * **Interpolation.** The path's waypoints are converted once to joint values by inverse
//!   kinematics (seeded point to point, so the robot stays on one branch); at the controller
//!   rate the joints are interpolated linearly between them in time at the programmed feed
//!   rates. The *desired* pose is the Cartesian polyline through the waypoints (what the CAM
//!   program means); joint interpolation departs from it by well under a micrometre.
//! * **External correction** `ξ = [δp; δφ]` (m, rad, robot base axes): taken into account after
//!   a transport delay (whole cycles), the look-ahead of streaming interfaces (a moving average,
//!   UR `servoj`, ABB EGM), the interpolator's first-order filter, a bound on its size and one on
//!   its speed, and the joint servos' response to it (second order, damping 0.7, at the servo
//!   bandwidth; the programmed path itself is feed-forwarded and tracked exactly), then added
//!   through the Jacobian as a joint offset `δq = J⁻¹ ξ` (small corrections, so no IK per
//!   cycle): `s_com = s_des + ξ` (eq. 7).

//! * **Joint stream** ([`ControllerEmulation::follow_joint_stream`], FANUC Stream Motion): the
//!   motion source is the device, not the controller's clock. Each cycle the drives take the
//!   last joint command received ([`ControllerEmulation::set_joint_command`]; the start pose
//!   until the first), tracked exactly as a programmed path is (the joint servos are
//!   feed-forwarded); no correction pipeline (the device adds its correction to the joints).
//!   The *desired* point is then not a time's: it is the closest point of the programmed
//!   polyline to the tool where it really is ([`ControllerEmulation::project`]), searched
//!   forward from the last one, so the error is the tool's distance from the path whatever the
//!   device's timing (the approach, its ramps, its pauses) and an along-path lag is not an
//!   error of the part.

use crate::cell_config::RobotControllerConfig;
use crate::error::SimError;
use crate::toolpath::ToolPath;
use deflex_model::{Data, IkOptions, Pose, Robot};
use nalgebra::{Matrix6, Rotation3, Vector3, Vector6};
use std::collections::VecDeque;

/// Damping ratio of the servo response to a correction.
const SERVO_DAMPING: f64 = 0.7;

/// A second-order low-pass (bilinear transform of ω²/(s² + 2ζωs + ω²), unit DC gain) per
/// channel, direct form II transposed.
#[derive(Clone, Debug)]
struct Biquad {
    b: [f64; 3],
    a: [f64; 2],
    state: [[f64; 2]; 6],
}

impl Biquad {
    fn low_pass(cutoff_hz: f64, rate_hz: f64) -> Biquad {
        let w0 = 2.0 * std::f64::consts::PI * cutoff_hz / rate_hz;
        let (sin, cos) = w0.sin_cos();
        let q = 1.0 / (2.0 * SERVO_DAMPING);
        let alpha = sin / (2.0 * q);
        let a0 = 1.0 + alpha;
        let b0 = (1.0 - cos) / 2.0 / a0;
        Biquad {
            b: [b0, 2.0 * b0, b0],
            a: [-2.0 * cos / a0, (1.0 - alpha) / a0],
            state: [[0.0; 2]; 6],
        }
    }

    fn step(&mut self, input: &[f64; 6]) -> [f64; 6] {
        let mut out = [0.0; 6];
        for ((o, x), s) in out.iter_mut().zip(input).zip(self.state.iter_mut()) {
            let y = self.b[0] * x + s[0];
            s[0] = self.b[1] * x - self.a[0] * y + s[1];
            s[1] = self.b[2] * x - self.a[1] * y;
            *o = y;
        }
        out
    }
}

/// The correction pipeline: delay → look-ahead → first-order filter → size bound → speed bound
/// → servo response.
#[derive(Clone, Debug)]
pub struct CorrectionPipeline {
    period_s: f64,
    fifo: VecDeque<[f64; 6]>,
    delay_cycles: usize,
    window: VecDeque<[f64; 6]>,
    window_sum: [f64; 6],
    window_len: usize,
    alpha: f64,
    filtered: [f64; 6],
    limited: [f64; 6],
    servo: Option<Biquad>,
    applied: [f64; 6],
    requested: [f64; 6],
    max_m: f64,
    max_rad: f64,
    step_m: f64,
    step_rad: f64,
}

impl CorrectionPipeline {
    /// A pipeline for the controller settings; `servo` switches the servo response and the
    /// look-ahead on (`[cell.errors] servo`). The settings must have been validated (their
    /// bounds keep the buffers small: at most 10⁴ cycles each).
    pub fn new(config: &RobotControllerConfig, servo: bool) -> CorrectionPipeline {
        let period_s = 1.0 / config.rate_hz;
        let delay_cycles = (config.correction_delay_s / period_s).round() as usize;
        let alpha = if config.correction_filter_s > 0.0 {
            1.0 - (-period_s / config.correction_filter_s).exp()
        } else {
            1.0
        };
        let window_len = if servo {
            ((config.lookahead_s / period_s).round() as usize).max(1)
        } else {
            1
        };
        let mut fifo = VecDeque::with_capacity(delay_cycles + 2);
        fifo.extend(std::iter::repeat_n([0.0; 6], delay_cycles));
        let mut window = VecDeque::with_capacity(window_len + 1);
        window.extend(std::iter::repeat_n([0.0; 6], window_len));
        CorrectionPipeline {
            period_s,
            fifo,
            delay_cycles,
            window,
            window_sum: [0.0; 6],
            window_len,
            alpha,
            filtered: [0.0; 6],
            limited: [0.0; 6],
            servo: (servo && config.servo_bandwidth_hz > 0.0)
                .then(|| Biquad::low_pass(config.servo_bandwidth_hz, config.rate_hz)),
            applied: [0.0; 6],
            requested: [0.0; 6],
            max_m: config.max_correction_m,
            max_rad: config.max_correction_rad,
            step_m: config.max_correction_speed_m_s * period_s,
            step_rad: config.max_correction_speed_rad_s * period_s,
        }
    }

    /// Latest requested correction (held until replaced).
    pub fn set(&mut self, xi: [f64; 6]) {
        if xi.iter().all(|v| v.is_finite()) {
            self.requested = xi;
        }
    }

    /// Delay in whole controller cycles.
    pub fn delay_cycles(&self) -> usize {
        self.delay_cycles
    }

    /// Controller period (s).
    pub fn period_s(&self) -> f64 {
        self.period_s
    }

    /// Advance one cycle; returns the correction applied in this cycle. Allocation-free.
    pub fn advance(&mut self) -> [f64; 6] {
        self.fifo.push_back(self.requested);
        let delayed = self.fifo.pop_front().unwrap_or([0.0; 6]);
        // Look-ahead: moving average over the window (a running sum; the window is full).
        let oldest = self.window.pop_front().unwrap_or([0.0; 6]);
        self.window.push_back(delayed);
        let n = self.window_len as f64;
        let mut smoothed = [0.0; 6];
        for i in 0..6 {
            self.window_sum[i] += delayed[i] - oldest[i];
            smoothed[i] = self.window_sum[i] / n;
        }
        if self.window_len == 1 {
            smoothed = delayed;
        }
        for (f, d) in self.filtered.iter_mut().zip(smoothed) {
            *f += self.alpha * (d - *f);
        }
        // Size bound on the target, then speed bound on the change.
        let mut target = self.filtered;
        clamp_norm(&mut target[0..3], self.max_m);
        clamp_norm(&mut target[3..6], self.max_rad);
        let mut change = [0.0; 6];
        for ((c, t), a) in change.iter_mut().zip(target).zip(self.limited) {
            *c = t - a;
        }
        clamp_norm(&mut change[0..3], self.step_m);
        clamp_norm(&mut change[3..6], self.step_rad);
        for (a, c) in self.limited.iter_mut().zip(change) {
            *a += c;
        }
        self.applied = match self.servo.as_mut() {
            Some(servo) => servo.step(&self.limited),
            None => self.limited,
        };
        self.applied
    }

    /// Correction applied in the last cycle.
    pub fn applied(&self) -> [f64; 6] {
        self.applied
    }
}

fn clamp_norm(v: &mut [f64], max: f64) {
    let n = v.iter().map(|x| x * x).sum::<f64>().sqrt();
    if n > max {
        let s = max / n;
        v.iter_mut().for_each(|x| *x *= s);
    }
}

/// One interpolation cycle of the emulated controller.
#[derive(Clone, Copy, Debug)]
pub struct ControllerCycle {
    /// Simulated time (s).
    pub time_s: f64,
    /// Desired TCP position (world, m): the programmed polyline.
    pub desired_m: Vector3<f64>,
    /// Horizontal unit direction of the programmed motion (zero when not moving horizontally).
    pub feed_dir: Vector3<f64>,
    /// Interpolated joint values without correction (rad).
    pub q_nominal: [f64; 6],
    /// Joint values sent to the drives (with the correction) (rad).
    pub q_command: [f64; 6],
    /// Correction applied (m, rad).
    pub correction: [f64; 6],
    /// Past the end of the path.
    pub finished: bool,
}

/// Joint-space interpolation between IK'd waypoints plus the correction input.
#[derive(Clone, Debug)]
pub struct ControllerEmulation {
    robot: Robot,
    data: Data,
    times: Vec<f64>,
    q: Vec<[f64; 6]>,
    p: Vec<Vector3<f64>>,
    tool_rotation: Rotation3<f64>,
    segment: usize,
    cycle: u64,
    period_s: f64,
    pipeline: CorrectionPipeline,
    /// Joint stream mode: the last command received (`None` before the first).
    stream: Option<JointStream>,
}

/// The state of a joint stream ([`ControllerEmulation::follow_joint_stream`]).
#[derive(Clone, Copy, Debug)]
struct JointStream {
    /// The joints commanded (rad): the last command, the start pose before the first.
    command: [f64; 6],
    /// The device ended the stream.
    ended: bool,
}

/// Segments searched forward from the last projection's ([`ControllerEmulation::project`]).
const PROJECTION_WINDOW: usize = 64;

impl ControllerEmulation {
    /// Plan the path: waypoints (R_p, mm) → world poses with the tool orientation of the seed
    /// configuration → joint values by IK.
    pub fn new(
        robot: &Robot,
        config: &RobotControllerConfig,
        servo: bool,
        path: &ToolPath,
        part_frame: &Pose,
        seed_q: &[f64; 6],
    ) -> Result<ControllerEmulation, SimError> {
        ControllerEmulation::with_reference(robot, config, servo, path, None, part_frame, seed_q)
    }

    /// [`ControllerEmulation::new`] for a robot program `path` that means another path,
    /// `reference`: an offline-compensated program (each waypoint the compensated target of the
    /// reference's waypoint with the same index). The robot interpolates the program; the
    /// *desired* pose and the feed direction are the reference's at the same segment and
    /// fraction, so the twin measures the error against what the part should be. `None`: the
    /// program is its own reference.
    pub fn with_reference(
        robot: &Robot,
        config: &RobotControllerConfig,
        servo: bool,
        path: &ToolPath,
        reference: Option<&ToolPath>,
        part_frame: &Pose,
        seed_q: &[f64; 6],
    ) -> Result<ControllerEmulation, SimError> {
        path.validate()?;
        if let Some(reference) = reference {
            reference.validate()?;
            if reference.waypoints.len() != path.waypoints.len() {
                return Err(SimError::Path(format!(
                    "the program \"{}\" has {} waypoints, its reference \"{}\" {}: a compensated \
                     program has one waypoint per reference waypoint",
                    path.name,
                    path.waypoints.len(),
                    reference.name,
                    reference.waypoints.len()
                )));
            }
        }
        if robot.joint_count() != 6 {
            return Err(SimError::config(
                "part.robot",
                "the twin needs a 6-joint robot",
            ));
        }
        let tool_rotation = robot
            .tcp_pose(seed_q)
            .map_err(|e| SimError::config("part.seed_q_deg", e.to_string()))?
            .rotation;
        let options = IkOptions {
            position_tolerance_m: 1e-10,
            orientation_tolerance_rad: 1e-10,
            ..IkOptions::default()
        };
        let mut seed: Vec<f64> = seed_q.to_vec();
        let mut times = Vec::with_capacity(path.waypoints.len());
        let mut qs = Vec::with_capacity(path.waypoints.len());
        let mut ps: Vec<Vector3<f64>> = Vec::with_capacity(path.waypoints.len());
        let mut t = 0.0;
        for (i, w) in path.waypoints.iter().enumerate() {
            let p = part_frame * nalgebra::Point3::from(Vector3::from(w.p_mm) * 1e-3);
            if let Some(prev) = ps.last() {
                let prev: &Vector3<f64> = prev;
                let length = (p.coords - prev).norm();
                t += length / (w.feed_mm_s.unwrap_or(config.rapid_feed_mm_s) * 1e-3);
            }
            let target = Pose::from_parts(p.coords.into(), tool_rotation);
            let solution =
                robot
                    .inverse_kinematics(&target, &seed, &options)
                    .map_err(|source| SimError::Unreachable {
                        what: format!(
                            "waypoint {i} of \"{}\" at ({:.3}, {:.3}, {:.3}) mm in R_p",
                            path.name, w.p_mm[0], w.p_mm[1], w.p_mm[2]
                        ),
                        source,
                    })?;
            seed.copy_from_slice(&solution.q);
            let mut q = [0.0; 6];
            q.copy_from_slice(&solution.q);
            times.push(t);
            qs.push(q);
            ps.push(p.coords);
        }
        if let Some(reference) = reference {
            for (p, w) in ps.iter_mut().zip(&reference.waypoints) {
                *p = (part_frame * nalgebra::Point3::from(Vector3::from(w.p_mm) * 1e-3)).coords;
            }
        }
        Ok(ControllerEmulation {
            robot: robot.clone(),
            data: Data::new(),
            times,
            q: qs,
            p: ps,
            tool_rotation,
            segment: 0,
            cycle: 0,
            period_s: 1.0 / config.rate_hz,
            pipeline: CorrectionPipeline::new(config, servo),
            stream: None,
        })
    }

    /// From now on the drives follow the joints a device streams (see the module
    /// documentation), starting at the path's start pose until the first command.
    pub fn follow_joint_stream(&mut self) {
        if self.stream.is_none() {
            self.stream = Some(JointStream {
                command: self.q[0],
                ended: false,
            });
        }
    }

    /// The joints streamed for the next cycle (rad); ignored unless following a joint stream,
    /// or when not finite.
    pub fn set_joint_command(&mut self, q: [f64; 6]) {
        if let Some(s) = self.stream.as_mut()
            && q.iter().all(|v| v.is_finite())
        {
            s.command = q;
        }
    }

    /// The device ended its stream: the next cycle is the run's last.
    pub fn end_joint_stream(&mut self) {
        if let Some(s) = self.stream.as_mut() {
            s.ended = true;
        }
    }

    /// Following a joint stream.
    pub fn follows_joint_stream(&self) -> bool {
        self.stream.is_some()
    }

    /// The closest point to `p` (world, m) of the programmed polyline's segments from the
    /// current one forward over 64 segments (the earliest on a tie), which
    /// becomes the current segment. Allocation-free.
    pub fn project(&mut self, p: &Vector3<f64>) -> Vector3<f64> {
        let last = self.p.len() - 1;
        if last == 0 {
            return self.p[0];
        }
        let mut best = (f64::INFINITY, self.segment, self.p[self.segment]);
        let end = (self.segment + PROJECTION_WINDOW).min(last);
        for k in self.segment..end {
            let (a, b) = (self.p[k], self.p[k + 1]);
            let ab = b - a;
            let len2 = ab.norm_squared();
            let f = if len2 > 0.0 {
                ((p - a).dot(&ab) / len2).clamp(0.0, 1.0)
            } else {
                0.0
            };
            let q = a + ab * f;
            let d = (p - q).norm_squared();
            if d < best.0 {
                best = (d, k, q);
            }
        }
        self.segment = best.1;
        best.2
    }

    /// Controller period (s).
    pub fn period_s(&self) -> f64 {
        self.period_s
    }

    /// Path duration (s).
    pub fn duration_s(&self) -> f64 {
        *self.times.last().unwrap_or(&0.0)
    }

    /// Tool orientation held along the path.
    pub fn tool_rotation(&self) -> Rotation3<f64> {
        self.tool_rotation
    }

    /// Number of waypoints.
    pub fn waypoint_count(&self) -> usize {
        self.q.len()
    }

    /// Request a correction (see [`CorrectionPipeline`]).
    pub fn set_correction(&mut self, xi: [f64; 6]) {
        self.pipeline.set(xi);
    }

    /// Run one controller cycle. Allocation-free.
    pub fn advance(&mut self) -> ControllerCycle {
        if let Some(stream) = self.stream {
            return self.advance_stream(stream);
        }
        let time_s = self.cycle as f64 * self.period_s;
        self.cycle += 1;
        let last = self.times.len() - 1;
        while self.segment < last - 1 && self.times[self.segment + 1] <= time_s {
            self.segment += 1;
        }
        let (a, b) = (self.segment, (self.segment + 1).min(last));
        let span = self.times[b] - self.times[a];
        let f = if span > 0.0 {
            ((time_s - self.times[a]) / span).clamp(0.0, 1.0)
        } else {
            1.0
        };
        let mut q_nominal = [0.0; 6];
        for (i, q) in q_nominal.iter_mut().enumerate() {
            *q = self.q[a][i] + f * (self.q[b][i] - self.q[a][i]);
        }
        let desired_m = self.p[a] + (self.p[b] - self.p[a]) * f;
        let mut dir = self.p[b] - self.p[a];
        dir.z = 0.0;
        let finished = time_s >= self.times[last];
        let feed_dir = if finished || dir.norm() < 1e-12 {
            Vector3::zeros()
        } else {
            dir.normalize()
        };
        let correction = self.pipeline.advance();
        let mut q_command = q_nominal;
        if correction.iter().any(|v| *v != 0.0) {
            let dq = self.joint_offset(&q_nominal, &correction);
            for (q, d) in q_command.iter_mut().zip(dq.iter()) {
                *q += d;
            }
        }
        ControllerCycle {
            time_s,
            desired_m,
            feed_dir,
            q_nominal,
            q_command,
            correction,
            finished,
        }
    }

    /// One cycle following a joint stream: the command, the desired point where the last
    /// projection left it (the cell projects the true tool once it is known), the feed direction
    /// of that segment.
    fn advance_stream(&mut self, stream: JointStream) -> ControllerCycle {
        let time_s = self.cycle as f64 * self.period_s;
        self.cycle += 1;
        let last = self.p.len() - 1;
        let (a, b) = (self.segment, (self.segment + 1).min(last));
        let mut dir = self.p[b] - self.p[a];
        dir.z = 0.0;
        let feed_dir = if stream.ended || dir.norm() < 1e-12 {
            Vector3::zeros()
        } else {
            dir.normalize()
        };
        ControllerCycle {
            time_s,
            desired_m: self.p[a],
            feed_dir,
            q_nominal: stream.command,
            q_command: stream.command,
            correction: [0.0; 6],
            finished: stream.ended,
        }
    }

    /// `δq = J⁻¹ ξ` at `q` (6×6 geometric Jacobian at the TCP; damped when near singular).
    fn joint_offset(&mut self, q: &[f64; 6], xi: &[f64; 6]) -> Vector6<f64> {
        self.robot
            .forward_kinematics(&mut self.data, q)
            .expect("6 joints");
        let columns = self
            .robot
            .geometric_jacobian_columns(&self.data, &self.data.tcp_position());
        let j = Matrix6::from_fn(|r, c| columns[c][r]);
        let xi = Vector6::from_row_slice(xi);
        match j.lu().solve(&xi) {
            Some(dq) if dq.iter().all(|v| v.is_finite()) => dq,
            _ => {
                let jt = j.transpose();
                let damped = j * jt + Matrix6::identity() * 1e-6;
                jt * damped.lu().solve(&xi).unwrap_or_else(Vector6::zeros)
            }
        }
    }
}
