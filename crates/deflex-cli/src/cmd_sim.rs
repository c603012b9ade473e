//! `deflex sim ...` (placeholder until the simulation crate lands).

use crate::args::CliResult;
use clap::Subcommand;

#[derive(Subcommand)]
pub enum SimCommand {}

pub fn sim(command: SimCommand, _json: bool) -> CliResult {
    match command {}
}
