//! Reading a deflex MCAP file back into cycle samples (for `deflex plot` and tests), streaming:
//! memory stays bounded by one chunk, whatever the file's length.

use crate::channels as ch;
use crate::{ReadError, SessionRecord};
use deflex_files::FileIoError;
use deflex_telemetry::FaultKind;
use deflex_telemetry::ros::{
    DiagnosticArrayMsg, JointStateMsg, PoseStampedMsg, RosMessage, TwistStampedMsg,
    Vector3StampedMsg, WrenchStampedMsg,
};
use deflex_telemetry::{CycleSample, LATE_UNKNOWN, StreamSource};
use nalgebra::{Quaternion, UnitQuaternion};
use std::io::Read;
use std::path::Path;

/// The 8 bytes an MCAP file starts with.
pub const MCAP_MAGIC: &[u8; 8] = b"\x89MCAP0\r\n";

/// Largest record (or decompressed chunk) the reader accepts (bytes).
pub const MAX_RECORD_BYTES: usize = 64 << 20;

/// True when `path` starts with the MCAP magic bytes.
pub fn is_mcap(path: &Path) -> std::io::Result<bool> {
    let mut head = [0u8; 8];
    let mut file = deflex_files::open_input(path).map_err(deflex_files::InputError::into_io)?;
    let mut n = 0;
    while n < 8 {
        match file.read(&mut head[n..])? {
            0 => break,
            k => n += k,
        }
    }
    Ok(n == 8 && &head == MCAP_MAGIC)
}

/// What a recording held besides its cycles.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct RecordingSummary {
    /// The session description (`/deflex/session`), when present.
    pub session: Option<SessionRecord>,
    /// Cycles read.
    pub cycles: u64,
    /// The twin's path error was recorded.
    pub path_error_known: bool,
    /// Messages of channels this reader does not know (skipped).
    pub foreign_messages: u64,
}

/// The channels the reader decodes, by the index used below.
const KNOWN: [(&str, &str); 12] = [
    (ch::JOINT_STATES, JointStateMsg::NAME),
    (ch::WRENCH_RAW, WrenchStampedMsg::NAME),
    (ch::WRENCH_SENSOR, WrenchStampedMsg::NAME),
    (ch::WRENCH_TCP, WrenchStampedMsg::NAME),
    (ch::TCP_POSE, PoseStampedMsg::NAME),
    (ch::PROGRAM_POSE, PoseStampedMsg::NAME),
    (ch::DEFLECTION, TwistStampedMsg::NAME),
    (ch::CORRECTION, TwistStampedMsg::NAME),
    (ch::ERROR, TwistStampedMsg::NAME),
    (ch::FEEDFORWARD, TwistStampedMsg::NAME),
    (ch::PATH_ERROR, Vector3StampedMsg::NAME),
    (ch::DIAGNOSTICS, DiagnosticArrayMsg::NAME),
];

/// The state carried from one `/diagnostics` message to the following cycles.
#[derive(Clone, Copy)]
struct Carried {
    phase_code: u32,
    flags: u32,
    fault: u32,
    late_answers: u64,
    robot_late: u64,
    robot_telegrams: u64,
    sensor_samples: u64,
}

/// Calls `f` with every cycle of the deflex MCAP file `path`, in order, rebuilt from its
/// channels. Fields a file does not carry stay at [`CycleSample::default`]; `path_s_m`,
/// `loop_gain` and `cycle_time_s` are known only on the cycles that have a `/diagnostics`
/// message (NaN elsewhere), the phase, flags, fault and counters are carried from the last one.
pub fn for_each_cycle(
    path: &Path,
    mut f: impl FnMut(&CycleSample),
) -> Result<RecordingSummary, ReadError> {
    let name = path.display().to_string();
    if !is_mcap(path).map_err(|e| FileIoError::new(path, e))? {
        return Err(ReadError::NotMcap { path: name });
    }
    let file = std::io::BufReader::new(
        deflex_files::open_input(path).map_err(deflex_files::InputError::into_file_io)?,
    );
    let options =
        mcap::sans_io::LinearReaderOptions::default().with_record_length_limit(MAX_RECORD_BYTES);
    let reader = mcap::io::MessageReader::new_with_options(file, options);

    let mut summary = RecordingSummary::default();
    let mut topics_seen: Vec<String> = Vec::new();
    let mut current: Option<(u32, u64, CycleSample)> = None;
    let mut carried: Option<Carried> = None;
    let mut first_time: Option<u64> = None;
    for (i, message) in reader.enumerate() {
        let message = message.map_err(|e| ReadError::Mcap {
            path: name.clone(),
            message: e.to_string(),
        })?;
        let index = i as u64 + 1;
        let topic = message.channel.topic.as_str();
        if !topics_seen.iter().any(|t| t == topic) && topics_seen.len() < 64 {
            topics_seen.push(topic.to_string());
        }
        if topic == ch::SESSION {
            summary.session = serde_json::from_slice(&message.data).ok();
            continue;
        }
        let Some(k) = KNOWN.iter().position(|(t, _)| *t == topic) else {
            summary.foreign_messages += 1;
            continue;
        };
        let schema = message.channel.schema.as_ref().map(|s| s.name.as_str());
        if schema != Some(KNOWN[k].1) {
            return Err(ReadError::WrongSchema {
                path: name,
                topic: topic.to_string(),
                expected: KNOWN[k].1,
                found: schema.unwrap_or("none").to_string(),
            });
        }
        let key = (message.sequence, message.log_time);
        if current.as_ref().is_none_or(|(s, t, _)| (*s, *t) != key) {
            if let Some((_, _, sample)) = current.take() {
                summary.cycles += 1;
                f(&sample);
            }
            let start = summary
                .session
                .as_ref()
                .map(|s| s.start_unix_ns)
                .unwrap_or_else(|| *first_time.get_or_insert(message.log_time));
            let mut sample = CycleSample {
                time_s: message.log_time.saturating_sub(start) as f64 * 1e-9,
                cycle: u64::from(message.sequence),
                cycle_time_s: f64::NAN,
                ..CycleSample::default()
            };
            if let Some(c) = carried {
                sample.phase_code = c.phase_code;
                sample.flags = c.flags;
                sample.fault = c.fault;
                sample.late_answers = c.late_answers;
                sample.robot_late = c.robot_late;
                sample.robot_telegrams = c.robot_telegrams;
                sample.sensor_samples = c.sensor_samples;
            }
            current = Some((key.0, key.1, sample));
        }
        let sample = &mut current.as_mut().expect("set above").2;
        let applied = apply(sample, topic, &message.data).map_err(|e| ReadError::Decode {
            path: name.clone(),
            topic: topic.to_string(),
            index,
            source: e,
        })?;
        match applied {
            Applied::PathError => summary.path_error_known = true,
            Applied::Diagnostics => {
                carried = Some(Carried {
                    phase_code: sample.phase_code,
                    flags: sample.flags,
                    fault: sample.fault,
                    late_answers: sample.late_answers,
                    robot_late: sample.robot_late,
                    robot_telegrams: sample.robot_telegrams,
                    sensor_samples: sample.sensor_samples,
                });
            }
            Applied::Other => {}
        }
    }
    if let Some((_, _, sample)) = current.take() {
        summary.cycles += 1;
        f(&sample);
    }
    if summary.cycles == 0 {
        return Err(ReadError::Foreign {
            path: name,
            topics: topics_seen,
        });
    }
    Ok(summary)
}

/// What a message changed besides the sample's values.
enum Applied {
    PathError,
    Diagnostics,
    Other,
}

/// Decodes one message of a known topic into the cycle's sample.
fn apply(
    sample: &mut CycleSample,
    topic: &str,
    data: &[u8],
) -> Result<Applied, deflex_telemetry::ros::CdrError> {
    match topic {
        ch::JOINT_STATES => {
            let m: JointStateMsg = deflex_telemetry::ros::decode(data)?;
            sample.set_q(&m.position);
        }
        ch::WRENCH_RAW | ch::WRENCH_SENSOR | ch::WRENCH_TCP => {
            let m: WrenchStampedMsg = deflex_telemetry::ros::decode(data)?;
            let w = &m.wrench;
            let v = [
                w.force.x, w.force.y, w.force.z, w.torque.x, w.torque.y, w.torque.z,
            ];
            match topic {
                ch::WRENCH_RAW => sample.wrench_raw = v,
                ch::WRENCH_SENSOR => sample.wrench_sensor = v,
                _ => sample.wrench_tcp = v,
            }
        }
        ch::TCP_POSE => {
            let m: PoseStampedMsg = deflex_telemetry::ros::decode(data)?;
            let p = m.pose.position;
            sample.tcp_position_m = [p.x, p.y, p.z];
            let o = m.pose.orientation;
            let q = UnitQuaternion::from_quaternion(Quaternion::new(o.w, o.x, o.y, o.z));
            sample.set_tcp_rotation(&q.to_rotation_matrix());
        }
        ch::PROGRAM_POSE => {
            // Derived on reading (corrected TCP − ξ); decoded only to check it.
            let _: PoseStampedMsg = deflex_telemetry::ros::decode(data)?;
        }
        ch::DEFLECTION | ch::CORRECTION | ch::ERROR | ch::FEEDFORWARD => {
            let m: TwistStampedMsg = deflex_telemetry::ros::decode(data)?;
            let t = &m.twist;
            let v = [
                t.linear.x,
                t.linear.y,
                t.linear.z,
                t.angular.x,
                t.angular.y,
                t.angular.z,
            ];
            match topic {
                ch::DEFLECTION => sample.deflection = v,
                ch::CORRECTION => sample.correction = v,
                ch::ERROR => sample.error = v,
                _ => sample.feedforward = v,
            }
        }
        ch::PATH_ERROR => {
            let m: Vector3StampedMsg = deflex_telemetry::ros::decode(data)?;
            sample.truth_error_m = m.vector.to_array();
            return Ok(Applied::PathError);
        }
        _ => {
            let m: DiagnosticArrayMsg = deflex_telemetry::ros::decode(data)?;
            if let Some(status) = m.status.iter().find(|s| s.name == ch::STATUS_NAME) {
                apply_diagnostics(sample, status);
                return Ok(Applied::Diagnostics);
            }
        }
    }
    Ok(Applied::Other)
}

fn apply_diagnostics(
    sample: &mut CycleSample,
    status: &deflex_telemetry::ros::DiagnosticStatusMsg,
) {
    let number = |key: &str| {
        status
            .value(key)
            .and_then(|v| v.parse::<f64>().ok())
            .unwrap_or(f64::NAN)
    };
    let count = |key: &str| status.value(key).and_then(|v| v.parse::<u64>().ok());
    if let Some(phase) = status.value(ch::diag::PHASE) {
        // A controller's phase, or the simulated cell's state (`twin-cell` recordings).
        sample.phase_code = [StreamSource::Runtime, StreamSource::TwinCell]
            .iter()
            .find_map(|s| s.phase_names().iter().position(|n| *n == phase))
            .unwrap_or(0) as u32;
    }
    sample.flags = count(ch::diag::FLAGS).unwrap_or(0) as u32;
    let fault = status.value(ch::diag::FAULT).unwrap_or("");
    sample.fault =
        CycleSample::fault_to_code(FaultKind::ALL.into_iter().find(|k| k.name() == fault));
    sample.cycle_time_s = number(ch::diag::CYCLE_TIME_S);
    sample.path_s_m = number(ch::diag::PATH_S_M);
    sample.loop_gain = number(ch::diag::LOOP_GAIN);
    sample.late_answers = count(ch::diag::LATE_ANSWERS).unwrap_or(0);
    sample.robot_late = count(ch::diag::ROBOT_LATE).unwrap_or(LATE_UNKNOWN);
    sample.robot_telegrams = count(ch::diag::ROBOT_TELEGRAMS).unwrap_or(0);
    sample.sensor_samples = count(ch::diag::SENSOR_SAMPLES).unwrap_or(0);
}
