//! The state vocabulary of a session, shared by the control law that sets it and every sink
//! that shows it: the controller's [`Phase`], its status [`Flags`] and the [`FaultKind`]s of the
//! safety supervision (why a correction was stopped).

/// Life-cycle phase.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Phase {
    /// Not started: ξ = 0.
    Idle,
    /// Averaging out-of-contact readings for the bias: ξ = 0.
    Taring,
    /// Ramping in or applying the law.
    Running,
    /// Ramping out after `Controller::stop`.
    Stopping,
    /// Stopped: ξ = 0.
    Stopped,
    /// A fault is latched: ξ goes to / stays at the safe value.
    Faulted,
}

impl Phase {
    /// Lower-case name.
    pub fn name(self) -> &'static str {
        match self {
            Phase::Idle => "idle",
            Phase::Taring => "taring",
            Phase::Running => "running",
            Phase::Stopping => "stopping",
            Phase::Stopped => "stopped",
            Phase::Faulted => "faulted",
        }
    }
}

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
    /// (estimated loop gain, see `deflex_control::runaway`).
    ContactRunaway,
    /// The TCP pose the robot reports (KUKA RSI `RIst`, ABB EGM feedback) is farther from the
    /// model's forward kinematics at the same joints than the tolerance (m; rad on the
    /// orientation): wrong tool, base, robot file or units (see `deflex_control::model_check`).
    ModelMismatch,
}

/// Number of fault kinds.
pub const FAULT_KINDS: usize = 12;

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
        FaultKind::ModelMismatch,
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
            FaultKind::ModelMismatch => "model_mismatch",
        }
    }

    /// Unit of the fault's value and limit (a [`FaultKind::ModelMismatch`] on the orientation
    /// is in rad: its fault record says which).
    pub fn unit(self) -> &'static str {
        match self {
            FaultKind::ModelMismatch => "m",
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

    /// Position in [`FaultKind::ALL`] (the bit of its flag).
    pub fn index(self) -> usize {
        FaultKind::ALL.iter().position(|k| *k == self).unwrap_or(0)
    }
}

impl std::fmt::Display for FaultKind {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(self.name())
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
    /// Fault: the robot's reported TCP pose is not the model's.
    pub const MODEL_MISMATCH: u32 = 1 << 11;
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
    /// the path, past its end): no prior this cycle (`deflex_control::feedforward`).
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
