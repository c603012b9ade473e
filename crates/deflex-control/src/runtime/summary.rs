//! What a run of the runtime reports: the live status while it runs and the summary at its end,
//! including how the session ended (the robot's program finished, an operator stop, a failure).

use crate::controller::Phase;
use crate::safety::{Fault, Flags};
use crate::stats::StatsSummary;
use std::net::SocketAddr;

/// Live status for the operator (read any time, lock-free).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct LiveStatus {
    /// Controller time (s).
    pub time_s: f64,
    /// Phase.
    pub phase: Phase,
    /// Flags of the last cycle.
    pub flags: Flags,
    /// Force norm at the TCP (N).
    pub force_n: f64,
    /// Position correction ξ_p (m).
    pub xi_m: [f64; 3],
    /// Rotation correction norm (rad).
    pub xi_rot_rad: f64,
    /// Control cycles so far.
    pub cycles: u64,
    /// Robot telegrams answered so far.
    pub telegrams: u64,
    /// Sensor samples received so far.
    pub samples: u64,
    /// Answers the robot counted as late, when its protocol reports it (KUKA RSI `Delay`).
    pub robot_late: Option<u64>,
    /// Packets from hosts other than the robot, refused.
    pub foreign: u64,
}

/// How a session ended.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum SessionEnd {
    /// The robot stopped sending and stayed silent until the idle exit: the normal end of its
    /// program (the correction was ramped out as it went silent).
    RobotFinished,
    /// Stopped on request (operator signal, `--duration-s`): the correction was ramped out.
    Stopped,
    /// Stopped on request before the robot and the sensor were both heard.
    StoppedBeforeStart,
    /// The run failed ([`RunSummary::error`] says why).
    Failed,
}

impl SessionEnd {
    /// The phase shown to people: `ended (robot program finished)`, `stopped`, ….
    pub fn describe(self, final_phase: Phase, fault: Option<&Fault>) -> String {
        match self {
            SessionEnd::RobotFinished if fault.is_none() => "ended (robot program finished)".into(),
            SessionEnd::RobotFinished => format!(
                "ended (robot program finished) after a fault ({})",
                final_phase.name()
            ),
            SessionEnd::Stopped => "stopped (correction ramped out)".into(),
            SessionEnd::StoppedBeforeStart => "stopped before start".into(),
            SessionEnd::Failed => "failed".into(),
        }
    }

    /// Stable machine name (`ended`, `stopped`, `stopped_before_start`, `failed`).
    pub fn name(self) -> &'static str {
        match self {
            SessionEnd::RobotFinished => "ended",
            SessionEnd::Stopped => "stopped",
            SessionEnd::StoppedBeforeStart => "stopped_before_start",
            SessionEnd::Failed => "failed",
        }
    }
}

/// What a run did.
#[derive(Clone, Debug)]
pub struct RunSummary {
    /// Control cycle time statistics (deadline: the control period).
    pub control: StatsSummary,
    /// Robot-link reply latency (receipt of a telegram → reply sent; deadline: robot cycle).
    /// Its deadline misses are the telegrams answered later than one robot cycle.
    pub reply_latency: StatsSummary,
    /// Control cycles run.
    pub cycles: u64,
    /// Telegrams answered.
    pub telegrams: u64,
    /// Number of joints the robot's telegrams carry (0 if none arrived).
    pub robot_joints: usize,
    /// Receive timeouts on the robot link (10 ms each while waiting).
    pub robot_timeouts: u64,
    /// Malformed robot packets.
    pub robot_bad_packets: u64,
    /// Other robot link errors (send failures…).
    pub robot_errors: u64,
    /// Packets (or TCP connections) from hosts other than the robot, refused.
    pub robot_foreign: u64,
    /// The last refused host.
    pub last_foreign: Option<SocketAddr>,
    /// Answers the robot itself counted as late or missing over the session, when its protocol
    /// reports it (KUKA RSI `Delay D`, last minus first).
    pub robot_late: Option<u64>,
    /// Sensor samples received.
    pub samples: u64,
    /// Samples lost on the network.
    pub sample_gaps: u64,
    /// Samples with a fault status word.
    pub sensor_faults: u64,
    /// Malformed sensor packets and other sensor link errors.
    pub sensor_errors: u64,
    /// Sensor packets from hosts other than the sensor, refused.
    pub sensor_foreign: u64,
    /// Controller phase at the end.
    pub phase: Phase,
    /// How the session ended.
    pub end: SessionEnd,
    /// The latched fault, if any. A loss of the robot link that lasted until the idle exit is
    /// the end of the robot's program, reported by [`RunSummary::end`], not here.
    pub fault: Option<Fault>,
    /// Times the runaway guard acted, and the first time as a fault record.
    pub runaway_events: u64,
    /// First runaway the guard acted on.
    pub first_runaway: Option<Fault>,
    /// Largest force norm seen at the TCP once tared (N).
    pub max_force_n: f64,
    /// Largest |ξ_p| (m).
    pub max_xi_m: f64,
    /// Largest change between two consecutive answers per axis, as sent (m, rad).
    pub max_step_sent: [f64; 6],
    /// Log records dropped.
    pub log_dropped: u64,
    /// Real-time warnings.
    pub warnings: Vec<String>,
    /// Set when the run failed (no data, a joint-count mismatch, a thread that panicked…).
    pub error: Option<String>,
}

impl RunSummary {
    /// A summary in `phase` with every statistic and counter at zero, no fault, no warnings
    /// and no error.
    pub(super) fn zeroed(phase: Phase) -> Self {
        RunSummary {
            control: StatsSummary::default(),
            reply_latency: StatsSummary::default(),
            cycles: 0,
            telegrams: 0,
            robot_joints: 0,
            robot_timeouts: 0,
            robot_bad_packets: 0,
            robot_errors: 0,
            robot_foreign: 0,
            last_foreign: None,
            robot_late: None,
            samples: 0,
            sample_gaps: 0,
            sensor_faults: 0,
            sensor_errors: 0,
            sensor_foreign: 0,
            phase,
            end: SessionEnd::Failed,
            fault: None,
            runaway_events: 0,
            first_runaway: None,
            max_force_n: 0.0,
            max_xi_m: 0.0,
            max_step_sent: [0.0; 6],
            log_dropped: 0,
            warnings: Vec::new(),
            error: None,
        }
    }

    /// The phase as people read it: `ended (robot program finished)`, `stopped (…)`, or the
    /// controller's phase (`faulted`, …) when the session ended otherwise.
    pub fn phase_text(&self) -> String {
        match self.end {
            SessionEnd::Failed if self.error.is_none() => self.phase.name().into(),
            end => end.describe(self.phase, self.fault.as_ref()),
        }
    }
}
