//! The twin's cell for a robot spec (built-in name or robot file) or from a `[cell]` TOML file:
//! the files are read here, the cell is built by `deflex-sim` from their text.

use crate::load::load_robot;
use deflex_files::{FileIoError, FileTooLarge};
use deflex_model::builtin;
use deflex_sim::{CellConfig, SimError};
use std::path::Path;

/// Largest cell TOML read (bytes).
pub const MAX_CELL_FILE_BYTES: u64 = 1 << 20;

/// The cell of a robot (built-in name or robot file, read here): see `deflex_sim::profile`.
pub fn cell_for_robot(spec: &str) -> Result<CellConfig, SimError> {
    if spec.trim().is_empty() || builtin(spec).is_some() {
        return CellConfig::for_robot(spec);
    }
    CellConfig::for_robot_description(spec, load_robot(spec)?)
}

/// Why a cell file could not be used.
#[derive(Debug, thiserror::Error)]
pub enum TwinCellFileError {
    /// The file could not be read.
    #[error(transparent)]
    Read(#[from] FileIoError),
    /// The file is larger than a cell file may be ([`MAX_CELL_FILE_BYTES`]).
    #[error(transparent)]
    TooLarge(#[from] FileTooLarge),
    /// The file's settings (a field error names the file).
    #[error(transparent)]
    Cell(#[from] SimError),
}

/// Read a `[cell]` TOML file (see `deflex_sim::CellConfig::from_toml_str_with`) for the robot
/// it names, or for `robot` (`--robot`, which wins), a robot file being read here. A field error
/// names the file.
pub fn load_cell(path: &Path, robot: Option<&str>) -> Result<CellConfig, TwinCellFileError> {
    let shown = path.display().to_string();
    let text = deflex_files::read_bounded(path, MAX_CELL_FILE_BYTES)
        .map_err(|e| e.reported_as::<TwinCellFileError>("a cell file"))?;
    let config = CellConfig::from_toml_str_with(&text, robot, &|spec| Ok(load_robot(spec)?))
        .map_err(|e| match e {
            SimError::Config { field, message } => SimError::Config {
                field: format!("{shown}: {field}"),
                message,
            },
            other => other,
        })?;
    Ok(config)
}
