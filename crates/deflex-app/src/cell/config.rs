//! `CELL.toml`: everything `deflex run` needs: robot link, sensor link, sensor mounting and
//! tool, model file, gains of eq. 17, limits, safety, log path. SI units throughout, the unit in
//! each key's name. Unknown keys are errors (typos must not silently fall back to defaults);
//! every choice is an enum; every error names the file and the field. The documented example is
//! `docs/cell.example.toml`.
//!
//! The sections are in [`sections`], their choices in [`choices`]; [`CellFile::controller_config`]
//! turns a file into the law's [`deflex_control::ControllerConfig`]; the links it describes are
//! opened by [`crate::cell::links`]; its feed-forward table is read by [`crate::cell::feedforward`].

pub mod choices;
mod controller_config;
pub mod sections;
mod validate;

pub use choices::{CorrectionAxis, RobotKind, Ros2Qos, Ros2Topic, RsiAnswerKind, SensorKind};
pub use sections::{
    ControlSection, FeedForwardSection, LimitsSection, LogSection, ModelCheckSection, ModelSection,
    MountingSection, REQUIRED_KEYS, RobotSection, Ros2Section, SensorSection,
};
pub use validate::{BOUNDS, bounds_of, valid_ros2_name};

use crate::cell::feedforward::TableLoadError;
use deflex_files::{FileIoError, FileTooLarge};
use serde::Deserialize;
use std::path::{Path, PathBuf};

/// A configuration problem, naming the file and the field.
#[derive(Debug, thiserror::Error)]
pub enum ConfigError {
    /// The file could not be read: `PATH: cannot read: ERROR` (a [`FileIoError`] becomes this
    /// with that context).
    #[error(transparent)]
    Read(FileIoError),
    /// The file is larger than [`MAX_CELL_CONFIG_BYTES`].
    #[error(transparent)]
    TooLarge(#[from] FileTooLarge),
    /// TOML syntax, a type or an unknown key or choice (the parser's message names the line, the
    /// key and the choices).
    #[error("{path}: {}{message}", field.as_ref().map(|f| format!("field `{f}`: ")).unwrap_or_default())]
    Parse {
        /// File.
        path: String,
        /// Dotted key at the error, when it can be told.
        field: Option<String>,
        /// The parser's message.
        message: String,
    },
    /// A key without default is missing.
    #[error("{path}: field `{section}.{key}` is required")]
    Missing {
        /// File.
        path: String,
        /// Section.
        section: &'static str,
        /// Key.
        key: &'static str,
    },
    /// A number beyond its bounds ([`BOUNDS`]).
    #[error(
        "{path}: field `{field}`: expected a number from {lowest} to {highest}{}, got {value}",
        if unit.is_empty() { String::new() } else { format!(" {unit}") }
    )]
    OutOfBounds {
        /// File.
        path: String,
        /// Dotted field name, with the index of an array element (`sensor.range[2]`).
        field: String,
        /// The value.
        value: f64,
        /// Lowest accepted.
        lowest: f64,
        /// Highest accepted.
        highest: f64,
        /// Unit.
        unit: &'static str,
    },
    /// A value that cannot be used, for the reason given.
    #[error("{path}: field `{field}`: {reason}")]
    Invalid {
        /// File.
        path: String,
        /// Dotted field name.
        field: &'static str,
        /// Why.
        reason: InvalidReason,
    },
    /// The feed-forward table of `[feedforward]` cannot be used.
    #[error("{path}: field `feedforward.table`: {error}")]
    FeedForward {
        /// File.
        path: String,
        /// What is wrong with the table (names the table, its line and column).
        error: TableLoadError,
    },
}

impl From<FileIoError> for ConfigError {
    fn from(error: FileIoError) -> Self {
        ConfigError::Read(error.context("cannot read"))
    }
}

/// Why a value of `CELL.toml` cannot be used (besides bounds and unknown choices).
#[derive(Clone, Debug, PartialEq, thiserror::Error)]
pub enum InvalidReason {
    /// `robot.peer` / `robot.bind` / `robot.allow_any_peer` that cannot be served safely.
    #[error("{0}")]
    Peer(deflex_io::PeerConfigError),
    /// `robot.kind = "ur-rtde"` without `robot.peer`.
    #[error(
        "robot.kind = \"ur-rtde\" connects to the UR controller: set robot.peer to its address \
         (e.g. \"192.168.1.10:30004\"; port 0 = 30004)"
    )]
    RtdeNeedsPeer,
    /// An empty text where a name is needed.
    #[error("must {0}")]
    Empty(&'static str),
    /// An RSI `<Sen Type>` that is not a plain name.
    #[error("expected a plain name (letters, digits, _ - ., at most 64), got \"{0}\"")]
    SenType(String),
    /// The robot timeout is shorter than one robot cycle.
    #[error("must be at least one robot cycle (robot.cycle_s = {cycle_s} s), got {timeout_s} s")]
    TimeoutBelowCycle {
        /// `robot.timeout_s`.
        timeout_s: f64,
        /// `robot.cycle_s`.
        cycle_s: f64,
    },
    /// The runaway guard's release gain is not below its limit.
    #[error("must be below limits.runaway_gain_limit ({limit}), got {release}")]
    ReleaseNotBelowLimit {
        /// `limits.runaway_release_gain`.
        release: f64,
        /// `limits.runaway_gain_limit`.
        limit: f64,
    },
    /// A ROS 2 name (namespace, node or topic) that ROS 2 refuses.
    #[error(
        "expected a ROS 2 name ({0}: letters, digits and _ between single /, not starting with a \
         digit, at most 255 characters), got \"{1}\""
    )]
    Ros2Name(&'static str, String),
    /// A frame id that cannot be one.
    #[error("expected a frame id (1–255 printable characters, no spaces), got \"{0}\"")]
    FrameId(String),
    /// `sensor.kind = "ros2"` without the `[ros2]` section that says which DDS domain and QoS.
    #[error(
        "sensor.kind = \"ros2\" needs a [ros2] section (domain_id, qos; topics = [] to publish nothing)"
    )]
    Ros2SectionMissing,
    /// The publishing rate is above the control rate.
    #[error("must be at most control.rate_hz ({control_hz} Hz), got {rate_hz} Hz")]
    PublishAboveControlRate {
        /// `ros2.publish_rate_hz`.
        rate_hz: f64,
        /// `control.rate_hz`.
        control_hz: f64,
    },
    /// A lead with a pre-compensated program.
    #[error(
        "a lead applies to mode = \"feed-forward\" only (the program applies its compensation \
         itself), got {lead_s} s"
    )]
    LeadWithPrecompensated {
        /// `feedforward.lead_s`.
        lead_s: f64,
    },
}

/// A whole `CELL.toml`.
#[derive(Clone, Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct CellFile {
    /// Robot link.
    pub robot: RobotSection,
    /// Sensor link.
    pub sensor: SensorSection,
    /// Mounting and tool.
    #[serde(default)]
    pub mounting: MountingSection,
    /// Model.
    pub model: ModelSection,
    /// Gains.
    #[serde(default)]
    pub control: ControlSection,
    /// Limits.
    #[serde(default)]
    pub limits: LimitsSection,
    /// The robot's reported TCP pose against the model's.
    #[serde(default)]
    pub model_check: ModelCheckSection,
    /// Log; absent = no CSV.
    #[serde(default)]
    pub log: Option<LogSection>,
    /// Feed-forward from an offline compensation; absent = the online correction alone.
    #[serde(default)]
    pub feedforward: Option<FeedForwardSection>,
    /// ROS 2 bridge; absent = deflex stays off the ROS 2 graph.
    #[serde(default)]
    pub ros2: Option<Ros2Section>,
    /// Directory of the file (for relative paths); set by [`CellFile::load`].
    #[serde(skip)]
    pub base_dir: PathBuf,
    /// Path of the file, for messages.
    #[serde(skip)]
    pub origin: String,
}

/// The dotted key (`section.key`) of the line holding byte `offset` of a TOML text: the key
/// before the line's `=` under the nearest `[section]` header above it.
fn dotted_key_at(text: &str, offset: usize) -> Option<String> {
    let before = text.get(..offset.min(text.len()))?;
    let line_start = before.rfind('\n').map_or(0, |i| i + 1);
    let line = text[line_start..].lines().next()?;
    let key = line.split_once('=')?.0.trim().trim_matches('"');
    if key.is_empty() || key.starts_with('[') {
        return None;
    }
    let section = before[..line_start].lines().rev().find_map(|l| {
        let l = l.trim();
        l.strip_prefix('[')
            .and_then(|rest| rest.split_once(']'))
            .map(|(name, _)| name.trim_matches(['[', ']', ' ']).to_string())
    });
    Some(match section {
        Some(s) => format!("{s}.{key}"),
        None => key.to_string(),
    })
}

/// The first key of [`REQUIRED_KEYS`] missing from a section that is present (`sensor.address`
/// only for a sensor on the network: `sensor.kind = "ros2"` takes a topic instead; `robot.bind`
/// only for a robot that connects to deflex: deflex connects to a `ur-rtde` controller).
fn missing_required(table: &toml::Table) -> Option<(&'static str, &'static str)> {
    let sensor = table.get("sensor").and_then(toml::Value::as_table);
    let ros2_sensor = sensor
        .and_then(|s| s.get("kind"))
        .and_then(toml::Value::as_str)
        == Some("ros2");
    let rtde_robot = table
        .get("robot")
        .and_then(toml::Value::as_table)
        .and_then(|s| s.get("kind"))
        .and_then(toml::Value::as_str)
        == Some("ur-rtde");
    REQUIRED_KEYS.iter().copied().find(|(section, key)| {
        let exempt = (ros2_sensor && (*section, *key) == ("sensor", "address"))
            || (rtde_robot && (*section, *key) == ("robot", "bind"));
        !exempt
            && table
                .get(*section)
                .and_then(toml::Value::as_table)
                .is_some_and(|s| !s.contains_key(*key))
    })
}

/// Largest cell configuration read (bytes): a configuration is a few kilobytes.
pub const MAX_CELL_CONFIG_BYTES: u64 = 4 << 20;

impl CellFile {
    /// Reads and validates a file.
    pub fn load(path: &Path) -> Result<Self, ConfigError> {
        let origin = path.display().to_string();
        // A regular file of at most MAX_CELL_CONFIG_BYTES, counted while reading.
        let text = deflex_files::read_bounded(path, MAX_CELL_CONFIG_BYTES)
            .map_err(|e| e.reported_as::<ConfigError>("a cell configuration"))?;
        let base = path.parent().map(Path::to_path_buf).unwrap_or_default();
        Self::parse(&text, &origin, base)
    }

    /// Parses and validates text; `origin` names it in errors, `base_dir` resolves relative paths.
    pub fn parse(text: &str, origin: &str, base_dir: PathBuf) -> Result<Self, ConfigError> {
        let parse_error = |e: toml::de::Error| ConfigError::Parse {
            path: origin.to_string(),
            field: e.span().and_then(|span| dotted_key_at(text, span.start)),
            message: e.to_string().trim_end().to_string(),
        };
        let table: toml::Table = toml::from_str(text).map_err(parse_error)?;
        if let Some((section, key)) = missing_required(&table) {
            return Err(ConfigError::Missing {
                path: origin.to_string(),
                section,
                key,
            });
        }
        let mut cell: CellFile = toml::from_str(text).map_err(parse_error)?;
        cell.base_dir = base_dir;
        cell.origin = origin.to_string();
        cell.validate()?;
        Ok(cell)
    }

    /// The model specification: a path resolved against the file's directory when it exists
    /// there, otherwise the text as given (built-in names).
    pub fn model_spec(&self) -> String {
        let p = self.base_dir.join(&self.model.file);
        if Path::new(&self.model.file).is_relative() && p.exists() {
            p.display().to_string()
        } else {
            self.model.file.clone()
        }
    }

    /// The log path resolved against the file's directory.
    pub fn log_path(&self) -> Option<PathBuf> {
        self.log.as_ref().map(|l| self.base_dir.join(&l.path))
    }

    /// The feed-forward table's path resolved against the file's directory.
    pub fn feedforward_table_path(&self) -> Option<PathBuf> {
        self.feedforward
            .as_ref()
            .map(|f| self.base_dir.join(&f.table))
    }

    /// The settings of `[feedforward]` (validated at load).
    pub fn feedforward_config(&self) -> Option<deflex_control::FeedForwardConfig> {
        self.feedforward
            .as_ref()
            .map(|f| deflex_control::FeedForwardConfig {
                mode: f.mode,
                index: f.index,
                lead_s: f.lead_s,
                max_offset_m: f.max_offset_m,
                window_m: f.window_m,
                time_offset_s: f.time_offset_s,
            })
    }

    /// The feed-forward of `[feedforward]` for the model `robot` (the table is in its world
    /// frame), or `None` without the section. Errors name the file and the field, and the table
    /// with its line and column.
    pub fn feedforward(
        &self,
        robot: &deflex_model::Robot,
    ) -> Result<Option<deflex_control::FeedForward>, ConfigError> {
        let (Some(path), Some(config)) = (self.feedforward_table_path(), self.feedforward_config())
        else {
            return Ok(None);
        };
        crate::cell::feedforward::load_feedforward(&path, robot, config)
            .map(Some)
            .map_err(|error| ConfigError::FeedForward {
                path: self.origin.clone(),
                error,
            })
    }
}
