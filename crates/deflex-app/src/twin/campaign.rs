//! Measurement campaigns on the twin (`deflex sim campaign`, SIMULATED): a calibration plan, a
//! validation grid of dead-weight loads or the spiral of Fig. 14, measured on the twin's true
//! robot with the simulated laser tracker and load cell, written in the measurement format.

use crate::error::Result;
use deflex_calibrate::measurements::{MeasurementRow, load_case_count};
use deflex_sim::CellConfig;
use deflex_sim::twin_campaign::{
    GridParams, SpiralParams, campaign_text, run_campaign, spiral, validation_grid,
};
use serde_json::json;
use std::fmt::Write as _;
use std::path::{Path, PathBuf};

/// Which validation grid: the robot cell's (the paper's for the TX200) or the paper's.
// Plain comments on the variants: doc comments would become clap's help text and change the
// CLI's `--help`.
#[allow(missing_docs)]
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
#[cfg_attr(feature = "clap", derive(clap::ValueEnum))]
pub enum GridChoice {
    // The robot cell's grid.
    #[default]
    Cell,
    // The paper's grid.
    Paper,
}

impl GridChoice {
    /// The name the CLI uses.
    pub fn name(self) -> &'static str {
        match self {
            GridChoice::Cell => "cell",
            GridChoice::Paper => "paper",
        }
    }
}

/// The grid `choice` of the cell `config`: the cell's own (the paper's for the TX200) or the
/// paper's (200 poses, 600 N and 1100 N, at the TX200's work area), for a front end to adjust.
pub fn grid_params(choice: GridChoice, config: &CellConfig) -> Result<GridParams> {
    Ok(match choice {
        GridChoice::Paper => GridParams::paper(),
        GridChoice::Cell => GridParams::for_cell(config)?,
    })
}

/// The spiral of Fig. 14 of the cell `config` (the paper's for the TX200), for a front end to
/// adjust.
pub fn spiral_params(config: &CellConfig) -> Result<SpiralParams> {
    Ok(SpiralParams::for_cell(config)?)
}

/// What a campaign measures.
#[derive(Clone, Debug)]
pub enum CampaignKind {
    /// A plan file (the measurement format without displacement columns).
    Plan(PathBuf),
    /// A validation grid.
    Grid(GridParams),
    /// A spiral (Fig. 14).
    Spiral(SpiralParams),
}

/// A campaign measured on the twin and written.
#[derive(Clone, Debug)]
pub struct CampaignFile {
    /// What was measured, in words.
    pub campaign: String,
    /// The rows measured.
    pub rows: Vec<MeasurementRow>,
    /// The robot the twin played.
    pub robot: String,
    /// The cell's robot as given (built-in name or file).
    pub robot_spec: String,
    /// The seed of the tracker and load-cell noise.
    pub seed: u64,
    /// The file written.
    pub out: PathBuf,
}

/// Measure `what` on the twin of `config` with the noise of `seed` and write the campaign to
/// `out`, whole or not at all: the `# SIMULATED` header, the robot lines (a plan's own when it
/// names its robot), the rows.
pub fn measure(
    config: &CellConfig,
    what: &CampaignKind,
    seed: u64,
    out: &Path,
) -> Result<CampaignFile> {
    let mut plan_header = None;
    let (campaign, rows) = match what {
        CampaignKind::Plan(plan) => {
            let plan_file = crate::load::read_file(plan, None, false)?;
            let rows = run_campaign(config, &plan_file.rows, seed)?;
            plan_header = Some(plan_file.header);
            (format!("plan {}", plan.display()), rows)
        }
        CampaignKind::Grid(params) => {
            params.validate()?;
            let plan = validation_grid(config, params)?;
            let rows = run_campaign(config, &plan, seed)?;
            let loads: Vec<String> = params.loads_n.iter().map(|l| format!("{l:.0} N")).collect();
            (
                format!(
                    "validation grid {} × {} over {:.3} × {:.3} m at z = {:.3} m, {}",
                    params.points_xy[0],
                    params.points_xy[1],
                    params.size_xy_m[0],
                    params.size_xy_m[1],
                    params.height_m,
                    loads.join(" and ")
                ),
                rows,
            )
        }
        CampaignKind::Spiral(params) => {
            params.validate()?;
            let rows = spiral(config, params, seed)?;
            (
                format!(
                    "spiral (Fig. 14) {:.3} m long at z = {:.3} m, {:.0} N",
                    params.length_m, params.center_m[2], params.load_n
                ),
                rows,
            )
        }
    };
    let text = campaign_text(config, &rows, &campaign, seed, plan_header.as_ref())?;
    crate::table::write_text(out, &text)?;
    Ok(CampaignFile {
        campaign,
        rows,
        robot: super::robot_name(config),
        robot_spec: config.part.robot.clone(),
        seed,
        out: out.to_path_buf(),
    })
}

impl CampaignFile {
    /// Load cases of the campaign and its largest displacement (m).
    fn counts(&self) -> (usize, f64) {
        let max = self
            .rows
            .iter()
            .filter_map(|r| r.displacement_m)
            .map(|d| (d[0] * d[0] + d[1] * d[1] + d[2] * d[2]).sqrt())
            .fold(0.0, f64::max);
        (load_case_count(&self.rows), max)
    }

    /// As JSON (SI).
    pub fn to_json(&self) -> serde_json::Value {
        let (cases, max) = self.counts();
        json!({
            "simulated": true,
            "robot": self.robot,
            "robot_spec": self.robot_spec,
            "campaign": self.campaign,
            "seed": self.seed,
            "rows": self.rows.len(),
            "load_cases": cases,
            "max_displacement_m": max,
            "out": self.out.display().to_string(),
        })
    }

    /// As text (mm).
    pub fn text(&self) -> String {
        let (cases, max) = self.counts();
        let mut out = String::new();
        let _ = writeln!(
            out,
            "SIMULATED campaign on the twin of the {}: {}",
            self.robot, self.campaign
        );
        let _ = writeln!(
            out,
            "  {} rows in {} load cases, largest displacement {:.3} mm → {}",
            self.rows.len(),
            cases,
            max * 1e3,
            self.out.display()
        );
        out
    }
}
