//! The ROS 2 parts of `deflex run`: the sensor link of `sensor.kind = "ros2"` (opened before the
//! session, handed to the application's session: `deflex_app::cell::run_session::RunPlan::start`),
//! the bridge of `[ros2]` (a sink of the telemetry stream, subscribed before the threads start)
//! and what both report at the end.
//!
//! They are built with the CLI's `ros2` cargo feature (`cargo install --path crates/deflex-cli
//! --features ros2`): the pure-Rust DDS stack they stand on (RustDDS, ros2-client) is the largest
//! part of the build, and a cell without ROS 2 never needs it. Without the feature, a `CELL.toml`
//! that asks for ROS 2 is refused before any link opens, naming the field and the command that
//! builds a `deflex` with it (`CliError::Ros2NotBuilt`).

use crate::error::CliError;

/// The command that builds a `deflex` with ROS 2, as a literal (for `concat!`): named by the
/// refusal of a build without it and by that build's `deflex --version`.
#[cfg(not(feature = "ros2"))]
macro_rules! ros2_build_command {
    () => {
        "cargo install --path crates/deflex-cli --features ros2"
    };
}
use deflex_app::cell::config::CellFile;
use deflex_app::cell::config::SensorKind;
use deflex_io::ForceSensorLink;
use deflex_runtime::Telemetry;
#[cfg(not(feature = "ros2"))]
pub(crate) use ros2_build_command;

#[cfg(feature = "ros2")]
pub use built::{Ros2Outcome, Ros2Parts};
#[cfg(not(feature = "ros2"))]
pub use not_built::{Ros2Outcome, Ros2Parts};

#[cfg(feature = "ros2")]
mod built {
    use super::*;
    use deflex_app::cell::config::Ros2Section;
    use deflex_ros2::sensor::SensorCountsHandle;
    use deflex_ros2::{
        BridgeReport, BridgeSettings, Refusal, Ros2Bridge, Ros2Error, Ros2SensorLink, SensorCounts,
        SensorSettings,
    };
    use serde_json::json;
    use std::time::Duration;

    /// The bridge's settings of a `[ros2]` section.
    pub fn bridge_settings_of(r: &Ros2Section) -> BridgeSettings {
        BridgeSettings {
            domain_id: r.domain_id,
            namespace: r.namespace.clone(),
            node_name: r.node_name.clone(),
            qos: r.qos,
            depth: r.depth,
            publish_rate_hz: r.publish_rate_hz,
            diagnostics_rate_hz: r.diagnostics_rate_hz,
            topics: r.topics.clone(),
        }
    }

    /// The bridge's settings of a `CELL.toml`'s `[ros2]`, `None` without it.
    pub fn bridge_settings(cell: &CellFile) -> Option<BridgeSettings> {
        cell.ros2.as_ref().map(bridge_settings_of)
    }

    /// The ROS 2 sensor link's settings of a `CELL.toml`'s `[sensor]` and `[ros2]` (`None`
    /// without `[ros2]`). The link's node is `<ros2.node_name>_ft` in `ros2.namespace`.
    pub fn sensor_settings(cell: &CellFile) -> Option<SensorSettings> {
        let r = cell.ros2.as_ref()?;
        Some(SensorSettings {
            domain_id: r.domain_id,
            namespace: r.namespace.clone(),
            node_name: format!("{}_ft", r.node_name),
            qos: r.qos,
            topic: cell.sensor.topic.clone(),
            frame_id: r.sensor_frame.clone(),
            max_age: Duration::from_secs_f64(cell.sensor.max_age_s),
            queue_depth: cell.sensor.queue_depth,
        })
    }

    /// The open ROS 2 parts of a session.
    pub struct Ros2Parts {
        sensor: Option<Ros2SensorLink>,
        sensor_counts: Option<(String, SensorCountsHandle)>,
        bridge: Option<Ros2Bridge>,
        bridge_error: Option<Ros2Error>,
    }

    /// What the ROS 2 parts did.
    #[derive(Default)]
    pub struct Ros2Outcome {
        /// What the bridge published (with `[ros2]`): its topics and counts.
        bridge: Option<(Vec<String>, BridgeReport)>,
        /// What the sensor link took and refused (`sensor.kind = "ros2"`).
        sensor: Option<(String, SensorCounts)>,
    }

    impl Ros2Parts {
        /// Opens the sensor link of `sensor.kind = "ros2"` (validation made sure `[ros2]` is
        /// there; without it the runtime's own factory refuses the kind, naming it).
        pub fn open(cell: &CellFile) -> Result<Self, CliError> {
            let mut parts = Ros2Parts {
                sensor: None,
                sensor_counts: None,
                bridge: None,
                bridge_error: None,
            };
            if cell.sensor.kind == SensorKind::Ros2
                && let Some(settings) = sensor_settings(cell)
            {
                let link = Ros2SensorLink::open(&settings).map_err(|e| {
                    CliError::in_context(format!("{}: sensor.topic", cell.origin))(e.into())
                })?;
                parts.sensor_counts = Some((link.topic().to_string(), link.counts_handle()));
                parts.sensor = Some(link);
            }
            Ok(parts)
        }

        /// The sensor link for the session, if the cell's sensor is a ROS 2 topic.
        pub fn take_sensor(&mut self) -> Option<Box<dyn ForceSensorLink + Send>> {
            self.sensor.take().map(|link| Box::new(link) as _)
        }

        /// Subscribes the bridge of `[ros2]` to the telemetry stream (before the threads
        /// start): it publishes every cycle, never from the control thread. A bridge that
        /// cannot start is kept for [`Self::start_error`].
        pub fn subscribe_bridge(&mut self, cell: &CellFile, telemetry: &Telemetry) {
            if let Some(settings) = bridge_settings(cell) {
                match Ros2Bridge::spawn(&settings, telemetry.subscribe(), telemetry.info().clone())
                {
                    Ok(bridge) => self.bridge = Some(bridge),
                    Err(e) => self.bridge_error = Some(e),
                }
            }
        }

        /// Why the bridge could not start, if it could not.
        pub fn start_error(&mut self) -> Option<CliError> {
            self.bridge_error.take().map(Into::into)
        }

        /// The line `deflex run` prints when the bridge publishes.
        pub fn announce(&self, cell: &CellFile) {
            if let Some(bridge) = &self.bridge {
                eprintln!(
                    "deflex run: ROS 2: publishing {} topics under {} (domain {})",
                    bridge.topics().len(),
                    cell.ros2.as_ref().map_or("/", |r| r.namespace.as_str()),
                    cell.ros2.as_ref().map_or(0, |r| r.domain_id),
                );
            }
        }

        /// Ends the bridge (after the session) and reads the sensor link's counts.
        pub fn finish(self) -> Result<Ros2Outcome, CliError> {
            let bridge = match self.bridge {
                Some(b) => {
                    let topics = b.topics().to_vec();
                    Some((topics, b.finish()?))
                }
                None => None,
            };
            Ok(Ros2Outcome {
                bridge,
                sensor: self.sensor_counts.map(|(topic, h)| (topic, h.counts())),
            })
        }
    }

    impl Ros2Outcome {
        /// The `ros2_bridge` and `ros2_sensor` keys of `deflex run --json`.
        pub fn add_json(&self, value: &mut serde_json::Value) {
            if let Some((topics, r)) = &self.bridge {
                value["ros2_bridge"] = json!({"topics": topics, "cycles_read": r.cycles_read,
                    "cycles_published": r.cycles_published, "diagnostics": r.diagnostics,
                    "messages": r.messages, "write_errors": r.write_errors, "lost": r.lost});
            }
            if let Some((topic, c)) = &self.sensor {
                let refused: serde_json::Map<String, serde_json::Value> = Refusal::ALL
                    .iter()
                    .map(|r| (r.name().to_string(), json!(c.refused_for(*r))))
                    .collect();
                value["ros2_sensor"] = json!({"topic": topic, "received": c.received,
                    "accepted": c.accepted, "refused": refused, "overflow": c.overflow});
            }
        }

        /// The ROS 2 lines of the run summary (after the sensor's line).
        pub fn lines(&self) -> Vec<String> {
            let mut lines = Vec::new();
            if let Some((topic, c)) = &self.sensor {
                let refused: Vec<String> = Refusal::ALL
                    .iter()
                    .map(|r| format!("{} {}", c.refused_for(*r), r.name()))
                    .collect();
                lines.push(format!(
                    "  ROS 2 sensor {topic}: {} messages, {} accepted, refused: {}; {} dropped from the full queue",
                    c.received,
                    c.accepted,
                    refused.join(", "),
                    c.overflow
                ));
            }
            if let Some((topics, r)) = &self.bridge {
                lines.push(format!(
                    "  ROS 2 bridge: {} cycles published on {} topics ({} messages, {} diagnostics), {} not written, {} lost",
                    r.cycles_published,
                    topics.len(),
                    r.messages,
                    r.diagnostics,
                    r.write_errors,
                    r.lost
                ));
            }
            lines
        }
    }
}

#[cfg(not(feature = "ros2"))]
mod not_built {
    use super::*;

    /// What a `CELL.toml` asks of ROS 2, if anything: the field that asks (for the refusal of a
    /// build without the feature).
    fn ros2_field(cell: &CellFile) -> Option<&'static str> {
        if cell.sensor.kind == SensorKind::Ros2 {
            Some("sensor.kind = \"ros2\"")
        } else if cell.ros2.is_some() {
            Some("[ros2]")
        } else {
            None
        }
    }

    /// A `deflex` built without ROS 2 has no ROS 2 parts: [`Ros2Parts::open`] refuses a cell
    /// that asks for them.
    pub struct Ros2Parts;

    /// Nothing: no ROS 2 part ran.
    #[derive(Default)]
    pub struct Ros2Outcome;

    impl Ros2Parts {
        /// Refuses a cell with `[ros2]` or `sensor.kind = "ros2"`, before any link opens.
        pub fn open(cell: &CellFile) -> Result<Self, CliError> {
            match ros2_field(cell) {
                Some(field) => Err(CliError::Ros2NotBuilt {
                    origin: cell.origin.to_string(),
                    field,
                }),
                None => Ok(Ros2Parts),
            }
        }

        /// No sensor link of this kind.
        pub fn take_sensor(&mut self) -> Option<Box<dyn ForceSensorLink + Send>> {
            None
        }

        /// No bridge to subscribe.
        pub fn subscribe_bridge(&mut self, _cell: &CellFile, _telemetry: &Telemetry) {}

        /// No bridge that could fail.
        pub fn start_error(&mut self) -> Option<CliError> {
            None
        }

        /// Nothing to announce.
        pub fn announce(&self, _cell: &CellFile) {}

        /// Nothing to end.
        pub fn finish(self) -> Result<Ros2Outcome, CliError> {
            Ok(Ros2Outcome)
        }
    }

    impl Ros2Outcome {
        /// No ROS 2 keys in `deflex run --json`.
        pub fn add_json(&self, _value: &mut serde_json::Value) {}

        /// No ROS 2 lines in the summary.
        pub fn lines(&self) -> Vec<String> {
            Vec::new()
        }
    }
}
