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
//! NAME/NAME.pjx   project: start.pgx, stop.pgx, part1.pgx …, NAME.dtx, millimeterUnit="true"
//! NAME/NAME.dtx   fPart (frame, in world), tTool (tool, in flange), mApproach[0..1] (joint
//!                 and approach moves) + mPath[k] (mdesc), jStart (jointRx: the start joint
//!                 move), pClear[0..1] (the clearance points), pPathK / nSpeedK (pointRx in
//!                 fPart with their config; num: index into mPath), one pair per part
//! NAME/start.pgx  movej(jStart[0], tTool, mApproach[0])       start joint move
//!                 movel(pClear[0] …), movel(pPath1[0], tTool, mApproach[1])   approach
//!                 call part1() … call partK()
//!                 movel(pClear[1], tTool, mApproach[1])       retract
//!                 waitEndMove()
//! NAME/partK.pgx  for l_i = … to size(pPathK) - 1
//!                   movel(pPathK[l_i], tTool, mPath[nSpeedK[l_i]])
//!                 endFor
//! NAME/stop.pgx   resetMotion()
//! ```
//!
//! * Points: `x, y, z` in mm, `rx, ry, rz` in degrees, `R = Rx(rx)·Ry(ry)·Rz(rz)` (see
//!   [`deflex_model::conventions`]), expressed in the frame `fPart` (the program frame, child of
//!   `world`); the tool `tTool` (child of `flange`) holds the model's TCP. Each point carries
//!   its `config` (`shoulder`, `elbow`, `wrist`, [`crate::program::config`]) when known; `movel` keeps
//!   the configuration it starts in, the start joint move sets it.
//! * `mdesc`: `accel`, `vel`, `decel` in % of the nominal joint values (`joint_percent`),
//!   `tmax` the TCP speed (mm/s), `rmax` the reorientation speed (deg/s), `blend`
//!   (`off`/`joint`/`Cartesian`) with `leave` = `reach` = `blend_mm` (mm).
//! * VAL3 has no tool load in a `tool`; the header prints the one the cell assumes.

use crate::program::ProgramInput;
use crate::program::common::{Checked, comment_text, header_lines, num, speed_index, speed_table};
use crate::program::config::staubli_config;
use crate::program::error::ProgramError;
use crate::program::names::{VAL3, sanitize};
use crate::program::plan::{Plan, plan};
use crate::program::settings::ProgramSettings;
use crate::program::sink::{ProgramSink, emit, put};
use deflex_model::Pose;
use deflex_model::conventions::staubli_rxryrz_deg;
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

/// ` shoulder="righty" elbow="epositive" wrist="wpositive"` when the configuration is known.
fn config_attributes(p: &Checked) -> String {
    p.config.as_ref().map_or(String::new(), |c| {
        let (shoulder, elbow, wrist) = staubli_config(c);
        format!(" shoulder=\"{shoulder}\" elbow=\"{elbow}\" wrist=\"{wrist}\"")
    })
}

/// Longest `pointRx` line of the data file.
const LINE_BYTES: usize = 200;

/// The data file's head: the header comments, the frame, the tool, the motion descriptors
/// (approach and the path's speeds, with the blend), the start joint position and the
/// clearance points; the parts' arrays follow it.
fn data_file_head(
    input: &ProgramInput,
    settings: &ProgramSettings,
    plan: &Plan<'_>,
    speeds: &[f64],
) -> String {
    let s = &settings.staubli;
    let common = &settings.program;
    let (tool, frame) = (&s.tool_name, &s.frame_name);
    let percent = num(s.joint_percent, 1);
    let blend = if common.blend_mm > 0.0 {
        s.blend.word()
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

    let mut dtx = String::with_capacity(8192);
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
    data_open(&mut dtx, "mApproach", "mdesc", 2);
    let _ = writeln!(
        dtx,
        "      <Value key=\"0\" {} />",
        mdesc(common.rapid_speed_mm_s, "off", 0.0)
    );
    let _ = writeln!(
        dtx,
        "      <Value key=\"1\" {} />\n    </Data>",
        mdesc(common.approach_speed_mm_s, "off", 0.0)
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
    if let Some(c) = &plan.clear[0].config {
        let q = c.joints_rad.map(f64::to_degrees);
        data_open(&mut dtx, "jStart", "jointRx", 1);
        let _ = writeln!(
            dtx,
            "      <Value key=\"0\" j1=\"{}\" j2=\"{}\" j3=\"{}\" j4=\"{}\" j5=\"{}\" j6=\"{}\" />\n    </Data>",
            num(q[0], 4),
            num(q[1], 4),
            num(q[2], 4),
            num(q[3], 4),
            num(q[4], 4),
            num(q[5], 4)
        );
    }
    // The clearance points (start, end), then each part's points and speed indices; part 1
    // starts with the first path point (the approach's target).
    data_open(&mut dtx, "pClear", "pointRx", 2);
    let mut previous: Option<[f64; 3]> = None;
    for (k, c) in plan.clear.iter().enumerate() {
        let r = staubli_rxryrz_deg(&c.rotation, previous);
        previous = Some(r);
        let _ = writeln!(
            dtx,
            "      <Value key=\"{k}\" {}{} fatherId=\"{frame}[0]\" />",
            trsf_attributes(c.position_mm.into(), r),
            config_attributes(c)
        );
    }
    let _ = writeln!(dtx, "    </Data>");
    dtx
}

/// The project file (`NAME.pjx`): start, stop and the parts' programs, and the data file.
fn project_file(name: &str, programs: &[(String, String)]) -> String {
    let program_list: String = programs
        .iter()
        .map(|(p, _)| format!("    <Program file=\"{p}.pgx\" />\n"))
        .collect();
    let pjx = format!(
        "{XML_HEADER}\n<Project xmlns=\"http://www.staubli.com/robotics/VAL3/Project/3\">\n  \
         <Parameters version=\"s7.3.1\" stackSize=\"5000\" millimeterUnit=\"true\" />\n  \
         <Programs>\n    <Program file=\"start.pgx\" />\n    <Program file=\"stop.pgx\" />\n{program_list}  \
         </Programs>\n  <Database>\n    <Data file=\"{name}.dtx\" />\n  </Database>\n  \
         <Libraries>\n  </Libraries>\n</Project>\n"
    );
    pjx
}

/// The `start` program: the start joint move, the approach, the parts in order, the retract.
fn start_program(
    plan: &Plan<'_>,
    name: &str,
    tool: &str,
    frame: &str,
    programs: &[(String, String)],
) -> String {
    let start_move = if plan.clear[0].config.is_some() {
        format!("movej(jStart[0], {tool}, mApproach[0])\n  ")
    } else {
        format!("movej(pClear[0], {tool}, mApproach[0])\n  ")
    };
    let calls: String = programs
        .iter()
        .map(|(p, _)| format!("call {p}()\n  "))
        .collect();
    format!(
        "{XML_HEADER}\n{PROGRAMS_OPEN}\n  <Program name=\"start\" access=\"public\">\n    \
         <Code><![CDATA[\nbegin\n  \
         // deflex path: {} points in {frame}, tool {tool}; see {name}.dtx\n  \
         // start joint move to the clearance point above the start, approach, parts, retract\n  \
         {start_move}\
         movel(pClear[0], {tool}, mApproach[1])\n  \
         movel(pPath1[0], {tool}, mApproach[1])\n  \
         {calls}\
         movel(pClear[1], {tool}, mApproach[1])\n  \
         waitEndMove()\nend\n]]></Code>\n  </Program>\n</Programs>\n",
        plan.len()
    )
}

/// Write the application to `sink`: the data file in pieces, one per part, as the parts are
/// made (it holds every point); returns the files, the project first.
pub(crate) fn export(
    input: &ProgramInput,
    settings: &ProgramSettings,
    sink: &mut dyn ProgramSink,
) -> Result<Vec<String>, ProgramError> {
    let plan = plan(FORMAT, input, settings, LINE_BYTES)?;
    let speeds = speed_table(FORMAT, plan.points_from(0), MAX_SPEEDS)?;
    let name = sanitize(&settings.program.name, &VAL3);
    let (tool, frame) = (&settings.staubli.tool_name, &settings.staubli.frame_name);
    let dtx_path = format!("{name}/{name}.dtx");
    sink.begin(&dtx_path)?;
    let dtx = data_file_head(input, settings, &plan, &speeds);
    put(sink, FORMAT, &dtx)?;
    let mut previous: Option<[f64; 3]> = None;
    let mut programs = Vec::new();
    for (part, range) in plan.parts.iter().enumerate() {
        // This part's arrays, written to the data file when complete.
        let start = if part == 0 { 0 } else { range.start };
        let indices = start..range.end;
        let mut dtx = String::with_capacity(indices.len() * 200 + 256);
        let array = format!("pPath{}", part + 1);
        let speeds_array = format!("nSpeed{}", part + 1);
        data_open(&mut dtx, &speeds_array, "num", indices.len());
        for (key, i) in indices.clone().enumerate() {
            let _ = writeln!(
                dtx,
                "      <Value key=\"{key}\" value=\"{}\" />",
                speed_index(&speeds, &plan.point(i))
            );
        }
        let _ = writeln!(dtx, "    </Data>");
        data_open(&mut dtx, &array, "pointRx", indices.len());
        for (key, i) in indices.clone().enumerate() {
            let p = &plan.point(i);
            let r = staubli_rxryrz_deg(&p.rotation, previous);
            previous = Some(r);
            let _ = writeln!(
                dtx,
                "      <Value key=\"{key}\" {}{} fatherId=\"{frame}[0]\" />",
                trsf_attributes(p.position_mm.into(), r),
                config_attributes(p)
            );
        }
        let _ = writeln!(dtx, "    </Data>");
        put(sink, FORMAT, &dtx)?;
        let program = format!("part{}", part + 1);
        let first = if part == 0 { 1 } else { 0 };
        let text = format!(
            "{XML_HEADER}\n{PROGRAMS_OPEN}\n  <Program name=\"{program}\" access=\"public\">\n    \
             <Locals>\n      <Local name=\"l_i\" type=\"num\" xsi:type=\"array\" size=\"1\" />\n    \
             </Locals>\n    <Code><![CDATA[\nbegin\n  \
             // part {} of {}: path points {} to {}\n  \
             for l_i = {first} to size({array}) - 1\n    \
             movel({array}[l_i], {tool}, mPath[{speeds_array}[l_i]])\n  \
             endFor\nend\n]]></Code>\n  </Program>\n</Programs>\n",
            part + 1,
            plan.parts.len(),
            start,
            range.end - 1
        );
        programs.push((program, text));
    }
    put(sink, FORMAT, "  </Datas>\n</Database>\n")?;
    sink.end()?;

    let pjx = project_file(&name, &programs);
    let start = start_program(&plan, &name, tool, frame, &programs);
    let stop = format!(
        "{XML_HEADER}\n{PROGRAMS_OPEN}\n  <Program name=\"stop\" access=\"public\">\n    \
         <Code><![CDATA[\nbegin\n  resetMotion()\nend\n]]></Code>\n  </Program>\n</Programs>\n"
    );
    let mut files = vec![format!("{name}/{name}.pjx"), dtx_path];
    emit(sink, FORMAT, &files[0], &pjx)?;
    for (file, text) in [("start", &start), ("stop", &stop)] {
        let path = format!("{name}/{file}.pgx");
        emit(sink, FORMAT, &path, text)?;
        files.push(path);
    }
    for (program, text) in programs {
        let path = format!("{name}/{program}.pgx");
        emit(sink, FORMAT, &path, &text)?;
        files.push(path);
    }
    Ok(files)
}

const PROGRAMS_OPEN: &str = "<Programs xmlns:xsi=\"http://www.w3.org/2001/XMLSchema-instance\" xmlns=\"http://www.staubli.com/robotics/VAL3/Program/2\">";
