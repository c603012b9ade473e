//! What the reader refuses, and what it notes without refusing.

use thiserror::Error;

/// Why a program is refused. Every variant is carried by a [`GcodeError`], which adds the line,
/// the column and the word.
#[derive(Clone, Debug, Error, PartialEq)]
pub enum GcodeErrorKind {
    /// The text is larger than [`crate::gcode::MAX_TEXT_BYTES`] or a line longer than
    /// [`crate::gcode::MAX_LINE_CHARS`].
    #[error("{what} is {size}, more than {max}")]
    TooLarge {
        /// `the program` or `the line`.
        what: &'static str,
        /// Its size (bytes or characters).
        size: usize,
        /// The bound.
        max: usize,
    },
    /// Not a letter followed by a number.
    #[error("expected a letter followed by a number")]
    Syntax,
    /// A word's number is not a finite number.
    #[error("expected a number after the letter")]
    BadNumber,
    /// `(` without `)` or the other way round.
    #[error("unbalanced comment parentheses")]
    Comment,
    /// A G or M code outside the supported subset, with what to do instead.
    #[error("unsupported: {reason}")]
    Unsupported {
        /// What it is and why deflex does not take it.
        reason: &'static str,
    },
    /// Tool length or radius compensation (G41/G42/G43/G44, H, D): the path must be the tool
    /// centre point itself.
    #[error(
        "tool {which} compensation is refused: write the program for the tool centre point (the \
         ball centre) with compensation off (G40, G49); the robot's TCP is the tool's centre"
    )]
    ToolCompensation {
        /// `radius` or `length`.
        which: &'static str,
    },
    /// Two words of the same modal group, or the same axis twice, on one line.
    #[error("conflicts with {other} on the same line")]
    Conflict {
        /// The word it conflicts with.
        other: String,
    },
    /// A word that needs another one (I/J/K or R without G2/G3, P without G4/G2/G3, …).
    #[error("{message}")]
    Missing {
        /// What is missing.
        message: &'static str,
    },
    /// A coordinate beyond [`crate::gcode::ReadOptions::max_coordinate_mm`] (default
    /// [`crate::gcode::MAX_COORDINATE_MM`]) of the work offset's origin.
    #[error("{value:.3} mm is beyond ±{max} mm of the work offset's origin")]
    Coordinate {
        /// The coordinate (mm).
        value: f64,
        /// The bound (mm).
        max: f64,
    },
    /// A feed outside [`crate::gcode::MIN_FEED_MM_MIN`] ..=
    /// [`crate::gcode::ReadOptions::max_feed_mm_min`] (default [`crate::gcode::MAX_FEED_MM_MIN`]).
    #[error("feed {value} mm/min is outside {min} ..= {max} mm/min")]
    Feed {
        /// The feed (mm/min).
        value: f64,
        /// Lower bound.
        min: f64,
        /// Upper bound.
        max: f64,
    },
    /// A feed move before any F word.
    #[error("a feed move before any F word: set the feed first")]
    NoFeed,
    /// An incremental move or an arc before the position on that axis is known.
    #[error(
        "the position on {axis} is not known yet (no absolute {axis} word before): start the \
         program with an absolute move (G90) to X, Y and Z"
    )]
    UnknownPosition {
        /// The axis letter.
        axis: char,
    },
    /// An arc whose geometry does not close.
    #[error(transparent)]
    Arc(#[from] crate::gcode::arc::ArcError),
    /// A `P` (turns) word that is not a whole number within bounds.
    #[error(
        "P (turns) must be a whole number 1 ..= {}",
        crate::gcode::arc::MAX_TURNS
    )]
    Turns,
    /// A second work offset in one program.
    #[error(
        "a second work offset ({second}) after {first}: deflex places one part frame per \
         program; split the program at the change"
    )]
    SecondWorkOffset {
        /// The first one.
        first: &'static str,
        /// The new one.
        second: &'static str,
    },
    /// More path points than [`crate::gcode::ReadOptions::max_points`].
    #[error("more than {max} path points (arcs are interpolated to the chord tolerance)")]
    TooManyPoints {
        /// The bound.
        max: usize,
    },
    /// No move at all.
    #[error("no move in the program")]
    NoMove,
    /// A read option out of its range.
    #[error("read option {option}: expected {expected}, got {value}")]
    Option {
        /// The option.
        option: &'static str,
        /// The range.
        expected: &'static str,
        /// The value.
        value: f64,
    },
}

/// A refused program: where (1-based line and column of the word, 0 when it is the whole
/// program) and which word, and why ([`GcodeErrorKind`]).
#[derive(Clone, Debug, Error, PartialEq)]
#[error("line {line}, column {column}, `{word}`: {kind}")]
pub struct GcodeError {
    /// 1-based line (0: the whole program).
    pub line: usize,
    /// 1-based column of the word's letter (0: the whole line).
    pub column: usize,
    /// The word as written (or a short excerpt of the line).
    pub word: String,
    /// Why.
    pub kind: GcodeErrorKind,
}

/// What the reader did with a word it does not turn into motion: noted, never silently.
#[derive(Clone, Debug, PartialEq)]
pub enum NoteKind {
    /// A tool number or a tool change (`T1`, `M6`): the robot's tool is the model's.
    ToolIgnored,
    /// Spindle speed or direction (`S`, `M3`, `M4`, `M5`).
    SpindleIgnored,
    /// Coolant (`M7`, `M8`, `M9`).
    CoolantIgnored,
    /// Another M code that does not move the tool (`M0`, `M1`, `M2`/`M30` are the program end).
    MCodeIgnored,
    /// A dwell (`G4`): the path does not stop.
    DwellIgnored,
    /// A return to the machine's home (`G28`, `G30`): a robot path ends with its own retract.
    HomeIgnored,
    /// Modal settings that do not change the path (`G40`, `G49`, `G80`, `G94`, `G61`, `G64`,
    /// `G90.1`/`G91.1` are applied).
    SettingIgnored,
    /// A block-delete slash: the line is executed (block delete off).
    BlockDeleteExecuted,
    /// The program end (`M2`, `M30`, a closing `%`): what follows is not read.
    ProgramEnd,
    /// An axis never given an absolute value before the first move took the value of its
    /// first absolute word (or 0, the work offset's origin, if it has none).
    StartAxisFilled {
        /// The axis.
        axis: char,
        /// The value used (mm).
        value_mm: f64,
    },
}

impl std::fmt::Display for NoteKind {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            NoteKind::ToolIgnored => {
                write!(
                    f,
                    "tool word ignored: the TCP is the compensation's tool (its tool line)"
                )
            }
            NoteKind::SpindleIgnored => write!(f, "spindle word ignored"),
            NoteKind::CoolantIgnored => write!(f, "coolant word ignored"),
            NoteKind::MCodeIgnored => write!(f, "M code ignored (no motion)"),
            NoteKind::DwellIgnored => write!(f, "dwell ignored: the path does not stop"),
            NoteKind::HomeIgnored => write!(
                f,
                "machine home return ignored: the robot program ends with its own retract"
            ),
            NoteKind::SettingIgnored => write!(f, "setting without effect on the path"),
            NoteKind::BlockDeleteExecuted => {
                write!(f, "block delete `/`: the line is executed")
            }
            NoteKind::ProgramEnd => write!(f, "program end: the rest is not read"),
            NoteKind::StartAxisFilled { axis, value_mm } => write!(
                f,
                "{axis} not given before the first move: the start takes {axis}{value_mm}"
            ),
        }
    }
}

/// A diagnostic that does not refuse the program.
#[derive(Clone, Debug, PartialEq)]
pub struct Note {
    /// 1-based line.
    pub line: usize,
    /// The word (`T1`, `M6`, …).
    pub word: String,
    /// What was done with it.
    pub kind: NoteKind,
}

impl std::fmt::Display for Note {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(f, "line {}, `{}`: {}", self.line, self.word, self.kind)
    }
}
