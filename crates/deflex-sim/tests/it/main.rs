//! Integration tests of `deflex-sim`: one test binary (modules below), so a fresh clone links one
//! executable for this crate instead of one per file.

mod cells;
mod forming;
mod fuzz;
mod process_model;
mod unseen_plant;
