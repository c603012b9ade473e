//! Robot descriptions from disk: a built-in name or a TOML file, the URDF it names read from
//! beside it, and a robot's TOML written for another folder with its URDF path rewritten.

use crate::load::{BoundedReadError, read_bounded};
use deflex_model::{
    BUILTIN_ROBOTS, ModelError, ResolvedUrdf, Robot, UrdfResolver, builtin, robot_from_toml_str,
    robot_to_toml_with_urdf_path,
};
use std::path::{Path, PathBuf};

/// Largest robot file (TOML or URDF) read (bytes): far above any real description.
pub const MAX_ROBOT_FILE_BYTES: u64 = 64 << 20;

/// Why a robot file could not be read: the model reads no file, so reading is this module's
/// job and this its error. It reaches the callers as
/// [`ModelError::TextUnavailable`] (the message unchanged), beside the model's own errors.
#[derive(Debug, thiserror::Error)]
pub enum RobotFileError {
    /// A robot file (TOML or URDF) could not be read, or a robot spec names neither a built-in
    /// robot nor an existing file.
    #[error("{path}: cannot read file: {source}")]
    Read {
        /// The file (or the spec, with the built-in names).
        path: String,
        /// The operating-system error.
        source: std::io::Error,
    },
}

impl From<RobotFileError> for ModelError {
    fn from(error: RobotFileError) -> Self {
        ModelError::TextUnavailable(Box::new(error))
    }
}

/// Read a robot file (TOML or URDF) of at most [`MAX_ROBOT_FILE_BYTES`]; `shown` names it.
fn read_robot_text(path: &Path, shown: &str) -> Result<String, ModelError> {
    read_bounded(path, MAX_ROBOT_FILE_BYTES).map_err(|e| match e {
        BoundedReadError::Io(source) => RobotFileError::Read {
            path: shown.to_string(),
            source,
        }
        .into(),
        BoundedReadError::TooLarge(size) => ModelError::Invalid {
            path: shown.to_string(),
            field: "file".into(),
            message: format!(
                "more than the {MAX_ROBOT_FILE_BYTES} bytes a robot description may have (stopped reading after {size})"
            ),
        },
    })
}

/// Resolves a robot TOML's `urdf = "…"` on disk: a relative path from the TOML's folder.
pub struct FileUrdfResolver {
    /// The robot file's folder (`None`: the current folder).
    pub base_dir: Option<PathBuf>,
}

impl UrdfResolver for FileUrdfResolver {
    fn resolve(&self, reference: &str) -> Result<ResolvedUrdf, ModelError> {
        let path = match &self.base_dir {
            Some(dir) if Path::new(reference).is_relative() => dir.join(reference),
            _ => PathBuf::from(reference),
        };
        let xml = read_robot_text(&path, &path.display().to_string())?;
        Ok(ResolvedUrdf { path, xml })
    }
}

/// Read a robot TOML file (and the URDF it names, relative to the file's folder).
pub fn robot_from_toml_file(path: &Path) -> Result<Robot, ModelError> {
    let shown = path.display().to_string();
    let text = read_robot_text(path, &shown)?;
    let resolver = FileUrdfResolver {
        base_dir: path.parent().map(Path::to_path_buf),
    };
    robot_from_toml_str(&text, &shown, Some(&resolver))
}

/// Load a robot from a built-in name or a TOML file path. A URDF named in the TOML is resolved
/// relative to the TOML file's folder.
pub fn load_robot(spec: &str) -> Result<Robot, ModelError> {
    if let Some(robot) = builtin(spec) {
        return Ok(robot);
    }
    let path = Path::new(spec);
    if !path.exists() {
        let names: Vec<&str> = BUILTIN_ROBOTS.iter().map(|(n, _)| *n).collect();
        return Err(RobotFileError::Read {
            path: format!("{spec} (not a built-in robot: {})", names.join(", ")),
            source: std::io::Error::from(std::io::ErrorKind::NotFound),
        }
        .into());
    }
    let text = read_robot_text(path, spec)?;
    let resolver = FileUrdfResolver {
        base_dir: path.parent().map(Path::to_path_buf),
    };
    robot_from_toml_str(&text, spec, Some(&resolver))
}

/// [`deflex_model::robot_to_toml`] for a file that will be written at `destination`: a URDF
/// path is rewritten relative to `destination`'s folder (absolute when no relative path
/// exists), so the written robot still finds its URDF.
pub fn robot_to_toml_for(robot: &Robot, destination: &Path) -> String {
    let urdf_path = robot.urdf.as_ref().map(|urdf| {
        let target = absolute(&urdf.resolved);
        let folder = destination
            .parent()
            .filter(|p| !p.as_os_str().is_empty())
            .unwrap_or(Path::new("."));
        relative_path(&absolute(folder), &target)
            .unwrap_or(target)
            .display()
            .to_string()
    });
    robot_to_toml_with_urdf_path(robot, urdf_path)
}

/// An absolute, symlink-free path when the file exists; otherwise the path joined to the
/// current folder.
fn absolute(path: &Path) -> PathBuf {
    path.canonicalize().unwrap_or_else(|_| {
        std::env::current_dir()
            .map(|cwd| cwd.join(path))
            .unwrap_or_else(|_| path.to_path_buf())
    })
}

/// `target` relative to folder `from` (both absolute), e.g. `../robots/arm.urdf`.
fn relative_path(from: &Path, target: &Path) -> Option<PathBuf> {
    use std::path::Component;
    let from: Vec<Component> = from.components().collect();
    let to: Vec<Component> = target.components().collect();
    if from.first() != to.first() {
        return None;
    }
    let common = from.iter().zip(&to).take_while(|(a, b)| a == b).count();
    let mut out = PathBuf::new();
    for _ in common..from.len() {
        out.push("..");
    }
    for component in &to[common..] {
        out.push(component.as_os_str());
    }
    Some(out)
}
