//! Robot descriptions from disk: a built-in name or a TOML file, the URDF it names read from
//! beside it, and a robot's TOML written for another folder with its URDF path rewritten.

use deflex_files::{FileIoError, FileTooLarge};
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
    /// A robot file (TOML or URDF) could not be read: `PATH: cannot read file: ERROR` (a
    /// [`FileIoError`] becomes this with that context).
    #[error(transparent)]
    Read(FileIoError),
    /// A robot file larger than [`MAX_ROBOT_FILE_BYTES`].
    #[error(transparent)]
    TooLarge(#[from] FileTooLarge),
    /// A robot spec that names neither a built-in robot nor an existing file.
    #[error("{spec} (not a built-in robot: {}): cannot read file: {}", .builtins.join(", "), std::io::Error::from(std::io::ErrorKind::NotFound))]
    Unknown {
        /// The spec, as given.
        spec: String,
        /// The built-in robots' names.
        builtins: Vec<&'static str>,
    },
}

impl From<FileIoError> for RobotFileError {
    fn from(error: FileIoError) -> Self {
        RobotFileError::Read(error.context("cannot read file"))
    }
}

impl From<RobotFileError> for ModelError {
    fn from(error: RobotFileError) -> Self {
        ModelError::TextUnavailable(Box::new(error))
    }
}

/// Read a robot file (TOML or URDF) of at most [`MAX_ROBOT_FILE_BYTES`].
fn read_robot_text(path: &Path) -> Result<String, ModelError> {
    deflex_files::read_bounded(path, MAX_ROBOT_FILE_BYTES).map_err(|e| {
        e.reported_as::<RobotFileError>("a robot description")
            .into()
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
        let xml = read_robot_text(&path)?;
        Ok(ResolvedUrdf { path, xml })
    }
}

/// Read a robot TOML file (and the URDF it names, relative to the file's folder).
pub fn robot_from_toml_file(path: &Path) -> Result<Robot, ModelError> {
    let shown = path.display().to_string();
    let text = read_robot_text(path)?;
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
        return Err(RobotFileError::Unknown {
            spec: spec.to_string(),
            builtins: BUILTIN_ROBOTS.iter().map(|(n, _)| *n).collect(),
        }
        .into());
    }
    let text = read_robot_text(path)?;
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
