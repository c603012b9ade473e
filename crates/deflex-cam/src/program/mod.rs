//! # Robot programs out (`deflex_cam::program`)
//!
//! Robot programs from a tool path (a sequence of TCP poses with speeds), in the languages that
//! controllers load without any real-time option:
//!
//! | format | files | motion | units | orientation |
//! | --- | --- | --- | --- | --- |
//! | [`Format::Krl`] KUKA | `NAME.src` + `NAME.dat` | `LIN {X …, A …} C_DIS`, `$VEL.CP`, `$APO.CDIS`, `$BASE`/`$TOOL` | mm, deg, m/s | A-B-C (Z-Y'-X'') |
//! | [`Format::Rapid`] ABB | `NAME.mod` | `MoveL robtarget, speeddata, zonedata, tooldata \WObj` | mm, deg/s | quaternion `[q1..q4]`, q1 = w |
//! | [`Format::Val3`] Stäubli | `NAME/NAME.pjx`, `.dtx`, `start.pgx`, `stop.pgx` | `movel(point, tool, mdesc)` | mm, deg | Rx-Ry-Rz (X-Y'-Z'') |
//! | [`Format::UrScript`] UR | `NAME.script` | `movel(p[x,y,z,rx,ry,rz], a, v, r=…)` | m, rad, m/s | rotation vector |
//! | [`Format::Fanuc`] FANUC | `NAME.ls` (TP, ASCII) | `L P[n] 250mm/sec CNT100`, `/POS` with `UF`, `UT`, `CONFIG` | mm, deg, mm/s (whole) | W-P-R (fixed X, Y, Z) |
//! | [`Format::Inform`] Yaskawa | `NAME.JBI` (INFORM job) | `MOVL C00001 V=10.0 PL=1`, `//POS` with `///USER`, `///TOOL`, `///RCONF` | mm, deg, mm/s (0.1) | Rx-Ry-Rz (fixed X, Y, Z) |
//! | [`Format::Gcode`] CAM / twin | `NAME.gcode` | `G1 X Y Z F` | mm, mm/min | none (positions only) |
//!
//! Every program runs safely from wherever the robot is: a safe-start block, a joint move to a
//! clearance point above the start (with the vendor's configuration data, [`config`]), an
//! approach straight onto the first point at the approach speed, the path (rapids as one
//! straight move at the rapid speed), a retract to a clearance point above the end; a long path
//! is split into parts a main program calls in order (the limits and their sources are in
//! `plan`'s documentation: 5000 moves and 1 MiB per file by default).
//!
//! The conventions and their sources are in [`deflex_model::conventions`]; the user's template
//! (frame and tool names, speeds, zones, clearance, limits, tool load) is [`ProgramSettings`],
//! read from TOML. Every exporter
//! bounds the number of points and the line length, names things within the language's rules
//! ([`names`]) and has a reader ([`readback`]) that the round-trip tests use: poses read back
//! from a program agree with the path to the printed precision (≤ 1 µm, ≤ 1e-6 rad).
//!
//! **None of these programs has been run on a real controller** (or in RoboGuide-like vendor
//! simulators): they follow the public documentation cited in each module.
//!
//! ```
//! use deflex_cam::program::{export, Format, ProgramInput, ProgramPoint, ProgramSettings};
//! use deflex_model::Pose;
//! let points = vec![
//!     ProgramPoint { pose: Pose::identity(), speed_m_s: None },
//!     ProgramPoint { pose: Pose::translation(0.01, 0.0, 0.0), speed_m_s: Some(0.01) },
//! ];
//! let input = ProgramInput::new(points);
//! let files = export(Format::UrScript, &input, &ProgramSettings::default()).unwrap();
//! assert!(files[0].contents.contains("movel(pose_trans("));
//! assert!(files[0].contents.contains("# retract"));
//! ```

#![warn(missing_docs)]

pub mod common;
pub mod config;
pub mod error;
mod fanuc;
mod gcode;
mod inform;
mod krl;
pub mod names;
mod plan;
mod rapid;
pub mod readback;
pub mod settings;
pub mod sink;
mod urscript;
mod val3;

pub use error::ProgramError;
pub use fanuc::MAX_POINTS_PER_PART as FANUC_MAX_POINTS_PER_PART;
pub use inform::MAX_POINTS_PER_PART as INFORM_MAX_POINTS_PER_PART;
pub use settings::{Clearance, Coordinates, ProgramSettings, StaubliBlend};
pub use sink::{DirectorySink, MemorySink, ProgramSink};

use deflex_files::FileIoError;
use deflex_model::{Pose, ToolLoad};
use std::path::Path;

/// One point of a program: the TCP pose in the program frame and the speed of the move that
/// ends there.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ProgramPoint {
    /// TCP pose in the program frame (m).
    pub pose: Pose,
    /// TCP speed of the move ending here (m/s); `None`: a rapid move (one straight move at the
    /// settings' rapid speed). The first point is reached by the approach move.
    pub speed_m_s: Option<f64>,
}

/// The arm's configuration at a pose: the joint values (rad, the controller's axes) and where
/// the wrist centre lies, from which each vendor's configuration data is written (KUKA
/// Status/Turn, ABB `robconf`, Stäubli `config`, FANUC `CONFIG`, Yaskawa `///RCONF`). The
/// caller computes it with the robot model (`deflex compensate` does); the conventions are in
/// [`config`].
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ArmConfiguration {
    /// Joint values A1 … A6 (rad).
    pub joints_rad: [f64; 6],
    /// The wrist centre lies behind axis 1 (negative x in the frame of axis 1, which turns with
    /// it): KUKA's "overhead area", ABB's "behind axis 1", Stäubli's `lefty`.
    pub wrist_behind_axis_1: bool,
    /// The wrist centre lies behind the lower arm (the line from axis 2 to axis 3, seen in the
    /// arm's plane): ABB's `cfx` second criterion.
    pub wrist_behind_lower_arm: bool,
    /// Axis 3 at or beyond its stretched value φ (the elbow straight): KUKA Status bit 1.
    pub elbow_beyond_stretched: bool,
    /// The elbow (axis 3) lies above the line from axis 2 to the wrist centre (seen in the
    /// arm's plane, "above" along R0's z): FANUC's `U` (else `D`), Yaskawa's upper arm (else
    /// lower arm). Geometric, so it does not depend on axis 3's sense.
    pub elbow_up: bool,
}

/// What an exporter writes: the points plus the frames a program declares or checks.
#[derive(Clone, Debug, PartialEq)]
pub struct ProgramInput {
    /// Header comment lines (what the path is, how it was compensated; SIMULATED when it is).
    pub description: Vec<String>,
    /// The program frame (part frame or robot base) in the robot base frame R0: the value of the
    /// KUKA base, ABB work object, Stäubli frame or UR feature the positions refer to.
    pub frame_in_robot: Pose,
    /// Whether the program frame is the part frame or the robot base (`$NULLFRAME`, no work
    /// offset).
    pub coordinates: Coordinates,
    /// Name of the part frame on the controller when the path names one (a G-code work offset
    /// such as `G54`), for the headers and the G-code safe start.
    pub frame_name: Option<String>,
    /// The TCP in the flange frame (the robot model's tool).
    pub tool_in_flange: Pose,
    /// The tool's load, centre of mass in the flange frame, when known
    /// ([`settings::CommonSettings::tool_mass_kg`] overrides it).
    pub tool_load_in_flange: Option<ToolLoad>,
    /// Where [`ProgramInput::tool_load_in_flange`] comes from, for the header (`program
    /// template`, `the robot's twin cell`, …); unused without a load.
    pub tool_load_source: String,
    /// The points, in order.
    pub points: Vec<ProgramPoint>,
    /// The configuration at each point (empty: unknown; else one per point).
    pub configurations: Vec<ArmConfiguration>,
    /// The configuration at the clearance points above the start and the end
    /// ([`ProgramInput::clearance_poses`]), when known: the start joint move and the
    /// configuration data of the first motion.
    pub clearance_configurations: Option<[ArmConfiguration; 2]>,
}

impl ProgramInput {
    /// Points in the robot base frame with the flange as tool and no description.
    pub fn new(points: Vec<ProgramPoint>) -> ProgramInput {
        ProgramInput {
            description: Vec::new(),
            frame_in_robot: Pose::identity(),
            coordinates: Coordinates::Part,
            frame_name: None,
            tool_in_flange: Pose::identity(),
            tool_load_in_flange: None,
            tool_load_source: String::new(),
            points,
            configurations: Vec::new(),
            clearance_configurations: None,
        }
    }

    /// Program input from TCP poses in the *world* frame of a robot model: `robot_base` is the
    /// robot base frame R0 in the world, `part` the part frame in the world; `coordinates`
    /// chooses which of the two the program's positions refer to.
    pub fn from_world_poses(
        world_points: impl IntoIterator<Item = (Pose, Option<f64>)>,
        robot_base: &Pose,
        part: &Pose,
        coordinates: Coordinates,
        tool_in_flange: &Pose,
        description: Vec<String>,
    ) -> ProgramInput {
        let frame_in_world = match coordinates {
            Coordinates::Part => *part,
            Coordinates::Robot => *robot_base,
        };
        let to_frame = frame_in_world.inverse();
        ProgramInput {
            description,
            frame_in_robot: robot_base.inverse() * frame_in_world,
            coordinates,
            frame_name: None,
            tool_in_flange: *tool_in_flange,
            tool_load_in_flange: None,
            tool_load_source: String::new(),
            points: world_points
                .into_iter()
                .map(|(pose, speed_m_s)| ProgramPoint {
                    pose: to_frame * pose,
                    speed_m_s,
                })
                .collect(),
            configurations: Vec::new(),
            clearance_configurations: None,
        }
    }

    /// The clearance poses above the first and the last point (program frame), where the
    /// approach starts and the retract ends ([`settings::Clearance`]); the tool keeps the
    /// orientation of the first and the last point.
    pub fn clearance_poses(&self, settings: &ProgramSettings) -> Option<[Pose; 2]> {
        plan::clearance_poses(self, settings)
    }
}

/// The output formats.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum Format {
    /// KUKA KRL (`.src` + `.dat`).
    Krl,
    /// ABB RAPID (`.mod`).
    Rapid,
    /// Stäubli VAL3 (an SRS application folder).
    Val3,
    /// Universal Robots URScript (`.script`).
    UrScript,
    /// G-code in the part frame (`.gcode`).
    Gcode,
    /// FANUC TP in its ASCII form (`.ls`).
    Fanuc,
    /// Yaskawa INFORM job (`.JBI`).
    Inform,
}

impl Format {
    /// Every format.
    pub const ALL: [Format; 7] = [
        Format::Krl,
        Format::Rapid,
        Format::Val3,
        Format::UrScript,
        Format::Gcode,
        Format::Fanuc,
        Format::Inform,
    ];

    /// The name used on the command line (`krl`, `rapid`, `val3`, `urscript`, `gcode`,
    /// `fanuc`, `inform`).
    pub fn name(self) -> &'static str {
        match self {
            Format::Krl => "krl",
            Format::Rapid => "rapid",
            Format::Val3 => "val3",
            Format::UrScript => "urscript",
            Format::Gcode => "gcode",
            Format::Fanuc => "fanuc",
            Format::Inform => "inform",
        }
    }

    /// A format by its command-line name.
    pub fn parse(name: &str) -> Option<Format> {
        Format::ALL.into_iter().find(|f| f.name() == name.trim())
    }

    /// Whether the format carries the orientation (G-code does not).
    pub fn has_orientation(self) -> bool {
        self != Format::Gcode
    }
}

/// One produced file: a path relative to the output folder (`NAME.src`, `NAME/start.pgx`) and
/// its text.
#[derive(Clone, Debug, PartialEq)]
pub struct ProgramFile {
    /// Relative path (forward slashes).
    pub path: String,
    /// Contents (ASCII, `\n` line ends; `\r\n` for KRL and RAPID, as their editors write).
    pub contents: String,
}

/// Write `input` as a program in `format`, in memory (see [`export_to`] for large programs).
pub fn export(
    format: Format,
    input: &ProgramInput,
    settings: &ProgramSettings,
) -> Result<Vec<ProgramFile>, ProgramError> {
    let mut sink = MemorySink::default();
    let order = export_to(format, input, settings, &mut sink)?;
    // In the order the exporter lists them: the main program first.
    let mut files = sink.files;
    files.sort_by_key(|f| order.iter().position(|p| *p == f.path));
    Ok(files)
}

/// Write `input` as a program in `format` to `sink`, file by file and each part as soon as it
/// is complete (a [`DirectorySink`] never holds more than a part in memory); returns the
/// files' paths, the main program first. A failed export may leave the files written so far.
pub fn export_to(
    format: Format,
    input: &ProgramInput,
    settings: &ProgramSettings,
    sink: &mut dyn ProgramSink,
) -> Result<Vec<String>, ProgramError> {
    settings.validate("settings")?;
    match format {
        Format::Krl => krl::export(input, settings, sink),
        Format::Rapid => rapid::export(input, settings, sink),
        Format::Val3 => val3::export(input, settings, sink),
        Format::UrScript => urscript::export(input, settings, sink),
        Format::Gcode => gcode::export(input, settings, sink),
        Format::Fanuc => fanuc::export(input, settings, sink),
        Format::Inform => inform::export(input, settings, sink),
    }
}

/// Write produced files under `dir` (which must exist), each whole or not at all
/// ([`deflex_files::write_atomic`]); sub-folders are created.
pub fn write_files(dir: &Path, files: &[ProgramFile]) -> Result<(), ProgramError> {
    for file in files {
        if file
            .path
            .split('/')
            .any(|part| part.is_empty() || part == "..")
        {
            return Err(FileIoError::other(
                &file.path,
                std::io::ErrorKind::InvalidInput,
                "not a plain relative path",
            )
            .into());
        }
        let path = dir.join(&file.path);
        if let Some(parent) = path.parent() {
            std::fs::create_dir_all(parent).map_err(|e| FileIoError::new(parent, e))?;
        }
        deflex_files::write_atomic(&path, file.contents.as_bytes())
            .map_err(|e| FileIoError::new(&path, e))?;
    }
    Ok(())
}
