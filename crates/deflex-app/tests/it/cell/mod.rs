//! CELL.toml, the link factory, a session from a CELL.toml, the compensated path's table for the controller.
//!
//! * `config`: `CELL.toml` parsing, bounds and the errors that name the file and the field, the
//!   documented example (it parses, and documents every key), the link settings and the
//!   `[feedforward]` section;
//! * `links`: the link factory, both sides of every robot protocol from one `CELL.toml`, on
//!   loopback;
//! * `feedforward_table`: the feed-forward table read from `compensated_path.csv` rows;
//! * `sessions`: `deflex run` and `deflex cell --sim` as the front ends drive them, their
//!   refusals before any link opens, their file names, and both together over loopback.

mod config;
mod feedforward_table;
mod links;
mod model_check;
mod sessions;
pub(crate) mod stream_path;
