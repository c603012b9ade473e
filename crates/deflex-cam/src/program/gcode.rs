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
