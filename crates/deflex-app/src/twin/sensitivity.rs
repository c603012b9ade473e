//! The closed loop's sensitivity sweep on the twin (`deflex sim sensitivity`, SIMULATED): the
//! correction delay, the model's compliance scale, the F/T gain error, the bias drift and the
//! contact stiffness, each varied around the cell's own values with every error source on
//! (`crate::study::sensitivity`), written as a table, a heatmap and a summary.

use crate::error::{Error, Result};
use crate::study::sensitivity::{SensitivityPlan, SensitivityResult, run_sensitivity};
use deflex_model::Robot;
use deflex_sim::CellConfig;
use serde_json::json;
use std::fmt::Write as _;
use std::path::Path;

/// The controller's model of a sweep: the identified robot in `model` (a robot file, e.g. from
/// `deflex calibrate`), else identified from a calibration campaign on the twin, as a user
/// would.
pub fn sweep_model(config: &CellConfig, model: Option<&Path>, seed: u64) -> Result<Robot> {
    Ok(match model {
        Some(path) => super::load_model(path)?,
        None => super::identify_from_twin_campaign(config, seed)?,
    })
}

/// A sensitivity sweep done.
#[derive(Clone, Debug)]
pub struct SensitivitySweep {
    /// The robot the twin played.
    pub robot: String,
    /// The cell's robot as given (built-in name or file).
    pub robot_spec: String,
    /// The controller's model's name.
    pub model: String,
    /// The seed of every run.
    pub seed: u64,
    /// What was varied.
    pub plan: SensitivityPlan,
    /// The runs' numbers.
    pub result: SensitivityResult,
}

/// Run the sweep `plan` on the twin of `config` with the controller's `model`; `progress` hears
/// the fraction of runs done.
pub fn sweep(
    config: &CellConfig,
    model: &Robot,
    plan: &SensitivityPlan,
    seed: u64,
    progress: &(dyn Fn(f64) + Sync),
) -> Result<SensitivitySweep> {
    let result = run_sensitivity(config, model, plan, seed, progress)?;
    Ok(SensitivitySweep {
        robot: super::robot_name(config),
        robot_spec: config.part.robot.clone(),
        model: model.name.clone(),
        seed,
        plan: plan.clone(),
        result,
    })
}

impl SensitivitySweep {
    /// `summary.json` (and the `--json` output): the robot, the model, the plan and every run.
    pub fn summary_value(&self) -> Result<serde_json::Value> {
        let value = |what: &'static str, v: serde_json::Result<serde_json::Value>| {
            v.map_err(|e| Error::Serialise {
                what,
                reason: e.to_string(),
            })
        };
        Ok(json!({
            "simulated": true,
            "robot": self.robot,
            "robot_spec": self.robot_spec,
            "model": self.model,
            "seed": self.seed,
            "plan": value("the sensitivity plan", serde_json::to_value(&self.plan))?,
            "result": value("the sensitivity result", serde_json::to_value(&self.result))?,
        }))
    }

    /// Write `sensitivity.csv`, `summary.json` and `sensitivity_heatmap.png` into the folder
    /// `out`, built aside and swapped in whole. Needs the `report` feature (the heatmap):
    /// refused without it, nothing written ([`SensitivitySweep::summary_value`] and
    /// `crate::report::study::csv_files::sensitivity_csv` give the text in every build).
    pub fn write(&self, out: &Path) -> Result<()> {
        let drawing = crate::report::require(
            "the sensitivity sweep's folder with its heatmap (`deflex sim sensitivity --out`)",
        )?;
        let summary = self.summary_value()?;
        let summary = serde_json::to_string_pretty(&summary).map_err(|e| Error::Serialise {
            what: "summary.json",
            reason: e.to_string(),
        })?;
        let building = deflex_files::AtomicDir::create(out).map_err(Error::io_on(out))?;
        let dir = building.path();
        for (name, text) in [
            (
                "sensitivity.csv",
                crate::report::study::csv_files::sensitivity_csv(&self.result),
            ),
            ("summary.json", summary),
        ] {
            deflex_files::write_atomic(dir.join(name), text)
                .map_err(Error::io_on(&out.join(name)))?;
        }
        drawing.sensitivity_heatmap(&self.result, &dir.join("sensitivity_heatmap.png"))?;
        building.commit().map_err(Error::io_on(out))
    }

    /// The table of every condition (mm, %, N), and the folder written.
    pub fn text(&self, out: &Path) -> String {
        let result = &self.result;
        let mut text = String::new();
        let _ = writeln!(
            text,
            "SIMULATED closed-loop sensitivity on the twin of the {} ({} runs, sensitivity cone, every error source on)",
            self.robot, result.runs
        );
        let _ = writeln!(
            text,
            "{:<22} {:<34} {:>9} {:>9} {:>8} {:>8}  fault",
            "factor", "condition", "open mm", "closed mm", "improv %", "max |F| N"
        );
        for r in &result.rows {
            let _ = writeln!(
                text,
                "{:<22} {:<34} {:>9.3} {:>9.3} {:>8.1} {:>8.0}  {}",
                r.factor,
                r.condition,
                r.open_max_mm,
                r.closed_max_mm,
                r.improvement_percent,
                r.closed_max_force_N,
                r.fault.as_deref().unwrap_or("–")
            );
        }
        let _ = writeln!(
            text,
            "wrote sensitivity.csv, sensitivity_heatmap.png, summary.json to {}",
            out.display()
        );
        text
    }
}
