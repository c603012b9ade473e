//! Offline compensation of a tool path and its robot programs (`deflex compensate`, Python's
//! `deflex.compensate`), for cells without a real-time option: one workflow under both front
//! ends.
//!
//! 1. [`setup`]: the robot and its twin cell ([`deflex_sim::CellConfig::for_robot`]: part frame,
//!    seed configuration, sheet, tool) unless the options say otherwise, the tool path (a
//!    built-in one, a CAM G-code file or an array) placed in the world, cut to
//!    [`Options::length_mm`] and split to [`Options::max_segment_mm`], the wrench source, every
//!    check that needs the robot or the path (the tool axis of a 3-axis program, the arm's reach,
//!    the programs' point limit). The path's tool axis is −Z of its part frame; a seed that holds
//!    the tool more than [`MAX_TOOL_AXIS_DEG`] off it is refused.
//! 2. [`compensate`]: the iteration (`deflex_compensate`) against the twin's process model, a
//!    log's forces (its force–depth law when the log supports it, or the logged wrenches,
//!    [`LogForces`]) or given wrenches. When the law's iteration does not converge, the logged
//!    wrenches are used instead, with a warning.
//! 3. The outputs: [`write_output_folder`] writes the CLI's folder whole — `compensated_path.csv`,
//!    `summary.json`, `summary.txt` and, when every point is compensated and the iteration
//!    converged, `programs/` with one program per format, each read back and compared
//!    ([`ProgramPlan`]). When points cannot be compensated or the iteration did not converge, the
//!    table and the summaries are still written, no program is, and the run is refused
//!    ([`refusal`]). Python takes the same pieces: [`table_csv`], [`summary_dict`],
//!    [`ProgramPlan::export_checked`].
//!
//! The options are the front ends' values in the units of what they set: the tool path's
//! millimetres (its cut, its splitting, its arcs' chords, the part origin of the cell), SI
//! otherwise. Range checks of the options name the option as the front end spells it and are the
//! front end's; the checks that need the robot, the cell or the path are here and name the option
//! through [`crate::OptionNames`] (the front end's spelling).

mod output;
mod path;
mod programs;
mod run;
mod setup;
mod summary;

pub use output::{FolderSummary, write_output_folder};
pub use path::MAX_TOOL_AXIS_DEG;
pub use programs::{ProgramCheck, ProgramPlan, is_part_file};
pub use run::{CompensationRun, compensate};
pub use setup::{RobotChoice, Setup, robot_from_spec, setup};
pub use summary::{
    compensation_json, description, refusal, statuses, summary_dict, summary_text, table_comments,
    table_csv,
};

use crate::error::{Error, Result};
use deflex_cam::program::{Format, ProgramFile, ProgramSettings};
use std::path::{Path, PathBuf};

/// What a log gives the compensation (`--log-forces`).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
#[cfg_attr(feature = "clap", derive(clap::ValueEnum))]
pub enum LogForces {
    /// The force–depth law when the log supports it as a cause (the commanded depth explains
    /// the held-out force at least as well as the path position, the loop gain is below the
    /// bound, the force does not fall with depth: `deflex_compensate::LawEvidence`), else the
    /// logged wrenches; the default.
    Auto,
    /// The force–depth law identified from the log, whatever the evidence: the compensated
    /// tool, reaching deeper, meets the force the log shows at that depth
    /// (`deflex_compensate::logged`).
    Law,
    /// The logged wrenches as they are (one pass).
    Fixed,
}

impl std::str::FromStr for LogForces {
    type Err = Error;

    /// `auto`, `law` or `fixed`.
    fn from_str(text: &str) -> Result<LogForces> {
        match text {
            "auto" => Ok(LogForces::Auto),
            "law" => Ok(LogForces::Law),
            "fixed" => Ok(LogForces::Fixed),
            other => Err(Error::invalid(
                "log_forces",
                format!("expected \"auto\", \"law\" or \"fixed\", got \"{other}\""),
            )),
        }
    }
}

/// A program format to write, or none (`--format`).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
#[cfg_attr(feature = "clap", derive(clap::ValueEnum))]
pub enum ProgramFormat {
    /// KUKA KRL (`.src` + `.dat`).
    Krl,
    /// ABB RAPID (`.mod`).
    Rapid,
    /// Stäubli VAL3 (an SRS application folder).
    Val3,
    /// Universal Robots URScript (`.script`).
    Urscript,
    /// G-code in the part frame.
    Gcode,
    /// FANUC TP in its ASCII form (`.ls`).
    Fanuc,
    /// Yaskawa INFORM job (`.JBI`).
    Inform,
    /// No program.
    None,
}

impl ProgramFormat {
    /// The program format, `None` for [`ProgramFormat::None`].
    pub fn format(self) -> Option<Format> {
        match self {
            ProgramFormat::Krl => Some(Format::Krl),
            ProgramFormat::Rapid => Some(Format::Rapid),
            ProgramFormat::Val3 => Some(Format::Val3),
            ProgramFormat::Urscript => Some(Format::UrScript),
            ProgramFormat::Gcode => Some(Format::Gcode),
            ProgramFormat::Fanuc => Some(Format::Fanuc),
            ProgramFormat::Inform => Some(Format::Inform),
            ProgramFormat::None => None,
        }
    }

    /// The formats a list asks for, each once in the order given; none when the list holds
    /// [`ProgramFormat::None`].
    pub fn formats(list: &[ProgramFormat]) -> Vec<Format> {
        if list.contains(&ProgramFormat::None) {
            return Vec::new();
        }
        let mut out: Vec<Format> = Vec::new();
        for f in list.iter().filter_map(|f| f.format()) {
            if !out.contains(&f) {
                out.push(f);
            }
        }
        out
    }
}

/// A program format by name (`krl`, `rapid`, `val3`, `urscript`, `gcode`, `fanuc`, `inform`),
/// as Python names it.
pub fn format(name: &str) -> Result<Format> {
    Format::parse(name).ok_or_else(|| {
        Error::invalid(
            "formats",
            format!(
                "unknown format \"{}\"; expected krl, rapid, val3, urscript, gcode, fanuc or inform",
                name.trim()
            ),
        )
    })
}

/// The frame an array path is given in.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Frame {
    /// The part frame (G-code's), placed in the world at the cell's part origin.
    Part,
    /// The robot model's world frame.
    World,
}

impl std::str::FromStr for Frame {
    type Err = Error;

    /// `part` or `world`.
    fn from_str(text: &str) -> Result<Frame> {
        match text {
            "part" => Ok(Frame::Part),
            "world" => Ok(Frame::World),
            other => Err(Error::invalid(
                "frame",
                format!("expected \"part\" or \"world\", got \"{other}\""),
            )),
        }
    }
}

/// The names of the built-in tool paths.
pub const BUILTIN_PATHS: [&str; 3] = ["cone", "cone-contour", "pyramid"];

/// The path to compensate.
#[derive(Clone, Debug)]
pub enum PathSpec {
    /// A built-in path: `cone` (the paper's helical cone), `cone-contour` or `pyramid`.
    Builtin(String),
    /// A CAM G-code file (part frame, mm).
    Gcode(PathBuf),
    /// TCP positions (`rows × 3`, m) or poses (`rows × 6`: position m and rotation vector rad),
    /// in `frame`; positions alone keep the tool orientation of the seed configuration.
    Array {
        /// Row-major values.
        values: Vec<f64>,
        /// 3 or 6.
        cols: usize,
        /// Frame of the values.
        frame: Frame,
        /// Feed of every move (m/s); `None` moves are rapids.
        feed_m_s: Option<f64>,
    },
}

impl PathSpec {
    /// A path named as the user writes it: a built-in name ([`BUILTIN_PATHS`]), else a G-code
    /// file.
    pub fn named(text: &str) -> PathSpec {
        if BUILTIN_PATHS.contains(&text) {
            PathSpec::Builtin(text.to_string())
        } else {
            PathSpec::Gcode(PathBuf::from(text))
        }
    }

    /// The path as the user gave it, for messages and notes.
    pub fn shown(&self) -> String {
        match self {
            PathSpec::Builtin(name) => name.clone(),
            PathSpec::Gcode(file) => file.display().to_string(),
            PathSpec::Array { .. } => "array path".into(),
        }
    }
}

/// Where the wrench at each point comes from.
#[derive(Clone, Debug)]
pub enum WrenchSpec {
    /// The twin's forming model (SIMULATED), evaluated at each iteration's commanded path.
    Process,
    /// A `deflex run` log or a `deflex sim isf` log of a previous run of this path.
    Log(PathBuf),
    /// One wrench for every point (`6` values) or one per point (`points × 6`), world axes at
    /// the TCP (N, N·m).
    Array(Vec<f64>),
}

impl WrenchSpec {
    /// `process` or `log:FILE`, as both front ends write them; `None` for anything else (the
    /// front end says what it takes).
    pub fn parse(text: &str) -> Option<WrenchSpec> {
        match text.strip_prefix("log:") {
            Some(file) => Some(WrenchSpec::Log(PathBuf::from(file))),
            None if text == "process" => Some(WrenchSpec::Process),
            None => None,
        }
    }
}

/// The compensation's options: what the front ends' flags and keywords set (see the module
/// documentation for the units).
#[derive(Clone, Debug)]
pub struct Options {
    /// Twin settings (`[cell]` TOML) over the robot's cell: part placement, seed, sheet.
    pub twin_config: Option<PathBuf>,
    /// Part frame origin in the robot's world (mm, the cell's unit); default the cell's.
    pub part_xyz_mm: Option<[f64; 3]>,
    /// IK seed near the start of the path (rad); default the cell's seed (6 joints).
    pub seed_q: Option<Vec<f64>>,
    /// Only the first part of the path (mm of travel, 0.001 ..= 1e6).
    pub length_mm: Option<f64>,
    /// Split feed moves longer than this (mm) before compensating.
    pub max_segment_mm: Option<f64>,
    /// Chord tolerance of G-code arcs (mm, 0.0001 ..= 1).
    pub chord_tolerance_mm: f64,
    /// Compensate the position only (keep the desired orientation).
    pub position_only: bool,
    /// Add the deflection under the robot's own weight.
    pub include_gravity: bool,
    /// Convergence tolerance (m; the same number in rad for the orientation).
    pub tolerance_m: f64,
    /// Most process/compensation iterations (1 ..= 200).
    pub max_iterations: usize,
    /// What a log gives the compensation.
    pub log_forces: LogForces,
    /// With a log's force–depth law: use the log's measured TCP (a sim log's laser-tracker
    /// columns) to correct what the robot model misses.
    pub use_measured_tcp: bool,
    /// The programs the output folder gets (checked against the template's point limit).
    pub formats: Vec<Format>,
    /// The program template (TOML); default [`ProgramSettings::default`].
    pub program_config: Option<PathBuf>,
}

impl Default for Options {
    /// The CLI's defaults: the cell's placement, 1 µm, 30 iterations, a log's force–depth law
    /// when the log supports it (`auto`), no program.
    fn default() -> Options {
        Options {
            twin_config: None,
            part_xyz_mm: None,
            seed_q: None,
            length_mm: None,
            max_segment_mm: None,
            chord_tolerance_mm: 0.005,
            position_only: false,
            include_gravity: false,
            tolerance_m: 1e-6,
            max_iterations: 30,
            log_forces: LogForces::Auto,
            use_measured_tcp: true,
            formats: Vec::new(),
            program_config: None,
        }
    }
}

/// Program settings from a TOML file (`--program-config`), or the defaults.
pub fn settings(path: Option<&Path>) -> Result<ProgramSettings> {
    Ok(match path {
        Some(p) => ProgramSettings::load(p)?,
        None => ProgramSettings::default(),
    })
}

/// The robot programs of `run` in each of `formats` (by name: `krl`, `rapid`, `val3`,
/// `urscript`, `gcode`, [`format()`]) with the template `settings` (a program TOML file, or the
/// defaults), each read back and compared with the path ([`ProgramPlan::export_checked`]).
/// Refused as the command line refuses them when points are not compensated or the iteration
/// did not converge ([`refusal`]), before the template and the names are read (Python's
/// `Compensation.program` and `write_programs`).
pub fn program_files(
    run: &CompensationRun,
    formats: &[String],
    settings: Option<&Path>,
) -> Result<Vec<ProgramFile>> {
    refusal(run)?;
    let settings = self::settings(settings)?;
    let formats = formats
        .iter()
        .map(|name| format(name))
        .collect::<Result<Vec<_>>>()?;
    let plan = ProgramPlan::new(&run.setup, &run.result, description(run), &settings)?;
    let mut files = Vec::new();
    for format in formats {
        files.extend(plan.export_checked(format, &settings)?);
    }
    Ok(files)
}

/// Write program files under `dir` (created), each whole; returns their paths.
pub fn write_program_files(dir: &Path, files: &[ProgramFile]) -> Result<Vec<PathBuf>> {
    std::fs::create_dir_all(dir).map_err(Error::io_on(dir))?;
    deflex_cam::program::write_files(dir, files)?;
    Ok(files.iter().map(|f| dir.join(&f.path)).collect())
}
