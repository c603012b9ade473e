//! # deflex-sim — the digital twin of the robotised ISF cell (SIMULATED)
//!
//! A simulated version of the cell of Johra et al. (Robotics 2022, 11, 48, Section 4), or of the
//! same cell around another 6-joint robot ([`profile`]): a robot whose *true* kinematics and
//! elasticity ([`plant`], on its own product-of-exponentials spring chain, [`chain`]) differ from
//! any model, its controller with an Alter/RSI/`servoj`-style correction input and servo dynamics
//! ([`controller_emulation`]), an ATI force/torque sensor with gain error, drift and a mounting
//! the controller is not told ([`sensor`]), a laser tracker with a registration error
//! ([`tracker`]), a sheet formed by a hemispherical tool with an elastic–plastic contact whose
//! Aerens force level follows the tool's actual step-down and wall angle ([`sheet`]) or a stiff
//! fixture ([`fixture`]), tool paths (cone, pyramid, plunge, G-code: [`toolpath`], [`gcode`]),
//! calibration campaigns ([`twin_campaign`]) and the forming run ([`forming`]) driven through the
//! steppable [`cell::Cell`]. Every error source is documented where it is configured
//! ([`cell_config`]) and switchable.
//!
//! **The plant is never read by a controller or by calibration**: they only get
//! [`cell::ControllerInput`] (time, measured joints, raw F/T samples) or campaign measurement
//! files. Every output is labelled SIMULATED. All randomness comes from one
//! `ChaCha8Rng` seed, so a run is reproducible bit for bit.
//!
//! See [`plant`] for the documented plant values (the `PLANT` section) and why.
//!
//! ## Measured numbers (default cell, paper cone, seed 1, no correction)
//!
//! `cargo run --release -p deflex-sim --example cone_open_loop -- OUT_DIR` (also checked by
//! `tests/it/forming.rs::paper_cone_uncorrected_acceptance`): 494 s of forming at 250 Hz
//! (123 467 cycles) simulate in ≈ 0.6 s; maximum TCP error 3.90 mm (paper: 3.84 mm), RMS
//! 2.00 mm, max Fz 1233 N (Aerens level 1260 N at the programmed step-down and wall angle), max
//! in-plane force 471 N near the end, part formed 12.1 mm deep instead of the programmed 15 mm.
//!
//! ## Using the cell from a controller
//!
//! ```no_run
//! use deflex_sim::{CellConfig, ControllerInput, CorrectionController, ToolPath, run_forming};
//! struct Hold;
//! impl CorrectionController for Hold {
//!     fn period_s(&self) -> f64 { 0.01 }
//!     fn step(&mut self, input: &ControllerInput) -> [f64; 6] {
//!         let _raw = input.wrench_samples; // sensor frame, bias and tool weight included
//!         [0.0; 6]
//!     }
//! }
//! let run = run_forming(&CellConfig::default(), ToolPath::paper_cone(), 1, Some(&mut Hold)).unwrap();
//! println!("{}", run.summary_json().unwrap());
//! ```

#![warn(missing_docs)]

pub mod cell;
pub mod cell_config;
pub mod chain;
pub mod controller_emulation;
pub mod error;
pub mod fixture;
pub mod forming;
pub mod forming_log;
pub mod gcode;
pub mod plant;
pub mod process_model;
pub mod profile;
mod range_check;
pub mod sensor;
pub mod sheet;
pub mod toolpath;
pub mod tracker;
pub mod twin;
pub mod twin_campaign;

pub use cell::{Cell, CellStep, ControllerInput, CorrectionController, SensorSample};
pub use cell_config::{CellConfig, ErrorSources, ProcessKind};
pub use error::SimError;
pub use forming::{
    CycleObserver, FormingLog, FormingRun, FormingSummary, run_forming, run_forming_with_progress,
    run_program_observed, run_program_with_progress,
};
pub use process_model::{FormingProcess, builtin_tool_path, compensated_tool_path, tcp_path};
pub use toolpath::{ConeParams, PlungeParams, PyramidParams, ToolPath, Waypoint};
