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

/// Why the correction was stopped (or, for [`FaultKind::ContactRunaway`] with the guard's
/// default action, why its growth was held).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum FaultKind {
    /// Force norm at the TCP above its limit (N).
    ForceOverLimit,
    /// Torque norm at the TCP above its limit (N·m).
    TorqueOverLimit,
    /// No force sample for longer than the sensor timeout (s).
    SensorTimeout,
    /// The sensor flags a fault in its status word (the value is the word).
    SensorStatus,
    /// No robot state for longer than the robot timeout (s).
    RobotLinkLost,
    /// A non-finite input (joint value, wrench channel, time) or result.
    NonFinite,
    /// A raw reading channel at or beyond the sensor's range (N or N·m).
    SensorOverRange,
    /// A joint outside the model's limits plus the margin (rad).
    JointOutOfLimits,
    /// A joint changed more than plausible between two control cycles (rad).
    JointJump,
    /// The robot reports a different number of joints than the model has.
    JointCountMismatch,
    /// The correction pushes into a contact stiff enough that the force rises in step with it
    /// (estimated loop gain, see [`crate::runaway`]).
    ContactRunaway,
}

/// Number of fault kinds.
pub const FAULT_KINDS: usize = 11;

impl FaultKind {
    /// All kinds, in flag-bit order.
    pub const ALL: [FaultKind; FAULT_KINDS] = [
        FaultKind::ForceOverLimit,
        FaultKind::TorqueOverLimit,
        FaultKind::SensorTimeout,
        FaultKind::SensorStatus,
        FaultKind::RobotLinkLost,
        FaultKind::NonFinite,
        FaultKind::SensorOverRange,
        FaultKind::JointOutOfLimits,
        FaultKind::JointJump,
        FaultKind::JointCountMismatch,
        FaultKind::ContactRunaway,
    ];

    /// Stable snake-case name used in logs and status: the check that tripped.
    pub fn name(self) -> &'static str {
        match self {
            FaultKind::ForceOverLimit => "force_over_limit",
            FaultKind::TorqueOverLimit => "torque_over_limit",
            FaultKind::SensorTimeout => "sensor_timeout",
            FaultKind::SensorStatus => "sensor_status",
            FaultKind::RobotLinkLost => "robot_link_lost",
            FaultKind::NonFinite => "non_finite",
            FaultKind::SensorOverRange => "sensor_over_range",
            FaultKind::JointOutOfLimits => "joint_out_of_limits",
            FaultKind::JointJump => "joint_jump",
            FaultKind::JointCountMismatch => "joint_count_mismatch",
            FaultKind::ContactRunaway => "contact_runaway",
        }
    }

    /// Unit of the fault's value and limit.
    pub fn unit(self) -> &'static str {
        match self {
            FaultKind::ForceOverLimit | FaultKind::SensorOverRange => "N",
            FaultKind::TorqueOverLimit => "N·m",
            FaultKind::SensorTimeout | FaultKind::RobotLinkLost => "s",
            FaultKind::JointOutOfLimits | FaultKind::JointJump => "rad",
            FaultKind::SensorStatus
            | FaultKind::NonFinite
            | FaultKind::JointCountMismatch
            | FaultKind::ContactRunaway => "",
        }
    }

    /// The status flag of this kind.
    pub fn flag(self) -> u32 {
        let index = FaultKind::ALL.iter().position(|k| *k == self).unwrap_or(0);
        1 << index
    }

    fn index(self) -> usize {
        FaultKind::ALL.iter().position(|k| *k == self).unwrap_or(0)
    }
}

impl std::fmt::Display for FaultKind {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(self.name())
    }
}

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
}

impl std::fmt::Display for Fault {
    /// `joint_out_of_limits: joint 3 value 3.2000 rad limit 3.1416 rad at t = 1.230 s`.
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        let unit = self.kind.unit();
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

/// Status bits of a control cycle (logged as an integer, decoded by [`Flags::describe`]). Bits
/// 0–15 are the fault kinds in [`FaultKind::ALL`] order (the kind detected this cycle, and the
/// latched one); bits 16 and up are states.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Default, Hash)]
pub struct Flags(pub u32);

impl Flags {
    /// Fault: force over limit.
    pub const FORCE_OVER_LIMIT: u32 = 1 << 0;
    /// Fault: torque over limit.
    pub const TORQUE_OVER_LIMIT: u32 = 1 << 1;
    /// Fault: sensor silent.
    pub const SENSOR_TIMEOUT: u32 = 1 << 2;
    /// Fault: sensor status word.
    pub const SENSOR_STATUS: u32 = 1 << 3;
    /// Fault: robot link lost.
    pub const ROBOT_LINK_LOST: u32 = 1 << 4;
    /// Fault: non-finite value.
    pub const NON_FINITE: u32 = 1 << 5;
    /// Fault: reading beyond the sensor's range.
    pub const SENSOR_OVER_RANGE: u32 = 1 << 6;
    /// Fault: joint outside its limits.
    pub const JOINT_OUT_OF_LIMITS: u32 = 1 << 7;
    /// Fault: implausible joint jump.
    pub const JOINT_JUMP: u32 = 1 << 8;
    /// Fault: joint count differs from the model's.
    pub const JOINT_COUNT_MISMATCH: u32 = 1 << 9;
    /// Contact runaway detected (a fault, or the guard's hold; see [`Flags::RUNAWAY_HOLD`]).
    pub const CONTACT_RUNAWAY: u32 = 1 << 10;
    /// A fault is latched (the correction is going to / at its safe value).
    pub const LATCHED: u32 = 1 << 16;
    /// ξ hit a size bound.
    pub const SATURATED_SIZE: u32 = 1 << 17;
    /// ξ hit a rate bound.
    pub const SATURATED_RATE: u32 = 1 << 18;
    /// A ramp (in or out) is in progress.
    pub const RAMPING: u32 = 1 << 19;
    /// The law drives the correction.
    pub const ACTIVE: u32 = 1 << 20;
    /// Taring the sensor (out of contact).
    pub const TARING: u32 = 1 << 21;
    /// This cycle reused a previous wrench sample (no new sample arrived).
    pub const STALE_WRENCH: u32 = 1 << 22;
    /// The runaway guard holds the correction's growth along the corrected direction.
    pub const RUNAWAY_HOLD: u32 = 1 << 23;
    /// A feed-forward table is set but the robot is not on its path (acquiring the start, off
    /// the path, past its end): no prior this cycle ([`crate::feedforward`]).
    pub const FEEDFORWARD_OFF_PATH: u32 = 1 << 24;

    /// True if `bit` is set.
    pub fn has(self, bit: u32) -> bool {
        self.0 & bit != 0
    }

    /// Sets `bit`.
    pub fn set(&mut self, bit: u32) {
        self.0 |= bit;
    }

    /// `|`-separated names of the set bits (allocates: for writer threads and humans only).
    pub fn describe(self) -> String {
        const STATES: [(u32, &str); 9] = [
            (Flags::LATCHED, "latched"),
            (Flags::SATURATED_SIZE, "saturated_size"),
            (Flags::SATURATED_RATE, "saturated_rate"),
            (Flags::RAMPING, "ramping"),
            (Flags::ACTIVE, "active"),
            (Flags::TARING, "taring"),
            (Flags::STALE_WRENCH, "stale_wrench"),
            (Flags::RUNAWAY_HOLD, "runaway_hold"),
            (Flags::FEEDFORWARD_OFF_PATH, "feedforward_off_path"),
        ];
        let names: Vec<&str> = FaultKind::ALL
            .iter()
            .map(|k| (k.flag(), k.name()))
            .chain(STATES)
            .filter(|(bit, _)| self.has(*bit))
            .map(|(_, n)| n)
            .collect();
        names.join("|")
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
