//! What one control cycle of the telemetry stream ([`CycleSample`]) is as ROS 2 messages: the
//! one mapping shared by the MCAP recorder (`deflex-record`) and the ROS 2 bridge
//! (`deflex-ros2`), so a recording and the live graph carry the same values in the same frames.
//!
//! | stream | type | frame ([`SessionInfo`]) | content |
//! | --- | --- | --- | --- |
//! | `joint_states` | `sensor_msgs/msg/JointState` | – | joint values the robot reported (rad), named as the model's joints |
//! | `wrench_raw` | `geometry_msgs/msg/WrenchStamped` | `sensor_frame` | raw F/T reading, cycle mean (N, N·m) |
//! | `wrench_sensor` | `geometry_msgs/msg/WrenchStamped` | `sensor_frame` | bias and tool gravity removed, low-pass filtered |
//! | `wrench_tcp` | `geometry_msgs/msg/WrenchStamped` | `base_frame` | the environment's wrench on the tool **at the TCP**, base axes (eq. 2) |
//! | `tcp_pose` | `geometry_msgs/msg/PoseStamped` | `base_frame` | the corrected TCP: forward kinematics of the reported joints |
//! | `program_pose` | `geometry_msgs/msg/PoseStamped` | `base_frame` | the program's (desired) TCP: position minus ξ, orientation exp(−ξ_r)·R |
//! | `deflection` | `geometry_msgs/msg/TwistStamped` | `base_frame` | estimated deflection δŝ (eq. 15): `linear` m, `angular` rad — a displacement, not a velocity |
//! | `correction` | `geometry_msgs/msg/TwistStamped` | `base_frame` | applied correction ξ (eq. 7), same convention |
//! | `error` | `geometry_msgs/msg/TwistStamped` | `base_frame` | tracking error ε = −ξ − δŝ (eq. 5), same convention |
//! | `feedforward` | `geometry_msgs/msg/TwistStamped` | `base_frame` | the feed-forward prior (zero without one) |
//! | `path_error` | `geometry_msgs/msg/Vector3Stamped` | `base_frame` | twin only: true TCP minus desired TCP (m); absent on a real cell |
//! | `diagnostics` | `diagnostic_msgs/msg/DiagnosticArray` | – | one status [`STATUS_NAME`] (level OK, WARN when saturated, ramping or holding, ERROR with a latched fault) whose values are the keys of [`diag`] |

use crate::Flags;
use crate::ros::{
    DiagnosticArrayMsg, DiagnosticStatusMsg, HeaderMsg, JointStateMsg, KeyValueMsg, PointMsg,
    PoseMsg, PoseStampedMsg, QuaternionMsg, TimeMsg, TwistMsg, TwistStampedMsg, Vector3Msg,
    Vector3StampedMsg, WrenchMsg, WrenchStampedMsg,
};
use crate::{CycleSample, LATE_UNKNOWN, SessionInfo};
use nalgebra::{Rotation3, UnitQuaternion, Vector3 as V3};

/// Name of the diagnostic status.
pub const STATUS_NAME: &str = "deflex/controller";

/// Keys of the [`STATUS_NAME`] diagnostic status (values are decimal text, SI units; an unknown
/// value is empty).
pub mod diag {
    /// Controller phase name (`idle`, `taring`, `running`, `stopping`, `stopped`, `faulted`).
    pub const PHASE: &str = "phase";
    /// Status bits as an integer (`crate::Flags`).
    pub const FLAGS: &str = "flags";
    /// Status bits by name (`Flags::describe`).
    pub const STATUS: &str = "status";
    /// Latched fault name, empty when none.
    pub const FAULT: &str = "fault";
    /// Cycle number.
    pub const CYCLE: &str = "cycle";
    /// Computation time of the cycle (s).
    pub const CYCLE_TIME_S: &str = "cycle_time_s";
    /// Answers sent later than one robot cycle after the telegram.
    pub const LATE_ANSWERS: &str = "late_answers";
    /// Answers the robot counted late (empty when it does not say).
    pub const ROBOT_LATE: &str = "robot_late";
    /// Robot telegrams answered.
    pub const ROBOT_TELEGRAMS: &str = "robot_telegrams";
    /// F/T samples received.
    pub const SENSOR_SAMPLES: &str = "sensor_samples";
    /// Arc length on the feed-forward path (m), empty when unknown.
    pub const PATH_S_M: &str = "path_s_m";
    /// The runaway guard's loop-gain estimate, empty when unknown.
    pub const LOOP_GAIN: &str = "loop_gain";
}

/// The messages of one cycle, by stream. Every message's stamp is the cycle's.
#[derive(Clone, Debug, PartialEq)]
pub struct CycleMessages {
    /// Joint values.
    pub joint_states: JointStateMsg,
    /// Raw F/T reading, sensor frame.
    pub wrench_raw: WrenchStampedMsg,
    /// Compensated F/T reading, sensor frame.
    pub wrench_sensor: WrenchStampedMsg,
    /// Environment wrench at the TCP, base frame.
    pub wrench_tcp: WrenchStampedMsg,
    /// Corrected TCP.
    pub tcp_pose: PoseStampedMsg,
    /// Program (desired) TCP.
    pub program_pose: PoseStampedMsg,
    /// δŝ.
    pub deflection: TwistStampedMsg,
    /// ξ.
    pub correction: TwistStampedMsg,
    /// ε.
    pub error: TwistStampedMsg,
    /// Feed-forward prior.
    pub feedforward: TwistStampedMsg,
    /// Twin only: true minus desired TCP; `None` when unknown (a real cell).
    pub path_error: Option<Vector3StampedMsg>,
}

fn header(stamp: TimeMsg, frame: &str) -> HeaderMsg {
    HeaderMsg {
        stamp,
        frame_id: frame.to_string(),
    }
}

fn wrench(stamp: TimeMsg, frame: &str, w: &[f64; 6]) -> WrenchStampedMsg {
    WrenchStampedMsg {
        header: header(stamp, frame),
        wrench: WrenchMsg {
            force: Vector3Msg::from_slice(&w[..3]),
            torque: Vector3Msg::from_slice(&w[3..]),
        },
    }
}

fn twist(stamp: TimeMsg, frame: &str, v: &[f64; 6]) -> TwistStampedMsg {
    TwistStampedMsg {
        header: header(stamp, frame),
        twist: TwistMsg {
            linear: Vector3Msg::from_slice(&v[..3]),
            angular: Vector3Msg::from_slice(&v[3..]),
        },
    }
}

/// A position and a rotation as a `geometry_msgs/Pose` (unit quaternion of `r`).
pub fn pose(p: V3<f64>, r: &Rotation3<f64>) -> PoseMsg {
    let q = UnitQuaternion::from_rotation_matrix(r);
    PoseMsg {
        position: PointMsg {
            x: p.x,
            y: p.y,
            z: p.z,
        },
        orientation: QuaternionMsg {
            x: q.i,
            y: q.j,
            z: q.k,
            w: q.w,
        },
    }
}

impl CycleMessages {
    /// The messages of cycle `s` of the session `info`, stamped `stamp`.
    pub fn new(info: &SessionInfo, s: &CycleSample, stamp: TimeMsg) -> CycleMessages {
        let base = info.base_frame.as_str();
        let sensor = info.sensor_frame.as_str();
        let rotation = s.tcp_rotation();
        // The robot realises s_com = s_des + ξ: the program's orientation is exp(−ξ_r)·R.
        let program_rotation =
            Rotation3::from_scaled_axis(-V3::from_column_slice(&s.correction[3..])) * rotation;
        CycleMessages {
            joint_states: JointStateMsg {
                header: header(stamp, ""),
                name: info.joint_names.clone(),
                position: s.q().to_vec(),
                velocity: Vec::new(),
                effort: Vec::new(),
            },
            wrench_raw: wrench(stamp, sensor, &s.wrench_raw),
            wrench_sensor: wrench(stamp, sensor, &s.wrench_sensor),
            wrench_tcp: wrench(stamp, base, &s.wrench_tcp),
            tcp_pose: PoseStampedMsg {
                header: header(stamp, base),
                pose: pose(s.tcp_position(), &rotation),
            },
            program_pose: PoseStampedMsg {
                header: header(stamp, base),
                pose: pose(s.program_position_m(), &program_rotation),
            },
            deflection: twist(stamp, base, &s.deflection),
            correction: twist(stamp, base, &s.correction),
            error: twist(stamp, base, &s.error),
            feedforward: twist(stamp, base, &s.feedforward),
            path_error: s
                .truth_error_m
                .iter()
                .all(|v| v.is_finite())
                .then(|| Vector3StampedMsg {
                    header: header(stamp, base),
                    vector: Vector3Msg::from_slice(&s.truth_error_m),
                }),
        }
    }
}

/// The diagnostics of cycle `s`: one status [`STATUS_NAME`] whose hardware id is the robot's
/// name, with the values of [`diag`] followed by `extra` (a sink's own counters).
pub fn diagnostics(
    info: &SessionInfo,
    s: &CycleSample,
    stamp: TimeMsg,
    extra: &[(&str, String)],
) -> DiagnosticArrayMsg {
    let flags = s.status_flags();
    let fault = s.fault_kind();
    let level = if fault.is_some() {
        DiagnosticStatusMsg::ERROR
    } else if flags.0
        & (Flags::SATURATED_SIZE | Flags::SATURATED_RATE | Flags::RUNAWAY_HOLD | Flags::RAMPING)
        != 0
    {
        DiagnosticStatusMsg::WARN
    } else {
        DiagnosticStatusMsg::OK
    };
    let finite = |v: f64| {
        if v.is_finite() {
            format!("{v}")
        } else {
            String::new()
        }
    };
    let kv = |k: &str, v: String| KeyValueMsg {
        key: k.to_string(),
        value: v,
    };
    let phase = info.source.phase_name(s.phase_code);
    let status = flags.describe();
    let message = match fault {
        Some(kind) => format!("{phase}: fault {}", kind.name()),
        None if status.is_empty() => phase.to_string(),
        None => format!("{phase}: {status}"),
    };
    let mut values = vec![
        kv(diag::PHASE, phase.to_string()),
        kv(diag::FLAGS, flags.0.to_string()),
        kv(diag::STATUS, status),
        kv(
            diag::FAULT,
            fault.map_or(String::new(), |k| k.name().to_string()),
        ),
        kv(diag::CYCLE, s.cycle.to_string()),
        kv(diag::CYCLE_TIME_S, finite(s.cycle_time_s)),
        kv(diag::LATE_ANSWERS, s.late_answers.to_string()),
        kv(
            diag::ROBOT_LATE,
            if s.robot_late == LATE_UNKNOWN {
                String::new()
            } else {
                s.robot_late.to_string()
            },
        ),
        kv(diag::ROBOT_TELEGRAMS, s.robot_telegrams.to_string()),
        kv(diag::SENSOR_SAMPLES, s.sensor_samples.to_string()),
        kv(diag::PATH_S_M, finite(s.path_s_m)),
        kv(diag::LOOP_GAIN, finite(s.loop_gain)),
    ];
    values.extend(extra.iter().map(|(k, v)| kv(k, v.clone())));
    DiagnosticArrayMsg {
        header: header(stamp, ""),
        status: vec![DiagnosticStatusMsg {
            level,
            name: STATUS_NAME.to_string(),
            message,
            hardware_id: info.robot.clone(),
            values,
        }],
    }
}

/// When a sink sends the diagnostics of a cycle: on every change of phase, flags or fault, and
/// otherwise at most every `period_s` of session time (also after session time went back).
#[derive(Clone, Debug)]
pub struct DiagnosticsPacer {
    period_s: f64,
    last_time_s: f64,
    last_state: Option<(u32, u32, u32)>,
}

impl DiagnosticsPacer {
    /// A pacer sending at least every `period_s` (s).
    pub fn new(period_s: f64) -> DiagnosticsPacer {
        DiagnosticsPacer {
            period_s,
            last_time_s: f64::NEG_INFINITY,
            last_state: None,
        }
    }

    /// True when the diagnostics of `s` are due (and then counts them as sent).
    pub fn due(&mut self, s: &CycleSample) -> bool {
        let state = (s.phase_code, s.flags, s.fault);
        let due = self.last_state != Some(state)
            || s.time_s - self.last_time_s + 1e-9 >= self.period_s
            || s.time_s < self.last_time_s;
        if due {
            self.last_state = Some(state);
            self.last_time_s = s.time_s;
        }
        due
    }
}

/// Session time `t` (s) as nanoseconds (0 for negative or non-finite times).
pub fn seconds_to_ns(t: f64) -> u64 {
    if t.is_finite() && t > 0.0 {
        (t * 1e9).round().min(u64::MAX as f64) as u64
    } else {
        0
    }
}
