//! The twin's cell for a robot spec (built-in name or robot file) or from a `[cell]` TOML file:
//! the files are read here, the cell is built by `deflex-sim` from their text.

use deflex_load::{BoundedReadError, load_robot, read_bounded};
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
pub enum CellFileError {
    /// The file could not be read.
    #[error("{path}: {source}")]
    Read {
        /// The file.
        path: String,
        /// The operating system's error.
        source: std::io::Error,
    },
    /// The file is larger than a cell file may be.
    #[error(
        "{path}: more than the {limit} bytes a cell file may have (stopped reading after {bytes})"
    )]
    TooLarge {
        /// The file.
        path: String,
        /// Its size.
        bytes: u64,
        /// [`MAX_CELL_FILE_BYTES`].
        limit: u64,
    },
    /// The file's settings (a field error names the file).
    #[error(transparent)]
    Cell(#[from] SimError),
}

/// Read a `[cell]` TOML file (see `deflex_sim::CellConfig::from_toml_str_with`) for the robot
/// it names, or for `robot` (`--robot`, which wins), a robot file being read here. A field error
/// names the file.
pub fn load_cell(path: &Path, robot: Option<&str>) -> Result<CellConfig, CellFileError> {
    let shown = path.display().to_string();
    let text = read_bounded(path, MAX_CELL_FILE_BYTES).map_err(|e| match e {
        BoundedReadError::Io(source) => CellFileError::Read {
            path: shown.clone(),
            source,
        },
        BoundedReadError::TooLarge(bytes) => CellFileError::TooLarge {
            path: shown.clone(),
            bytes,
            limit: MAX_CELL_FILE_BYTES,
        },
    })?;
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

#[cfg(test)]
mod tests {
    use super::*;

    fn temp_dir(name: &str) -> std::path::PathBuf {
        let dir = std::env::temp_dir().join(format!("deflex-twin-{name}-{}", std::process::id()));
        let _ = std::fs::remove_dir_all(&dir);
        std::fs::create_dir_all(&dir).unwrap();
        dir
    }

    #[test]
    fn the_cell_of_a_robot_file_carries_its_description() {
        let dir = temp_dir("cell");
        let path = dir.join("my-ur10e.toml");
        std::fs::write(
            &path,
            deflex_model::robot_to_toml(&deflex_model::builtin("ur10e").unwrap()),
        )
        .unwrap();
        let spec = path.to_str().unwrap();
        let cell = cell_for_robot(spec).unwrap();
        assert_eq!(cell.part.robot, spec);
        let nominal = cell.nominal_robot().unwrap();
        let builtin = deflex_model::builtin("ur10e").unwrap();
        assert_eq!(nominal.name, builtin.name);
        assert_eq!(nominal.joints, builtin.joints);
        assert_eq!(
            nominal.tool,
            cell.tool(),
            "the cell's tool replaces the file's"
        );
        // A twin file naming it, and the flag winning over the file.
        let twin = dir.join("twin.toml");
        std::fs::write(
            &twin,
            format!("[cell.part]\nrobot = \"{spec}\"\n[cell.controller]\nrate_hz = 500.0\n"),
        )
        .unwrap();
        let from_file = load_cell(&twin, None).unwrap();
        assert_eq!(from_file.part.robot, spec);
        assert!(from_file.part.description.is_some());
        assert_eq!(from_file.controller.rate_hz, 500.0);
        assert_eq!(load_cell(&twin, Some("tx200")).unwrap().part.robot, "tx200");
        // Errors name the file and the field.
        std::fs::write(&twin, "[cell.controller]\nrate_hz = -1.0\n").unwrap();
        let e = load_cell(&twin, None).unwrap_err().to_string();
        assert!(e.contains("twin.toml") && e.contains("rate_hz"), "{e}");
        let e = load_cell(&dir.join("absent.toml"), None)
            .unwrap_err()
            .to_string();
        assert!(e.contains("absent.toml"), "{e}");
        let e = cell_for_robot("/nonexistent/arm.toml")
            .unwrap_err()
            .to_string();
        assert!(e.contains("/nonexistent/arm.toml"), "{e}");
        let _ = std::fs::remove_dir_all(&dir);
    }
}
