//! `deflex calibrate`, `validate`, `plan` (placeholder until the calibration crate lands).

use crate::args::CliResult;
use clap::Args;

#[derive(Args)]
pub struct CalibrateArgs {}
#[derive(Args)]
pub struct ValidateArgs {}
#[derive(Args)]
pub struct PlanArgs {}

pub fn calibrate(_args: CalibrateArgs, _json: bool) -> CliResult {
    Err("calibrate: not available in this build yet".into())
}
pub fn validate(_args: ValidateArgs, _json: bool) -> CliResult {
    Err("validate: not available in this build yet".into())
}
pub fn plan(_args: PlanArgs, _json: bool) -> CliResult {
    Err("plan: not available in this build yet".into())
}
