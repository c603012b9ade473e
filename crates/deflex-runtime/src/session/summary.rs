//! What a run of the runtime reports: the live status while it runs and the summary at its end,
//! including how the session ended (the robot's program finished, an operator stop, a failure).

use crate::stats::StatsSummary;
use deflex_control::{Fault, PoseMismatch};
use deflex_io::LinkCounters;
use deflex_telemetry::{FaultKind, Flags, Phase};
use std::net::SocketAddr;

/// The thread a failure came from.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum SessionThread {
    /// The control thread (the law, paced by the clock).
    Control,
    /// The robot-link thread.
    RobotLink,
    /// The sensor thread.
    Sensor,
}

/// Why a session failed, with the values that explain it.
#[derive(Clone, Debug, PartialEq)]
pub enum SessionError {
    /// The robot or the sensor was not heard within the startup timeout.
    NoData {
        /// Time waited (s).
        waited_s: f64,
        /// A robot telegram arrived.
        robot_heard: bool,
        /// A sensor sample arrived.
        sensor_heard: bool,
    },
    /// The robot's telegrams carry another number of joints than the model has
    /// ([`FaultKind::JointCountMismatch`]).
    JointCountMismatch {
        /// Joint values per telegram.
        reported: usize,
        /// The model's joints.
        model_joints: usize,
        /// The model's name.
        model: String,
    },
    /// A joint of the first telegram lies outside the model's limits plus the safety margin
    /// ([`FaultKind::JointOutOfLimits`]).
    JointOutOfLimits {
        /// Joint, from 1.
        joint: usize,
        /// Its value (rad).
        value_rad: f64,
        /// The model's limits (rad).
        limits_rad: [f64; 2],
        /// The margin allowed beyond them (rad).
        margin_rad: f64,
    },
    /// The TCP pose the robot reports with its first telegram is farther from the model's
    /// forward kinematics at the same joints than the tolerance
    /// ([`FaultKind::ModelMismatch`], [`deflex_control::model_check`]).
    ModelMismatch {
        /// How far (position, orientation, the position offset in base axes).
        mismatch: PoseMismatch,
        /// The position tolerance (m).
        position_tolerance_m: f64,
        /// The orientation tolerance (rad).
        orientation_tolerance_rad: f64,
        /// The model's name.
        model: String,
        /// The model's tool: flange → TCP translation (m).
        tool_m: [f64; 3],
    },
    /// A thread panicked; the links ramped the correction out and stopped.
    ThreadPanicked {
        /// Which.
        thread: SessionThread,
        /// The panic's message.
        message: String,
    },
}

impl SessionError {
    /// The fault kind this refusal corresponds to, when it is one of the law's checks.
    pub fn fault_kind(&self) -> Option<FaultKind> {
        match self {
            SessionError::JointCountMismatch { .. } => Some(FaultKind::JointCountMismatch),
            SessionError::JointOutOfLimits { .. } => Some(FaultKind::JointOutOfLimits),
            SessionError::ModelMismatch { .. } => Some(FaultKind::ModelMismatch),
            _ => None,
        }
    }
}

impl std::fmt::Display for SessionError {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        let heard = |h: bool| if h { "received" } else { "missing" };
        match self {
            SessionError::NoData {
                waited_s,
                robot_heard,
                sensor_heard,
            } => write!(
                f,
                "no data within {waited_s:.1} s: robot state {}, sensor samples {}",
                heard(*robot_heard),
                heard(*sensor_heard)
            ),
            SessionError::JointCountMismatch {
                reported,
                model_joints,
                model,
            } => write!(
                f,
                "{}: the robot's telegrams carry {reported} joint values but the model \"{model}\" \
                 has {model_joints} joints; refusing to run (use the model of this robot)",
                FaultKind::JointCountMismatch.name()
            ),
            SessionError::JointOutOfLimits {
                joint,
                value_rad,
                limits_rad: [lo, hi],
                margin_rad,
            } => write!(
                f,
                "{}: joint {joint} reported at {value_rad:.4} rad ({:.2}°), outside the model's \
                 limits [{lo:.4}, {hi:.4}] rad ([{:.2}°, {:.2}°]) plus the {margin_rad:.3} rad \
                 margin; refusing to run (wrong model, or the robot is not where its program \
                 starts)",
                FaultKind::JointOutOfLimits.name(),
                value_rad.to_degrees(),
                lo.to_degrees(),
                hi.to_degrees(),
            ),
            SessionError::ModelMismatch {
                mismatch,
                position_tolerance_m,
                orientation_tolerance_rad,
                model,
                tool_m,
            } => {
                let [dx, dy, dz] = mismatch.offset_m.map(|v| v * 1e3);
                let [tx, ty, tz] = tool_m.map(|v| v * 1e3);
                write!(
                    f,
                    "{}: the TCP pose the robot reports is {:.2} mm and {:.2} mrad from the \
                     model \"{model}\" at the same joints (reported − model [{dx:.2}, {dy:.2}, \
                     {dz:.2}] mm, robot base axes; tolerance {:.2} mm, {:.2} mrad); refusing to \
                     run. Likely causes: the tool (the model's flange → TCP is [{tx:.1}, {ty:.1}, \
                     {tz:.1}] mm: compare with the controller's active tool), the base (the \
                     robot file's frame R0 is not the frame the controller reports in), the \
                     robot file (another robot or geometry), or units (lengths in mm where m are \
                     expected)",
                    FaultKind::ModelMismatch.name(),
                    mismatch.position_m * 1e3,
                    mismatch.orientation_rad * 1e3,
                    position_tolerance_m * 1e3,
                    orientation_tolerance_rad * 1e3,
                )
            }
            SessionError::ThreadPanicked { thread, message } => match thread {
                SessionThread::Control => write!(
                    f,
                    "control thread panicked ({message}); the links ramped the correction out and \
                     stopped"
                ),
                SessionThread::RobotLink => write!(f, "robot link thread panicked ({message})"),
                SessionThread::Sensor => write!(f, "sensor thread panicked ({message})"),
            },
        }
    }
}

impl std::error::Error for SessionError {}

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
    /// The robot link was held by a connection that served no robot lines while another was
    /// refused ([`RunSummary::robot_starved`]): the robot may have been locked out.
    RobotStarved,
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
            SessionEnd::RobotStarved => "faulted (robot_link_starved: another connection held \
                 the robot link while the robot was served no answers)"
                .into(),
        }
    }

    /// Stable machine name (`ended`, `stopped`, `stopped_before_start`, `failed`).
    pub fn name(self) -> &'static str {
        match self {
            SessionEnd::RobotFinished => "ended",
            SessionEnd::Stopped => "stopped",
            SessionEnd::StoppedBeforeStart => "stopped_before_start",
            SessionEnd::Failed => "failed",
            SessionEnd::RobotStarved => "robot_starved",
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
    /// Messages from the robot dropped unanswered because they were no new state (a sequence
    /// number that did not advance, a robot clock going back, another joint count).
    pub robot_dropped: u64,
    /// A second connection was refused while the one holding the session served no robot
    /// lines: the robot may have been locked out. The session counts as faulted.
    pub robot_starved: bool,
    /// The robot link's own counters at the end (accepted, answers, refusals and drops by
    /// reason).
    pub robot_link: LinkCounters,
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
    /// The `robot_link_lost` latched by the robot's final silence (no telegram after it until
    /// the idle exit): the end of its program, not a fault, but shown as `faulted` by the live
    /// line while it lasted; the summary names it so that the two agree.
    pub final_silence: Option<Fault>,
    /// Times the runaway guard acted, and the first time as a fault record.
    pub runaway_events: u64,
    /// First runaway the guard acted on.
    pub first_runaway: Option<Fault>,
    /// The largest difference between the TCP pose the robot reported and the model's at the
    /// same joints ([`deflex_control::model_check`]); `None` when the protocol reports no pose
    /// (Stäubli, the simple line links) or the check is off.
    pub pose_mismatch_max: Option<PoseMismatch>,
    /// Largest force norm seen at the TCP once tared (N).
    pub max_force_n: f64,
    /// Largest |ξ_p| (m).
    pub max_xi_m: f64,
    /// Largest change between two consecutive answers per axis, as sent (m, rad).
    pub max_step_sent: [f64; 6],
    /// Control cycles the CSV log lost (its reader fell more than the telemetry ring behind);
    /// set by the caller that ran the log sink (`deflex_record::csv_log::LogReport::dropped`).
    pub log_dropped: u64,
    /// Real-time warnings.
    pub warnings: Vec<String>,
    /// Set when the run failed (no data, a joint-count mismatch, a thread that panicked…).
    pub error: Option<SessionError>,
}

impl RunSummary {
    /// A summary in `phase` with every statistic and counter at zero, no fault, no warnings
    /// and no error.
    pub(crate) fn zeroed(phase: Phase) -> Self {
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
            robot_dropped: 0,
            robot_starved: false,
            robot_link: LinkCounters::default(),
            robot_late: None,
            samples: 0,
            sample_gaps: 0,
            sensor_faults: 0,
            sensor_errors: 0,
            sensor_foreign: 0,
            phase,
            end: SessionEnd::Failed,
            fault: None,
            final_silence: None,
            runaway_events: 0,
            first_runaway: None,
            pose_mismatch_max: None,
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
