//! KUKA KRL (KR C4, KSS 8.x): `NAME.src` (the motion) and `NAME.dat` (its data list: the
//! settings the user may edit on the controller).
//!
//! ```text
//! DEF deflex_path( )
//! BAS(#INITMOV, 0)
//! $TOOL = TOOL_DATA[1]
//! $BASE = BASE_DATA[1]
//! $ADVANCE = 3
//! $APO.CDIS = DEFLEX_CDIS
//! $VEL.ORI1 = DEFLEX_ORI_VEL
//! $VEL.ORI2 = DEFLEX_ORI_VEL
//! BAS(#VEL_PTP, DEFLEX_PTP_VEL)
//! PTP {X 20.0000, Y 0.0000, Z 0.0000, A 180.000000, B 0.000000, C 180.000000}
//! $VEL.CP = 0.01000
//! LIN {X 19.9239, Y 1.7431, Z -0.0033, A 180.000000, B 0.000000, C 180.000000} C_DIS
//! …
//! END
//! ```
//!
//! * Positions in mm in the frame `$BASE` (BASE_DATA\[n\], taught on the controller as the part
//!   frame; `base = 0` gives `$NULLFRAME`, the robot's world); orientation A-B-C in degrees
//!   (`Rz(A)·Ry(B)·Rx(C)`, see [`crate::orientation`]). `$TOOL` is TOOL_DATA\[n\], which must
//!   hold the model's TCP: the header prints the values the program assumes.
//! * `$VEL.CP` is in **m/s** and is set before a `LIN` whenever the speed changes; `$VEL.ORI1/2`
//!   in deg/s; `$APO.CDIS` (mm) is the approximation distance of `C_DIS` (the controller
//!   shortens it to half a segment when the points are closer, KUKA's approximation rule). The
//!   last `LIN` has no `C_DIS`, so the program ends exactly on the last point.
//! * The first motion is a slow `PTP` to the first point (axis speed `BAS(#VEL_PTP, …)`), given
//!   as a frame without Status/Turn: the controller keeps the current configuration, so start
//!   the program near the path (as with any CAM program).
//! * Angles stay in KUKA's display ranges (A, C ∈ (−180°, 180°], B ∈ [−90°, 90°]), so a tool
//!   pointing down (A ≈ C ≈ ±180°) may print A = 180 at one point and −179.99999 at the next:
//!   the same rotation. KUKA's `LIN` interpolates the orientation as a rotation, not the three
//!   angles one by one (the angles are coupled, a point noted by integrators, e.g.
//!   <https://industrialmonitordirect.com/blogs/knowledgebase/resolving-kuka-lin-rel-unwanted-axis-tilt-during-rotation>);
//!   at B = ±90° exactly KUKA itself sets A = 0, as [`crate::orientation::kuka_abc_deg`] does
//!   without a previous point.
//! * Positions are written inline in the `.src`, as CAM post-processors do for long paths, rather
//!   than as one `E6POS` declaration per point in the `.dat`; the `.dat` holds the settings.

use crate::ProgramFile;
use crate::common::{Checked, check_lines, check_points, comment_text, header_lines, num};
use crate::error::ProgramError;
use crate::names::{KRL, sanitize};
use crate::orientation::kuka_abc_deg;
use crate::settings::ProgramSettings;
use crate::{Pose, ProgramInput};
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

pub(crate) fn export(
    input: &ProgramInput,
    settings: &ProgramSettings,
) -> Result<Vec<ProgramFile>, ProgramError> {
    let points = check_points(FORMAT, input, settings)?;
    let name = sanitize(&settings.program.name, &KRL);
    let k = &settings.kuka;
    let blend = settings.program.blend_mm;
    let mut src = String::with_capacity(points.len() * 96 + 2048);
    let _ = writeln!(src, "&ACCESS RVP\r\n&REL 1\r\nDEF {name}( )\r");
    for line in header_lines(input) {
        let _ = writeln!(src, "; {}\r", comment_text(&line, &[]));
    }
    let _ = writeln!(
        src,
        "; TOOL_DATA[{}] must hold the model's TCP (mm, deg): {}\r",
        k.tool,
        pose_literal(&input.tool_in_flange)
    );
    let base = if k.base == 0 {
        "$NULLFRAME".to_string()
    } else {
        format!("BASE_DATA[{}]", k.base)
    };
    let _ = writeln!(
        src,
        "; {base} must hold the program frame relative to $WORLD (= $ROBROOT assumed): {}\r",
        pose_literal(&input.frame_in_robot)
    );
    let _ = writeln!(src, "BAS(#INITMOV, 0)\r");
    let _ = writeln!(src, "$TOOL = TOOL_DATA[{}]\r", k.tool);
    let _ = writeln!(src, "$BASE = {base}\r");
    let _ = writeln!(src, "$ADVANCE = {}\r", k.advance);
    let _ = writeln!(src, "$APO.CDIS = DEFLEX_CDIS\r");
    let _ = writeln!(src, "$VEL.ORI1 = DEFLEX_ORI_VEL\r");
    let _ = writeln!(src, "$VEL.ORI2 = DEFLEX_ORI_VEL\r");
    let _ = writeln!(src, "BAS(#VEL_PTP, DEFLEX_PTP_VEL)\r");
    let mut previous: Option<[f64; 3]> = None;
    let mut speed: Option<f64> = None;
    let last = points.len() - 1;
    for (i, p) in points.iter().enumerate() {
        let abc = kuka_abc_deg(&p.rotation, previous);
        previous = Some(abc);
        let literal = frame_literal(p.position_mm.into(), abc);
        if i == 0 {
            let _ = writeln!(src, "PTP {literal}\r");
            continue;
        }
        write_speed(&mut src, p, &mut speed);
        let approximate = if i < last && blend > 0.0 {
            " C_DIS"
        } else {
            ""
        };
        let _ = writeln!(src, "LIN {literal}{approximate}\r");
    }
    let _ = writeln!(src, "END\r");
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
    let _ = writeln!(dat, "; Axis speed of the first PTP motion (%):\r");
    let _ = writeln!(
        dat,
        "DECL REAL DEFLEX_PTP_VEL = {}\r",
        num(k.ptp_speed_percent, 3)
    );
    let _ = writeln!(dat, "ENDDAT\r");
    check_lines(FORMAT, &src)?;
    check_lines(FORMAT, &dat)?;
    Ok(vec![
        ProgramFile {
            path: format!("{name}.src"),
            contents: src,
        },
        ProgramFile {
            path: format!("{name}.dat"),
            contents: dat,
        },
    ])
}

/// `$VEL.CP = …` (m/s) before a motion whose speed differs from the current one.
fn write_speed(out: &mut String, point: &Checked, current: &mut Option<f64>) {
    let v = (point.speed_mm_s * 100.0).round() / 100.0;
    if *current != Some(v) {
        let _ = writeln!(out, "$VEL.CP = {}\r", num(v * 1e-3, 5));
        *current = Some(v);
    }
}
