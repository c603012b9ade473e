//! ABB RAPID (IRC5 / OmniCore): one module `NAME.mod` with `PROC main()`.
//!
//! ```text
//! MODULE deflex_path
//!   PERS tooldata deflex_tool := [TRUE,[[0,0,0],[1,0,0,0]],[1,[0,0,50],[1,0,0,0],0,0,0]];
//!   PERS wobjdata deflex_wobj := [FALSE,TRUE,"",[[1500,0,-183],[1,0,0,0]],[[0,0,0],[1,0,0,0]]];
//!   CONST speeddata deflex_v1 := [10,30,5000,1000];
//!   CONST zonedata deflex_zone := [FALSE,0.2,0.2,0.2,0.02,0.2,0.02];
//!   PROC main()
//!     ConfJ \Off;
//!     ConfL \Off;
//!     MoveJ [[20,0,0],[0,0,1,0],[0,0,0,0],[9E9,9E9,9E9,9E9,9E9,9E9]], deflex_vapp, fine, deflex_tool \WObj:=deflex_wobj;
//!     MoveL [[19.9239,1.7431,-0.0033],[0,0,1,0],[0,0,0,0],[9E9,…]], deflex_v1, deflex_zone, deflex_tool \WObj:=deflex_wobj;
//!     …
//!   ENDPROC
//! ENDMODULE
//! ```
//!
//! * `robtarget` = `[trans (mm), rot (quaternion q1..q4, q1 = w), robconf, extax]`; positions
//!   are relative to the work object (`\WObj`), whose `uframe` is the program frame in the
//!   robot's world. Quaternion sign: continuous along the path (see [`crate::orientation`]).
//! * `robconf` is written `[0,0,0,0]` with `ConfJ \Off` and `ConfL \Off`: the controller takes
//!   the configuration closest to the current one instead of checking the quadrants, since the
//!   model's joint zeros need not be ABB's.
//! * `speeddata` = `[v_tcp (mm/s), v_ori (deg/s), v_leax (mm/s), v_reax (deg/s)]`, one `CONST`
//!   per distinct speed (at most [`MAX_SPEEDS`]); `zonedata` = `[finep, pzone_tcp, pzone_ori,
//!   pzone_eax (mm), zone_ori (deg), zone_leax (mm), zone_reax (deg)]` from `blend_mm` (the
//!   controller shrinks a zone to half the distance to the neighbouring points, RAPID
//!   reference, `zonedata`); the last move is `fine`.
//! * `tooldata` = `[robhold, tframe [[x,y,z],[q]], tload [mass, cog, aom, ix, iy, iz]]`, declared
//!   from the model's TCP and the settings' mass unless `declare_tool = false`; `wobjdata` =
//!   `[robhold, ufprog, ufmec, uframe, oframe]`, declared with the program frame unless
//!   `declare_wobj = false`.

use crate::ProgramFile;
use crate::common::{check_lines, check_points, comment_text, header_lines, num, speed_table};
use crate::error::ProgramError;
use crate::names::{RAPID, sanitize};
use crate::orientation::abb_quaternion;
use crate::settings::ProgramSettings;
use crate::{Pose, ProgramInput};
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

pub(crate) fn export(
    input: &ProgramInput,
    settings: &ProgramSettings,
) -> Result<Vec<ProgramFile>, ProgramError> {
    let points = check_points(FORMAT, input, settings)?;
    let (speeds, speed_index) = speed_table(FORMAT, &points[1..], MAX_SPEEDS)?;
    let name = sanitize(&settings.program.name, &RAPID);
    let a = &settings.abb;
    let common = &settings.program;
    let tool = &a.tool_name;
    let wobj = &a.wobj_name;
    let mut out = String::with_capacity(points.len() * 180 + 4096);
    let _ = writeln!(out, "MODULE {name}\r");
    for line in header_lines(input) {
        let _ = writeln!(out, "  ! {}\r", comment_text(&line, &[]));
    }
    if a.declare_tool {
        let _ = writeln!(
            out,
            "  PERS tooldata {tool} := [TRUE,{},[{},[{},{},{}],[1,0,0,0],0,0,0]];\r",
            pose_text(&input.tool_in_flange),
            num(a.tool_mass_kg, 3),
            num(a.tool_cog_mm[0], 3),
            num(a.tool_cog_mm[1], 3),
            num(a.tool_cog_mm[2], 3)
        );
    } else {
        let _ = writeln!(
            out,
            "  ! The existing tool {tool} must hold the model's TCP: {}\r",
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
    let ori = num(common.orientation_speed_deg_s, 2);
    let _ = writeln!(
        out,
        "  CONST speeddata deflex_vapp := [{},{ori},5000,1000];\r",
        num(common.rapid_speed_mm_s, 2)
    );
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
    let _ = writeln!(out, "  PROC main()\r");
    let _ = writeln!(out, "    ConfJ \\Off;\r");
    let _ = writeln!(out, "    ConfL \\Off;\r");
    let mut previous: Option<[f64; 4]> = None;
    let last = points.len() - 1;
    for (i, p) in points.iter().enumerate() {
        let q = abb_quaternion(&p.rotation, previous);
        previous = Some(q);
        let target = format!(
            "[[{},{},{}],{},[0,0,0,0],[9E9,9E9,9E9,9E9,9E9,9E9]]",
            num(p.position_mm.x, 4),
            num(p.position_mm.y, 4),
            num(p.position_mm.z, 4),
            quaternion_text(q)
        );
        if i == 0 {
            let _ = writeln!(
                out,
                "    MoveJ {target}, deflex_vapp, fine, {tool} \\WObj:={wobj};\r"
            );
            continue;
        }
        let speed = format!("deflex_v{}", speed_index[i - 1] + 1);
        let zone = if i == last { "fine" } else { zone };
        let _ = writeln!(
            out,
            "    MoveL {target}, {speed}, {zone}, {tool} \\WObj:={wobj};\r"
        );
    }
    let _ = writeln!(out, "  ENDPROC\r\nENDMODULE\r");
    check_lines(FORMAT, &out)?;
    Ok(vec![ProgramFile {
        path: format!("{name}.mod"),
        contents: out,
    }])
}
