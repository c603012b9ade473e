//! # deflex
//!
//! deflex makes industrial robots accurate under load. A serial arm bends when a process pushes
//! back on its tool; deflex models that elasticity (modified Denavit–Hartenberg kinematics and the
//! Virtual Joint Method of Johra, Courteille, Deblaise and Guégan, *Robotics* 2022, 11, 48),
//! identifies it from measurements, compensates tool paths offline and corrects them online from
//! a force/torque sensor.
//!
//! This crate is the library API: it re-exports the crates a program embeds, one module per
//! concern, and the handful of types almost every program uses at the top level. Everything is
//! SI (m, rad, N, N·m), world frame unless a name says otherwise. The command-line tool
//! (`deflex-cli`), the runtime's threads and links (`deflex-runtime`), the reports and the live
//! view are front ends built on the same crates and are not part of this API.
//!
//! | module | crate | what it holds |
//! |---|---|---|
//! | [`model`] | `deflex-model` | the read-only [`Robot`] and its scratch [`Data`]: forward kinematics, Jacobians, the Cartesian compliance and deflection of eq. 15 (δs = J K⁻¹ Jᵀ w), inverse kinematics, URDF/TOML robots |
//! | [`measurements`] | `deflex-measurements` | the measurement and plan CSV formats (parse/format, validated at parse time) |
//! | [`load`] | `deflex-load` | reading robots and measurement files from disk, every read bounded |
//! | [`stiffness`] | `deflex-stiffness` | stiffness identification (Section 3): fixed-structure fits with uncertainties, the automatic structure search, experiment planning, validation, synthetic campaigns |
//! | [`absolute`] | `deflex-absolute` | elasto-geometric calibration from absolute tracker readings: geometry, registration, gravity sag, compliances, re-registration |
//! | [`compensate`] | `deflex-compensate` | offline compensation of a tool path (commanded = desired − predicted deflection), process models, log-derived wrenches |
//! | [`gcode`] | `deflex-gcode` | the CAM G-code reader (arcs, planes, work offsets) |
//! | [`program`] | `deflex-program` | robot programs in five controller languages, written and read back |
//! | [`control`] | `deflex-control` | the force-feedback correction law (Sections 2.1, 4.2): wrench processing, eq. 15 estimate, PID of eq. 17, limiter, safety, runaway guard, feed-forward |
//! | [`sim`] | `deflex-sim` | the digital twin's cell (SIMULATED): its own plant, sensor, tracker, sheet and controller emulation |
//! | [`twin`] | `deflex-twin` | the correction law run against the twin in-process, and the twin served over a real cell's protocols |
//!
//! ## Deflection of a pose (eq. 15)
//!
//! ```
//! use deflex::{Data, Wrench, builtin};
//! let robot = builtin("tx200").expect("built in");
//! let mut data = Data::new();
//! let q = [0.0, 0.5, 1.2, 0.0, 0.6, 0.0];
//! robot.forward_kinematics(&mut data, &q)?;
//! let push_down = Wrench::new(0.0, 0.0, -1000.0, 0.0, 0.0, 0.0); // 1 kN on the tool, world −z
//! let ds = robot.tcp_deflection(&data, &push_down);
//! assert!(ds[2] < 0.0); // the tool sinks
//! let c = robot.compliance_matrix(&data); // 6×6 Cartesian compliance J K⁻¹ Jᵀ
//! assert!((c * push_down - ds).norm() < 1e-12);
//! # Ok::<(), deflex::model::QLengthError>(())
//! ```
//!
//! ## Examples
//!
//! `cargo run -p deflex --example NAME` (each prints what it computed; SIMULATED where it is):
//!
//! * `deflect_pose`: the TCP deflection and compliance of a pose under a wrench;
//! * `calibrate_csv [FILE.csv]`: stiffness identification from a measurement CSV (without a file:
//!   a SIMULATED campaign written to a temporary CSV first);
//! * `compensate_path`: an offline compensation of a circle pressed into a surface;
//! * `twin_closed_loop`: the correction law closed around the digital twin, open vs closed loop
//!   (SIMULATED).
#![warn(missing_docs)]

pub use deflex_app::load;
pub use deflex_calibrate::geometry as absolute;
pub use deflex_calibrate::measurements;
pub use deflex_calibrate::stiffness;
pub use deflex_cam::gcode;
pub use deflex_cam::program;
pub use deflex_compensate as compensate;
pub use deflex_control as control;
pub use deflex_model as model;
pub use deflex_sim as sim;
pub use deflex_sim::twin;

pub use deflex_model::{
    Axis, BUILTIN_ROBOTS, Data, Displacement, EdofSite, ModelError, Pose, Robot, Wrench, builtin,
};
