//! FANUC TP (R-30iA / R-30iB / R-30iB Plus) in its ASCII form: `NAME.ls`.
//!
//! ```text
//! (tabs shown as spaces)
//! /PROG  DEFLEX_PATH
//! /ATTR
//! OWNER        = MNEDITOR;
//! COMMENT        = "deflex";
//! …                                   (PROG_SIZE, FILE_NAME, VERSION, LINE_COUNT, PROTECT, TCD)
//! DEFAULT_GROUP    = 1,*,*,*,*;
//! CONTROL_CODE    = 00000000 00000000;
//! /MN
//!    1:  ! header: the path, what to set ;
//!    …
//!   12:  UFRAME_NUM=1 ;
//!   13:  UTOOL_NUM=1 ;
//!   14:J P[1] 20% FINE ;                    clearance point above the start
//!   15:L P[2] 10mm/sec FINE ;               approach
//!   16:L P[3] 10mm/sec CNT100 ;             the path   (or CALL DEFLEX_PATH_P01 ; … when split)
//!    …
//!   99:L P[87] 10mm/sec FINE ;              retract
//! /POS
//! P[1]{
//!    GP1:
//!     UF : 1, UT : 1,        CONFIG : 'N U T, 0, 0, 0',
//!     X =    20.0000  mm,    Y =     0.0000  mm,    Z =    35.0000  mm,
//!     W =   180.000000 deg,    P =     0.000000 deg,    R =     0.000000 deg
//! };
//! …
//! /END
//! ```
//!
//! * Positions in mm in the user frame `UFRAME_NUM` ([`crate::program::settings::FanucSettings`];
//!   0, the world frame, with `coordinates = "robot"`, which assumes world = robot base), the
//!   tool `UTOOL_NUM`; orientation W-P-R in degrees, fixed-axis rotations about X, Y, Z
//!   (`Rz(R)·Ry(P)·Rx(W)`, [`deflex_model::conventions::fanuc_wpr_deg`]). Positions are
//!   printed to 0.1 µm and angles to 1e-6° (the controller stores single-precision reals,
//!   ~0.06 µm at 1 m).
//! * `CONFIG : 'F U T, t1, t4, t6'`: flip `F` when J5 < 0 (else `N`), `U` (elbow up) when the
//!   elbow is at or beyond its stretched value (the branch KUKA's Status bit 1 reports, set in
//!   the usual elbow-up pose), else `D`; `T` (front) when the wrist centre is in front of
//!   axis 1, else `B`; turn numbers of J1, J4, J6 `floor((q + 180°) / 360°)` (0 within
//!   −180° … 180°). Without configurations from the caller: `'N U T, 0, 0, 0'`.
//! * Speeds: `L … n mm/sec` takes whole mm/s (FANUC's speed field is an integer), so path speeds
//!   are rounded to 1 mm/s (at least 1); the joint move runs at `fanuc.joint_percent` %.
//!   Termination `CNTn` (`fanuc.cnt`) at inner path points; `FINE` at the clearance points, the
//!   first (approach) and last path point and rapids.
//! * A long path is split into parts of at most [`MAX_POINTS_PER_PART`] path points (or
//!   `program.max_points_per_part` when lower): `NAME_P01.ls` … each a TP program with its own
//!   `/POS` (positions renumbered from 1), called in order from the main program
//!   (`CALL NAME_P01 ;`), which holds the joint move, the approach and the retract.
//! * Comments (`! … ;`) are wrapped to [`COMMENT_CHARS`] characters, the `COMMENT` attribute
//!   holds at most 16; the header says what the user must set: the user frame, the tool frame,
//!   the payload schedule, and that an `.ls` file loads only with the controller's ASCII upload
//!   option (or after conversion to `.tp`, e.g. with ROBOGUIDE's `maketp`).

use crate::program::ProgramInput;
use crate::program::common::{Checked, comment_text, header_texts, num, wrap};
use crate::program::config::fanuc_config;
use crate::program::error::ProgramError;
use crate::program::names::{FANUC, sanitize};
use crate::program::plan::{Plan, part_name, plan_within};
use crate::program::settings::{Coordinates, ProgramSettings};
use crate::program::sink::{ProgramSink, emit};
use deflex_model::Pose;
use deflex_model::conventions::fanuc_wpr_deg;
use std::fmt::Write as _;

const FORMAT: &str = "FANUC TP";

/// Most path points in one TP program: a part stays far below the controllers' limits (TP
/// line numbers and position numbers go to 9999 — RoboDK's FANUC post-processor splits at
/// 9999 lines by default — and a program's positions take controller memory, ~100 bytes
/// each, out of a few MB for all TP programs).
pub const MAX_POINTS_PER_PART: usize = 2000;

/// Longest comment text in `/MN` (characters): older teach pendants show 32.
pub const COMMENT_CHARS: usize = 30;

/// Length of one point's `/POS` record (bytes), for the part size.
const POSITION_BYTES: usize = 200;

/// One TP program being written: its `/MN` lines and `/POS` records.
struct Tp {
    name: String,
    comment: String,
    mn: Vec<String>,
    pos: String,
    count: usize,
    uframe: u32,
    utool: u32,
    previous: Option<[f64; 3]>,
}

impl Tp {
    fn new(name: String, comment: &str, settings: &ProgramSettings, uframe: u32) -> Tp {
        Tp {
            name,
            comment: comment_text(comment, &['"', ';'])
                .chars()
                .take(16)
                .collect(),
            mn: Vec::new(),
            pos: String::new(),
            count: 0,
            uframe,
            utool: settings.fanuc.utool,
            previous: None,
        }
    }

    fn comment(&mut self, text: &str) {
        // `;` ends a TP line: written as `,`. Word by word, so that a long paragraph is
        // wrapped, not cut at `comment_text`'s length.
        let text: Vec<String> = text
            .replace(';', ",")
            .split_whitespace()
            .map(|w| comment_text(w, &[';', '!']))
            .collect();
        for line in wrap(&text.join(" "), COMMENT_CHARS) {
            self.mn.push(format!("  ! {line} ;"));
        }
    }

    /// A motion to `p`: `J P[k] n% FINE ;` or `L P[k] v mm/sec FINE|CNTn ;`.
    fn motion(&mut self, p: &Checked, speed: &str, termination: &str) {
        self.count += 1;
        let k = self.count;
        let kind = if speed.ends_with('%') { 'J' } else { 'L' };
        self.mn
            .push(format!("{kind} P[{k}] {speed} {termination} ;"));
        let wpr = fanuc_wpr_deg(&p.rotation, self.previous);
        self.previous = Some(wpr);
        let _ = write!(
            self.pos,
            "P[{k}]{{\n   GP1:\n\tUF : {}, UT : {},\t\tCONFIG : '{}',\n\
             \tX = {:>12}  mm,\tY = {:>12}  mm,\tZ = {:>12}  mm,\n\
             \tW = {:>12} deg,\tP = {:>12} deg,\tR = {:>12} deg\n}};\n",
            self.uframe,
            self.utool,
            fanuc_config(p.config.as_ref()),
            num(p.position_mm.x, 4),
            num(p.position_mm.y, 4),
            num(p.position_mm.z, 4),
            num(wpr[0], 6),
            num(wpr[1], 6),
            num(wpr[2], 6)
        );
    }

    fn text(&self) -> String {
        let mut out = String::with_capacity(self.pos.len() + self.mn.len() * 48 + 1024);
        let _ = writeln!(out, "/PROG  {}", self.name);
        let _ = writeln!(out, "/ATTR");
        let _ = writeln!(out, "OWNER\t\t= MNEDITOR;");
        let _ = writeln!(out, "COMMENT\t\t= \"{}\";", self.comment);
        let _ = writeln!(out, "PROG_SIZE\t= 0;");
        let _ = writeln!(out, "FILE_NAME\t= ;");
        let _ = writeln!(out, "VERSION\t\t= 0;");
        let _ = writeln!(out, "LINE_COUNT\t= {};", self.mn.len());
        let _ = writeln!(out, "MEMORY_SIZE\t= 0;");
        let _ = writeln!(out, "PROTECT\t\t= READ_WRITE;");
        let _ = writeln!(out, "TCD:  STACK_SIZE\t= 0,");
        let _ = writeln!(out, "      TASK_PRIORITY\t= 50,");
        let _ = writeln!(out, "      TIME_SLICE\t= 0,");
        let _ = writeln!(out, "      BUSY_LAMP_OFF\t= 0,");
        let _ = writeln!(out, "      ABORT_REQUEST\t= 0,");
        let _ = writeln!(out, "      PAUSE_REQUEST\t= 0;");
        let _ = writeln!(out, "DEFAULT_GROUP\t= 1,*,*,*,*;");
        let _ = writeln!(out, "CONTROL_CODE\t= 00000000 00000000;");
        let _ = writeln!(out, "/MN");
        for (i, line) in self.mn.iter().enumerate() {
            let _ = writeln!(out, "{:>4}:{line}", i + 1);
        }
        let _ = writeln!(out, "/POS");
        out.push_str(&self.pos);
        let _ = writeln!(out, "/END");
        out
    }
}

/// `n mm/sec`: whole mm/s, at least 1.
fn speed_text(speed_mm_s: f64) -> String {
    format!("{}mm/sec", speed_mm_s.round().max(1.0))
}

/// Write the program to `sink`, each part file as soon as it is complete; returns the files,
/// the main program first.
pub(crate) fn export(
    input: &ProgramInput,
    settings: &ProgramSettings,
    sink: &mut dyn ProgramSink,
) -> Result<Vec<String>, ProgramError> {
    // FANUC's own part limit on top of the template's.
    let plan = plan_within(FORMAT, input, settings, POSITION_BYTES, MAX_POINTS_PER_PART)?;
    let name = sanitize(&settings.program.name, &FANUC).to_ascii_uppercase();
    // Part names add `_P01`: keep room for them.
    let name = if plan.split() && name.len() > FANUC.max_len - 4 {
        name[..FANUC.max_len - 4].to_string()
    } else {
        name
    };
    let f = &settings.fanuc;
    let uframe = if input.coordinates == Coordinates::Robot {
        0
    } else {
        f.uframe
    };
    let mut main = Tp::new(name.clone(), "deflex path", settings, uframe);
    write_header(&mut main, input, settings, &plan, uframe);
    main.mn.push(format!("  UFRAME_NUM={uframe} ;"));
    main.mn.push(format!("  UTOOL_NUM={} ;", f.utool));
    main.motion(&plan.clear[0], &format!("{}%", f.joint_percent), "FINE");
    main.comment("approach");
    let approach = speed_text(settings.program.approach_speed_mm_s);
    let first = plan.point(0);
    main.motion(&first, &approach, "FINE");
    let last = plan.len() - 1;
    let cnt = format!("CNT{}", f.cnt);
    let mut parts = Vec::new();
    for (part, range) in plan.parts.iter().enumerate() {
        let part_name = part_name(&name, part).to_ascii_uppercase();
        let mut tp = if plan.split() {
            main.mn.push(format!("  CALL {part_name} ;"));
            let mut tp = Tp::new(part_name.clone(), "deflex part", settings, uframe);
            tp.comment(&format!(
                "part {} of {} of {name}: path points {} to {}",
                part + 1,
                plan.parts.len(),
                range.start,
                range.end - 1
            ));
            tp.mn.push(format!("  UFRAME_NUM={uframe} ;"));
            tp.mn.push(format!("  UTOOL_NUM={} ;", f.utool));
            tp.previous = main.previous;
            Some(tp)
        } else {
            None
        };
        let body = tp.as_mut().unwrap_or(&mut main);
        for i in range.clone() {
            let p = plan.point(i);
            let termination = if i < last && !p.rapid {
                cnt.as_str()
            } else {
                "FINE"
            };
            // Rapids: a comment line before the motion.
            if p.rapid {
                body.comment("rapid");
            }
            body.motion(&p, &speed_text(p.speed_mm_s), termination);
        }
        if let Some(tp) = tp {
            main.previous = tp.previous;
            let path = format!("{part_name}.ls");
            emit(sink, FORMAT, &path, &tp.text())?;
            parts.push(path);
        }
    }
    main.comment("retract");
    main.motion(&plan.clear[1], &approach, "FINE");
    let path = format!("{name}.ls");
    emit(sink, FORMAT, &path, &main.text())?;
    Ok(std::iter::once(path).chain(parts).collect())
}

/// The header comments: the path, and what the user must set on the controller.
fn write_header(
    tp: &mut Tp,
    input: &ProgramInput,
    settings: &ProgramSettings,
    plan: &Plan<'_>,
    uframe: u32,
) {
    let f = &settings.fanuc;
    for line in header_texts(input) {
        tp.comment(&line);
    }
    tp.comment(
        "Load: an .ls file needs the controller's ASCII upload option, or convert it to .tp \
         (e.g. ROBOGUIDE maketp).",
    );
    tp.comment(&format!(
        "Set UTOOL {} to the model's TCP (mm, deg): {}",
        f.utool,
        pose_text(&input.tool_in_flange)
    ));
    let frame = if uframe == 0 {
        "UFRAME 0 (world) must be the robot base".to_string()
    } else {
        format!(
            "Set UFRAME {uframe} to the program frame{}",
            input
                .frame_name
                .as_ref()
                .map_or(String::new(), |n| format!(" ({n})"))
        )
    };
    tp.comment(&format!(
        "{frame} (mm, deg): {}",
        pose_text(&input.frame_in_robot)
    ));
    match &plan.tool_load_in_flange {
        Some(l) => tp.comment(&format!(
            "Select PAYLOAD[{}] with the tool load: {} kg at {}, {}, {} mm",
            f.payload,
            num(l.mass_kg, 3),
            num(l.centre_of_mass_m[0] * 1e3, 3),
            num(l.centre_of_mass_m[1] * 1e3, 3),
            num(l.centre_of_mass_m[2] * 1e3, 3)
        )),
        None => tp.comment(&format!(
            "Select PAYLOAD[{}] with the tool load (not known to deflex)",
            f.payload
        )),
    }
}

/// A pose as `X Y Z W P R` (mm, deg) for the header.
fn pose_text(pose: &Pose) -> String {
    let t = pose.translation.vector * 1e3;
    let wpr = fanuc_wpr_deg(&pose.rotation, None);
    format!(
        "X {} Y {} Z {} W {} P {} R {}",
        num(t.x, 4),
        num(t.y, 4),
        num(t.z, 4),
        num(wpr[0], 6),
        num(wpr[1], 6),
        num(wpr[2], 6)
    )
}
