//! `deflex run` from a `CELL.toml`: the model, the feed-forward, the controller, both links,
//! the telemetry stream with the CSV log subscribed to it, and the threads; then, at the end,
//! the summary and the log committed (or, after a failure, left as it was).
//!
//! ```text
//! let run = CellRun::start(&cell, 60.0, Some(2.0))?;   // threads running
//! while !run.runtime.is_finished() { … run.runtime.status() … run.runtime.request_stop() … }
//! let outcome = run.finish()?;                          // summary, log rows, committed?
//! ```

use crate::cell::config::{CellFile, ConfigError, RobotKind};
use deflex_control::{ControlError, Controller, FeedForwardMode, PathIndex};
use deflex_io::{ForceSensorLink, LinkError};
use deflex_record::csv_log::{LogWriter, spawn_writer};
use deflex_runtime::clock::WallClock;
use deflex_runtime::session::{RunSummary, Runtime, RuntimeOptions, spawn};
use deflex_runtime::telemetry::{DEFAULT_CAPACITY, StreamSource, Telemetry, session_info};
use std::net::SocketAddr;
use std::path::{Path, PathBuf};

/// Why `deflex run` could not start.
#[derive(Debug, thiserror::Error)]
pub enum StartError {
    /// The model of `model.file` cannot be loaded.
    #[error("{origin}: model.file: {error}")]
    Model {
        /// The CELL.toml.
        origin: String,
        /// Why.
        error: deflex_model::ModelError,
    },
    /// `[feedforward]` or another part of the file cannot be used.
    #[error(transparent)]
    Config(#[from] ConfigError),
    /// The controller refuses its settings.
    #[error(transparent)]
    Controller(#[from] ControlError),
    /// The robot link cannot be bound.
    #[error("robot link on {bind}: {error}")]
    RobotLink {
        /// `robot.bind` (for `ur-rtde`, the controller's address `robot.peer`).
        bind: SocketAddr,
        /// Why.
        error: LinkError,
    },
    /// The sensor link cannot be opened.
    #[error("sensor link to {address}: {error}")]
    SensorLink {
        /// `sensor.address`.
        address: SocketAddr,
        /// Why.
        error: LinkError,
    },
    /// The log file cannot be created (`log.path PATH: ERROR`).
    #[error("log.path {0}")]
    Log(deflex_files::FileIoError),
    /// A thread cannot be started.
    #[error("{what}: {error}")]
    Thread {
        /// Which (`log writer`, `starting the runtime threads`).
        what: &'static str,
        /// Why.
        error: std::io::Error,
    },
}

/// The feed-forward a run uses (`[feedforward]`).
#[derive(Clone, Debug, PartialEq)]
pub struct FeedForwardInUse {
    /// Mode.
    pub mode: FeedForwardMode,
    /// Index.
    pub index: PathIndex,
    /// Lead (s).
    pub lead_s: f64,
    /// The table's file.
    pub table: PathBuf,
    /// Its points.
    pub points: usize,
    /// Its path length (m).
    pub length_m: f64,
}

/// A `deflex run` session started from a `CELL.toml`.
pub struct CellRun {
    /// The threads (status, stop, telemetry).
    pub runtime: Runtime,
    log: Option<LogWriter>,
    /// The CSV log's path, when `[log]` is set.
    pub log_path: Option<PathBuf>,
    /// The robot link's protocol.
    pub robot_kind: RobotKind,
    /// Largest step allowed between two answers (m): max rate × robot cycle.
    pub step_limit_m: f64,
    /// The feed-forward in use.
    pub feedforward: Option<FeedForwardInUse>,
    /// The model check's settings (`[model_check]`).
    pub model_check: deflex_control::ModelCheckConfig,
}

/// What a `deflex run` session did.
pub struct CellRunOutcome {
    /// The runtime's summary (its `log_dropped` filled from the log writer).
    pub summary: RunSummary,
    /// The CSV log's path, when `[log]` is set.
    pub log_path: Option<PathBuf>,
    /// Rows written.
    pub log_rows: u64,
    /// The log was committed to its path (a failed run leaves what was there).
    pub log_committed: bool,
    /// Why the log could not be written or committed (a full disk…), when it could not; the
    /// session itself ran (its summary is whole).
    pub log_error: Option<String>,
    /// The robot link's protocol.
    pub robot_kind: RobotKind,
    /// Largest step allowed between two answers (m).
    pub step_limit_m: f64,
    /// The feed-forward in use.
    pub feedforward: Option<FeedForwardInUse>,
    /// The model check's settings (`[model_check]`).
    pub model_check: deflex_control::ModelCheckConfig,
}

/// Loads the model, the feed-forward and the controller of `cell`.
fn controller_of(cell: &CellFile) -> Result<(Controller, Option<FeedForwardInUse>), StartError> {
    let model = crate::load::load_robot(&cell.model_spec()).map_err(|error| StartError::Model {
        origin: cell.origin.clone(),
        error,
    })?;
    let feedforward = cell.feedforward(&model)?;
    // A feed-forward comes from `[feedforward]`, which names its table.
    let in_use = feedforward
        .as_ref()
        .zip(cell.feedforward_table_path())
        .map(|(ff, table)| {
            let c = ff.config();
            FeedForwardInUse {
                mode: c.mode,
                index: c.index,
                lead_s: c.lead_s,
                table,
                points: ff.table().len(),
                length_m: ff.table().length_m(),
            }
        });
    let mut controller = Controller::new(model, cell.controller_config())?;
    controller.set_feedforward(feedforward);
    Ok((controller, in_use))
}

impl CellRun {
    /// Sets everything up from `cell` and starts the threads in wall time. Gives up when the
    /// robot and the sensor are not heard within `startup_timeout_s`; ends on its own once the
    /// robot has been silent for `idle_exit_s`.
    pub fn start(
        cell: &CellFile,
        startup_timeout_s: f64,
        idle_exit_s: Option<f64>,
    ) -> Result<CellRun, StartError> {
        Self::start_with(cell, startup_timeout_s, idle_exit_s, None, &mut |_| {})
    }

    /// [`CellRun::start`] with a sensor link opened by a front end (`sensor.kind = "ros2"`: the
    /// ROS 2 bridge's; `None`: the link of `[sensor]`), and `subscribe` called with the session's
    /// telemetry before the threads start, so a sink it subscribes sees every cycle.
    pub fn start_with(
        cell: &CellFile,
        startup_timeout_s: f64,
        idle_exit_s: Option<f64>,
        sensor: Option<Box<dyn ForceSensorLink + Send>>,
        subscribe: &mut dyn FnMut(&Telemetry),
    ) -> Result<CellRun, StartError> {
        let (controller, feedforward) = controller_of(cell)?;
        let joints = controller.robot().joint_count();
        let robot = cell
            .open_robot_link(joints)
            .map_err(|error| StartError::RobotLink {
                bind: cell.robot_link_address(),
                error,
            })?;
        let sensor = match sensor {
            Some(link) => link,
            None => cell
                .open_sensor_link()
                .map_err(|error| StartError::SensorLink {
                    address: cell.sensor.address,
                    error,
                })?,
        };
        let mut info = session_info(
            &controller,
            StreamSource::Runtime,
            cell.robot.kind.key(),
            cell.robot.cycle_s,
        );
        if let Some(ros2) = &cell.ros2 {
            info.base_frame = ros2.base_frame.clone();
            info.sensor_frame = ros2.sensor_frame.clone();
            info.tcp_frame = ros2.tcp_frame.clone();
        }
        let capacity = cell
            .log
            .as_ref()
            .map_or(DEFAULT_CAPACITY, |l| l.ring_capacity);
        let telemetry = Telemetry::new(info, capacity);
        let log_path = cell.log_path();
        let log = match &log_path {
            Some(path) => {
                // Written aside and renamed at the end: a failed run keeps an existing log.
                let file = deflex_files::AtomicFile::create(path).map_err(|error| {
                    StartError::Log(deflex_files::FileIoError::new(path, error))
                })?;
                Some(
                    spawn_writer(telemetry.subscribe(), joints, Box::new(file)).map_err(
                        |error| StartError::Thread {
                            what: "log writer",
                            error,
                        },
                    )?,
                )
            }
            None => None,
        };
        subscribe(&telemetry);
        let options = RuntimeOptions {
            robot_cycle_s: cell.robot.cycle_s,
            realtime: cell.control.realtime,
            lock_memory: cell.control.lock_memory,
            startup_timeout_s,
            idle_exit_s,
        };
        let runtime = match spawn(
            controller,
            robot,
            sensor,
            WallClock::new(),
            telemetry,
            options,
        ) {
            Ok(runtime) => runtime,
            Err(error) => {
                // The stream ended with the telemetry: the writer ends, nothing is committed.
                if let Some(log) = log {
                    let _ = log.finish(false);
                }
                return Err(StartError::Thread {
                    what: "starting the runtime threads",
                    error,
                });
            }
        };
        Ok(CellRun {
            runtime,
            log,
            log_path,
            robot_kind: cell.robot.kind,
            step_limit_m: cell.limits.max_rate_m_s * cell.robot.cycle_s,
            feedforward,
            model_check: cell.controller_config().model_check,
        })
    }

    /// The log's path and its write error as soon as it happened (a full disk), while the
    /// session runs.
    pub fn log_failure(&self) -> Option<(&Path, &str)> {
        let error = self.log.as_ref().and_then(LogWriter::failure)?;
        Some((self.log_path.as_deref()?, error))
    }

    /// Waits for the threads, then commits the log when the run did not fail.
    pub fn finish(self) -> std::io::Result<CellRunOutcome> {
        let mut summary = self.runtime.join();
        let commit = summary.error.is_none();
        let (log_rows, log_committed, log_error) = match self.log {
            Some(writer) => match writer.finish(commit) {
                Ok(report) => {
                    summary.log_dropped = report.dropped;
                    (report.written, report.committed, None)
                }
                Err(e) => (0, false, Some(e.to_string())),
            },
            None => (0, false, None),
        };
        Ok(CellRunOutcome {
            summary,
            log_path: self.log_path,
            log_rows,
            log_committed,
            log_error,
            robot_kind: self.robot_kind,
            step_limit_m: self.step_limit_m,
            feedforward: self.feedforward,
            model_check: self.model_check,
        })
    }
}
