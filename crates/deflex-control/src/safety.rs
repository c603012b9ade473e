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

/// Why the correction was stopped.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum FaultKind {
    /// Force (or torque) norm at the TCP above its limit.
    ForceOverLimit,
    /// No force sample for longer than the sensor timeout (or the sensor flags a fault).
    SensorTimeout,
    /// No robot state for longer than the robot timeout.
    RobotLinkLost,
    /// A non-finite input (joint value, wrench, time) or result.
    NonFinite,
    /// A value outside its plausible range: joint outside its limits or jumping, wrench beyond
    /// the sensor's range.
    OutOfRange,
}

impl FaultKind {
    /// All kinds, in flag-bit order.
    pub const ALL: [FaultKind; 5] = [
        FaultKind::ForceOverLimit,
        FaultKind::SensorTimeout,
        FaultKind::RobotLinkLost,
        FaultKind::NonFinite,
        FaultKind::OutOfRange,
    ];

    /// Stable snake-case name used in logs and status.
    pub fn name(self) -> &'static str {
        match self {
            FaultKind::ForceOverLimit => "force_over_limit",
            FaultKind::SensorTimeout => "sensor_timeout",
            FaultKind::RobotLinkLost => "robot_link_lost",
            FaultKind::NonFinite => "non_finite",
            FaultKind::OutOfRange => "out_of_range",
        }
    }

    /// The status flag of this kind.
    pub fn flag(self) -> u32 {
        match self {
            FaultKind::ForceOverLimit => Flags::FORCE_OVER_LIMIT,
            FaultKind::SensorTimeout => Flags::SENSOR_TIMEOUT,
            FaultKind::RobotLinkLost => Flags::ROBOT_LINK_LOST,
            FaultKind::NonFinite => Flags::NON_FINITE,
            FaultKind::OutOfRange => Flags::OUT_OF_RANGE,
        }
    }
}

impl std::fmt::Display for FaultKind {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(self.name())
    }
}

/// A latched fault: what, when, and the offending value (N, s, rad… depending on the kind;
/// NaN for non-finite inputs).
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
}

impl std::fmt::Display for Fault {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(
            f,
            "{} at t = {:.3} s (value {:.4}, limit {:.4})",
            self.kind, self.time_s, self.value, self.limit
        )
    }
}

/// Status bits of a control cycle (logged as an integer, decoded by [`Flags::describe`]).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Default, Hash)]
pub struct Flags(pub u32);

impl Flags {
    /// Fault: force over limit.
    pub const FORCE_OVER_LIMIT: u32 = 1 << 0;
    /// Fault: sensor silent.
    pub const SENSOR_TIMEOUT: u32 = 1 << 1;
    /// Fault: robot link lost.
    pub const ROBOT_LINK_LOST: u32 = 1 << 2;
    /// Fault: non-finite value.
    pub const NON_FINITE: u32 = 1 << 3;
    /// Fault: out-of-range value.
    pub const OUT_OF_RANGE: u32 = 1 << 4;
    /// A fault is latched (the correction is going to / at its safe value).
    pub const LATCHED: u32 = 1 << 8;
    /// ξ hit a size bound.
    pub const SATURATED_SIZE: u32 = 1 << 9;
    /// ξ hit a rate bound.
    pub const SATURATED_RATE: u32 = 1 << 10;
    /// A ramp (in or out) is in progress.
    pub const RAMPING: u32 = 1 << 11;
    /// The law drives the correction.
    pub const ACTIVE: u32 = 1 << 12;
    /// Taring the sensor (out of contact).
    pub const TARING: u32 = 1 << 13;
    /// This cycle reused a previous wrench sample (no new sample arrived).
    pub const STALE_WRENCH: u32 = 1 << 14;

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
        const NAMES: [(u32, &str); 12] = [
            (Flags::FORCE_OVER_LIMIT, "force_over_limit"),
            (Flags::SENSOR_TIMEOUT, "sensor_timeout"),
            (Flags::ROBOT_LINK_LOST, "robot_link_lost"),
            (Flags::NON_FINITE, "non_finite"),
            (Flags::OUT_OF_RANGE, "out_of_range"),
            (Flags::LATCHED, "latched"),
            (Flags::SATURATED_SIZE, "saturated_size"),
            (Flags::SATURATED_RATE, "saturated_rate"),
            (Flags::RAMPING, "ramping"),
            (Flags::ACTIVE, "active"),
            (Flags::TARING, "taring"),
            (Flags::STALE_WRENCH, "stale_wrench"),
        ];
        let names: Vec<&str> = NAMES
            .iter()
            .filter(|(bit, _)| self.has(*bit))
            .map(|(_, n)| *n)
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
    counts: [u64; 5],
}

impl Safety {
    /// No fault latched.
    pub fn new(config: SafetyConfig) -> Self {
        Safety {
            config,
            latched: None,
            counts: [0; 5],
        }
    }

    /// The first fault since the last reset, if any.
    pub fn latched(&self) -> Option<Fault> {
        self.latched
    }

    /// Records a detected fault; latches it if none is latched. Returns true when newly latched.
    pub fn trip(&mut self, fault: Fault) -> bool {
        let index = FaultKind::ALL
            .iter()
            .position(|k| *k == fault.kind)
            .unwrap_or(0);
        self.counts[index] += 1;
        if self.latched.is_none() {
            self.latched = Some(fault);
            true
        } else {
            false
        }
    }

    /// Number of cycles on which each kind was detected (order of [`FaultKind::ALL`]).
    pub fn counts(&self) -> [u64; 5] {
        self.counts
    }

    /// Clears the latch (operator acknowledgement). Counters are kept.
    pub fn reset(&mut self) {
        self.latched = None;
    }
}
