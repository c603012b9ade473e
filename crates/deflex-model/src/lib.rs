//! # deflex-model
//!
//! The elasto-geometrical robot model of Johra et al. (2022), *Robotics* 11, 48, Section 2.2:
//! serial kinematics written as modified Denavit–Hartenberg parameters or a URDF chain, plus the
//! Virtual Joint Method (VJM): torsional springs ("elastic degrees of freedom", eDoFs) about the
//! x, y and/or z axis of each joint frame, with the spring centre allowed to slide along the joint
//! axis (the paper's δr), and optional base eDoFs (baseplate tilt).
//!
//! The crate follows Pinocchio's split: a read-only [`Robot`] (the model) and a [`Data`] scratch
//! space that the hot path fills without allocating. All quantities are SI (m, rad, N, N·m) and
//! expressed in the world frame unless a name says otherwise.
//!
//! The spatial types every other deflex crate uses are written here once: [`Pose`], [`Wrench`],
//! [`Displacement`], [`ToolLoad`], [`MAX_JOINTS`], and every vendor's orientation convention
//! (KUKA A-B-C, ABB quaternion, Stäubli X-Y'-Z'', the rotation vector) in [`conventions`], which
//! the programs (`deflex_cam::program`) and the wire protocols (`deflex_io`) share. The model
//! reads no file: robot descriptions come as text ([`robot_from_toml_str`]; the built-in ones
//! are compiled in from this crate's `robots/` folder).
//!
//! ```
//! use deflex_model::{Robot, Data, builtin};
//! let robot = builtin("tx200").unwrap();
//! let mut data = Data::new();
//! let q = [0.0, 49.7f64.to_radians(), 89.3f64.to_radians(), 0.0, 41f64.to_radians(), 0.0];
//! robot.forward_kinematics(&mut data, &q).unwrap();
//! let w = deflex_model::Wrench::new(0.0, 0.0, 1000.0, 0.0, 0.0, 0.0);
//! let ds = robot.tcp_deflection(&data, &w);
//! assert!(ds[2] > 0.0); // pushed up by an upward force
//! ```

#![warn(missing_docs)]

mod compliance;
pub mod conventions;
mod description;
pub mod dh;
mod error;
mod gravity;
mod inverse_kinematics;
mod kinematics;
mod robot;
pub mod spatial;
mod urdf;
pub mod wrench_transport;

pub use compliance::EdofColumns;
pub use description::{
    BUILTIN_ROBOTS, ResolvedUrdf, UrdfResolver, builtin, geometry_fingerprint, parse_edof_label,
    robot_from_toml_and_urdf_str, robot_from_toml_str, robot_to_toml, robot_to_toml_with_urdf_path,
};
pub use error::{ModelError, QLengthError};
pub use inverse_kinematics::{IkOptions, IkSolution, damped_gram, damped_least_squares_step};
pub use kinematics::Data;
pub use robot::{
    Axis, AxisStiffness, ComplianceCoupling, DhConvention, DhParams, Edof, EdofSite, Joint,
    LinkInertia, MAX_COUPLINGS, NamedPoint, NamedPose, Robot, STANDARD_GRAVITY, UrdfSource, bounds,
};
pub use spatial::{Displacement, Pose, ToolLoad, Wrench, edof_screw};

/// The paper's forming configuration of the TX200, in degrees: the TCP at the part origin
/// (≈ [1499, 0, −183] mm), tool pointing down. A good IK seed near the ISF cell.
pub const TX200_FORMING_Q_DEG: [f64; 6] = [0.0, 49.7, 89.3, 0.0, 41.0, 0.0];

/// Largest number of motorised joints a [`Robot`] may have (fixed so [`Data`] needs no heap).
pub const MAX_JOINTS: usize = 8;
/// Largest number of eDoFs: three per joint plus three at the base.
pub const MAX_EDOFS: usize = 3 * MAX_JOINTS + 3;
