//! G-code in the program frame (the part frame by default): what CAM systems and `deflex sim
//! isf --path FILE.gcode` read.
//!
//! ```text
//! ( deflex path … )
//! G21
//! G90
//! G0 X20.0000 Y0.0000 Z0.0000
//! G1 X19.9239 Y1.7431 Z-0.0033 F600.00
//! …
//! M30
//! ```
//!
//! Millimetres (`G21`), absolute (`G90`), `G0` for rapid moves and `G1 … F` (mm/min, modal) for
//! feed moves. G-code carries **positions only**: a compensated orientation is lost, and the
//! header says by how much the orientation varies along the path (a robot running G-code holds
//! its own tool orientation). Comments are `( … )` without parentheses inside, which is what
//! deflex's own G-code reader accepts.

use crate::ProgramFile;
use crate::ProgramInput;
use crate::common::{check_lines, check_points, comment_text, header_lines, num};
use crate::error::ProgramError;
use crate::names::{GCODE_FILE, sanitize};
use crate::orientation::rotation_distance;
use crate::settings::ProgramSettings;
use std::fmt::Write as _;

const FORMAT: &str = "G-code";

pub(crate) fn export(
    input: &ProgramInput,
    settings: &ProgramSettings,
) -> Result<Vec<ProgramFile>, ProgramError> {
    let points = check_points(FORMAT, input, settings)?;
    let name = sanitize(&settings.program.name, &GCODE_FILE);
    let d = settings.gcode.decimals;
    let mut out = String::with_capacity(points.len() * 48 + 1024);
    for line in header_lines(input) {
        let _ = writeln!(out, "( {} )", comment_text(&line, &['(', ')']));
    }
    let spread = points
        .iter()
        .map(|p| rotation_distance(&points[0].rotation, &p.rotation))
        .fold(0.0, f64::max);
    let _ = writeln!(
        out,
        "( positions only: the orientation varies by up to {} mrad along the path and is not written )",
        num(spread * 1e3, 4)
    );
    let _ = writeln!(out, "G21\nG90");
    let mut feed: Option<f64> = None;
    for (i, p) in points.iter().enumerate() {
        let xyz = format!(
            "X{} Y{} Z{}",
            num(p.position_mm.x, d),
            num(p.position_mm.y, d),
            num(p.position_mm.z, d)
        );
        if i == 0 || p.rapid {
            let _ = writeln!(out, "G0 {xyz}");
            continue;
        }
        let f = (p.speed_mm_s * 60.0 * 100.0).round() / 100.0;
        if feed == Some(f) {
            let _ = writeln!(out, "G1 {xyz}");
        } else {
            let _ = writeln!(out, "G1 {xyz} F{}", num(f, 2));
            feed = Some(f);
        }
    }
    let _ = writeln!(out, "M30");
    check_lines(FORMAT, &out)?;
    Ok(vec![ProgramFile {
        path: format!("{name}.gcode"),
        contents: out,
    }])
}
