//! `deflex run`, `deflex cell` (placeholder until the control crate lands).

use crate::args::CliResult;
use clap::Args;

#[derive(Args)]
pub struct RunArgs {}
#[derive(Args)]
pub struct CellArgs {}

pub fn run(_args: RunArgs, _json: bool) -> CliResult {
    Err("run: not available in this build yet".into())
}
pub fn cell(_args: CellArgs, _json: bool) -> CliResult {
    Err("cell: not available in this build yet".into())
}
