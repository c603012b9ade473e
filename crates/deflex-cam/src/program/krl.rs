//! KUKA KRL (KR C4, KSS 8.x): `NAME.src` (the motion) and `NAME.dat` (its data list: the
//! settings the user may edit on the controller).
//!
//! ```text
//! DEF deflex_path( )
//! ; header: what the path is, the TCP, the load and the base the program assumes
//! ;FOLD safe start
//! BAS(#INITMOV, 0)
//! $TOOL = TOOL_DATA[1]
//! $LOAD = LOAD_DATA[1]
//! $BASE = BASE_DATA[1]            ($NULLFRAME with coordinates = "robot")
//! $ADVANCE = 3 … BAS(#VEL_PTP, DEFLEX_PTP_VEL)
//! PTP $H_POS                      BCO run to HOME
//! ;ENDFOLD
//! PTP {X 20.0, Y 0.0, Z 35.0, A 180.0, B 0.0, C 180.0, S 2, T 10} ; clearance point
//! $VEL.CP = 0.01000
//! LIN {X 20.0, Y 0.0, Z 0.0, …} ; approach
//! $VEL.CP = 0.01000
//! LIN {X 19.9239, Y 1.7431, Z -0.0033, …} C_DIS      (or deflex_path_p01( ) … when split)
//! …
//! LIN {X …, Z 35.0, …} ; retract
//! PTP $H_POS
//! END
//! ```
//!
//! * Positions in mm in the frame `$BASE` (BASE_DATA\[n\], taught on the controller as the part
//!   frame; `$NULLFRAME` with `coordinates = "robot"` or `base = 0`); orientation A-B-C in
//!   degrees (`Rz(A)·Ry(B)·Rx(C)`, see [`deflex_model::conventions`]). `$TOOL` is TOOL_DATA\[n\], which
//!   must hold the model's TCP, and `$LOAD` LOAD_DATA\[n\], which must hold the tool load: the
//!   header prints the values the program assumes.
//! * `$VEL.CP` is in **m/s** and is set before a `LIN` whenever the speed changes; `$VEL.ORI1/2`
//!   in deg/s; `$APO.CDIS` (mm) is the approximation distance of `C_DIS` (the controller
//!   shortens it to half a segment when the points are closer, KUKA's approximation rule). The
//!   approach, a rapid, the last path point and the retract have no `C_DIS`.
//! * The first motion is a `PTP $H_POS` (KUKA's BCO run to HOME), then a `PTP` to the clearance
//!   point above the start with Status and Turn from the model's IK branch ([`crate::program::config`]),
//!   so the controller takes the configuration the compensation was computed for.
//! * Angles stay in KUKA's display ranges (A, C ∈ (−180°, 180°], B ∈ [−90°, 90°]), so a tool
//!   pointing down (A ≈ C ≈ ±180°) may print A = 180 at one point and −179.99999 at the next:
//!   the same rotation. KUKA's `LIN` interpolates the orientation as a rotation, not the three
//!   angles one by one (the angles are coupled, a point noted by integrators, e.g.
//!   <https://industrialmonitordirect.com/blogs/knowledgebase/resolving-kuka-lin-rel-unwanted-axis-tilt-during-rotation>);
//!   at B = ±90° exactly KUKA itself sets A = 0, as [`deflex_model::conventions::kuka_abc_deg`] does
//!   without a previous point.
//! * Positions are written inline in the `.src`, as CAM post-processors do for long paths, rather
//!   than as one `E6POS` declaration per point in the `.dat`; the `.dat` holds the settings. A
//!   long path is split into `NAME_p01.src` … (global subprograms the main `.src` calls in order;
//!   see [`crate::program::plan`] for the limits).

use crate::program::ProgramInput;
use crate::program::common::{Checked, comment_text, header_lines, num};
use crate::program::config::kuka_status_turn;
use crate::program::error::ProgramError;
use crate::program::names::{KRL, sanitize};
use crate::program::plan::{Plan, part_name, plan};
use crate::program::settings::Coordinates;
use crate::program::settings::ProgramSettings;
use crate::program::sink::{ProgramSink, emit};
use deflex_model::Pose;
use deflex_model::conventions::kuka_abc_deg;
use std::fmt::Write as _;

const FORMAT: &str = "KRL";

/// A KRL frame literal `{X …, Y …, Z …, A …, B …, C …}` (mm, deg).
fn frame_literal(position_mm: [f64; 3], abc_deg: [f64; 3]) -> String {
    format!(
        "{{X {}, Y {}, Z {}, A {}, B {}, C {}}}",
        num(position_mm[0], 4),
        num(position_mm[1], 4),
        num(position_mm[2], 4),
        num(abc_deg[0], 6),
        num(abc_deg[1], 6),
        num(abc_deg[2], 6)
    )
}

fn pose_literal(pose: &Pose) -> String {
    let t = pose.translation.vector * 1e3;
    frame_literal([t.x, t.y, t.z], kuka_abc_deg(&pose.rotation, None))
}

/// Longest motion line (characters and `\r\n`).
const LINE_BYTES: usize = 120;

/// `{X …, …, S s, T t}` for a PTP to a Cartesian point with its configuration.
fn ptp_literal(p: &Checked, abc: [f64; 3]) -> String {
    let frame = frame_literal(p.position_mm.into(), abc);
    match &p.config {
        Some(c) => {
            let (status, turn) = kuka_status_turn(c);
            format!("{}, S {status}, T {turn}}}", &frame[..frame.len() - 1])
        }
        None => frame,
    }
}

/// Write the program to `sink`, each part file as soon as it is complete; returns the files,
/// the main program first.
pub(crate) fn export(
    input: &ProgramInput,
    settings: &ProgramSettings,
    sink: &mut dyn ProgramSink,
) -> Result<Vec<String>, ProgramError> {
    let plan = plan(FORMAT, input, settings, LINE_BYTES)?;
    let name = sanitize(&settings.program.name, &KRL);
    // Part names add `_p01`: keep room for them within KRL's 24 characters.
    let name = if plan.split() && name.len() > 20 {
        name[..20].to_string()
    } else {
        name
    };
    let blend = settings.program.blend_mm;
    let mut src = String::with_capacity(4096 + if plan.split() { 0 } else { plan.len() * 96 });
    let _ = writeln!(src, "&ACCESS RVP\r\n&REL 1\r\nDEF {name}( )\r");
    write_header_and_safe_start(&mut src, input, settings, &plan);
    let mut previous: Option<[f64; 3]> = None;
    let mut speed: Option<f64> = None;
    let start_abc = kuka_abc_deg(&plan.clear[0].rotation, None);
    let _ = writeln!(
        src,
        "PTP {} ; clearance point above the start\r",
        ptp_literal(&plan.clear[0], start_abc)
    );
    previous = previous.or(Some(start_abc));
    // Approach: straight down onto the first point, exact stop.
    write_speed(&mut src, &plan.clear[0], &mut speed);
    let first = plan.point(0);
    let abc = kuka_abc_deg(&first.rotation, previous);
    previous = Some(abc);
    let _ = writeln!(
        src,
        "LIN {} ; approach\r",
        frame_literal(first.position_mm.into(), abc)
    );
    let last = plan.len() - 1;
    let mut parts = Vec::new();
    let mut text = String::new();
    for (part, range) in plan.parts.iter().enumerate() {
        let part_name = part_name(&name, part);
        let body = if plan.split() {
            let _ = writeln!(src, "{part_name}( )\r");
            text = String::with_capacity(range.len() * 96 + 512);
            let _ = writeln!(text, "&ACCESS RVP\r\n&REL 1\r\nDEF {part_name}( )\r");
            let _ = writeln!(
                text,
                "; part {} of {} of {name}: path points {} to {}\r",
                part + 1,
                plan.parts.len(),
                range.start,
                range.end - 1
            );
            // Each part sets its speed (a part must not rely on the previous one's).
            speed = None;
            &mut text
        } else {
            &mut src
        };
        for i in range.clone() {
            let p = &plan.point(i);
            let abc = kuka_abc_deg(&p.rotation, previous);
            previous = Some(abc);
            let literal = frame_literal(p.position_mm.into(), abc);
            write_speed(body, p, &mut speed);
            let approximate = if i < last && blend > 0.0 && !p.rapid {
                " C_DIS"
            } else {
                ""
            };
            let rapid = if p.rapid { " ; rapid" } else { "" };
            let _ = writeln!(body, "LIN {literal}{approximate}{rapid}\r");
        }
        if plan.split() {
            let _ = writeln!(body, "END\r");
            // The part is complete: to the sink, and freed.
            let path = format!("{part_name}.src");
            emit(sink, FORMAT, &path, &text)?;
            parts.push(path);
        }
    }
    // Retract: straight up to the clearance point, then HOME.
    speed = None;
    write_speed(&mut src, &plan.clear[1], &mut speed);
    let abc = kuka_abc_deg(&plan.clear[1].rotation, previous);
    let _ = writeln!(
        src,
        "LIN {} ; retract\r",
        frame_literal(plan.clear[1].position_mm.into(), abc)
    );
    let _ = writeln!(src, "PTP $H_POS\r");
    let _ = writeln!(src, "END\r");
    let dat = data_list(&name, settings);
    let main = [format!("{name}.src"), format!("{name}.dat")];
    emit(sink, FORMAT, &main[0], &src)?;
    emit(sink, FORMAT, &main[1], &dat)?;
    Ok(main.into_iter().chain(parts).collect())
}

/// The header comments (path, the TCP, load and base the program assumes) and the safe-start
/// fold (tool, load, base, advance, speeds, the BCO run to HOME).
fn write_header_and_safe_start(
    src: &mut String,
    input: &ProgramInput,
    settings: &ProgramSettings,
    plan: &Plan<'_>,
) {
    let k = &settings.kuka;
    for line in header_lines(input) {
        let _ = writeln!(src, "; {}\r", comment_text(&line, &[]));
    }
    let _ = writeln!(
        src,
        "; TOOL_DATA[{}] must hold the model's TCP (mm, deg): {}\r",
        k.tool,
        pose_literal(&input.tool_in_flange)
    );
    match &plan.tool_load_in_flange {
        Some(l) => {
            let _ = writeln!(
                src,
                "; LOAD_DATA[{}] must hold the tool load: M {} kg, CM {{X {}, Y {}, Z {}}} mm\r",
                k.tool,
                num(l.mass_kg, 3),
                num(l.centre_of_mass_m[0] * 1e3, 4),
                num(l.centre_of_mass_m[1] * 1e3, 4),
                num(l.centre_of_mass_m[2] * 1e3, 4)
            );
        }
        None => {
            let _ = writeln!(
                src,
                "; LOAD_DATA[{}] must hold the tool load (not known to deflex)\r",
                k.tool
            );
        }
    }
    // Positions in the robot base frame: no base, whatever `kuka.base` says.
    let base = if k.base == 0 || input.coordinates == Coordinates::Robot {
        "$NULLFRAME".to_string()
    } else {
        format!("BASE_DATA[{}]", k.base)
    };
    let _ = writeln!(
        src,
        "; {base} must hold the program frame{} relative to $WORLD (= $ROBROOT assumed): {}\r",
        input
            .frame_name
            .as_ref()
            .map_or(String::new(), |n| format!(" ({n})")),
        pose_literal(&input.frame_in_robot)
    );
    let _ = writeln!(src, ";FOLD safe start\r");
    let _ = writeln!(src, "BAS(#INITMOV, 0)\r");
    let _ = writeln!(src, "$TOOL = TOOL_DATA[{}]\r", k.tool);
    let _ = writeln!(src, "$LOAD = LOAD_DATA[{}]\r", k.tool);
    let _ = writeln!(src, "$BASE = {base}\r");
    let _ = writeln!(src, "$ADVANCE = {}\r", k.advance);
    let _ = writeln!(src, "$APO.CDIS = DEFLEX_CDIS\r");
    let _ = writeln!(src, "$VEL.ORI1 = DEFLEX_ORI_VEL\r");
    let _ = writeln!(src, "$VEL.ORI2 = DEFLEX_ORI_VEL\r");
    let _ = writeln!(src, "BAS(#VEL_PTP, DEFLEX_PTP_VEL)\r");
    let _ = writeln!(
        src,
        "; BCO run: the first motion goes to the robot's HOME ($H_POS)\r"
    );
    let _ = writeln!(src, "PTP $H_POS\r");
    let _ = writeln!(src, ";ENDFOLD\r");
}

/// `NAME.dat`: the settings the user may edit on the controller.
fn data_list(name: &str, settings: &ProgramSettings) -> String {
    let k = &settings.kuka;
    let blend = settings.program.blend_mm;
    let mut dat = String::with_capacity(1024);
    let _ = writeln!(dat, "&ACCESS RVP\r\n&REL 1\r\nDEFDAT {name}\r");
    let _ = writeln!(dat, "; Settings of {name}.src (edit here).\r");
    let _ = writeln!(dat, "; Approximation distance of C_DIS (mm):\r");
    let _ = writeln!(dat, "DECL REAL DEFLEX_CDIS = {}\r", num(blend, 3));
    let _ = writeln!(dat, "; Reorientation speed (deg/s):\r");
    let _ = writeln!(
        dat,
        "DECL REAL DEFLEX_ORI_VEL = {}\r",
        num(settings.program.orientation_speed_deg_s, 3)
    );
    let _ = writeln!(dat, "; Axis speed of the PTP motions (%):\r");
    let _ = writeln!(
        dat,
        "DECL REAL DEFLEX_PTP_VEL = {}\r",
        num(k.ptp_speed_percent, 3)
    );
    let _ = writeln!(dat, "ENDDAT\r");
    dat
}

/// `$VEL.CP = …` (m/s) before a motion whose speed differs from the current one.
fn write_speed(out: &mut String, point: &Checked, current: &mut Option<f64>) {
    let v = (point.speed_mm_s * 100.0).round() / 100.0;
    if *current != Some(v) {
        let _ = writeln!(out, "$VEL.CP = {}\r", num(v * 1e-3, 5));
        *current = Some(v);
    }
}
