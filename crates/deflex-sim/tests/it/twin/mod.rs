//! The twin (`deflex_sim::twin`, everything here is SIMULATED): the in-process closed loop with
//! the paper's Table 1 model, the twin's own telemetry stream, the served cell's geometry check.
//! What needs a model identified from the twin's campaign, a CELL.toml or a session over
//! loopback is in deflex-app's tests (`tests/it/twin`), which may read them.

mod cell_server;
mod closed_loop;
mod telemetry;
