//! Workflows on the digital twin (SIMULATED), one implementation under `deflex sim …` and
//! Python's `deflex.sim`: the twin's cell for a robot or a cell file and its robot file
//! ([`cell_robot()`]), the tool path from its name ([`path`]), a forming run open or closed loop
//! with the outlets a front end attaches and its output folder ([`form()`], [`run_folder`]), the
//! measurement campaigns ([`campaign`]), the closed loop's sensitivity sweep ([`sensitivity`]),
//! the correction controller from an identified model file, and a model identified from the
//! twin's own calibration campaign the way a user would identify one on hardware.

use crate::error::Result;
use deflex_model::Robot;
use deflex_sim::CellConfig;
use deflex_sim::twin::{TwinController, TwinError, controller_config_for};
use std::path::{Path, PathBuf};

pub mod campaign;
pub mod cell_robot;
pub mod form;
pub mod path;
pub mod run_folder;
pub mod sensitivity;

pub use cell_robot::{CellRobotFile, cell_robot, write_cell_robot};
pub use form::{
    FormConflict, FormCorrection, FormOptions, FormingSetup, Outlets, TwinRun, check_correction,
    form, log_columns, log_table, summary_json,
};
pub use path::{PathChoice, tool_path};
pub use run_folder::{PLOT_DIR, RECORDING, RunFolder, RunRecording, WrittenRun, write_outputs};

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
    Ok(TwinController::new(
        load_model(path)?,
        controller_config_for(cell),
        false,
    )?)
}

/// The identified model the correction controller uses (`--model MODEL.toml`): a robot file,
/// or a built-in name; an error names the option and the file.
pub fn load_model(path: &Path) -> Result<Robot, TwinSetupError> {
    crate::load::load_robot(&path.display().to_string()).map_err(|error| TwinSetupError::Model {
        path: path.to_path_buf(),
        error,
    })
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

/// The twin's cell (the CLI's `load_config`): the robot's cell (`robot`, a built-in name or
/// robot file, else the twin file's, else the TX200's) with the twin file's settings over it.
pub fn cell_config(robot: Option<&str>, config: Option<&Path>) -> Result<CellConfig> {
    Ok(match (config, robot) {
        (Some(p), robot) => crate::cell::twin_cell_file::load_cell(p, robot)?,
        (None, Some(robot)) => crate::cell::twin_cell_file::cell_for_robot(robot)?,
        (None, None) => CellConfig::default(),
    })
}

/// The name of the robot the twin of `config` plays, for outputs: the nominal robot's, else the
/// cell's robot as given (a cell whose robot cannot be built is named as the user named it).
pub fn robot_name(config: &CellConfig) -> String {
    config
        .nominal_robot()
        .map(|r| r.name)
        .unwrap_or_else(|_| config.part.robot.clone())
}
