//! A cell: `CELL.toml`, the link factory for both sides, a whole session from a `CELL.toml`, the
//! offline compensation's table read for the controller.

pub mod cell_run;
pub mod config;
pub mod feedforward;
pub mod links;
pub mod twin_cell_file;
