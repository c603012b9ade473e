//! No parser panics, whatever its input: one module per layer's parsers.

pub mod engine;

mod calibrate;
mod cam;
mod cell_config;
mod io;
mod model;
mod sim;
