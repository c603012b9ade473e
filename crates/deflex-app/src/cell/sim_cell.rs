//! `deflex cell --sim`: the digital twin served on loopback over the protocols of a real cell
//! (`deflex_sim::twin::cell_server`, its ends from the link factory: [`CellFile::cell_sides`]),
//! from the same `CELL.toml` as `deflex run`:
//!
//! 1. [`SimCellPlan::load`] reads the file and refuses a ROS 2 sensor (the twin plays a Net F/T);
//! 2. [`SimCellPlan::start`] names the twin's ground-truth log ([`sim_cell_log_path`]) and its
//!    MCAP recording beside it, and starts the recording of the twin's own stream
//!    ([`StreamSource::TwinCell`]) on its own thread;
//! 3. [`SimCellSession::serve`] serves the twin until its path is done (or the stop flag), then
//!    writes the log and commits the recording (both only when the session served), and tells
//!    what it did ([`SimCellReport`], with its text and JSON).
//!
//! The front end keeps the flags, the twin's settings it picks with them, the signal handling,
//! the live view it attaches to [`SimCellSession::ring`] and printing.

use crate::cell::config::{CellFile, SensorKind};
use crate::cell::run_session::{Recording, mcap_beside};
use crate::cell::run_summary::stats_json;
use crate::error::Error;
use deflex_record::McapRecorder;
use deflex_sim::twin::cell_server::{
    CellEnd, CellEvent, CellOutcome, ServeOptions, serve_cell_with,
};
use deflex_sim::twin::{TwinCellStream, twin_cell_session_info};
use deflex_sim::{ConeParams, ToolPath};
use deflex_telemetry::{Broadcast, CycleSample, SessionInfo, StreamSource, broadcast};
use serde_json::json;
use std::path::{Path, PathBuf};
use std::sync::Arc;
use std::sync::atomic::AtomicBool;

/// The tool path the twin's robot program runs.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum SimCellPath {
    /// The paper's cone (as `deflex sim isf`).
    Cone,
    /// The helical cone.
    Helical,
}

impl SimCellPath {
    /// Every path, in the order their names are listed.
    pub const ALL: [SimCellPath; 2] = [SimCellPath::Cone, SimCellPath::Helical];

    /// The path's name (`cone`, `helical`).
    pub fn name(self) -> &'static str {
        match self {
            SimCellPath::Cone => "cone",
            SimCellPath::Helical => "helical",
        }
    }

    /// The path of a name, `None` for another text.
    pub fn from_name(text: &str) -> Option<SimCellPath> {
        Self::ALL.into_iter().find(|p| p.name() == text)
    }

    /// The tool path, only its first `length_mm` of travel when given.
    pub fn tool_path(self, length_mm: Option<f64>) -> Result<ToolPath, Error> {
        let path = match self {
            SimCellPath::Cone => ToolPath::paper_cone(),
            SimCellPath::Helical => ToolPath::cone(&ConeParams {
                helical: true,
                ..ConeParams::default()
            })?,
        };
        Ok(match length_mm {
            Some(l) => path.truncated(l),
            None => path,
        })
    }
}

/// The twin's ground-truth log of a `cell --sim` session: `log` when given, else beside the
/// `CELL.toml`'s run log, named after it (`deflex-run.csv` → `deflex-run.sim-cell.csv`), or
/// `deflex-run.sim-cell.csv` beside the `CELL.toml` without `[log]`.
pub fn sim_cell_log_path(file: &CellFile, log: Option<&Path>) -> PathBuf {
    if let Some(p) = log {
        return p.to_path_buf();
    }
    let run_log = file
        .log_path()
        .unwrap_or_else(|| file.base_dir.join("deflex-run.csv"));
    let stem = run_log
        .file_stem()
        .map_or_else(|| "deflex-run".into(), |s| s.to_string_lossy().into_owned());
    run_log.with_file_name(format!("{stem}.sim-cell.csv"))
}

/// A `CELL.toml` read for `deflex cell --sim`.
pub struct SimCellPlan {
    /// The cell.
    pub cell: CellFile,
}

impl SimCellPlan {
    /// Reads and validates the `CELL.toml` at `config`; a sensor that is a ROS 2 topic is
    /// refused (the simulated cell plays an ATI Net F/T).
    pub fn load(config: &Path) -> Result<SimCellPlan, Error> {
        let cell = CellFile::load(config)?;
        if cell.sensor.kind == SensorKind::Ros2 {
            return Err(Error::SimCellNeedsNetFt {
                origin: cell.origin.clone(),
            });
        }
        Ok(SimCellPlan { cell })
    }

    /// Prepares the session for the twin of `options`: its ground-truth log (`log`, or
    /// [`sim_cell_log_path`]) and the MCAP recording beside it (`--log` names it in a refusal),
    /// the twin's stream and its recording, started.
    pub fn start(self, options: ServeOptions, log: Option<&Path>) -> Result<SimCellSession, Error> {
        let log_path = sim_cell_log_path(&self.cell, log);
        let mcap_path = mcap_beside(&log_path, "--log")?;
        let nominal = options.twin.nominal_robot()?;
        let info = Arc::new(twin_cell_session_info(&nominal, &options.twin));
        debug_assert_eq!(info.source, StreamSource::TwinCell);
        let (publisher, ring) = broadcast::<CycleSample>(1 << 14);
        let recorder = McapRecorder::spawn(&mcap_path, &ring, info.clone())?;
        let stream = TwinCellStream::new(nominal).with_publisher(publisher);
        Ok(SimCellSession {
            cell: self.cell,
            options,
            log_path,
            recorder,
            stream,
            ring,
            info,
        })
    }
}

/// A `cell --sim` session ready to serve, its recording running.
pub struct SimCellSession {
    cell: CellFile,
    options: ServeOptions,
    log_path: PathBuf,
    recorder: McapRecorder,
    stream: TwinCellStream,
    ring: Arc<Broadcast<CycleSample>>,
    info: Arc<SessionInfo>,
}

impl SimCellSession {
    /// The twin's stream (SIMULATED ground truth), for a live view.
    pub fn ring(&self) -> &Arc<Broadcast<CycleSample>> {
        &self.ring
    }

    /// The twin's session description.
    pub fn info(&self) -> &Arc<SessionInfo> {
        &self.info
    }

    /// Ends a session that will not serve (a sink of the front end that could not start): the
    /// recording is discarded.
    pub fn abort(self) {
        let _ = self.recorder.finish_with(false);
    }

    /// Serves the twin until the path is done (or `stop`), reporting its progress to `events`;
    /// then writes the ground-truth log and commits the recording beside it, both only when
    /// the session served.
    pub fn serve(
        self,
        stop: &AtomicBool,
        events: &mut dyn FnMut(CellEvent),
    ) -> Result<SimCellReport, Error> {
        let SimCellSession {
            cell,
            options,
            log_path,
            recorder,
            mut stream,
            ..
        } = self;
        let served = cell
            .cell_sides(&options.twin)
            .map_err(Error::from)
            .and_then(|sides| {
                serve_cell_with(&sides, &options, stop, events, Some(&mut stream))
                    .map_err(Error::from)
            });
        drop(stream); // the stream ends
        let outcome = match served {
            Ok(o) => o,
            Err(e) => {
                let _ = recorder.finish_with(false);
                return Err(e);
            }
        };
        let log_rows = outcome.log.rows.len();
        let mcap_path = recorder.path().to_path_buf();
        let written = deflex_files::write_atomic(&log_path, outcome.log.to_csv())
            .map_err(Error::io_on(&log_path));
        let recording = recorder.finish_with(written.is_ok());
        written?;
        Ok(SimCellReport {
            outcome,
            log_path,
            log_rows,
            recording: Recording {
                path: mcap_path,
                result: recording,
            },
        })
    }
}

/// What `cell --sim` served and wrote.
pub struct SimCellReport {
    /// The twin's run.
    pub outcome: CellOutcome,
    /// The ground-truth log written.
    pub log_path: PathBuf,
    /// Its rows.
    pub log_rows: usize,
    /// The MCAP recording of the twin's stream.
    pub recording: Recording,
}

impl SimCellReport {
    /// How the session ended, for people.
    fn phase_text(&self) -> &'static str {
        match self.outcome.end {
            CellEnd::ProgramFinished => "ended (robot program finished)",
            CellEnd::Stopped => "stopped (signal)",
        }
    }

    /// The summary `deflex cell --sim` prints, each line ending in a newline (the front end adds
    /// its live view's line after it).
    pub fn summary_text(&self) -> String {
        let o = &self.outcome;
        let s = &o.summary;
        let mut lines = vec![
            format!(
                "deflex cell (SIMULATED {} cell, `{}`): {:.1} s simulated, {} robot cycles, phase: {}",
                o.robot,
                o.robot_spec,
                o.duration_s,
                o.cycles,
                self.phase_text()
            ),
            format!(
                "  late answers: {} (the robot's count: no answer before its next cycle; `deflex run` \
                 over KUKA RSI reports the same number from the telegrams' Delay)",
                o.late
            ),
            format!("  robot-side round trip: {}", o.round_trip),
            format!(
                "  max TCP error norm {:.3} mm (rms {:.3} mm), max force {:.0} N, max correction {:.3} mm",
                s.max_error_norm_m * 1e3,
                s.rms_error_norm_m() * 1e3,
                s.max_force_norm_n,
                s.max_correction_m * 1e3
            ),
            format!(
                "  log: {} ({} rows, SIMULATED ground truth)",
                self.log_path.display(),
                self.log_rows
            ),
        ];
        let mcap = &self.recording;
        lines.push(match &mcap.result {
            Ok(r) => format!(
                "  recording: {} (MCAP, the twin's stream: {} samples, {} lost, {:.1} MB)",
                mcap.path.display(),
                r.stats.recorded,
                r.lost,
                r.stats.bytes as f64 / 1e6
            ),
            Err(e) => format!("  recording: failed: {e}"),
        });
        lines.iter().map(|l| format!("{l}\n")).collect()
    }

    /// The summary `deflex cell --sim --json` prints, without the front end's `view` key.
    pub fn summary_json(&self) -> serde_json::Value {
        let o = &self.outcome;
        let s = &o.summary;
        let mut value = json!({
            "simulated": true, "robot": o.robot, "robot_spec": o.robot_spec,
            "model_geometry_matches": o.model_geometry_matches,
            "phase": match o.end { CellEnd::ProgramFinished => "ended", CellEnd::Stopped => "stopped" },
            "phase_text": self.phase_text(), "cycles": o.cycles, "late_replies": o.late,
            "duration_s": o.duration_s,
            "round_trip": stats_json(&o.round_trip),
            "max_error_norm_mm": s.max_error_norm_m * 1e3, "rms_error_norm_mm": s.rms_error_norm_m() * 1e3,
            "max_force_norm_n": s.max_force_norm_n, "max_fz_n": s.max_fz_n,
            "max_correction_mm": s.max_correction_m * 1e3,
            "log": self.log_path, "log_rows": self.log_rows,
        });
        let mcap = &self.recording;
        let ok = mcap.result.as_ref().ok();
        value["mcap"] = json!({
            "path": mcap.path, "committed": ok.is_some(),
            "cycles": ok.map(|r| r.stats.recorded), "lost": ok.map(|r| r.lost),
            "error": mcap.result.as_ref().err().map(ToString::to_string),
        });
        value
    }
}
