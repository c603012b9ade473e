//! G-code files for the twin and for `compensate`: the file is read here (a regular file of at
//! most [`MAX_GCODE_BYTES`], counted while reading), its text is read by `deflex_sim::gcode`
//! (the CAM reader `deflex_cam::gcode` behind it). The errors are the twin's ([`SimError`]).

use deflex_sim::gcode::{GcodeProgram, ReadOptions, default_options, parse_gcode_with};
use deflex_sim::{SimError, ToolPath, builtin_tool_path};
use std::path::Path;

/// Largest G-code file read (bytes).
pub const MAX_GCODE_BYTES: u64 = 64 << 20;

/// Read a G-code file into a [`ToolPath`] (the twin's default options,
/// `deflex_sim::gcode::default_options`).
pub fn read_gcode(path: &Path) -> Result<ToolPath, SimError> {
    read_gcode_with(path, &default_options()).map(|(toolpath, _)| toolpath)
}

/// Read a G-code file: the tool path (named after the file) and the program as read (its work
/// offset, moves and notes). An error names the whole path.
pub fn read_gcode_with(
    path: &Path,
    options: &ReadOptions,
) -> Result<(ToolPath, GcodeProgram), SimError> {
    // A regular file of at most MAX_GCODE_BYTES, counted while reading.
    let text = deflex_files::read_bounded(path, MAX_GCODE_BYTES)
        .map_err(|e| SimError::Path(e.to_string()))?;
    // Errors name the whole path; the tool path is named after the file.
    let (mut toolpath, program) = parse_gcode_with(&text, &path.display().to_string(), options)?;
    if let Some(name) = path.file_name() {
        toolpath.name = name.to_string_lossy().into_owned();
    }
    Ok((toolpath, program))
}

/// A built-in path by name (`cone`: the paper's helical cone, `cone-contour`, `pyramid`; see
/// `deflex_sim::builtin_tool_path`) or else a G-code file ([`read_gcode`]).
pub fn tool_path_by_name(spec: &str) -> Result<ToolPath, SimError> {
    builtin_tool_path(spec).unwrap_or_else(|| read_gcode(Path::new(spec)))
}
