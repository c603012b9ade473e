//! Stäubli VAL3 (CS8/CS9): an application folder as Stäubli Robotics Suite (SRS) stores it.
//!
//! **File layout, honestly.** A VAL3 application is not one text file: it is a folder with a
//! project file `NAME.pjx` (XML: parameters, the list of programs, the data file), a data file
//! `NAME.dtx` (XML: every global variable with its values) and one `.pgx` per program (XML
//! wrapping the VAL3 code in a CDATA block). Stäubli does not publish the XML schemas; the
//! element and attribute names written here (`Project/3`, `Data/2`, `Program/2` namespaces,
//! `pointRx`, `frame`, `tool`, `mdesc` and `num` arrays with `Value key=…` rows) follow public
//! VAL3 post-processor output for s7-era controllers. Older CS8 versions (s5/s6) use a different
//! data-file dialect. These files have not been opened in SRS nor run on a controller; if SRS
//! refuses them, the points are still readable in the `.dtx` and the motion is four lines of
//! `start()`.
//!
//! ```text
//! NAME/NAME.pjx   project: start.pgx, stop.pgx, NAME.dtx, millimeterUnit="true"
//! NAME/NAME.dtx   fPart (frame, in world), tTool (tool, in flange), mApproach + mPath[k]
//!                 (mdesc), nSpeed[i] (num: index into mPath), pPath[i] (pointRx in fPart)
//! NAME/start.pgx  movej(pPath[0], tTool, mApproach)
//!                 for l_i = 1 to size(pPath) - 1
//!                   movel(pPath[l_i], tTool, mPath[nSpeed[l_i]])
//!                 endFor
//!                 waitEndMove()
//! NAME/stop.pgx   resetMotion()
//! ```
//!
//! * Points: `x, y, z` in mm, `rx, ry, rz` in degrees, `R = Rx(rx)·Ry(ry)·Rz(rz)` (see
//!   [`crate::orientation`]), expressed in the frame `fPart` (the program frame, child of
//!   `world`); the tool `tTool` (child of `flange`) holds the model's TCP.
//! * `mdesc`: `accel`, `vel`, `decel` in % of the nominal joint values (`joint_percent`),
//!   `tmax` the TCP speed (mm/s), `rmax` the reorientation speed (deg/s), `blend`
//!   (`off`/`joint`/`Cartesian`) with `leave` = `reach` = `blend_mm` (mm).

use crate::ProgramFile;
use crate::common::{check_lines, check_points, comment_text, header_lines, num, speed_table};
use crate::error::ProgramError;
use crate::names::{VAL3, sanitize};
use crate::orientation::staubli_rxryrz_deg;
use crate::settings::ProgramSettings;
use crate::{Pose, ProgramInput};
use std::fmt::Write as _;

const FORMAT: &str = "VAL3";

/// Most distinct speeds (entries of `mPath`).
pub const MAX_SPEEDS: usize = 64;

const XML_HEADER: &str = "<?xml version=\"1.0\" encoding=\"utf-8\"?>";

/// `x="…" y="…" z="…" rx="…" ry="…" rz="…"` (mm, deg).
fn trsf_attributes(position_mm: [f64; 3], r_deg: [f64; 3]) -> String {
    format!(
        "x=\"{}\" y=\"{}\" z=\"{}\" rx=\"{}\" ry=\"{}\" rz=\"{}\"",
        num(position_mm[0], 4),
        num(position_mm[1], 4),
        num(position_mm[2], 4),
        num(r_deg[0], 6),
        num(r_deg[1], 6),
        num(r_deg[2], 6)
    )
}

fn pose_attributes(pose: &Pose) -> String {
    let t = pose.translation.vector * 1e3;
    trsf_attributes([t.x, t.y, t.z], staubli_rxryrz_deg(&pose.rotation, None))
}

fn data_open(out: &mut String, name: &str, kind: &str, size: usize) {
    let _ = writeln!(
        out,
        "    <Data name=\"{name}\" access=\"public\" xsi:type=\"array\" type=\"{kind}\" size=\"{size}\">"
    );
}

pub(crate) fn export(
    input: &ProgramInput,
    settings: &ProgramSettings,
) -> Result<Vec<ProgramFile>, ProgramError> {
    let points = check_points(FORMAT, input, settings)?;
    let (speeds, speed_index) = speed_table(FORMAT, &points, MAX_SPEEDS)?;
    let name = sanitize(&settings.program.name, &VAL3);
    let s = &settings.staubli;
    let common = &settings.program;
    let (tool, frame) = (&s.tool_name, &s.frame_name);
    let percent = num(s.joint_percent, 1);
    let blend = if common.blend_mm > 0.0 {
        s.blend.as_str()
    } else {
        "off"
    };
    let rmax = num(common.orientation_speed_deg_s, 2);
    let mdesc = |tmax: f64, blend: &str, distance: f64| {
        format!(
            "accel=\"{percent}\" vel=\"{percent}\" decel=\"{percent}\" tmax=\"{}\" rmax=\"{rmax}\" blend=\"{blend}\" leave=\"{}\" reach=\"{}\"",
            num(tmax, 2),
            num(distance, 3),
            num(distance, 3)
        )
    };

    let mut dtx = String::with_capacity(points.len() * 140 + 4096);
    let _ = writeln!(dtx, "{XML_HEADER}");
    let _ = writeln!(
        dtx,
        "<Database xmlns:xsi=\"http://www.w3.org/2001/XMLSchema-instance\" xmlns=\"http://www.staubli.com/robotics/VAL3/Data/2\">"
    );
    for line in header_lines(input) {
        let _ = writeln!(
            dtx,
            "  <!-- {} -->",
            comment_text(&line, &['-', '<', '>', '&'])
        );
    }
    let _ = writeln!(dtx, "  <Datas>");
    data_open(&mut dtx, frame, "frame", 1);
    let _ = writeln!(
        dtx,
        "      <Value key=\"0\" {} fatherId=\"world[0]\" />\n    </Data>",
        pose_attributes(&input.frame_in_robot)
    );
    data_open(&mut dtx, tool, "tool", 1);
    let _ = writeln!(
        dtx,
        "      <Value key=\"0\" {} fatherId=\"flange[0]\" />\n    </Data>",
        pose_attributes(&input.tool_in_flange)
    );
    data_open(&mut dtx, "mApproach", "mdesc", 1);
    let _ = writeln!(
        dtx,
        "      <Value key=\"0\" {} />\n    </Data>",
        mdesc(common.rapid_speed_mm_s, "off", 0.0)
    );
    data_open(&mut dtx, "mPath", "mdesc", speeds.len());
    for (k, v) in speeds.iter().enumerate() {
        let _ = writeln!(
            dtx,
            "      <Value key=\"{k}\" {} />",
            mdesc(*v, blend, common.blend_mm)
        );
    }
    let _ = writeln!(dtx, "    </Data>");
    data_open(&mut dtx, "nSpeed", "num", points.len());
    for (i, k) in speed_index.iter().enumerate() {
        let _ = writeln!(dtx, "      <Value key=\"{i}\" value=\"{k}\" />");
    }
    let _ = writeln!(dtx, "    </Data>");
    data_open(&mut dtx, "pPath", "pointRx", points.len());
    let mut previous: Option<[f64; 3]> = None;
    for (i, p) in points.iter().enumerate() {
        let r = staubli_rxryrz_deg(&p.rotation, previous);
        previous = Some(r);
        let _ = writeln!(
            dtx,
            "      <Value key=\"{i}\" {} fatherId=\"{frame}[0]\" />",
            trsf_attributes(p.position_mm.into(), r)
        );
    }
    let _ = writeln!(dtx, "    </Data>\n  </Datas>\n</Database>");

    let pjx = format!(
        "{XML_HEADER}\n<Project xmlns=\"http://www.staubli.com/robotics/VAL3/Project/3\">\n  \
         <Parameters version=\"s7.3.1\" stackSize=\"5000\" millimeterUnit=\"true\" />\n  \
         <Programs>\n    <Program file=\"start.pgx\" />\n    <Program file=\"stop.pgx\" />\n  \
         </Programs>\n  <Database>\n    <Data file=\"{name}.dtx\" />\n  </Database>\n  \
         <Libraries>\n  </Libraries>\n</Project>\n"
    );
    let programs_open = "<Programs xmlns:xsi=\"http://www.w3.org/2001/XMLSchema-instance\" xmlns=\"http://www.staubli.com/robotics/VAL3/Program/2\">";
    let start = format!(
        "{XML_HEADER}\n{programs_open}\n  <Program name=\"start\" access=\"public\">\n    \
         <Locals>\n      <Local name=\"l_i\" type=\"num\" xsi:type=\"array\" size=\"1\" />\n    \
         </Locals>\n    <Code><![CDATA[\nbegin\n  \
         // deflex path: {} points in {frame}, tool {tool}; see {name}.dtx\n  \
         movej(pPath[0], {tool}, mApproach)\n  \
         for l_i = 1 to size(pPath) - 1\n    \
         movel(pPath[l_i], {tool}, mPath[nSpeed[l_i]])\n  \
         endFor\n  \
         waitEndMove()\nend\n]]></Code>\n  </Program>\n</Programs>\n",
        points.len()
    );
    let stop = format!(
        "{XML_HEADER}\n{programs_open}\n  <Program name=\"stop\" access=\"public\">\n    \
         <Code><![CDATA[\nbegin\n  resetMotion()\nend\n]]></Code>\n  </Program>\n</Programs>\n"
    );
    for text in [&dtx, &pjx, &start, &stop] {
        check_lines(FORMAT, text)?;
    }
    Ok(vec![
        ProgramFile {
            path: format!("{name}/{name}.pjx"),
            contents: pjx,
        },
        ProgramFile {
            path: format!("{name}/{name}.dtx"),
            contents: dtx,
        },
        ProgramFile {
            path: format!("{name}/start.pgx"),
            contents: start,
        },
        ProgramFile {
            path: format!("{name}/stop.pgx"),
            contents: stop,
        },
    ])
}
