//! The twin (`deflex_sim::twin`, everything here is SIMULATED): the twin's own telemetry stream,
//! the served cell's geometry check. The in-process closed loop against the open loop (with the
//! paper's Table 1 model, a model identified from the twin's campaign, a model file), and what
//! needs a CELL.toml or a session over loopback, are in deflex-app's tests (`tests/it/twin`).

mod cell_server;
mod telemetry;
