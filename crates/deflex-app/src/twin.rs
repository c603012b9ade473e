//! Workflows on the digital twin (SIMULATED): the correction controller of `deflex sim isf
//! --correction on` from an identified model file, and a model identified from the twin's own
//! calibration campaign the way a user would identify one on hardware.

use deflex_model::Robot;
use deflex_sim::CellConfig;
use deflex_sim::twin::{TwinController, TwinError, controller_config_for};
use std::path::{Path, PathBuf};

/// Why a twin workflow could not be set up.
#[derive(Debug, thiserror::Error)]
pub enum TwinSetupError {
    /// The twin refuses its settings, or the controller its configuration.
    #[error(transparent)]
    Twin(#[from] TwinError),
    /// The twin refuses its settings or its path.
    #[error(transparent)]
    Sim(#[from] deflex_sim::SimError),
    /// The controller refuses its settings.
    #[error(transparent)]
    Controller(#[from] deflex_control::ControlError),
    /// The identification from the twin's campaign failed.
    #[error(transparent)]
    Calibration(#[from] deflex_calibrate::stiffness::CalibError),
    /// The correction needs the identified model, and none was given.
    #[error("the correction needs the identified robot model: --model MODEL.toml")]
    ModelRequired,
    /// The identified model cannot be loaded.
    #[error("--model {}: {error}", path.display())]
    Model {
        /// The file.
        path: PathBuf,
        /// Why.
        error: deflex_model::ModelError,
    },
}

/// The controller for `deflex sim isf --correction on --model MODEL.toml`: `model` is the
/// identified robot (a `deflex calibrate` output, never the plant); the mounting, tool and
/// sensor range come from the twin's cell settings.
pub fn twin_controller(
    cell: &CellConfig,
    model: Option<&Path>,
) -> Result<TwinController, TwinSetupError> {
    let path = model.ok_or(TwinSetupError::ModelRequired)?;
    let robot = crate::load::load_robot(&path.display().to_string()).map_err(|error| {
        TwinSetupError::Model {
            path: path.to_path_buf(),
            error,
        }
    })?;
    Ok(TwinController::new(
        robot,
        controller_config_for(cell),
        false,
    )?)
}

/// A model identified from the twin's own calibration campaign, the way a user would do it on
/// hardware (plan for the full eDoF family → laser-tracker campaign on the twin → structure
/// search from the nominal model). Never reads the plant. Used by tests and embedders; the demo
/// runs the same steps with its reporting around them.
pub fn identify_from_twin_campaign(cell: &CellConfig, seed: u64) -> Result<Robot, TwinSetupError> {
    let nominal = cell.nominal_robot()?;
    let options = deflex_calibrate::stiffness::plan::PlanOptions {
        full_family: true,
        ..deflex_calibrate::stiffness::plan::PlanOptions::for_a_real_cell()
    };
    let plan = deflex_calibrate::stiffness::plan::plan_experiments(&nominal, &options)?;
    let rows = deflex_sim::twin_campaign::run_campaign(cell, &plan.rows, seed)?;
    let result = deflex_calibrate::stiffness::search_structure(
        &nominal,
        &rows,
        &deflex_calibrate::stiffness::SearchOptions::default(),
        &mut |_| {},
    )?;
    Ok(result.calibration.to_robot(&nominal))
}
