//! # deflex
//!
//! deflex makes industrial robots accurate under load. A serial arm bends when a process pushes
//! back on its tool; deflex models that elasticity (modified Denavit–Hartenberg kinematics and the
//! Virtual Joint Method of Johra, Courteille, Deblaise and Guégan, *Robotics* 2022, 11, 48),
//! identifies it from measurements, compensates tool paths offline and corrects them online from
//! a force/torque sensor.
//!
//! This crate is the library API: one module per library package, each re-exported whole under
//! the name of its role, and at the top level the handful of types almost every program uses.
//! Everything is SI (m, rad, N, N·m), world frame unless a name says otherwise. It includes
//! **every library layer** of the workspace (docs/src/architecture.md), and nothing else:
//!
//! | module | package (layer) | what it holds |
//! |---|---|---|
//! | [`model`] | `deflex-model` (0, foundation) | the read-only [`Robot`] and its scratch [`Data`]: forward kinematics, Jacobians, the Cartesian compliance and deflection of eq. 15 (δs = J K⁻¹ Jᵀ w), inverse kinematics, gravity, `Pose`/`Wrench`/`ToolLoad`, every vendor's orientation convention, robots from TOML/URDF text |
//! | [`files`] | `deflex-files` (0) | whole-or-nothing outputs and bounded inputs |
//! | [`plot`] | `deflex-plot` (0) | plots and self-contained HTML pages from plain data, drawn into memory |
//! | [`telemetry`] | `deflex-telemetry` (1, messages) | the per-cycle sample, session info, phases, flags, faults, a long job's progress, the wait-free ring, their ROS 2 forms |
//! | [`calibrate`] | `deflex-calibrate` (2, science) | stiffness identification (Section 3), elasto-geometric calibration from absolute readings, their measurement formats |
//! | [`compensate`] | `deflex-compensate` (2) | offline compensation of a tool path (commanded = desired − predicted deflection) |
//! | [`control`] | `deflex-control` (2) | the force-feedback correction law (Sections 2.1, 4.2): wrench processing, eq. 15 estimate, PID of eq. 17, limiter, safety, runaway guard, feed-forward |
//! | [`cam`] | `deflex-cam` (2) | G-code in; robot programs in five languages written and read back; calibrated geometry out (URDF, UR calibration, DH table) |
//! | [`io`] | `deflex-io` (3, links) | the robot and sensor protocols, both sides |
//! | [`record`] | `deflex-record` (4, outlets) | the run log (CSV), MCAP recordings, run traces |
//! | [`view`] | `deflex-view` (4) | the live browser view of a session |
//! | [`runtime`] | `deflex-runtime` (5, runtime) | the real-time session: threads, clock, typed messages, send shaper |
//! | [`sim`] | `deflex-sim` (6, simulation) | the digital twin (SIMULATED): its own plant, sensor, tracker, sheet and robot controller; the twin in closed loop, served over the protocols, in simulated time |
//! | [`app`] | `deflex-app` (7, application) | the workflows of the `deflex` command and the Python package: CELL.toml and sessions, calibrations, compensation and programs, the twin's runs, the study, report pages (its `report` feature, on here), the user's files |
//!
//! Not included: the ROS 2 bridge (`deflex-ros2`, an outlet with a large DDS dependency: depend on
//! it directly), and the front ends (the `deflex` command line, the Python package).
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

pub use deflex_app as app;
pub use deflex_calibrate as calibrate;
pub use deflex_cam as cam;
pub use deflex_compensate as compensate;
pub use deflex_control as control;
pub use deflex_files as files;
pub use deflex_io as io;
pub use deflex_model as model;
pub use deflex_plot as plot;
pub use deflex_record as record;
pub use deflex_runtime as runtime;
pub use deflex_sim as sim;
pub use deflex_telemetry as telemetry;
pub use deflex_view as view;

pub use deflex_model::{
    Axis, BUILTIN_ROBOTS, Data, Displacement, EdofSite, ModelError, Pose, Robot, Wrench, builtin,
};
