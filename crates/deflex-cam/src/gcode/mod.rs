//! # G-code in (`deflex_cam::gcode`)
//!
//! A reader of the ISO/Fanuc-style G-code subset that CAM systems emit for 3-axis forming and
//! milling: text in, a typed tool path and diagnostics out. Pure parsing: no file, no I/O.
//!
//! ## What is read
//!
//! | words | meaning |
//! | --- | --- |
//! | `%`, `O1000`, `N10`, `( … )`, `; …`, `/` | tape markers (a second `%` ends the program), program number, line numbers, both comment styles, block delete (the line is executed) |
//! | `G0`, `G1` | rapid and linear feed moves (`X Y Z`, modal) |
//! | `G2`, `G3` | clockwise / counter-clockwise arcs with `I J K` (centre offsets; `G90.1`/`G91.1` absolute/incremental) or `R` (negative: more than 180°), helical with the third axis, full circles, `P` turns; interpolated to [`ReadOptions::chord_tolerance_mm`] ([`arc`]) |
//! | `G17`, `G18`, `G19` | arc plane XY, ZX, YZ |
//! | `G20`, `G21` | inch, millimetre |
//! | `G90`, `G91` | absolute, incremental |
//! | `G54` … `G59` | the work offset: the *named part frame* the program is written in ([`WorkOffset`]); one per program |
//! | `F` | feed per minute (`G94`), in the unit in force |
//! | `G40`, `G49`, `G80`, `G94`, `G90.1`, `G91.1` | accepted (compensation off, cycles off, feed per minute, arc-centre mode) |
//! | `T`, `S`, `M3`–`M9`, `M0`, `M1`, `G4`, `G28`, `G30`, `G61`, `G64` | ignored, each with a [`Note`] |
//! | `M2`, `M30` | program end |
//!
//! Refused with an error naming the line, the column and the word ([`GcodeError`]): tool radius
//! and length compensation (`G41`, `G42`, `G43`, `G44`, `H`, `D`: the path must be the tool
//! centre, which is the robot's TCP), canned cycles (`G81`…), machine coordinates (`G53`),
//! coordinate-system setting (`G10`, `G92`), polar, rotation and scaling (`G15`/`G16`, `G68`,
//! `G51`), inverse-time and per-revolution feeds (`G93`, `G95`), subprograms (`M98`, `M99`),
//! rotary and extra axes (`A B C U V W`), and anything else.
//!
//! ## The path
//!
//! Coordinates are the tool centre point in the work offset's frame, mm after units. A program
//! may start anywhere: the path starts where the first move starts. An axis the program has not
//! given an absolute value before its first move takes the value of its first absolute word
//! (CAM writes `G0 X30 Y0` then `G0 Z5`: the path starts at X30 Y0 Z5), noted; an incremental
//! move or an arc on an axis not yet known is an error. Zero-length moves add no point.
//! The tool axis of a 3-axis program is +Z of the work offset.
//!
//! Bounds: [`MAX_TEXT_BYTES`] of text, [`MAX_LINE_CHARS`] per line,
//! [`ReadOptions::max_points`] points, coordinates within ±[`ReadOptions::max_coordinate_mm`]
//! (default [`MAX_COORDINATE_MM`]), feeds within [`MIN_FEED_MM_MIN`] ..=
//! [`ReadOptions::max_feed_mm_min`] (default [`MAX_FEED_MM_MIN`]) mm/min.
//!
//! [`read`] reads a whole program into a [`GcodeProgram`]; [`LineReader`] reads one line at a time
//! and hands each line's move out as it is read, keeping nothing but the modal state (the
//! programs deflex writes, read back by [`crate::program::readback`], may be too long to hold).
//!
//! ```
//! let program = deflex_cam::gcode::read(
//!     "%\nO1000 (RING)\nG17 G21 G40 G90 G54\nT1 M6\nG0 X10 Y0\nG0 Z2\nG1 Z0 F300\nG3 X10 Y0 I-10 J0\nM30\n%\n",
//!     &deflex_cam::gcode::ReadOptions::default(),
//! )
//! .unwrap();
//! assert_eq!(program.work_offset, Some(deflex_cam::gcode::WorkOffset::G54));
//! assert_eq!(program.points[0].p_mm, [10.0, 0.0, 2.0]);
//! assert!(program.notes.iter().any(|n| n.word == "T1"));
//! ```

#![warn(missing_docs)]

pub mod arc;
mod error;
mod interpreter;
pub mod words;

pub use error::{GcodeError, GcodeErrorKind, Note, NoteKind};
pub use interpreter::{LineMove, LineReader};

/// Largest program read (bytes).
pub const MAX_TEXT_BYTES: usize = 256 << 20;
/// Longest line (characters).
pub const MAX_LINE_CHARS: usize = 4096;
/// Largest |coordinate| (mm, after units).
pub const MAX_COORDINATE_MM: f64 = 10_000.0;
/// Slowest feed (mm/min): 0.01 mm/s.
pub const MIN_FEED_MM_MIN: f64 = 0.6;
/// Fastest feed (mm/min): 1 m/s.
pub const MAX_FEED_MM_MIN: f64 = 60_000.0;
/// Widest coordinate bound [`ReadOptions::max_coordinate_mm`] may set (mm): 100 m, the bound of
/// the programs deflex writes ([`crate::program`]).
pub const MAX_COORDINATE_BOUND_MM: f64 = 100_000.0;
/// Highest feed bound [`ReadOptions::max_feed_mm_min`] may set (mm/min): 2 m/s, the fastest
/// speed of the programs deflex writes ([`crate::program`]).
pub const MAX_FEED_BOUND_MM_MIN: f64 = 120_000.0;

/// Settings of [`read`].
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ReadOptions {
    /// Largest distance of an interpolated chord from its arc (mm), 1e-4 ..= 1.
    pub chord_tolerance_mm: f64,
    /// Most path points (arcs included), 2 ..= 10 000 000.
    pub max_points: usize,
    /// Largest |coordinate| of a move or an arc centre (mm, after units), 1 ..=
    /// [`MAX_COORDINATE_BOUND_MM`].
    pub max_coordinate_mm: f64,
    /// Fastest feed (mm/min), [`MIN_FEED_MM_MIN`] ..= [`MAX_FEED_BOUND_MM_MIN`].
    pub max_feed_mm_min: f64,
}

impl Default for ReadOptions {
    /// 5 µm chords (a tenth of a forming tool's scallop), at most a million points, coordinates
    /// within ±[`MAX_COORDINATE_MM`], feeds up to [`MAX_FEED_MM_MIN`].
    fn default() -> Self {
        ReadOptions {
            chord_tolerance_mm: 0.005,
            max_points: 1_000_000,
            max_coordinate_mm: MAX_COORDINATE_MM,
            max_feed_mm_min: MAX_FEED_MM_MIN,
        }
    }
}

/// The arc plane.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Plane {
    /// `G17`: X, Y; normal Z.
    Xy,
    /// `G18`: Z, X; normal Y.
    Zx,
    /// `G19`: Y, Z; normal X.
    Yz,
}

impl Plane {
    /// Indices of the plane's first and second axis and of its normal (right-handed).
    pub fn axes(self) -> (usize, usize, usize) {
        match self {
            Plane::Xy => (0, 1, 2),
            Plane::Zx => (2, 0, 1),
            Plane::Yz => (1, 2, 0),
        }
    }

    /// `G17`, `G18`, `G19`.
    pub fn code(self) -> &'static str {
        match self {
            Plane::Xy => "G17",
            Plane::Zx => "G18",
            Plane::Yz => "G19",
        }
    }
}

/// A work offset: the part frame the program is written in, taught on the machine (on a
/// robot: the base / work object / frame of the part).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum WorkOffset {
    /// `G54`.
    G54,
    /// `G55`.
    G55,
    /// `G56`.
    G56,
    /// `G57`.
    G57,
    /// `G58`.
    G58,
    /// `G59`.
    G59,
}

impl WorkOffset {
    /// All, in order.
    pub const ALL: [WorkOffset; 6] = [
        WorkOffset::G54,
        WorkOffset::G55,
        WorkOffset::G56,
        WorkOffset::G57,
        WorkOffset::G58,
        WorkOffset::G59,
    ];

    /// `G54` … `G59`.
    pub fn name(self) -> &'static str {
        match self {
            WorkOffset::G54 => "G54",
            WorkOffset::G55 => "G55",
            WorkOffset::G56 => "G56",
            WorkOffset::G57 => "G57",
            WorkOffset::G58 => "G58",
            WorkOffset::G59 => "G59",
        }
    }

    /// 1 for `G54` … 6 for `G59` (the controller's work-offset number).
    pub fn number(self) -> u32 {
        WorkOffset::ALL.iter().position(|w| *w == self).unwrap_or(0) as u32 + 1
    }
}

/// What a move does.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum MoveKind {
    /// `G0`: rapid.
    Rapid,
    /// `G1`: straight at the feed.
    Linear,
    /// `G2`/`G3`: an arc (helical when the normal coordinate changes).
    Arc {
        /// Centre (mm; its normal coordinate is the start's).
        center_mm: [f64; 3],
        /// The plane.
        plane: Plane,
        /// `G3` (counter-clockwise about the plane's normal) or `G2`.
        counter_clockwise: bool,
        /// Signed sweep (rad; positive counter-clockwise), full turns included.
        sweep_rad: f64,
    },
}

/// One move of the program (the typed path).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Move {
    /// 1-based line.
    pub line: usize,
    /// Rapid, linear or arc.
    pub kind: MoveKind,
    /// Start (mm).
    pub start_mm: [f64; 3],
    /// End (mm).
    pub end_mm: [f64; 3],
    /// Feed (mm/s); `None` for a rapid.
    pub feed_mm_s: Option<f64>,
    /// Index in [`GcodeProgram::points`] of the move's last point.
    pub last_point: usize,
}

/// One point of the interpolated path.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct GcodePoint {
    /// Tool centre point (mm, work offset frame).
    pub p_mm: [f64; 3],
    /// Feed of the move ending here (mm/s); `None`: a rapid, and the first point.
    pub feed_mm_s: Option<f64>,
    /// 1-based line of the move (of the first move for the first point).
    pub line: usize,
}

/// A program read.
#[derive(Clone, Debug, PartialEq)]
pub struct GcodeProgram {
    /// The `O` number, if any.
    pub number: Option<u32>,
    /// The work offset the moves are written in, if the program names one.
    pub work_offset: Option<WorkOffset>,
    /// The moves, in order.
    pub moves: Vec<Move>,
    /// The path: the start of the first move, then the end of every move, arcs interpolated.
    pub points: Vec<GcodePoint>,
    /// What was ignored or assumed.
    pub notes: Vec<Note>,
    /// The chord tolerance used (mm).
    pub chord_tolerance_mm: f64,
}

impl GcodeProgram {
    /// Length of the path (mm).
    pub fn length_mm(&self) -> f64 {
        self.points
            .windows(2)
            .map(|w| {
                let d: [f64; 3] = std::array::from_fn(|i| w[1].p_mm[i] - w[0].p_mm[i]);
                (d[0] * d[0] + d[1] * d[1] + d[2] * d[2]).sqrt()
            })
            .sum()
    }
}

/// Read a program (see the crate documentation).
pub fn read(text: &str, options: &ReadOptions) -> Result<GcodeProgram, GcodeError> {
    interpreter::read(text, options)
}
