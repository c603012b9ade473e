//! The modal state machine: words of a line → settings, then at most one motion. [`crate::gcode::read`]
//! keeps the path; [`LineReader`] hands each line's move out and keeps nothing but the state.

use crate::gcode::arc;
use crate::gcode::error::{GcodeError, GcodeErrorKind as K, Note, NoteKind};
use crate::gcode::words::{Word, split};
use crate::gcode::{
    GcodePoint, GcodeProgram, MAX_COORDINATE_BOUND_MM, MAX_FEED_BOUND_MM_MIN, MAX_LINE_CHARS,
    MAX_TEXT_BYTES, MIN_FEED_MM_MIN, Move, MoveKind, Plane, ReadOptions, WorkOffset,
};

/// Modal motion.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum Motion {
    Rapid,
    Linear,
    Cw,
    Ccw,
}

/// A move as recorded: line, kind, start (maybe not known yet), end, feed, index of its last
/// point.
type RawMove = (
    usize,
    MoveKind,
    [Option<f64>; 3],
    [f64; 3],
    Option<f64>,
    usize,
);

/// A point whose coordinates may not be known yet (before the first absolute word of an axis).
#[derive(Clone, Copy, Debug)]
struct RawPoint {
    p: [Option<f64>; 3],
    feed_mm_s: Option<f64>,
    line: usize,
}

struct State {
    options: ReadOptions,
    motion: Option<Motion>,
    plane: Plane,
    scale: f64,
    absolute: bool,
    arc_center_absolute: bool,
    feed_mm_min: Option<f64>,
    position: [Option<f64>; 3],
    work_offset: Option<WorkOffset>,
    number: Option<u32>,
    /// Points of the path so far, kept in `points` or not.
    point_count: usize,
    /// Whether the points and moves are kept ([`crate::gcode::read`]) or only counted ([`LineReader`]).
    keep_path: bool,
    points: Vec<RawPoint>,
    moves: Vec<RawMove>,
    /// The move of the line being read, with its start and end as known so far.
    line_move: Option<LineMove>,
    notes: Vec<Note>,
    /// First absolute value of each axis (mm) and its line, for the start.
    first_value: [Option<(f64, usize)>; 3],
}

/// What one line asks for, gathered before anything is applied.
#[derive(Default)]
struct Block<'a> {
    motion: Option<(&'a Word, Motion)>,
    plane: Option<(&'a Word, Plane)>,
    units: Option<(&'a Word, f64)>,
    distance: Option<(&'a Word, bool)>,
    arc_distance: Option<(&'a Word, bool)>,
    work_offset: Option<(&'a Word, WorkOffset)>,
    dwell: Option<&'a Word>,
    home: Option<&'a Word>,
    end: Option<&'a Word>,
    axes: [Option<&'a Word>; 3],
    offsets: [Option<&'a Word>; 3],
    radius: Option<&'a Word>,
    turns: Option<&'a Word>,
    feed: Option<&'a Word>,
}

fn set<'a, T>(
    slot: &mut Option<(&'a Word, T)>,
    word: &'a Word,
    value: T,
    line: usize,
) -> Result<(), GcodeError> {
    if let Some((other, _)) = slot {
        return Err(word.error(
            line,
            K::Conflict {
                other: other.text.clone(),
            },
        ));
    }
    *slot = Some((word, value));
    Ok(())
}

fn set_word<'a>(
    slot: &mut Option<&'a Word>,
    word: &'a Word,
    line: usize,
) -> Result<(), GcodeError> {
    if let Some(other) = slot {
        return Err(word.error(
            line,
            K::Conflict {
                other: other.text.clone(),
            },
        ));
    }
    *slot = Some(word);
    Ok(())
}

const UNSUPPORTED_G: &str = "a G code outside deflex's subset (G0-G3, G4, G17-G21, G28/G30, G40, \
                             G49, G54-G59, G61/G64, G80, G90/G91, G90.1/G91.1, G94)";

impl State {
    fn note(&mut self, line: usize, word: &Word, kind: NoteKind) {
        // One note per word and kind is enough (a tool change per level would repeat).
        if self.notes.len() < 1000
            && !self
                .notes
                .iter()
                .any(|n| n.kind == kind && n.word == word.text)
        {
            self.notes.push(Note {
                line,
                word: word.text.clone(),
                kind,
            });
        }
    }

    /// Sort the words of a line into a block.
    fn block<'a>(&mut self, words: &'a [Word], line: usize) -> Result<Block<'a>, GcodeError> {
        let mut b = Block::default();
        for w in words {
            match w.letter {
                'N' => {}
                'O' => {
                    self.number = Some(w.value.abs().min(1e9) as u32);
                }
                'G' => self.g_word(&mut b, w, line)?,
                'M' => self.m_word(&mut b, w, line)?,
                'T' => self.note(line, w, NoteKind::ToolIgnored),
                'S' => self.note(line, w, NoteKind::SpindleIgnored),
                'H' | 'D' if w.value == 0.0 => {}
                'H' => return Err(w.error(line, K::ToolCompensation { which: "length" })),
                'D' => return Err(w.error(line, K::ToolCompensation { which: "radius" })),
                'X' | 'Y' | 'Z' => {
                    let axis = (w.letter as u8 - b'X') as usize;
                    set_word(&mut b.axes[axis], w, line)?;
                }
                'I' | 'J' | 'K' => {
                    let axis = (w.letter as u8 - b'I') as usize;
                    set_word(&mut b.offsets[axis], w, line)?;
                }
                'R' => set_word(&mut b.radius, w, line)?,
                'P' => set_word(&mut b.turns, w, line)?,
                'F' => set_word(&mut b.feed, w, line)?,
                'A' | 'B' | 'C' | 'U' | 'V' | 'W' => {
                    return Err(w.error(
                        line,
                        K::Unsupported {
                            reason: "rotary or extra axes: deflex reads 3-axis programs (X Y Z)",
                        },
                    ));
                }
                _ => {
                    return Err(w.error(
                        line,
                        K::Unsupported {
                            reason: "a word outside deflex's subset (N O G M T S F X Y Z I J K R P)",
                        },
                    ));
                }
            }
        }
        Ok(b)
    }

    fn g_word<'a>(
        &mut self,
        b: &mut Block<'a>,
        w: &'a Word,
        line: usize,
    ) -> Result<(), GcodeError> {
        let unsupported = |reason| Err(w.error(line, K::Unsupported { reason }));
        let Some(code) = w.code10() else {
            return unsupported(UNSUPPORTED_G);
        };
        match code {
            0 => set(&mut b.motion, w, Motion::Rapid, line),
            10 => set(&mut b.motion, w, Motion::Linear, line),
            20 => set(&mut b.motion, w, Motion::Cw, line),
            30 => set(&mut b.motion, w, Motion::Ccw, line),
            40 => set_word(&mut b.dwell, w, line),
            170 => set(&mut b.plane, w, Plane::Xy, line),
            180 => set(&mut b.plane, w, Plane::Zx, line),
            190 => set(&mut b.plane, w, Plane::Yz, line),
            200 => set(&mut b.units, w, 25.4, line),
            210 => set(&mut b.units, w, 1.0, line),
            280 | 300 => set_word(&mut b.home, w, line),
            400 | 490 | 800 | 940 => Ok(()),
            610 | 640 => {
                self.note(line, w, NoteKind::SettingIgnored);
                Ok(())
            }
            410 | 420 => Err(w.error(line, K::ToolCompensation { which: "radius" })),
            430 | 434 | 440 => Err(w.error(line, K::ToolCompensation { which: "length" })),
            540..=590 if code % 10 == 0 => {
                let offset = WorkOffset::ALL[((code - 540) / 10) as usize];
                set(&mut b.work_offset, w, offset, line)
            }
            900 => set(&mut b.distance, w, true, line),
            910 => set(&mut b.distance, w, false, line),
            901 => set(&mut b.arc_distance, w, true, line),
            911 => set(&mut b.arc_distance, w, false, line),
            530 => unsupported("G53 (machine coordinates): write the program in a work offset"),
            100 | 920 => unsupported(
                "G10/G92 (setting a coordinate system in the program): teach the part frame instead",
            ),
            541 => unsupported("G54.1 (extended work offsets): use G54-G59"),
            810..=890 => unsupported("canned cycles (G81-G89): let the CAM system write them out"),
            930 | 950 => unsupported("inverse-time or per-revolution feed: use G94 (per minute)"),
            150 | 160 => unsupported("polar coordinates (G15/G16)"),
            680 | 690 | 510 | 500 => unsupported("coordinate rotation or scaling (G68/G51)"),
            _ => unsupported(UNSUPPORTED_G),
        }
    }

    fn m_word<'a>(
        &mut self,
        b: &mut Block<'a>,
        w: &'a Word,
        line: usize,
    ) -> Result<(), GcodeError> {
        match w.code10() {
            Some(20) | Some(300) => set_word(&mut b.end, w, line),
            Some(30) | Some(40) | Some(50) => {
                self.note(line, w, NoteKind::SpindleIgnored);
                Ok(())
            }
            Some(60) => {
                self.note(line, w, NoteKind::ToolIgnored);
                Ok(())
            }
            Some(70) | Some(80) | Some(90) => {
                self.note(line, w, NoteKind::CoolantIgnored);
                Ok(())
            }
            Some(980) | Some(990) => Err(w.error(
                line,
                K::Unsupported {
                    reason: "subprograms (M98/M99): let the CAM system write the program out",
                },
            )),
            _ => {
                self.note(line, w, NoteKind::MCodeIgnored);
                Ok(())
            }
        }
    }

    /// A coordinate in mm, checked.
    fn coordinate(
        &self,
        w: &Word,
        line: usize,
        base: Option<f64>,
        absolute: bool,
    ) -> Result<f64, GcodeError> {
        let v = w.value * self.scale;
        let value = if absolute {
            v
        } else {
            match base {
                Some(b) => b + v,
                None => {
                    let axis = w.letter;
                    return Err(w.error(line, K::UnknownPosition { axis }));
                }
            }
        };
        if value.abs() > self.options.max_coordinate_mm {
            return Err(w.error(
                line,
                K::Coordinate {
                    value,
                    max: self.options.max_coordinate_mm,
                },
            ));
        }
        Ok(value)
    }

    fn push_point(
        &mut self,
        p: [Option<f64>; 3],
        feed_mm_s: Option<f64>,
        line: usize,
        w: &Word,
    ) -> Result<(), GcodeError> {
        if self.point_count >= self.options.max_points {
            return Err(w.error(
                line,
                K::TooManyPoints {
                    max: self.options.max_points,
                },
            ));
        }
        if self.keep_path {
            self.points.push(RawPoint { p, feed_mm_s, line });
        }
        self.point_count += 1;
        Ok(())
    }

    /// Apply one line.
    fn line(&mut self, words: &[Word], line: usize) -> Result<bool, GcodeError> {
        let b = self.block(words, line)?;
        if let Some((_, scale)) = b.units {
            self.scale = scale;
        }
        if let Some((_, plane)) = b.plane {
            self.plane = plane;
        }
        if let Some((_, absolute)) = b.distance {
            self.absolute = absolute;
        }
        if let Some((_, absolute)) = b.arc_distance {
            self.arc_center_absolute = absolute;
        }
        if let Some((w, offset)) = b.work_offset {
            match self.work_offset {
                Some(first) if first != offset && self.point_count > 0 => {
                    return Err(w.error(
                        line,
                        K::SecondWorkOffset {
                            first: first.name(),
                            second: offset.name(),
                        },
                    ));
                }
                _ => self.work_offset = Some(offset),
            }
        }
        if let Some(w) = b.feed {
            let per_min = w.value * self.scale;
            if !(MIN_FEED_MM_MIN..=self.options.max_feed_mm_min).contains(&per_min) {
                return Err(w.error(
                    line,
                    K::Feed {
                        value: per_min,
                        min: MIN_FEED_MM_MIN,
                        max: self.options.max_feed_mm_min,
                    },
                ));
            }
            self.feed_mm_min = Some(per_min);
        }
        if let Some((_, motion)) = b.motion {
            self.motion = Some(motion);
        }
        let has_axes = b.axes.iter().any(Option::is_some);
        if let Some(w) = b.dwell {
            self.note(line, w, NoteKind::DwellIgnored);
            if b.motion.is_some() {
                return Err(w.error(
                    line,
                    K::Conflict {
                        other: b.motion.map(|(m, _)| m.text.clone()).unwrap_or_default(),
                    },
                ));
            }
            // G4 P… or G4 X…: the time, no motion.
        } else if let Some(w) = b.home {
            // G28/G30 with axis words: the intermediate point; nothing moves in the path.
            self.note(line, w, NoteKind::HomeIgnored);
        } else {
            let arc_words = b.offsets.iter().any(Option::is_some) || b.radius.is_some();
            let arc = matches!(self.motion, Some(Motion::Cw | Motion::Ccw));
            if arc_words && !arc {
                let w = b.offsets.iter().flatten().next().copied().or(b.radius);
                let w = w.expect("an arc word was found");
                return Err(w.error(
                    line,
                    K::Missing {
                        message: "I, J, K or R without an arc motion (G2/G3)",
                    },
                ));
            }
            if let Some(w) = b.turns
                && !arc
            {
                return Err(w.error(
                    line,
                    K::Missing {
                        message: "P without G2/G3 (turns) or G4 (dwell)",
                    },
                ));
            }
            if has_axes || (arc && arc_words) {
                self.motion_line(&b, line)?;
            }
        }
        if let Some(w) = b.end {
            self.note(line, w, NoteKind::ProgramEnd);
            return Ok(true);
        }
        Ok(false)
    }

    /// Execute the motion of a line with axis (or arc) words.
    fn motion_line(&mut self, b: &Block, line: usize) -> Result<(), GcodeError> {
        let first_word = b
            .axes
            .iter()
            .chain(b.offsets.iter())
            .flatten()
            .next()
            .copied()
            .or(b.radius)
            .expect("a motion line has an axis or arc word");
        let Some(motion) = self.motion else {
            return Err(first_word.error(
                line,
                K::Missing {
                    message: "coordinates without a motion mode: give G0, G1, G2 or G3 first",
                },
            ));
        };
        let mut target = self.position;
        for (axis, word) in b.axes.iter().enumerate() {
            if let Some(w) = *word {
                let v = self.coordinate(w, line, self.position[axis], self.absolute)?;
                if self.absolute && self.first_value[axis].is_none() {
                    self.first_value[axis] = Some((v, line));
                }
                target[axis] = Some(v);
            }
        }
        let feed_mm_s = match motion {
            Motion::Rapid => None,
            _ => Some(
                self.feed_mm_min
                    .ok_or_else(|| first_word.error(line, K::NoFeed))?
                    / 60.0,
            ),
        };
        let start = self.position;
        if self.point_count == 0 {
            self.push_point(start, None, line, first_word)?;
        }
        let kind = match motion {
            Motion::Rapid | Motion::Linear => {
                let moved = (0..3).any(|a| match (start[a], target[a]) {
                    (Some(s), Some(t)) => (t - s).abs() > 1e-9,
                    (None, Some(_)) => false,
                    _ => false,
                });
                if moved {
                    self.push_point(target, feed_mm_s, line, first_word)?;
                }
                if motion == Motion::Rapid {
                    MoveKind::Rapid
                } else {
                    MoveKind::Linear
                }
            }
            Motion::Cw | Motion::Ccw => self.arc(
                b,
                line,
                first_word,
                start,
                target,
                feed_mm_s,
                motion == Motion::Ccw,
            )?,
        };
        let end: [f64; 3] = std::array::from_fn(|a| target[a].unwrap_or(f64::NAN));
        let last = self.point_count - 1;
        if self.keep_path {
            self.moves.push((line, kind, start, end, feed_mm_s, last));
        }
        self.line_move = Some(LineMove {
            line,
            kind,
            start_mm: start,
            end_mm: target,
            feed_mm_s,
        });
        self.position = target;
        Ok(())
    }

    #[allow(clippy::too_many_arguments)]
    fn arc(
        &mut self,
        b: &Block,
        line: usize,
        first_word: &Word,
        start: [Option<f64>; 3],
        target: [Option<f64>; 3],
        feed_mm_s: Option<f64>,
        ccw: bool,
    ) -> Result<MoveKind, GcodeError> {
        let known = |p: [Option<f64>; 3]| -> Result<[f64; 3], GcodeError> {
            let mut out = [0.0; 3];
            for a in 0..3 {
                out[a] = p[a].ok_or_else(|| {
                    first_word.error(
                        line,
                        K::UnknownPosition {
                            axis: ['X', 'Y', 'Z'][a],
                        },
                    )
                })?;
            }
            Ok(out)
        };
        let (s, e) = (known(start)?, known(target)?);
        let (a1, a2, normal) = self.plane.axes();
        let arc_error = |error: arc::ArcError| first_word.error(line, K::Arc(error));
        if let Some(w) = b.offsets[normal] {
            return Err(w.error(
                line,
                K::Missing {
                    message: "a centre offset along the plane's normal (K in G17, J in G18, I in G19)",
                },
            ));
        }
        let center = match (b.radius, b.offsets[a1].is_some() || b.offsets[a2].is_some()) {
            (Some(r), false) => {
                arc::center_from_radius(&s, &e, r.value * self.scale, self.plane, ccw)
                    .map_err(arc_error)?
            }
            (None, true) => {
                if self.arc_center_absolute && [a1, a2].iter().any(|a| b.offsets[*a].is_none()) {
                    return Err(first_word.error(
                        line,
                        K::Missing {
                            message: "G90.1 (absolute arc centres) needs both in-plane centre words",
                        },
                    ));
                }
                let mut c = s;
                for a in [a1, a2] {
                    let offset = b.offsets[a].map_or(0.0, |w| w.value * self.scale);
                    c[a] = if self.arc_center_absolute {
                        offset
                    } else {
                        s[a] + offset
                    };
                    if c[a].abs() > self.options.max_coordinate_mm {
                        return Err(arc_error(arc::ArcError::CentreOutOfRange {
                            centre_mm: c[a],
                            max_mm: self.options.max_coordinate_mm,
                        }));
                    }
                }
                c
            }
            (Some(r), true) => {
                return Err(r.error(
                    line,
                    K::Conflict {
                        other: "I/J/K".into(),
                    },
                ));
            }
            (None, false) => {
                return Err(first_word.error(
                    line,
                    K::Missing {
                        message: "an arc (G2/G3) needs I, J, K or R",
                    },
                ));
            }
        };
        let turns = match b.turns {
            None => 1,
            Some(w)
                if w.value.fract() == 0.0
                    && (1.0..=f64::from(arc::MAX_TURNS)).contains(&w.value) =>
            {
                w.value as u32
            }
            Some(w) => {
                return Err(w.error(line, K::Turns));
            }
        };
        let sweep = arc::sweep(&s, &e, &center, self.plane, ccw, turns).map_err(arc_error)?;
        let steps = arc::steps(&sweep, self.options.chord_tolerance_mm);
        let room = (self.options.max_points - self.point_count) as f64;
        if steps > room {
            return Err(first_word.error(
                line,
                K::TooManyPoints {
                    max: self.options.max_points,
                },
            ));
        }
        let n = steps as usize;
        for k in 1..=n {
            let p = arc::point(&sweep, &s, &e, &center, self.plane, k, n);
            self.push_point(p.map(Some), feed_mm_s, line, first_word)?;
        }
        Ok(MoveKind::Arc {
            center_mm: center,
            plane: self.plane,
            counter_clockwise: ccw,
            sweep_rad: sweep.sweep,
        })
    }
}

/// A move as [`LineReader`] hands it out: a [`Move`] before the program's start is resolved.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct LineMove {
    /// 1-based line.
    pub line: usize,
    /// Rapid, linear or arc.
    pub kind: MoveKind,
    /// Start (mm); an axis is `None` while the program has given it no value (before its first
    /// absolute word: [`crate::gcode::read`] fills it in at the end, a line reader cannot).
    pub start_mm: [Option<f64>; 3],
    /// End (mm); `None` as for the start.
    pub end_mm: [Option<f64>; 3],
    /// Feed (mm/s); `None` for a rapid.
    pub feed_mm_s: Option<f64>,
}

/// A program read one line at a time: each line's move is handed out as it is read, and nothing
/// is kept but the modal state and the notes (at most 1000), so a program of any length reads in
/// little memory. The same language, checks and errors as [`crate::gcode::read`], line for line;
/// [`ReadOptions::max_points`] counts the points the path would have. The caller bounds the text
/// ([`crate::gcode::MAX_TEXT_BYTES`] is [`crate::gcode::read`]'s bound); each line is checked
/// against [`MAX_LINE_CHARS`].
///
/// ```
/// use deflex_cam::gcode::{LineReader, MoveKind, ReadOptions};
/// let mut reader = LineReader::new(&ReadOptions::default()).unwrap();
/// let mut ends = Vec::new();
/// for line in "%\n( part )\nG21 G90 G54\nG0 X10 Y0 Z5\nG1 Z0 F300\nM30\n%\n".lines() {
///     if let Some(m) = reader.read_line(line).unwrap() {
///         ends.push((m.kind, m.end_mm, m.feed_mm_s));
///     }
/// }
/// assert_eq!(ends[1], (MoveKind::Linear, [Some(10.0), Some(0.0), Some(0.0)], Some(5.0)));
/// assert!(reader.ended());
/// ```
pub struct LineReader {
    state: State,
    /// 1-based number of the last line read.
    line: usize,
    percent_seen: bool,
    code_seen: bool,
    ended: bool,
}

impl LineReader {
    /// A reader with `options` (checked as [`crate::gcode::read`] checks them).
    pub fn new(options: &ReadOptions) -> Result<LineReader, GcodeError> {
        check_options(options)?;
        Ok(LineReader::start(options, false))
    }

    fn start(options: &ReadOptions, keep_path: bool) -> LineReader {
        LineReader {
            state: State {
                options: *options,
                motion: None,
                plane: Plane::Xy,
                scale: 1.0,
                absolute: true,
                arc_center_absolute: false,
                feed_mm_min: None,
                position: [None; 3],
                work_offset: None,
                number: None,
                point_count: 0,
                keep_path,
                points: Vec::new(),
                moves: Vec::new(),
                line_move: None,
                notes: Vec::new(),
                first_value: [None; 3],
            },
            line: 0,
            percent_seen: false,
            code_seen: false,
            ended: false,
        }
    }

    /// Read the next line (its text without the line break): the move it executes, if any.
    /// Once the program has ended (`M2`, `M30`, a closing `%`) every further line is ignored.
    pub fn read_line(&mut self, raw: &str) -> Result<Option<LineMove>, GcodeError> {
        if self.ended {
            return Ok(None);
        }
        self.line += 1;
        let line = self.line;
        let length = raw.chars().count();
        if length > MAX_LINE_CHARS {
            return Err(GcodeError {
                line,
                column: 0,
                word: raw.chars().take(24).collect(),
                kind: K::TooLarge {
                    what: "the line",
                    size: length,
                    max: MAX_LINE_CHARS,
                },
            });
        }
        let parsed = split(raw, line)?;
        if parsed.percent {
            if self.percent_seen || self.code_seen {
                if self.code_seen {
                    self.state.notes.push(Note {
                        line,
                        word: "%".into(),
                        kind: NoteKind::ProgramEnd,
                    });
                }
                self.ended = true;
                return Ok(None);
            }
            self.percent_seen = true;
            return Ok(None);
        }
        if parsed.words.is_empty() {
            return Ok(None);
        }
        self.code_seen = true;
        if parsed.block_delete {
            self.state
                .note(line, &parsed.words[0], NoteKind::BlockDeleteExecuted);
        }
        self.state.line_move = None;
        if self.state.line(&parsed.words, line)? {
            self.ended = true;
        }
        Ok(self.state.line_move.take())
    }

    /// Whether the program has ended (`M2`, `M30`, a closing `%`).
    pub fn ended(&self) -> bool {
        self.ended
    }

    /// What was ignored or assumed so far.
    pub fn notes(&self) -> &[Note] {
        &self.state.notes
    }
}

/// The options' bounds.
fn check_options(options: &ReadOptions) -> Result<(), GcodeError> {
    let whole = |kind| GcodeError {
        line: 0,
        column: 0,
        word: String::new(),
        kind,
    };
    if !(options.chord_tolerance_mm.is_finite()
        && (1e-4..=1.0).contains(&options.chord_tolerance_mm))
    {
        return Err(whole(K::Option {
            option: "chord_tolerance_mm",
            expected: "1e-4 ..= 1",
            value: options.chord_tolerance_mm,
        }));
    }
    if !(2..=10_000_000).contains(&options.max_points) {
        return Err(whole(K::Option {
            option: "max_points",
            expected: "2 ..= 10 000 000",
            value: options.max_points as f64,
        }));
    }
    if !(1.0..=MAX_COORDINATE_BOUND_MM).contains(&options.max_coordinate_mm) {
        return Err(whole(K::Option {
            option: "max_coordinate_mm",
            expected: "1 ..= 100 000",
            value: options.max_coordinate_mm,
        }));
    }
    if !(MIN_FEED_MM_MIN..=MAX_FEED_BOUND_MM_MIN).contains(&options.max_feed_mm_min) {
        return Err(whole(K::Option {
            option: "max_feed_mm_min",
            expected: "0.6 ..= 120 000",
            value: options.max_feed_mm_min,
        }));
    }
    Ok(())
}

/// See [`crate::gcode::read`].
pub(crate) fn read(text: &str, options: &ReadOptions) -> Result<GcodeProgram, GcodeError> {
    check_options(options)?;
    if text.len() > MAX_TEXT_BYTES {
        return Err(GcodeError {
            line: 0,
            column: 0,
            word: String::new(),
            kind: K::TooLarge {
                what: "the program",
                size: text.len(),
                max: MAX_TEXT_BYTES,
            },
        });
    }
    let mut reader = LineReader::start(options, true);
    for raw in text.lines() {
        reader.read_line(raw)?;
        if reader.ended {
            break;
        }
    }
    finish(reader.state)
}

/// Fill the start's unknown axes and build the program.
fn finish(mut state: State) -> Result<GcodeProgram, GcodeError> {
    if state.points.len() < 2 {
        return Err(GcodeError {
            line: 0,
            column: 0,
            word: String::new(),
            kind: K::NoMove,
        });
    }
    let first_line = state.points[0].line;
    let mut fill = [0.0; 3];
    for axis in 0..3 {
        let (value, from_line) = state.first_value[axis].unwrap_or((0.0, usize::MAX));
        fill[axis] = value;
        // Noted when the value comes from a later line than the first move (or from nowhere).
        if state.points[0].p[axis].is_none() && from_line > first_line {
            state.notes.push(Note {
                line: first_line,
                word: ['X', 'Y', 'Z'][axis].to_string(),
                kind: NoteKind::StartAxisFilled {
                    axis: ['X', 'Y', 'Z'][axis],
                    value_mm: value,
                },
            });
        }
    }
    let resolve =
        |p: [Option<f64>; 3]| -> [f64; 3] { std::array::from_fn(|a| p[a].unwrap_or(fill[a])) };
    let mut points: Vec<GcodePoint> = Vec::with_capacity(state.points.len());
    for raw in &state.points {
        points.push(GcodePoint {
            p_mm: resolve(raw.p),
            feed_mm_s: if points.is_empty() {
                None
            } else {
                raw.feed_mm_s
            },
            line: raw.line,
        });
    }
    // Points that only filled an unknown axis are the same place: drop the repeats (the path's
    // moves are never zero-length).
    let mut keep: Vec<usize> = Vec::with_capacity(points.len());
    let mut dedup: Vec<GcodePoint> = Vec::with_capacity(points.len());
    for p in points {
        if let Some(last) = dedup.last()
            && (0..3).all(|a| (last.p_mm[a] - p.p_mm[a]).abs() <= 1e-9)
        {
            keep.push(dedup.len() - 1);
            continue;
        }
        keep.push(dedup.len());
        dedup.push(p);
    }
    if dedup.len() < 2 {
        return Err(GcodeError {
            line: first_line,
            column: 0,
            word: String::new(),
            kind: K::NoMove,
        });
    }
    let moves = state
        .moves
        .iter()
        .map(|&(line, kind, start, end, feed_mm_s, last)| Move {
            line,
            kind,
            start_mm: resolve(start),
            end_mm: std::array::from_fn(|a| if end[a].is_nan() { fill[a] } else { end[a] }),
            feed_mm_s,
            last_point: keep[last],
        })
        .collect();
    Ok(GcodeProgram {
        number: state.number,
        work_offset: state.work_offset,
        moves,
        points: dedup,
        notes: state.notes,
        chord_tolerance_mm: state.options.chord_tolerance_mm,
    })
}
