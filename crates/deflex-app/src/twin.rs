//! Workflows on the digital twin (SIMULATED): the twin's cell for a robot or a cell file, a
//! forming run (`deflex sim isf`, Python's `deflex.sim.form`), the correction controller of
//! `deflex sim isf --correction on` from an identified model file, and a model identified from
//! the twin's own calibration campaign the way a user would identify one on hardware.

use crate::error::{Error, Result, bounded};
use crate::load::gcode_file::read_gcode;
use deflex_model::Robot;
use deflex_sim::twin::{TwinController, TwinError, controller_config_for};
use deflex_sim::{
    CellConfig, ConeParams, FormingRun, PlungeParams, ProcessKind, PyramidParams, ToolPath,
    run_forming,
};
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

/// The twin's cell (the CLI's `load_config`): the robot's cell (`robot`, a built-in name or
/// robot file, else the twin file's, else the TX200's) with the twin file's settings over it.
pub fn cell_config(robot: Option<&str>, config: Option<&Path>) -> Result<CellConfig> {
    Ok(match (config, robot) {
        (Some(p), robot) => crate::cell::twin_cell_file::load_cell(p, robot)?,
        (None, Some(robot)) => crate::cell::twin_cell_file::cell_for_robot(robot)?,
        (None, None) => CellConfig::default(),
    })
}

/// The robot file of the simulated cell: the robot with the cell's tool and base pivot.
pub fn cell_robot(config: &CellConfig) -> Result<Robot> {
    Ok(config.nominal_robot()?)
}

/// Options of a forming run (the CLI's flags, SI).
#[derive(Clone, Debug, Default)]
pub struct FormOptions {
    /// The robot the twin plays (built-in name or robot file).
    pub robot: Option<String>,
    /// Twin settings (`[cell]` TOML).
    pub config: Option<PathBuf>,
    /// Random seed (sensor and tracker noise).
    pub seed: u64,
    /// Only the first part of the path (m of travel).
    pub length_m: Option<f64>,
    /// Feed of the built-in paths (m/s).
    pub feed_m_s: Option<f64>,
    /// Contact stiffness of the fixture for `plunge` (N/m).
    pub fixture_stiffness_n_m: Option<f64>,
    /// The identified model the correction controller uses: `Some` runs the closed loop.
    pub correction_model: Option<Robot>,
}

/// The tool path of `deflex sim isf --path`: `cone`, `cone-contour`, `pyramid`, `plunge` or a
/// G-code file, with the feed and the length of the CLI.
pub fn tool_path(spec: &str, feed_m_s: Option<f64>, length_m: Option<f64>) -> Result<ToolPath> {
    let feed = match feed_m_s {
        Some(f) => Some(bounded("feed_m_s", f, 1e-4, 1.0, "m/s")? * 1e3),
        None => None,
    };
    let path = match spec {
        "cone" | "cone-contour" => {
            let mut p = ConeParams {
                helical: spec == "cone",
                ..ConeParams::default()
            };
            if let Some(f) = feed {
                p.feed_mm_s = f;
            }
            ToolPath::cone(&p)?
        }
        "pyramid" => {
            let mut p = PyramidParams::default();
            if let Some(f) = feed {
                p.feed_mm_s = f;
            }
            ToolPath::pyramid(&p)?
        }
        "plunge" => {
            let mut p = PlungeParams::default();
            if let Some(f) = feed {
                p.traverse_feed_mm_s = f;
            }
            ToolPath::plunge(&p)?
        }
        file => {
            if feed.is_some() {
                return Err(Error::invalid(
                    "feed_m_s",
                    "applies to the built-in paths; a G-code file sets its own F",
                ));
            }
            read_gcode(Path::new(file))?
        }
    };
    Ok(match length_m {
        Some(l) => path.truncated(bounded("length_m", l, 1e-6, 1e3, "m")? * 1e3),
        None => path,
    })
}

/// A finished twin run.
pub struct TwinRun {
    /// The run (log, summary, profiles).
    pub run: FormingRun,
    /// The cell it ran in.
    pub config: CellConfig,
    /// The correction controller's status line (closed loop only).
    pub controller_status: Option<String>,
}

/// `deflex sim isf`: form `path` on the twin, closed loop when a correction model is given.
pub fn form(path: &str, options: &FormOptions) -> Result<TwinRun> {
    let mut config = cell_config(options.robot.as_deref(), options.config.as_deref())?;
    if path == "plunge" {
        config.process.kind = ProcessKind::Fixture;
    }
    if let Some(k) = options.fixture_stiffness_n_m {
        if path != "plunge" {
            return Err(Error::invalid(
                "fixture_stiffness_n_m",
                "applies to the path \"plunge\"",
            ));
        }
        config.process.fixture_stiffness_n_m =
            bounded("fixture_stiffness_n_m", k, 1e4, 1e9, "N/m")?;
    }
    let tool_path = tool_path(path, options.feed_m_s, options.length_m)?;
    // Closed loop: the deflex correction controller in-process, in simulated time, with the
    // nominal mounting and tool of the cell (never the plant's).
    let (run, controller_status) = match &options.correction_model {
        Some(model) => {
            let closed = deflex_sim::twin::run_closed_loop(
                &config,
                tool_path,
                options.seed,
                model.clone(),
                deflex_sim::twin::controller_config_for(&config),
                false,
                &mut |_| {},
            )?;
            (closed.forming, Some(closed.status))
        }
        None => (run_forming(&config, tool_path, options.seed, None)?, None),
    };
    Ok(TwinRun {
        run,
        config,
        controller_status,
    })
}

/// The run's summary as the CLI's `summary.json` text.
pub fn summary_json(run: &TwinRun) -> String {
    run.run.summary_json()
}

/// The run's outputs (`log.csv`, `summary.json`, `profile.csv`, plots), written whole into
/// `dir`.
pub fn write_outputs(run: &TwinRun, dir: &Path) -> Result<Vec<PathBuf>> {
    crate::report::forming_run::write_forming_run(&run.run, dir).map_err(|source| {
        Error::Report(crate::report::PageError {
            report: "forming run",
            source,
        })
    })
}

/// The log as SI columns (part frame R_p; the wrench on the tool at the TCP; the correction
/// applied; the contact state). One row per logged cycle.
pub fn log_columns(run: &TwinRun) -> Vec<(&'static str, Vec<f64>)> {
    let rows = &run.run.log.rows;
    let col = |f: &dyn Fn(&deflex_sim::forming::LogRow) -> f64| rows.iter().map(f).collect();
    let mut out: Vec<(&'static str, Vec<f64>)> = vec![("time_s", col(&|r| r.time_s))];
    type Pick = fn(&deflex_sim::forming::LogRow) -> nalgebra::Vector3<f64>;
    let vectors: [(&str, Pick); 5] = [
        ("des", |r| r.truth.desired_m),
        ("cmd", |r| r.truth.commanded_m),
        ("true", |r| r.truth.true_m),
        ("tracked", |r| r.tracked_m),
        ("err", |r| r.truth.path_error_m()),
    ];
    const NAMES: [[&str; 3]; 5] = [
        ["des_x_m", "des_y_m", "des_z_m"],
        ["cmd_x_m", "cmd_y_m", "cmd_z_m"],
        ["true_x_m", "true_y_m", "true_z_m"],
        ["tracked_x_m", "tracked_y_m", "tracked_z_m"],
        ["err_x_m", "err_y_m", "err_z_m"],
    ];
    for ((_, pick), names) in vectors.iter().zip(NAMES) {
        for (k, name) in names.iter().enumerate() {
            out.push((name, col(&|r| pick(r)[k])));
        }
    }
    out.push(("err_norm_m", col(&|r| r.truth.path_error_m().norm())));
    for (k, name) in ["fx_N", "fy_N", "fz_N", "mx_Nm", "my_Nm", "mz_Nm"]
        .iter()
        .enumerate()
    {
        out.push((name, col(&|r| r.truth.wrench[k])));
    }
    for (k, name) in [
        "sensor_fx_N",
        "sensor_fy_N",
        "sensor_fz_N",
        "sensor_tx_Nm",
        "sensor_ty_Nm",
        "sensor_tz_Nm",
    ]
    .iter()
    .enumerate()
    {
        out.push((name, col(&|r| r.sensor.wrench_sensor[k])));
    }
    out.push((
        "sensor_saturated",
        col(&|r| if r.sensor.saturated { 1.0 } else { 0.0 }),
    ));
    for (k, name) in [
        "corr_x_m",
        "corr_y_m",
        "corr_z_m",
        "corr_rx_rad",
        "corr_ry_rad",
        "corr_rz_rad",
    ]
    .iter()
    .enumerate()
    {
        out.push((name, col(&|r| r.truth.correction[k])));
    }
    for (k, name) in [
        "defl_x_m",
        "defl_y_m",
        "defl_z_m",
        "defl_rx_rad",
        "defl_ry_rad",
        "defl_rz_rad",
    ]
    .iter()
    .enumerate()
    {
        out.push((name, col(&|r| r.truth.deflection[k])));
    }
    out.push(("penetration_m", col(&|r| r.truth.contact.penetration_m)));
    out.push(("flow_level_N", col(&|r| r.truth.contact.flow_n)));
    out.push(("tool_depth_m", col(&|r| r.truth.contact.depth_m)));
    out
}
