//! `deflex run` from a `CELL.toml`, the session as the front end drives it:
//!
//! 1. [`RunPlan::load`] reads and checks the file (its `[log] path` refused before any link
//!    opens; the MCAP recording's name beside the log, [`mcap_beside`]);
//! 2. [`RunPlan::start`] loads the model and the feed-forward table, opens the links (a sensor
//!    link the front end built may be handed in: the ROS 2 one, which only the command-line
//!    tool builds), subscribes the CSV log and the front end's sinks, and starts the threads
//!    ([`CellRun`]);
//! 3. [`RunSession::record`] starts the MCAP recording, from the oldest sample the ring holds;
//! 4. [`RunSession::wait`] runs the session until it ends, the stop flag is set (Ctrl-C, the
//!    live view's stop button: the correction ramps out) or the duration is over, reporting
//!    the live status and a log that cannot be written ([`RunEvent`]);
//! 5. [`RunSession::finish`] joins the threads, commits the log and the recording (both, or
//!    neither after a failed run) and tells what the session did ([`RunReport`], its text and
//!    JSON in [`crate::cell::run_summary`]).
//!
//! The front end keeps what is its own: the flags, the signal handling, the outlets it attaches
//! to the session's telemetry (the live view, the ROS 2 bridge), printing and the exit codes.

use crate::cell::cell_run::{CellRun, CellRunOutcome, FeedForwardInUse};
use crate::cell::config::CellFile;
use crate::error::Error;
use deflex_io::ForceSensorLink;
use deflex_record::{McapRecorder, RecordError, RecordOptions, RecordReport};
use deflex_runtime::{LiveStatus, Runtime, Telemetry};
use std::path::{Path, PathBuf};
use std::sync::atomic::{AtomicBool, Ordering};
use std::time::{Duration, Instant};

/// How long a `deflex run` session waits and runs (the front end's flags, checked).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct RunOptions {
    /// Give up when no robot telegram and sensor sample arrive within this time (s).
    pub startup_timeout_s: f64,
    /// End once the robot has been silent this long after the session started (s).
    pub idle_exit_s: f64,
    /// Stop, ramping the correction out, after this long (s); `None`: when the robot ends.
    pub duration_s: Option<f64>,
}

/// The MCAP recording beside the CSV log `log`: the same name with the extension `.mcap`
/// (`deflex-run.csv` → `deflex-run.mcap`). A log already named `.mcap` is refused, naming
/// `field` (the setting or flag that gave the log).
pub fn mcap_beside(log: &Path, field: &str) -> Result<PathBuf, Error> {
    let mcap = log.with_extension("mcap");
    if mcap == log {
        return Err(Error::invalid(
            field,
            format!(
                "expected a log name other than NAME.mcap (the MCAP recording is written beside \
                 the CSV log with the extension .mcap; give the log another extension, .csv), \
                 got {}",
                log.display()
            ),
        ));
    }
    Ok(mcap)
}

/// The MCAP recording of a session: where, and what it held (or why it failed).
#[derive(Debug)]
pub struct Recording {
    /// The recording's file.
    pub path: PathBuf,
    /// What it held, or why it could not be written.
    pub result: Result<RecordReport, RecordError>,
}

/// A `CELL.toml` read and checked for `deflex run`, before any link opens.
pub struct RunPlan {
    /// The cell.
    pub cell: CellFile,
    /// The MCAP recording beside the CSV log (with `[log]`).
    pub mcap_path: Option<PathBuf>,
    /// When the session's wall clock started: once the file was read and checked.
    started: Instant,
}

impl RunPlan {
    /// Reads and validates the `CELL.toml` at `config` and refuses a `[log] path` that deflex
    /// may not replace (a folder, a device, the configuration itself), naming the file.
    pub fn load(config: &Path) -> Result<RunPlan, Error> {
        let cell = CellFile::load(config)?;
        if let Some(log) = cell.log_path() {
            deflex_files::check_output_flag("[log] path", &log, deflex_files::OutputKind::File)
                .map_err(|source| Error::CellOutput {
                    origin: deflex_files::shown_path(config),
                    source,
                })?;
        }
        let mcap_path = match cell.log_path() {
            Some(log) => Some(mcap_beside(&log, "log.path")?),
            None => None,
        };
        Ok(RunPlan {
            cell,
            mcap_path,
            started: Instant::now(),
        })
    }

    /// Starts the session: the model, the feed-forward, the links and the threads in wall time
    /// ([`CellRun::start_with`]). `sensor` is a sensor link the front end opened
    /// (`sensor.kind = "ros2"`), `None` for the link of `[sensor]`; `subscribe` is called with
    /// the session's telemetry before the threads start, so a sink it subscribes sees every
    /// cycle.
    pub fn start(
        &self,
        options: &RunOptions,
        sensor: Option<Box<dyn ForceSensorLink + Send>>,
        subscribe: &mut dyn FnMut(&Telemetry),
    ) -> Result<RunSession, Error> {
        let run = CellRun::start_with(
            &self.cell,
            options.startup_timeout_s,
            Some(options.idle_exit_s),
            sensor,
            subscribe,
        )?;
        let feedforward = run.feedforward.as_ref().map(FeedForwardInUse::describe);
        Ok(RunSession {
            run,
            recorder: None,
            mcap_path: self.mcap_path.clone(),
            started: self.started,
            duration_s: options.duration_s,
            feedforward,
        })
    }
}

/// What a running session reports to the front end while [`RunSession::wait`] waits.
#[derive(Debug)]
pub enum RunEvent<'a> {
    /// The live status, once a second, with the control rate since the previous one (Hz).
    Status {
        /// The session's state.
        status: LiveStatus,
        /// Control cycles per second since the previous status.
        rate_hz: f64,
    },
    /// The CSV log cannot be written (a full disk): reported once, when it happens; the session
    /// stops, ramping the correction out, rather than running on without its record.
    LogFailed {
        /// The log's path.
        path: &'a Path,
        /// The writer's error.
        error: &'a str,
    },
}

/// A `deflex run` session whose threads are running.
pub struct RunSession {
    run: CellRun,
    recorder: Option<McapRecorder>,
    mcap_path: Option<PathBuf>,
    started: Instant,
    duration_s: Option<f64>,
    feedforward: Option<String>,
}

impl RunSession {
    /// The threads: status, stop, the telemetry ring and the session's description (for the
    /// front end's sinks).
    pub fn runtime(&self) -> &Runtime {
        &self.run.runtime
    }

    /// The feed-forward in use, described ([`FeedForwardInUse::describe`]).
    pub fn feedforward(&self) -> Option<&str> {
        self.feedforward.as_deref()
    }

    /// Starts the MCAP recording beside the CSV log (with `[log]`), on its own thread, from the
    /// oldest sample the ring holds (called right after the start, nothing is lost: no robot
    /// has answered yet). A recording that cannot start ends the session before the robot is
    /// served.
    pub fn record(mut self) -> Result<RunSession, Error> {
        let Some(path) = self.mcap_path.clone() else {
            return Ok(self);
        };
        let runtime = &self.run.runtime;
        match McapRecorder::spawn_with(
            path,
            runtime.telemetry().subscribe_from_oldest(),
            runtime.session_info().clone(),
            RecordOptions::default(),
        ) {
            Ok(recorder) => {
                self.recorder = Some(recorder);
                Ok(self)
            }
            Err(error) => {
                self.abort();
                Err(error.into())
            }
        }
    }

    /// Ends a session that cannot go on (a sink of the front end that could not start): the
    /// correction ramps out, the threads are joined, the recording is discarded and the CSV log
    /// is kept or committed as [`CellRun::finish`] decides.
    pub fn abort(self) {
        self.run.runtime.request_stop();
        if let Some(recorder) = self.recorder {
            let _ = recorder.finish_with(false);
        }
        let _ = self.run.finish();
    }

    /// Runs until the threads end: requests the stop (the correction ramps out) when `stop` is
    /// set or the duration is over, and when the CSV log cannot be written. Reports the live
    /// status every second and a log failure once, to `on_event`.
    pub fn wait(&self, stop: &AtomicBool, on_event: &mut dyn FnMut(RunEvent<'_>)) {
        let runtime = &self.run.runtime;
        let mut last_cycles = 0u64;
        let mut last_status = Instant::now();
        let mut log_failure_reported = false;
        while !runtime.is_finished() {
            std::thread::sleep(Duration::from_millis(20));
            let elapsed = self.started.elapsed().as_secs_f64();
            if stop.load(Ordering::SeqCst) || self.duration_s.is_some_and(|d| elapsed >= d) {
                runtime.request_stop();
            }
            if !log_failure_reported && let Some((path, error)) = self.run.log_failure() {
                log_failure_reported = true;
                on_event(RunEvent::LogFailed { path, error });
                runtime.request_stop();
            }
            if last_status.elapsed() >= Duration::from_secs(1) {
                let status = runtime.status();
                let rate_hz =
                    (status.cycles - last_cycles) as f64 / last_status.elapsed().as_secs_f64();
                last_cycles = status.cycles;
                last_status = Instant::now();
                on_event(RunEvent::Status { status, rate_hz });
            }
        }
    }

    /// Joins the threads and commits the CSV log and the MCAP recording when the run did not
    /// fail (a failed run leaves both earlier files whole).
    pub fn finish(self) -> Result<RunReport, Error> {
        let finished = self.run.finish();
        let commit = finished.as_ref().is_ok_and(|s| s.summary.error.is_none());
        let recording = self.recorder.map(|recorder| Recording {
            path: recorder.path().to_path_buf(),
            result: recorder.finish_with(commit),
        });
        let session = finished.map_err(Error::LogWriter)?;
        Ok(RunReport {
            session,
            wall_s: self.started.elapsed().as_secs_f64(),
            feedforward: self.feedforward,
            recording,
        })
    }
}

/// Everything a `deflex run` session did (its text and JSON: [`crate::cell::run_summary`]).
pub struct RunReport {
    /// The session: summary, log, link, feed-forward.
    pub session: CellRunOutcome,
    /// Wall time from the file read to the end (s).
    pub wall_s: f64,
    /// The feed-forward in use, described.
    pub feedforward: Option<String>,
    /// The MCAP recording beside the log (with `[log]`).
    pub recording: Option<Recording>,
}

impl FeedForwardInUse {
    /// The feed-forward in use, for people: mode, table, its points and length (mm), index and
    /// lead.
    pub fn describe(&self) -> String {
        format!(
            "{} from {} ({} points, {:.1} mm), indexed by {}{}",
            self.mode.name(),
            self.table.display(),
            self.points,
            self.length_m * 1e3,
            self.index.name(),
            if self.lead_s > 0.0 {
                format!(", lead {:.3} s", self.lead_s)
            } else {
                String::new()
            }
        )
    }
}
