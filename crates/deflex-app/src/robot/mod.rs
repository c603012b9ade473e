//! The robot model: loading and saving robot files, and what the model commands compute —
//! the batched maths of Python's `deflex.Robot` ([`batch`]), the description of `deflex model
//! show` ([`describe`]), one configuration's pose, deflection and inverse kinematics of `deflex
//! pose`, `deflect` and `ik` ([`single`]), and the deflection map of `deflex map` ([`map`]).

use crate::error::{Error, Result};
use deflex_model::Robot;
use std::path::Path;

pub mod batch;
pub mod describe;
pub mod fk;
pub mod map;
pub mod single;

pub use batch::{
    OnFailure, ROWS_PER_TASK, check_finite, compliances, deflections, gravity_sags,
    inverse_kinematics, jacobians, pose_from_matrix, poses, row, write_pose,
};

/// A robot by built-in name or file path (TOML, possibly naming a URDF): `crate::load::load_robot`.
pub fn load(spec: &str) -> Result<Robot> {
    Ok(crate::load::load_robot(spec)?)
}

/// A built-in robot by name.
pub fn builtin(name: &str) -> Result<Robot> {
    deflex_model::builtin(name).ok_or_else(|| {
        Error::invalid(
            "name",
            format!(
                "\"{name}\" is not a built-in robot (built-in: {})",
                builtin_names().join(", ")
            ),
        )
    })
}

/// Names of the built-in robots.
pub fn builtin_names() -> Vec<&'static str> {
    deflex_model::BUILTIN_ROBOTS
        .iter()
        .map(|(n, _)| *n)
        .collect()
}

/// A robot from TOML text; `origin` names it in errors, `base_dir` resolves a URDF path.
pub fn from_toml(text: &str, origin: &str, base_dir: Option<&Path>) -> Result<Robot> {
    let resolver = crate::load::FileUrdfResolver {
        base_dir: base_dir.map(Path::to_path_buf),
    };
    Ok(deflex_model::robot_from_toml_str(
        text,
        origin,
        Some(&resolver),
    )?)
}

/// The robot as TOML, URDF paths rewritten for a file at `destination` when given.
pub fn to_toml(robot: &Robot, destination: Option<&Path>) -> String {
    match destination {
        Some(path) => crate::load::robot_to_toml_for(robot, path),
        None => deflex_model::robot_to_toml(robot),
    }
}

/// Write the robot file whole or not at all.
pub fn save(robot: &Robot, path: &Path) -> Result<()> {
    crate::table::write_text(path, &to_toml(robot, Some(path)))
}

/// Joint limits `[lo, hi]` (rad) per joint, NaN where a joint has none.
pub fn limits(robot: &Robot) -> Vec<[f64; 2]> {
    robot
        .joints
        .iter()
        .map(|j| j.limits.unwrap_or([f64::NAN, f64::NAN]))
        .collect()
}

/// The default IK seed of the CLI: the paper's forming configuration for 6 joints, else zeros.
pub fn default_seed(robot: &Robot) -> Vec<f64> {
    if robot.joint_count() == 6 {
        deflex_model::TX200_FORMING_Q_DEG
            .map(f64::to_radians)
            .to_vec()
    } else {
        vec![0.0; robot.joint_count()]
    }
}

/// True when the model knows the arm's masses (a joint's inertia or a payload): the gravity sag
/// of the TCP can then be computed.
pub fn knows_masses(robot: &Robot) -> bool {
    robot.joints.iter().any(|j| j.inertia.is_some()) || robot.payload.is_some()
}
