//! G-code in the program frame (the part frame by default): what CAM systems and `deflex sim
//! isf --path FILE.gcode` read.
//!
//! ```text
//! %
//! ( deflex path … )
//! ( safe start )
//! G17 G40 G49 G80 G90 G21 G54
//! G0 X20.0000 Y0.0000 Z20.0000 ( clearance point )
//! G1 X20.0000 Y0.0000 Z0.0000 F600.00 ( approach )
//! G1 X19.9239 Y1.7431 Z-0.0033 F600.00
//! …
//! G1 X… Y… Z20.0000 F600.00 ( retract )
//! M30
//! %
//! ```
//!
//! The safe start sets the XY plane, cancels tool radius and length compensation and canned
//! cycles, absolute millimetres and the work offset of the path (`G54` unless the path named
//! another). `G0` for rapid moves and for the move to the clearance point above the start,
//! `G1 … F` (mm/min, modal) for feed moves, the approach and the retract. G-code carries
//! **positions only**: a compensated orientation is lost, and the header says by how much the
//! orientation varies along the path (a robot running G-code holds its own tool orientation).
//! Comments are `( … )` without parentheses inside. The program reads back with
//! [`crate::gcode`], the reader of CAM programs ([`crate::program::readback`]).

use crate::program::ProgramInput;
use crate::program::common::{Checked, comment_text, header_lines, num};
use crate::program::error::ProgramError;
use crate::program::names::{GCODE_FILE, sanitize};
use crate::program::plan::plan;
use crate::program::settings::ProgramSettings;
use crate::program::sink::{ProgramSink, put};
use deflex_model::conventions::rotation_distance;
use std::fmt::Write as _;

const FORMAT: &str = "G-code";

/// Lines written to the sink at a time.
const CHUNK_LINES: usize = 4096;

/// Write the program to `sink` (one file, in pieces of [`CHUNK_LINES`] lines).
pub(crate) fn export(
    input: &ProgramInput,
    settings: &ProgramSettings,
    sink: &mut dyn ProgramSink,
) -> Result<Vec<String>, ProgramError> {
    // G-code is not split: CNC controls stream long programs (the line bound is max_points).
    let plan = plan(FORMAT, input, settings, 1)?;
    let name = sanitize(&settings.program.name, &GCODE_FILE);
    let path = format!("{name}.gcode");
    let d = settings.gcode.decimals;
    sink.begin(&path)?;
    let mut out = String::with_capacity(CHUNK_LINES * 48 + 1024);
    let _ = writeln!(out, "%");
    for line in header_lines(input) {
        let _ = writeln!(out, "( {} )", comment_text(&line, &['(', ')']));
    }
    let first = plan.point(0);
    let spread = plan
        .points_from(0)
        .map(|p| rotation_distance(&first.rotation, &p.rotation))
        .fold(0.0, f64::max);
    let _ = writeln!(
        out,
        "( positions only: the orientation varies by up to {} mrad along the path and is not written )",
        num(spread * 1e3, 4)
    );
    let offset = input.frame_name.as_deref().unwrap_or("G54");
    operator_lines(&mut out, input, settings, offset)?;
    let _ = writeln!(out, "( safe start )\nG17 G40 G49 G80 G90 G21 {offset}");
    let xyz = |p: &Checked| {
        format!(
            "X{} Y{} Z{}",
            num(p.position_mm.x, d),
            num(p.position_mm.y, d),
            num(p.position_mm.z, d)
        )
    };
    let f = |v: f64| num((v * 60.0 * 100.0).round() / 100.0, 2);
    let _ = writeln!(out, "G0 {} ( clearance point )", xyz(&plan.clear[0]));
    let _ = writeln!(
        out,
        "G1 {} F{} ( approach )",
        xyz(&first),
        f(plan.clear[0].speed_mm_s)
    );
    let mut feed: Option<String> = None;
    for (k, p) in plan.points_from(1).enumerate() {
        if k % CHUNK_LINES == CHUNK_LINES - 1 {
            put(sink, FORMAT, &out)?;
            out.clear();
        }
        let p = &p;
        if p.rapid {
            let _ = writeln!(out, "G0 {}", xyz(p));
            continue;
        }
        let this = f(p.speed_mm_s);
        if feed.as_ref() == Some(&this) {
            let _ = writeln!(out, "G1 {}", xyz(p));
        } else {
            let _ = writeln!(out, "G1 {} F{this}", xyz(p));
            feed = Some(this);
        }
    }
    let _ = writeln!(
        out,
        "G1 {} F{} ( retract )",
        xyz(&plan.clear[1]),
        f(plan.clear[1].speed_mm_s)
    );
    let _ = writeln!(out, "M30\n%");
    put(sink, FORMAT, &out)?;
    sink.end()?;
    Ok(vec![path])
}

/// The work offset's number for `G10 L2 P…`: G54 = 1 … G59 = 6, G59.1 = 7 … G59.3 = 9.
fn work_offset_number(name: &str) -> Option<u32> {
    match name {
        "G54" => Some(1),
        "G55" => Some(2),
        "G56" => Some(3),
        "G57" => Some(4),
        "G58" => Some(5),
        "G59" => Some(6),
        "G59.1" => Some(7),
        "G59.2" => Some(8),
        "G59.3" => Some(9),
        _ => None,
    }
}

/// What the operator must enter for the program to be right, at the program's own precision
/// (`gcode.decimals` in mm, 6 decimals in degrees): the work offset `offset` (the program
/// frame in the robot base frame) and the tool; with `gcode.set_work_offset`, the `G10 L2`
/// line that sets the work offset instead (translation only: a rotated frame is refused).
fn operator_lines(
    out: &mut String,
    input: &ProgramInput,
    settings: &ProgramSettings,
    offset: &str,
) -> Result<(), ProgramError> {
    let d = settings.gcode.decimals;
    let xyz = |v: nalgebra::Vector3<f64>| {
        format!(
            "X{} Y{} Z{}",
            num(v.x * 1e3, d),
            num(v.y * 1e3, d),
            num(v.z * 1e3, d)
        )
    };
    let rpy = |r: &nalgebra::Rotation3<f64>| {
        let [a, b, c] = deflex_model::spatial::rpy_from_rotation(r);
        format!(
            "{} {} {}",
            num(a.to_degrees(), 6),
            num(b.to_degrees(), 6),
            num(c.to_degrees(), 6)
        )
    };
    let frame = &input.frame_in_robot;
    let rotated = frame.rotation.angle() > 0.0;
    let frame_text = format!(
        "{}{}",
        xyz(frame.translation.vector),
        if rotated {
            format!(", rotated by roll-pitch-yaw {} deg", rpy(&frame.rotation))
        } else {
            String::new()
        }
    );
    let tool = &input.tool_in_flange;
    let _ = writeln!(
        out,
        "( tool: the controller's TCP must be flange -> {} mm, roll-pitch-yaw {} deg )",
        xyz(tool.translation.vector),
        rpy(&tool.rotation)
    );
    match input.coordinates {
        crate::program::Coordinates::Robot => {
            let _ = writeln!(
                out,
                "( work offset {offset} must be zero: the positions are in the robot base frame )"
            );
            return Ok(());
        }
        crate::program::Coordinates::Part => {}
    }
    if !settings.gcode.set_work_offset {
        let _ = writeln!(
            out,
            "( work offset {offset} must hold the part frame in the robot base frame [mm]: {frame_text} )"
        );
        return Ok(());
    }
    let refuse = |message: String| ProgramError::Settings {
        source_name: "the program template".into(),
        key: "gcode.set_work_offset".into(),
        message,
    };
    let number = work_offset_number(offset).ok_or_else(|| {
        refuse(format!(
            "`{offset}` is not a work offset G10 L2 can set (G54 to G59.3)"
        ))
    })?;
    if rotated {
        return Err(refuse(format!(
            "the part frame is rotated (roll-pitch-yaw {} deg); G10 L2 sets a translation only: enter the work offset by hand",
            rpy(&frame.rotation)
        )));
    }
    let _ = writeln!(
        out,
        "( the program sets work offset {offset} to the part frame in the robot base frame [mm] )\nG10 L2 P{number} {frame_text}"
    );
    Ok(())
}
