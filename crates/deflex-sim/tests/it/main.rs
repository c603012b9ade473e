//! Integration tests of `deflex-sim`: one test binary (modules below), so a fresh clone links one
//! executable for this crate instead of one per file. The twin's tests are in [`twin`]; the
//! fuzzing of the twin's parsers is in the facade's test binary (`fuzz::sim`).

mod cell_config;
mod cells;
mod chain;
mod controller_emulation;
mod fixture;
mod forming;
mod gcode;
mod joint_stream;
mod plant;
mod process_model;
mod reported_pose;
mod sensor;
mod sheet;
mod toolpath;
mod tracker;
mod twin;
mod twin_campaign;
