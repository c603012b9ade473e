//! CAM G-code as a twin tool path: the reader is `deflex_cam::gcode` (the ISO/Fanuc subset CAM
//! systems emit: lines, arcs and helices interpolated to a chord tolerance, planes, units,
//! work offsets; see that crate for what is read, ignored with a note, and refused), shared
//! with `deflex compensate`. Coordinates are the TCP (the centre of the ball tip) in the part
//! frame R_p (the program's work offset), z up; the path starts at the program's first move
//! (no start at R_p's origin).
//!
//! The twin reads no file: it takes the program's text ([`parse_gcode`]) or the program as read
//! ([`tool_path_from_program`]); the application layer reads G-code files
//! (`deflex_app::load::gcode_file`).
//!
//! Bounds: at most [`MAX_WAYPOINTS`] path points, coordinates within ±[`MAX_COORDINATE_MM`],
//! feeds from [`MIN_FEED_MM_MIN`] to [`MAX_FEED_MM_MIN`] mm/min. A run of the program is further
//! bounded in time by the cell (`crate::cell_config::MAX_RUN_S`).

use crate::error::SimError;
use crate::toolpath::{ToolPath, Waypoint};
pub use deflex_cam::gcode::{GcodeProgram, ReadOptions};

/// Most path points of a program (arcs interpolated).
pub const MAX_WAYPOINTS: usize = 1_000_000;
/// Largest |coordinate| of a move (mm, after units).
pub const MAX_COORDINATE_MM: f64 = deflex_cam::gcode::MAX_COORDINATE_MM;
/// Slowest feed (mm/min): 0.01 mm/s.
pub const MIN_FEED_MM_MIN: f64 = deflex_cam::gcode::MIN_FEED_MM_MIN;
/// Fastest feed (mm/min): 1 m/s.
pub const MAX_FEED_MM_MIN: f64 = deflex_cam::gcode::MAX_FEED_MM_MIN;

/// The reader's options for the twin: the default chord tolerance, at most [`MAX_WAYPOINTS`].
pub fn default_options() -> ReadOptions {
    ReadOptions {
        max_points: MAX_WAYPOINTS,
        ..ReadOptions::default()
    }
}

/// Parse G-code text; `file` names the source in errors and becomes the path name.
pub fn parse_gcode(text: &str, file: &str) -> Result<ToolPath, SimError> {
    parse_gcode_with(text, file, &default_options()).map(|(toolpath, _)| toolpath)
}

/// [`parse_gcode`] with reader options, returning the program as read too.
pub fn parse_gcode_with(
    text: &str,
    file: &str,
    options: &ReadOptions,
) -> Result<(ToolPath, GcodeProgram), SimError> {
    let program = deflex_cam::gcode::read(text, options).map_err(|e| SimError::Gcode {
        file: file.to_string(),
        line: e.line,
        message: if e.line == 0 {
            e.kind.to_string()
        } else {
            format!("column {}, `{}`: {}", e.column, e.word, e.kind)
        },
    })?;
    Ok((tool_path_from_program(&program, file), program))
}

/// The path of a program as a [`ToolPath`] (no nominal step-down or wall angle: the twin's
/// sheet uses its defaults).
pub fn tool_path_from_program(program: &GcodeProgram, name: &str) -> ToolPath {
    ToolPath {
        name: name.to_string(),
        waypoints: program
            .points
            .iter()
            .map(|p| Waypoint {
                p_mm: p.p_mm,
                feed_mm_s: p.feed_mm_s,
            })
            .collect(),
        step_down_mm: None,
        wall_angle_deg: None,
    }
}
