//! ABB RAPID (IRC5 / OmniCore): one module `NAME.mod` with `PROC main()`.
//!
//! ```text
//! MODULE deflex_path
//!   PERS tooldata deflex_tool := [TRUE,[[0,0,200],[1,0,0,0]],[3.35,[3,-2,105],[1,0,0,0],0,0,0]];
//!   PERS wobjdata deflex_wobj := [FALSE,TRUE,"",[[1500,0,-183],[1,0,0,0]],[[0,0,0],[1,0,0,0]]];
//!   CONST jointtarget deflex_start := [[0,45.9,88.4,0,45.7,0],[9E9,…]];
//!   CONST speeddata deflex_vapp := [10,30,5000,1000];  deflex_vrapid, deflex_v1 …
//!   CONST zonedata deflex_zone := [FALSE,0.2,0.2,0.2,0.02,0.2,0.02];
//!   PROC main()
//!     ConfJ \On;
//!     ConfL \On;
//!     MoveAbsJ deflex_start, deflex_vrapid, fine, deflex_tool \WObj:=deflex_wobj;
//!     MoveJ [[20,0,35],[0,0,1,0],[0,0,0,1],[9E9,…]], deflex_vrapid, fine, …;   clearance point
//!     MoveL [[20,0,0],…], deflex_vapp, fine, …;                                approach
//!     MoveL [[19.9239,1.7431,-0.0033],[0,0,1,0],[0,0,0,1],[9E9,…]], deflex_v1, deflex_zone, …;
//!     …                                              (or deflex_path_p01; … when split)
//!     MoveL [[…,35],…], deflex_vapp, fine, …;                                  retract
//!   ENDPROC
//! ENDMODULE
//! ```
//!
//! * `robtarget` = `[trans (mm), rot (quaternion q1..q4, q1 = w), robconf, extax]`; positions
//!   are relative to the work object (`\WObj`), whose `uframe` is the program frame in the
//!   robot's world. Quaternion sign: continuous along the path (see [`deflex_model::conventions`]).
//! * `robconf` `[cf1, cf4, cf6, cfx]` is written from the model's joint values at every target
//!   ([`crate::program::config`]) with `ConfJ \On` and `ConfL \On`: the controller checks that it reaches
//!   each target in the configuration the compensation was computed for. Without configurations
//!   (a caller that gave none) it writes `[0,0,0,0]` with both `\Off`.
//! * The start joint move `MoveAbsJ deflex_start` goes to the joint values of the clearance
//!   point above the start (the model's IK, in degrees).
//! * `speeddata` = `[v_tcp (mm/s), v_ori (deg/s), v_leax (mm/s), v_reax (deg/s)]`, one `CONST`
//!   per distinct speed (at most [`MAX_SPEEDS`]); `zonedata` = `[finep, pzone_tcp, pzone_ori,
//!   pzone_eax (mm), zone_ori (deg), zone_leax (mm), zone_reax (deg)]` from `blend_mm` (the
//!   controller shrinks a zone to half the distance to the neighbouring points, RAPID
//!   reference, `zonedata`); the approach, rapids, the last move and the retract are `fine`.
//! * `tooldata` = `[robhold, tframe [[x,y,z],[q]], tload [mass, cog, aom, ix, iy, iz]]`, declared
//!   from the model's TCP and the tool load (the template's `program.tool_mass_kg`, else the
//!   caller's; refused when neither is known) unless `declare_tool = false`; `wobjdata` =
//!   `[robhold, ufprog, ufmec, uframe, oframe]`, declared with the program frame unless
//!   `declare_wobj = false`.
//! * A long path is split into modules `NAME_p01.mod` … each with one `PROC` of the same name,
//!   called in order from `main` (data declared in the main module are global to the task).

use crate::program::ProgramInput;
use crate::program::common::{Checked, comment_text, header_lines, num, speed_index, speed_table};
use crate::program::config::abb_robconf;
use crate::program::error::ProgramError;
use crate::program::names::{RAPID, sanitize};
use crate::program::plan::{Plan, part_name, plan};
use crate::program::settings::ProgramSettings;
use crate::program::sink::{ProgramSink, emit};
use deflex_model::Pose;
use deflex_model::conventions::abb_quaternion;
use std::fmt::Write as _;

const FORMAT: &str = "RAPID";

/// Most distinct speeds (one `speeddata` each).
pub const MAX_SPEEDS: usize = 64;

fn quaternion_text(q: [f64; 4]) -> String {
    format!(
        "[{},{},{},{}]",
        num(q[0], 9),
        num(q[1], 9),
        num(q[2], 9),
        num(q[3], 9)
    )
}

fn pose_text(pose: &Pose) -> String {
    let t = pose.translation.vector * 1e3;
    format!(
        "[[{},{},{}],{}]",
        num(t.x, 4),
        num(t.y, 4),
        num(t.z, 4),
        quaternion_text(abb_quaternion(&pose.rotation, None))
    )
}

/// Longest motion line (characters and `\r\n`).
const LINE_BYTES: usize = 200;

/// A robtarget aggregate with its `robconf` (`[0,0,0,0]` when the configuration is unknown).
fn robtarget(p: &Checked, q: [f64; 4]) -> String {
    let conf = p.config.as_ref().map_or([0; 4], abb_robconf);
    format!(
        "[[{},{},{}],{},[{},{},{},{}],[9E9,9E9,9E9,9E9,9E9,9E9]]",
        num(p.position_mm.x, 4),
        num(p.position_mm.y, 4),
        num(p.position_mm.z, 4),
        quaternion_text(q),
        conf[0],
        conf[1],
        conf[2],
        conf[3]
    )
}

/// The module's header comments and declarations: the tool and work object (declared, or the
/// existing ones the program assumes), the start joint target, the speeds and the zone; returns
/// the zone of the path's motions (`fine` without blending).
fn write_declarations(
    out: &mut String,
    input: &ProgramInput,
    settings: &ProgramSettings,
    plan: &Plan<'_>,
    speeds: &[f64],
) -> Result<&'static str, ProgramError> {
    let a = &settings.abb;
    let common = &settings.program;
    let tool = &a.tool_name;
    let wobj = &a.wobj_name;
    for line in header_lines(input) {
        let _ = writeln!(out, "  ! {}\r", comment_text(&line, &[]));
    }
    if a.declare_tool {
        let load = match (a.tool_mass_kg, &plan.tool_load_in_flange) {
            (Some(m), _) => (m, a.tool_cog_mm.unwrap_or([0.0; 3])),
            (None, Some(l)) => (l.mass_kg, l.centre_of_mass_m.map(|v| v * 1e3).into()),
            (None, None) => {
                return Err(ProgramError::Settings {
                    source_name: "program template".into(),
                    key: "program.tool_mass_kg".into(),
                    message: "RAPID declares the tool with its load and deflex knows none: give \
                              your tool's mass and centre of gravity (program.tool_mass_kg, \
                              program.tool_cog_mm), or use an existing tool (abb.declare_tool = \
                              false)"
                        .into(),
                });
            }
        };
        let _ = writeln!(
            out,
            "  PERS tooldata {tool} := [TRUE,{},[{},[{},{},{}],[1,0,0,0],0,0,0]];\r",
            pose_text(&input.tool_in_flange),
            num(load.0, 3),
            num(load.1[0], 3),
            num(load.1[1], 3),
            num(load.1[2], 3)
        );
    } else {
        let _ = writeln!(
            out,
            "  ! The existing tool {tool} must hold the model's TCP and the tool load: {}\r",
            pose_text(&input.tool_in_flange)
        );
    }
    if a.declare_wobj {
        let _ = writeln!(
            out,
            "  PERS wobjdata {wobj} := [FALSE,TRUE,\"\",{},[[0,0,0],[1,0,0,0]]];\r",
            pose_text(&input.frame_in_robot)
        );
    } else {
        let _ = writeln!(
            out,
            "  ! The existing work object {wobj} must hold the program frame: {}\r",
            pose_text(&input.frame_in_robot)
        );
    }
    if let Some(c) = &plan.clear[0].config {
        let q = c.joints_rad.map(f64::to_degrees);
        let _ = writeln!(
            out,
            "  CONST jointtarget deflex_start := [[{},{},{},{},{},{}],[9E9,9E9,9E9,9E9,9E9,9E9]];\r",
            num(q[0], 4),
            num(q[1], 4),
            num(q[2], 4),
            num(q[3], 4),
            num(q[4], 4),
            num(q[5], 4)
        );
    }
    let ori = num(common.orientation_speed_deg_s, 2);
    for (label, v) in [
        ("deflex_vapp", common.approach_speed_mm_s),
        ("deflex_vrapid", common.rapid_speed_mm_s),
    ] {
        let _ = writeln!(
            out,
            "  CONST speeddata {label} := [{},{ori},5000,1000];\r",
            num(v, 2)
        );
    }
    for (k, v) in speeds.iter().enumerate() {
        let _ = writeln!(
            out,
            "  CONST speeddata deflex_v{} := [{},{ori},5000,1000];\r",
            k + 1,
            num(*v, 2)
        );
    }
    let b = common.blend_mm;
    let zone = if b > 0.0 {
        let _ = writeln!(
            out,
            "  CONST zonedata deflex_zone := [FALSE,{},{},{},{},{},{}];\r",
            num(b, 4),
            num(b, 4),
            num(b, 4),
            num(0.1 * b, 4),
            num(b, 4),
            num(0.1 * b, 4)
        );
        "deflex_zone"
    } else {
        "fine"
    };
    Ok(zone)
}

/// Write the program to `sink`, each part module as soon as it is complete; returns the files,
/// the main module first.
pub(crate) fn export(
    input: &ProgramInput,
    settings: &ProgramSettings,
    sink: &mut dyn ProgramSink,
) -> Result<Vec<String>, ProgramError> {
    let plan = plan(FORMAT, input, settings, LINE_BYTES)?;
    let speeds = speed_table(FORMAT, plan.points_from(1), MAX_SPEEDS)?;
    let name = sanitize(&settings.program.name, &RAPID);
    let name = if plan.split() && name.len() > 28 {
        name[..28].to_string()
    } else {
        name
    };
    let a = &settings.abb;
    let tool = &a.tool_name;
    let wobj = &a.wobj_name;
    let configured = input.configurations.len() == plan.len();
    let mut out = String::with_capacity(8192 + if plan.split() { 0 } else { plan.len() * 180 });
    let _ = writeln!(out, "MODULE {name}\r");
    let zone = write_declarations(&mut out, input, settings, &plan, &speeds)?;
    let _ = writeln!(out, "  PROC main()\r");
    if configured {
        let _ = writeln!(out, "    ConfJ \\On;\r");
        let _ = writeln!(out, "    ConfL \\On;\r");
    } else {
        let _ = writeln!(
            out,
            "    ! configuration unknown: the nearest one is taken\r"
        );
        let _ = writeln!(out, "    ConfJ \\Off;\r");
        let _ = writeln!(out, "    ConfL \\Off;\r");
    }
    if plan.clear[0].config.is_some() {
        let _ = writeln!(
            out,
            "    MoveAbsJ deflex_start, deflex_vrapid, fine, {tool} \\WObj:={wobj};\r"
        );
    }
    let mut previous: Option<[f64; 4]> = None;
    let q = abb_quaternion(&plan.clear[0].rotation, previous);
    previous = Some(q);
    let _ = writeln!(
        out,
        "    MoveJ {}, deflex_vrapid, fine, {tool} \\WObj:={wobj};\r",
        robtarget(&plan.clear[0], q)
    );
    let first = plan.point(0);
    let q = abb_quaternion(&first.rotation, previous);
    previous = Some(q);
    let _ = writeln!(
        out,
        "    MoveL {}, deflex_vapp, fine, {tool} \\WObj:={wobj};\r",
        robtarget(&first, q)
    );
    let last = plan.len() - 1;
    let mut parts = Vec::new();
    let mut text = String::new();
    for (part, range) in plan.parts.iter().enumerate() {
        let part_name = part_name(&name, part);
        let (body, indent) = if plan.split() {
            let _ = writeln!(out, "    {part_name};\r");
            text = String::with_capacity(range.len() * 180 + 512);
            let _ = writeln!(text, "MODULE {part_name}\r");
            let _ = writeln!(
                text,
                "  ! part {} of {} of {name}: path points {} to {}\r",
                part + 1,
                plan.parts.len(),
                range.start,
                range.end - 1
            );
            let _ = writeln!(text, "  PROC {part_name}()\r");
            (&mut text, "    ")
        } else {
            (&mut out, "    ")
        };
        for i in range.clone() {
            let p = &plan.point(i);
            let q = abb_quaternion(&p.rotation, previous);
            previous = Some(q);
            let speed = if p.rapid {
                "deflex_vrapid".to_string()
            } else {
                format!("deflex_v{}", speed_index(&speeds, p) + 1)
            };
            let zone = if i == last || p.rapid { "fine" } else { zone };
            let _ = writeln!(
                body,
                "{indent}MoveL {}, {speed}, {zone}, {tool} \\WObj:={wobj};\r",
                robtarget(p, q)
            );
        }
        if plan.split() {
            let _ = writeln!(body, "  ENDPROC\r\nENDMODULE\r");
            // The part is complete: to the sink, and freed.
            let path = format!("{part_name}.mod");
            emit(sink, FORMAT, &path, &text)?;
            parts.push(path);
        }
    }
    let q = abb_quaternion(&plan.clear[1].rotation, previous);
    let _ = writeln!(
        out,
        "    MoveL {}, deflex_vapp, fine, {tool} \\WObj:={wobj};\r",
        robtarget(&plan.clear[1], q)
    );
    let _ = writeln!(out, "  ENDPROC\r\nENDMODULE\r");
    let main = format!("{name}.mod");
    emit(sink, FORMAT, &main, &out)?;
    Ok(std::iter::once(main).chain(parts).collect())
}
