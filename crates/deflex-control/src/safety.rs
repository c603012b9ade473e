//! Safety supervision of the correction loop.
//!
//! The paper warns that the correction "may lead to exceeding the payload capacity of the robot"
//! (Section 5): the loop pushes the tool further into the part to cancel the deflection δs of
//! eq. 15, which raises the process force (Fig. 18). Every condition below therefore *latches* a
//! fault; the controller then stops integrating (the PID of eq. 17 is frozen), stops following
//! the law, and ramps ξ to the safe value; the fault stays visible in the status flags, the
//! log and the live status until the operator resets it. Nothing here panics.
//!
//! **Safe value: zero by default** ([`SafeAction::Zero`]). ξ = 0 means s_com = s_des (eq. 7):
//! the robot returns smoothly to its own programmed path, the one the operator validated. It is
//! the only value that does not rely on the data that just proved untrustworthy, and in contact
//! it *reduces* the process force (the correction is what pushed the tool deeper), which is the
//! right reaction to a force over the limit. [`SafeAction::Hold`] (freeze ξ) is offered for
//! processes where retracting by the deflection would mark the part; it never grows either.

use deflex_telemetry::{FAULT_KINDS, FaultKind};

/// Which quantity a fault is about.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, Default)]
pub enum Channel {
    /// A scalar (force norm, a timeout, …).
    #[default]
    Whole,
    /// Correction / deflection axis `0..6` (`x y z rx ry rz`, base axes).
    Axis(u8),
    /// Joint index `0..` (shown 1-based).
    Joint(u8),
    /// Sensor channel `0..6` (`fx fy fz mx my mz`, sensor frame).
    Sensor(u8),
    /// Controller time.
    Time,
    /// The TCP position (the robot's reported pose against the model's).
    TcpPosition,
    /// The TCP orientation (the robot's reported pose against the model's).
    TcpOrientation,
}

const AXIS_NAMES: [&str; 6] = ["x", "y", "z", "rx", "ry", "rz"];
const SENSOR_NAMES: [&str; 6] = ["fx", "fy", "fz", "mx", "my", "mz"];

impl std::fmt::Display for Channel {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match *self {
            Channel::Whole => Ok(()),
            Channel::Axis(i) => write!(f, "axis {}", AXIS_NAMES.get(i as usize).unwrap_or(&"?")),
            Channel::Joint(i) => write!(f, "joint {}", u32::from(i) + 1),
            Channel::Sensor(i) => {
                write!(f, "sensor {}", SENSOR_NAMES.get(i as usize).unwrap_or(&"?"))
            }
            Channel::Time => f.write_str("time"),
            Channel::TcpPosition => f.write_str("TCP position"),
            Channel::TcpOrientation => f.write_str("TCP orientation"),
        }
    }
}

/// A latched fault: which check, on which axis, joint or channel, the offending value and the
/// limit it was compared with (in [`FaultKind::unit`]; NaN for non-finite inputs).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Fault {
    /// What happened.
    pub kind: FaultKind,
    /// Controller time when it was detected (s).
    pub time_s: f64,
    /// The offending value.
    pub value: f64,
    /// The limit it was compared with.
    pub limit: f64,
    /// The axis, joint or channel concerned.
    pub channel: Channel,
}

impl Fault {
    /// A fault on the whole quantity (no axis or joint).
    pub fn new(kind: FaultKind, time_s: f64, value: f64, limit: f64) -> Self {
        Fault {
            kind,
            time_s,
            value,
            limit,
            channel: Channel::Whole,
        }
    }

    /// The same fault on `channel`.
    pub fn on(mut self, channel: Channel) -> Self {
        self.channel = channel;
        self
    }

    /// Unit of the value and the limit: the kind's ([`FaultKind::unit`]), rad for a
    /// [`FaultKind::ModelMismatch`] on the TCP orientation.
    pub fn unit(&self) -> &'static str {
        match (self.kind, self.channel) {
            (FaultKind::ModelMismatch, Channel::TcpOrientation) => "rad",
            (kind, _) => kind.unit(),
        }
    }
}

impl std::fmt::Display for Fault {
    /// `joint_out_of_limits: joint 3 value 3.2000 rad limit 3.1416 rad at t = 1.230 s`.
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        let unit = self.unit();
        let sep = if unit.is_empty() { "" } else { " " };
        write!(f, "{}:", self.kind)?;
        if self.channel != Channel::Whole {
            write!(f, " {}", self.channel)?;
        }
        match self.kind {
            FaultKind::SensorStatus => write!(
                f,
                " status word {:#010x} (non-zero means fault)",
                self.value as u32
            )?,
            FaultKind::NonFinite => f.write_str(" value not finite")?,
            FaultKind::JointCountMismatch => write!(
                f,
                " the robot reports {} joints, the model has {}",
                self.value, self.limit
            )?,
            FaultKind::ContactRunaway => write!(
                f,
                " estimated loop gain {:.3} limit {:.3} (force rising with the correction)",
                self.value, self.limit
            )?,
            FaultKind::ModelMismatch if self.channel == Channel::TcpOrientation => write!(
                f,
                " reported {:.2} mrad from the model's at the same joints, limit {:.2} mrad \
                 (tool, base, robot file or units?)",
                self.value * 1e3,
                self.limit * 1e3
            )?,
            FaultKind::ModelMismatch => write!(
                f,
                " reported {:.2} mm from the model's at the same joints, limit {:.2} mm (tool, \
                 base, robot file or units?)",
                self.value * 1e3,
                self.limit * 1e3
            )?,
            _ => write!(
                f,
                " value {:.4}{sep}{unit} limit {:.4}{sep}{unit}",
                self.value, self.limit
            )?,
        }
        if matches!(
            self.kind,
            FaultKind::JointOutOfLimits | FaultKind::JointJump
        ) {
            write!(
                f,
                " ({:.2}° vs {:.2}°)",
                self.value.to_degrees(),
                self.limit.to_degrees()
            )?;
        }
        write!(f, " at t = {:.3} s", self.time_s)
    }
}

/// What the correction does once a fault is latched.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Default)]
pub enum SafeAction {
    /// Ramp ξ smoothly to zero (back to the programmed path). Default; see the module docs.
    #[default]
    Zero,
    /// Freeze ξ at its value when the fault was detected.
    Hold,
}

/// Limits of the supervision.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct SafetyConfig {
    /// Largest force norm at the TCP (N).
    pub max_force_n: f64,
    /// Largest torque norm at the TCP (N·m).
    pub max_torque_nm: f64,
    /// Largest age of the newest force sample (s).
    pub sensor_timeout_s: f64,
    /// Largest age of the newest robot state (s).
    pub robot_timeout_s: f64,
    /// Largest plausible raw reading per channel, the sensor's range (N, N·m).
    pub sensor_range: [f64; 6],
    /// Largest plausible joint change between two control cycles (rad).
    pub max_joint_step_rad: f64,
    /// Margin allowed beyond the model's joint limits (rad).
    pub joint_limit_margin_rad: f64,
    /// Reaction to a fault.
    pub safe_action: SafeAction,
}

impl Default for SafetyConfig {
    /// 2500 N, 400 N·m, 50 ms sensor and robot timeouts, the ATI Omega160 range
    /// (±2500 N, ±400 N·m), 0.05 rad per cycle, 0.02 rad margin, ramp to zero.
    fn default() -> Self {
        SafetyConfig {
            max_force_n: 2500.0,
            max_torque_nm: 400.0,
            sensor_timeout_s: 0.05,
            robot_timeout_s: 0.05,
            sensor_range: [2500.0, 2500.0, 2500.0, 400.0, 400.0, 400.0],
            max_joint_step_rad: 0.05,
            joint_limit_margin_rad: 0.02,
            safe_action: SafeAction::Zero,
        }
    }
}

/// The fault latch and counters.
#[derive(Clone, Debug, Default)]
pub struct Safety {
    /// Limits.
    pub config: SafetyConfig,
    latched: Option<Fault>,
    counts: [u64; FAULT_KINDS],
}

impl Safety {
    /// No fault latched.
    pub fn new(config: SafetyConfig) -> Self {
        Safety {
            config,
            latched: None,
            counts: [0; FAULT_KINDS],
        }
    }

    /// The first fault since the last reset, if any.
    pub fn latched(&self) -> Option<Fault> {
        self.latched
    }

    /// Records a detected fault; latches it if none is latched. Returns true when newly latched.
    pub fn trip(&mut self, fault: Fault) -> bool {
        self.counts[fault.kind.index()] += 1;
        if self.latched.is_none() {
            self.latched = Some(fault);
            true
        } else {
            false
        }
    }

    /// Number of cycles on which each kind was detected (order of [`FaultKind::ALL`]).
    pub fn counts(&self) -> [u64; FAULT_KINDS] {
        self.counts
    }

    /// Clears the latch (operator acknowledgement). Counters are kept.
    pub fn reset(&mut self) {
        self.latched = None;
    }
}
