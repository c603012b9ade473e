//! The robot file of the simulated cell (`deflex sim robot`, Python's `deflex.sim.cell_robot`):
//! the robot with the cell's tool and base pivot, the description a user would write for that
//! cell (the start of a calibration on the twin, or a correction model).

use crate::error::Result;
use deflex_model::Robot;
use deflex_sim::CellConfig;
use deflex_sim::profile::CellSummary;
use serde_json::json;
use std::fmt::Write as _;
use std::path::{Path, PathBuf};

/// The robot file of the simulated cell: the robot with the cell's tool and base pivot.
pub fn cell_robot(config: &CellConfig) -> Result<Robot> {
    Ok(config.nominal_robot()?)
}

/// The cell's robot file, written.
#[derive(Clone, Debug)]
pub struct CellRobotFile {
    /// The robot written.
    pub robot: Robot,
    /// The cell it belongs to.
    pub cell: CellSummary,
    /// The file.
    pub out: PathBuf,
}

/// Write the robot file of the cell `config` to `out`, whole or not at all, with a header saying
/// it describes the SIMULATED cell (a URDF path it names is rewritten for `out`'s folder).
pub fn write_cell_robot(config: &CellConfig, out: &Path) -> Result<CellRobotFile> {
    let robot = cell_robot(config)?;
    let cell = config.summary()?;
    let text = format!(
        "# The robot description of the SIMULATED deflex cell of `{}`: the robot file with the\n\
         # cell's tool and base pivot, as a user would describe that cell.\n{}",
        config.part.robot,
        crate::load::robot_to_toml_for(&robot, out)
    );
    crate::table::write_text(out, &text)?;
    Ok(CellRobotFile {
        robot,
        cell,
        out: out.to_path_buf(),
    })
}

impl CellRobotFile {
    /// As JSON (SI).
    pub fn to_json(&self) -> serde_json::Value {
        json!({
            "simulated": true,
            "robot": self.robot.name,
            "geometry_fingerprint": self.robot.geometry_fingerprint(),
            "tool_xyz_m": self.robot.tool.translation.vector.as_slice(),
            "cell": self.cell.to_json(),
            "out": self.out,
        })
    }

    /// As text (mm), with the cell.
    pub fn text(&self) -> String {
        let robot = &self.robot;
        let t = robot.tool.translation.vector * 1e3;
        let mut out = String::new();
        let _ = writeln!(
            out,
            "SIMULATED cell robot {} (tool {:.1} {:.1} {:.1} mm, geometry {}) → {}",
            robot.name,
            t.x,
            t.y,
            t.z,
            robot.geometry_fingerprint(),
            self.out.display()
        );
        let _ = writeln!(out, "{}", self.cell);
        out
    }
}
