//! # deflex-compensate
//!
//! Offline compensation of a tool path, for cells without a real-time correction option: the
//! robot is given `commanded = desired − predicted deflection`, the deflection predicted by the
//! elasto-geometrical model (eq. 15) at the joint values that reach the commanded pose, under
//! the wrench the process puts on the tool. The paper names this alternative in its
//! introduction (its refs. 33–36, e.g. Belchior et al. 2013 for robotic incremental forming).
//!
//! * [`TcpPath`]: the desired TCP poses (world frame of the robot model) with arc length,
//!   feeds and times.
//! * [`WrenchSource`]: a [`ProcessModel`] (documented so others can be added; the twin's forming
//!   model is adapted in `deflex_sim::process_model`), a process law identified from a previous
//!   run's log ([`LoggedProcess`]: the force follows the depth the tool reaches) or fixed
//!   wrenches, e.g. that log resampled on arc length ([`log`]).
//! * [`compensate()`]: the iteration against the process model until the commanded path
//!   converges, with a report per iteration; points that cannot be compensated are kept and
//!   flagged with their reason ([`PointFailure`]).
//! * [`table`]: the compensated path as a CSV text (SI columns) and back (an online controller
//!   that runs on top of a compensated program reads it into the control law's table).
//!
//! The maths is free of I/O: a log's rows come typed from the caller, which reads the file
//! through the recorder's log reader (`deflex_record`). Progress is reported as
//! [`deflex_telemetry::Progress`].

#![warn(missing_docs)]

pub mod compensate;
pub mod error;
pub mod ik;
pub mod log;
pub mod logged;
pub mod path;
pub mod process;
pub mod table;

pub use compensate::{
    CompensatedPoint, Compensation, CompensationOptions, IterationReport, PointFailure,
    WrenchSource, apply_displacement, commanded_pose, compensate,
};
pub use error::{CompensateError, LogError, PathError, ProcessError};
pub use ik::{IkFailure, TrackingIkOptions};
pub use logged::{
    Identification, LawEvidence, LoggedOptionError, LoggedProcess, LoggedProcessOptions, MARGIN,
    MAX_FALLING_SHARE, MAX_LOOP_GAIN, MIN_R2,
};
pub use path::{MAX_PATH_POINTS, PathPoint, TcpPath};
pub use process::{DepthProportional, ProcessModel, ProcessPoint};
