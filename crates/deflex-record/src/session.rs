//! The session description stored in a recording (`/deflex/session` and the `deflex` metadata
//! record): what [`deflex_telemetry::SessionInfo`] holds, in JSON.

use deflex_telemetry::SessionInfo;
use serde::{Deserialize, Serialize};
use std::collections::BTreeMap;

/// JSON Schema of the `/deflex/session` message.
pub const SESSION_JSON_SCHEMA: &str = r#"{
  "$schema": "https://json-schema.org/draft/2020-12/schema",
  "title": "deflex.Session",
  "description": "A deflex session: who published it, the robot, limits, rates and frame names (SI units). Limits that are unbounded are null.",
  "type": "object",
  "properties": {
    "label": {"type": "string", "description": "SIMULATED for the digital twin or a simulated cell, empty otherwise"},
    "simulated": {"type": "boolean"},
    "source": {"type": "string", "enum": ["runtime", "twin", "twin-cell"], "description": "runtime: deflex run; twin: the controller in-process on the digital twin; twin-cell: the digital twin's own stream (ground truth, no controller)"},
    "robot": {"type": "string"},
    "joint_names": {"type": "array", "items": {"type": "string"}},
    "protocol": {"type": "string"},
    "control_period_s": {"type": "number"},
    "robot_cycle_s": {"type": "number"},
    "correction_limit": {"type": "array", "items": {"type": ["number", "null"]}, "description": "x y z (m), rx ry rz (rad)"},
    "correction_rate_limit": {"type": "array", "items": {"type": ["number", "null"]}, "description": "m/s and rad/s"},
    "force_limit_n": {"type": ["number", "null"]},
    "base_frame": {"type": "string"},
    "sensor_frame": {"type": "string"},
    "tcp_frame": {"type": "string"},
    "start_unix_ns": {"type": "integer", "description": "wall-clock time of session time 0"}
  }
}"#;

/// The session description as recorded.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct SessionRecord {
    /// `SIMULATED` for the twin or a simulated cell, empty otherwise.
    pub label: String,
    /// The robot or the cell is the digital twin.
    pub simulated: bool,
    /// `runtime`, `twin` or `twin-cell` ([`deflex_telemetry::StreamSource::key`]).
    pub source: String,
    /// Robot name.
    pub robot: String,
    /// Joint names.
    pub joint_names: Vec<String>,
    /// Robot protocol.
    pub protocol: String,
    /// Control period (s).
    pub control_period_s: f64,
    /// Robot cycle (s).
    pub robot_cycle_s: f64,
    /// Correction bound per axis (m, rad); `None` when unbounded.
    pub correction_limit: Vec<Option<f64>>,
    /// Correction rate bound per axis (m/s, rad/s); `None` when unbounded.
    pub correction_rate_limit: Vec<Option<f64>>,
    /// Force norm limit (N); `None` when unbounded.
    pub force_limit_n: Option<f64>,
    /// Base frame name.
    pub base_frame: String,
    /// Sensor frame name.
    pub sensor_frame: String,
    /// TCP frame name.
    pub tcp_frame: String,
    /// Wall-clock time of session time 0 (ns since the Unix epoch).
    pub start_unix_ns: u64,
}

fn finite(v: f64) -> Option<f64> {
    v.is_finite().then_some(v)
}

impl SessionRecord {
    /// The record of `info`, with session time 0 at `start_unix_ns`.
    pub fn new(info: &SessionInfo, start_unix_ns: u64) -> SessionRecord {
        SessionRecord {
            label: if info.simulated { "SIMULATED" } else { "" }.into(),
            simulated: info.simulated,
            source: info.source.key().into(),
            robot: info.robot.clone(),
            joint_names: info.joint_names.clone(),
            protocol: info.protocol.clone(),
            control_period_s: info.control_period_s,
            robot_cycle_s: info.robot_cycle_s,
            correction_limit: info.correction_limit.iter().map(|v| finite(*v)).collect(),
            correction_rate_limit: info
                .correction_rate_limit
                .iter()
                .map(|v| finite(*v))
                .collect(),
            force_limit_n: finite(info.force_limit_n),
            base_frame: info.base_frame.clone(),
            sensor_frame: info.sensor_frame.clone(),
            tcp_frame: info.tcp_frame.clone(),
            start_unix_ns,
        }
    }

    /// Key/value form (the MCAP metadata record).
    pub fn to_map(&self) -> BTreeMap<String, String> {
        let list = |v: &[Option<f64>]| {
            v.iter()
                .map(|x| x.map_or("inf".to_string(), |x| x.to_string()))
                .collect::<Vec<_>>()
                .join(",")
        };
        BTreeMap::from([
            ("label".into(), self.label.clone()),
            ("simulated".into(), self.simulated.to_string()),
            ("source".into(), self.source.clone()),
            ("robot".into(), self.robot.clone()),
            ("joint_names".into(), self.joint_names.join(",")),
            ("protocol".into(), self.protocol.clone()),
            ("control_period_s".into(), self.control_period_s.to_string()),
            ("robot_cycle_s".into(), self.robot_cycle_s.to_string()),
            ("correction_limit".into(), list(&self.correction_limit)),
            (
                "correction_rate_limit".into(),
                list(&self.correction_rate_limit),
            ),
            (
                "force_limit_n".into(),
                self.force_limit_n.map_or("inf".into(), |v| v.to_string()),
            ),
            ("base_frame".into(), self.base_frame.clone()),
            ("sensor_frame".into(), self.sensor_frame.clone()),
            ("tcp_frame".into(), self.tcp_frame.clone()),
            ("start_unix_ns".into(), self.start_unix_ns.to_string()),
        ])
    }
}
