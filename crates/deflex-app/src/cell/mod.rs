//! A cell: `CELL.toml` ([`config`]), the link factory for both sides ([`links`]), the offline
//! compensation's table read for the controller ([`feedforward`]), a session's threads and log
//! from a `CELL.toml` ([`cell_run`]), and the two sessions both front ends drive: `deflex run`
//! ([`run_session`], its summary in [`run_summary`]) and `deflex cell --sim` ([`sim_cell`]);
//! the twin's own cell files ([`twin_cell_file`]); the joint path a FANUC Stream Motion link
//! streams, from `compensated_path.csv` ([`stream_path`]).

pub mod cell_run;
pub mod config;
pub mod feedforward;
pub mod links;
pub mod run_session;
pub mod run_summary;
pub mod sim_cell;
pub mod stream_path;
pub mod twin_cell_file;
