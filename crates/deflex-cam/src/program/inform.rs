//! Yaskawa INFORM (DX100 / DX200 / YRC1000) job files: `NAME.JBI`.
//!
//! ```text
//! /JOB
//! //NAME DEFLEX_PATH
//! //POS
//! ///NPOS 23,0,0,0,0,0                 robot positions C, then BC, EC, P, BP, EX (unused: 0)
//! ///USER 1                            (no USER line with POSTYPE BASE)
//! ///TOOL 1
//! ///POSTYPE USER                      or BASE
//! ///RECTAN
//! ///RCONF 0,0,0,0,0,0,0,0             from the IK branch; repeated when it changes
//! C00000=20.0000,0.0000,35.0000,180.000000,0.000000,0.000000
//! …
//! //INST
//! ///DATE 2000/01/01 00:00
//! ///COMM deflex path
//! ///ATTR SC,RW
//! ///GROUP1 RB1
//! NOP
//! 'header: the path, what to set, how to load
//! MOVJ C00000 VJ=10.00                 clearance point above the start
//! MOVL C00001 V=10.0 PL=0              approach
//! MOVL C00002 V=10.0 PL=1              the path   (or CALL JOB:DEFLEX_PATH_P01 … when split)
//! …
//! MOVL C00022 V=10.0 PL=0              retract
//! END
//! ```
//!
//! * Positions `C00000=X,Y,Z,Rx,Ry,Rz` in mm in user frame `///USER n` (`///POSTYPE USER`,
//!   [`crate::program::settings::InformSettings`]) or in the robot base frame (`///POSTYPE
//!   BASE`, written with `coordinates = "robot"`), tool `///TOOL n`; orientation Rx, Ry, Rz in
//!   degrees, fixed-axis rotations about X, Y, Z (`Rz·Ry·Rx`,
//!   [`deflex_model::conventions::yaskawa_rxryrz_deg`]). Printed to 0.1 µm and 1e-6°, the
//!   precision of the other formats; the controller may round them when it loads the job.
//! * `///RCONF l,m,n,o,p,q,0,0` (flip, upper/lower arm, front/rear, R, T, S ≥ 180°) from the
//!   caller's configurations ([`crate::program::config::yaskawa_rconf`]), written before the
//!   first position and again whenever it changes; without configurations all 0.
//! * Speeds: `MOVL … V=v` in mm/s to 0.1 mm/s (at least 0.1), INFORM's default linear speed
//!   unit; the joint move `MOVJ … VJ=` at `inform.joint_percent` %. Position level `PL=n`
//!   (`inform.pl`) at inner path points; `PL=0` at the approach, the first and the last path
//!   point, rapids and the retract.
//! * A long path is split into jobs of at most [`MAX_POINTS_PER_PART`] path points (or
//!   `program.max_points_per_part` when lower): `NAME_P01.JBI` … each with its own positions
//!   (numbered from `C00000`), called in order from the main job (`CALL JOB:NAME_P01`), which
//!   holds the joint move, the approach and the retract.
//! * Comments (`'…`) hold at most [`COMMENT_CHARS`] characters; the header says what the user
//!   must set — the user frame and the tool file (values in the robot frame and the flange
//!   frame at 0.1 µm and 1e-6°), the tool's mass and centre of gravity — and how a `.JBI` is
//!   loaded (the pendant's external memory, `EX.MEMORY → LOAD → JOB`, from a CF/SD card or USB
//!   memory — the FD/PC card on older controllers — or over Ethernet with MotoCom or the FTP
//!   option). Set the tool and the user frame *before* loading: the controller turns the
//!   Cartesian positions of a standard job into axis pulses with the frames it holds.
//! * `///DATE` is fixed (2000/01/01 00:00): the same path gives the same files; the controller
//!   writes its own date when the job is edited. Lines end with CR LF, as the controller's own
//!   job files.

use crate::program::ProgramInput;
use crate::program::common::{Checked, comment_text, header_texts, num, wrap};
use crate::program::config::yaskawa_rconf;
use crate::program::error::ProgramError;
use crate::program::names::{INFORM, sanitize};
use crate::program::plan::{Plan, part_name, plan_within};
use crate::program::settings::{Coordinates, InformPostype, ProgramSettings};
use crate::program::sink::{ProgramSink, emit};
use deflex_model::Pose;
use deflex_model::conventions::yaskawa_rxryrz_deg;
use std::fmt::Write as _;

const FORMAT: &str = "Yaskawa INFORM";

/// Most path points in one job: a job of 2000 points has about 2000 move steps and 2000
/// positions, far below what a DX100 / YRC1000 holds for all jobs together (tens of thousands
/// of steps and positions), and a pendant still opens and edits it quickly.
pub const MAX_POINTS_PER_PART: usize = 2000;

/// Longest comment text (`'…`, characters): the pendant shows 32.
pub const COMMENT_CHARS: usize = 32;

/// Length of one point's position and move lines (bytes), for the part size.
const POINT_BYTES: usize = 110;

/// The fixed `///DATE` (see the module documentation).
const DATE: &str = "2000/01/01 00:00";

/// One job being written: its positions and instructions.
struct Job {
    name: String,
    comment: String,
    positions: String,
    inst: Vec<String>,
    count: usize,
    rconf: Option<[u8; 8]>,
    previous: Option<[f64; 3]>,
}

impl Job {
    fn new(name: String, comment: &str) -> Job {
        Job {
            name,
            comment: comment.to_string(),
            positions: String::new(),
            inst: Vec::new(),
            count: 0,
            rconf: None,
            previous: None,
        }
    }

    fn comment(&mut self, text: &str) {
        // A quote inside a comment is dropped (`vendor's` → `vendors`): only the leading one
        // marks the comment.
        let words: Vec<String> = text
            .replace('\'', "")
            .split_whitespace()
            .map(|w| comment_text(w, &['\'']))
            .collect();
        for line in wrap(&words.join(" "), COMMENT_CHARS) {
            self.inst.push(format!("'{line}"));
        }
    }

    /// A position `Cnnnnn` for `p` (with its `///RCONF` when it changes); returns its name.
    fn position(&mut self, p: &Checked) -> String {
        let k = self.count;
        self.count += 1;
        let rconf = yaskawa_rconf(p.config.as_ref());
        if self.rconf != Some(rconf) {
            let fields: Vec<String> = rconf.iter().map(u8::to_string).collect();
            let _ = write!(self.positions, "///RCONF {}\r\n", fields.join(","));
            self.rconf = Some(rconf);
        }
        let r = yaskawa_rxryrz_deg(&p.rotation, self.previous);
        self.previous = Some(r);
        let _ = write!(
            self.positions,
            "C{k:05}={},{},{},{},{},{}\r\n",
            num(p.position_mm.x, 4),
            num(p.position_mm.y, 4),
            num(p.position_mm.z, 4),
            num(r[0], 6),
            num(r[1], 6),
            num(r[2], 6)
        );
        format!("C{k:05}")
    }

    fn text(&self, frames: &Frames) -> String {
        let mut out = String::with_capacity(self.positions.len() + self.inst.len() * 32 + 512);
        let mut line = |s: &str| {
            out.push_str(s);
            out.push_str("\r\n");
        };
        line("/JOB");
        line(&format!("//NAME {}", self.name));
        line("//POS");
        line(&format!("///NPOS {},0,0,0,0,0", self.count));
        if let Some(user) = frames.user {
            line(&format!("///USER {user}"));
        }
        line(&format!("///TOOL {}", frames.tool));
        line(&format!(
            "///POSTYPE {}",
            if frames.user.is_some() {
                "USER"
            } else {
                "BASE"
            }
        ));
        line("///RECTAN");
        out.push_str(&self.positions);
        let mut line = |s: &str| {
            out.push_str(s);
            out.push_str("\r\n");
        };
        line("//INST");
        line(&format!("///DATE {DATE}"));
        line(&format!("///COMM {}", self.comment));
        line("///ATTR SC,RW");
        line("///GROUP1 RB1");
        line("NOP");
        for i in &self.inst {
            line(i);
        }
        line("END");
        out
    }
}

/// The user frame (`None`: `POSTYPE BASE`) and the tool of every job.
struct Frames {
    user: Option<u32>,
    tool: u32,
}

/// `V=v`: mm/s to 0.1 mm/s, at least 0.1.
fn speed_text(speed_mm_s: f64) -> String {
    format!("V={:.1}", (speed_mm_s * 10.0).round().max(1.0) / 10.0)
}

/// Write the job to `sink`, each part file as soon as it is complete; returns the files, the
/// main job first.
pub(crate) fn export(
    input: &ProgramInput,
    settings: &ProgramSettings,
    sink: &mut dyn ProgramSink,
) -> Result<Vec<String>, ProgramError> {
    let y = &settings.inform;
    if y.postype == InformPostype::Base && input.coordinates == Coordinates::Part {
        return Err(ProgramError::Settings {
            source_name: "settings".into(),
            key: "inform.postype".into(),
            message: "\"base\" writes the positions in the robot base frame: use it with \
                      [program] coordinates = \"robot\" (or postype = \"user\" for the part frame)"
                .into(),
        });
    }
    let plan = plan_within(FORMAT, input, settings, POINT_BYTES, MAX_POINTS_PER_PART)?;
    let name = sanitize(&settings.program.name, &INFORM).to_ascii_uppercase();
    // Part names add `_P01` … `_P999`: keep room for them.
    let name = if plan.split() && name.len() > INFORM.max_len - 5 {
        name[..INFORM.max_len - 5].to_string()
    } else {
        name
    };
    let frames = Frames {
        user: (input.coordinates == Coordinates::Part).then_some(y.user),
        tool: y.tool,
    };
    let mut main = Job::new(name.clone(), "deflex path");
    write_header(&mut main, input, &plan, &frames);
    let c = main.position(&plan.clear[0]);
    main.inst
        .push(format!("MOVJ {c} VJ={:.2}", y.joint_percent));
    main.comment("approach");
    let approach = speed_text(settings.program.approach_speed_mm_s);
    let c = main.position(&plan.point(0));
    main.inst.push(format!("MOVL {c} {approach} PL=0"));
    let last = plan.len() - 1;
    let mut parts = Vec::new();
    for (part, range) in plan.parts.iter().enumerate() {
        let part_name = part_name(&name, part).to_ascii_uppercase();
        let mut job = if plan.split() {
            main.inst.push(format!("CALL JOB:{part_name}"));
            let mut job = Job::new(part_name.clone(), "deflex part");
            job.comment(&format!(
                "part {} of {} of {name}: path points {} to {}",
                part + 1,
                plan.parts.len(),
                range.start,
                range.end - 1
            ));
            job.previous = main.previous;
            Some(job)
        } else {
            None
        };
        let body = job.as_mut().unwrap_or(&mut main);
        for i in range.clone() {
            let p = plan.point(i);
            let pl = if i < last && !p.rapid { y.pl } else { 0 };
            if p.rapid {
                body.comment("rapid");
            }
            let c = body.position(&p);
            body.inst
                .push(format!("MOVL {c} {} PL={pl}", speed_text(p.speed_mm_s)));
        }
        if let Some(job) = job {
            main.previous = job.previous;
            let path = format!("{part_name}.JBI");
            emit(sink, FORMAT, &path, &job.text(&frames))?;
            parts.push(path);
        }
    }
    main.comment("retract");
    let c = main.position(&plan.clear[1]);
    main.inst.push(format!("MOVL {c} {approach} PL=0"));
    let path = format!("{name}.JBI");
    emit(sink, FORMAT, &path, &main.text(&frames))?;
    Ok(std::iter::once(path).chain(parts).collect())
}

/// The header comments: the path, what the user must set on the controller and how to load.
fn write_header(job: &mut Job, input: &ProgramInput, plan: &Plan<'_>, frames: &Frames) {
    for line in header_texts(input) {
        job.comment(&line);
    }
    job.comment(
        "Load: pendant EX.MEMORY > LOAD > JOB from a CF/SD card or USB memory (FD/PC card on \
         older controllers), or over Ethernet with MotoCom or the FTP option. Set the TOOL and \
         USER values below BEFORE loading: the controller converts the positions to pulses \
         with them.",
    );
    job.comment(&format!(
        "Set TOOL {} to the model TCP in the flange frame (mm, deg):",
        frames.tool
    ));
    pose_lines(job, &input.tool_in_flange);
    match &plan.tool_load_in_flange {
        Some(l) => {
            job.comment(&format!(
                "and its load (TOOL {}): W {} kg, centre of gravity (mm):",
                frames.tool,
                num(l.mass_kg, 3)
            ));
            for (axis, v) in ["Xg", "Yg", "Zg"].iter().zip(l.centre_of_mass_m.iter()) {
                job.comment(&format!("{axis} {}", num(v * 1e3, 4)));
            }
        }
        None => job.comment(&format!(
            "and its load (TOOL {} W, Xg, Yg, Zg): not known to deflex",
            frames.tool
        )),
    }
    match frames.user {
        Some(user) => {
            job.comment(&format!(
                "Set USER {user} to the program frame{} in the robot frame (mm, deg):",
                input
                    .frame_name
                    .as_ref()
                    .map_or(String::new(), |n| format!(" ({n})"))
            ));
            pose_lines(job, &input.frame_in_robot);
        }
        None => {
            job.comment("POSTYPE BASE: the positions are in the robot base frame (no user frame)")
        }
    }
}

/// A pose as one `X …` … `Rz …` comment per value (mm to 0.1 µm, deg to 1e-6°).
fn pose_lines(job: &mut Job, pose: &Pose) {
    let t = pose.translation.vector * 1e3;
    let r = yaskawa_rxryrz_deg(&pose.rotation, None);
    for (name, value) in ["X", "Y", "Z"].iter().zip(t.iter()) {
        job.comment(&format!("{name} {}", num(*value, 4)));
    }
    for (name, value) in ["Rx", "Ry", "Rz"].iter().zip(r.iter()) {
        job.comment(&format!("{name} {}", num(*value, 6)));
    }
}
