//! What every exporter writes, in order: the checked path, the clearance points above its start
//! and end, the tool load, and the split into parts.
//!
//! ```text
//! safe start (vendor block) → joint move to the clearance point above the first point
//!   → approach: straight down onto the first point at the approach speed
//!   → the path (rapids as one straight move at the rapid speed), in parts when long
//!   → retract: straight up to the clearance point above the last point at the approach speed
//! ```
//!
//! **Parts.** A path of more than `program.max_points_per_part` moves (or whose motion lines
//! would pass `program.max_part_kb`) is split: the main program holds the safe start, the
//! approach and the retract and calls the parts (`NAME_p01` …) in order. The defaults (5000
//! moves, 1 MiB) are below what controllers take comfortably: RoboDK's post-processors split
//! programs at 2500–9999 lines by default (`MAX_LINES_X_PROG`, e.g. 5000 for several robot
//! brands, 9999 for Fanuc), and KUKA, ABB and UR controllers load and parse programs of a few
//! MB slowly or not at all (the issue that asked for this: a 408 kB `.src`, an 838 kB RAPID
//! module, a 650 kB URScript). Raise them for your controller knowingly. FANUC TP programs
//! stop at 2000 points a part whatever the template says (`FANUC_MAX_POINTS_PER_PART`).

use crate::program::ProgramInput;
use crate::program::common::{Checked, check_input, checked};
use crate::program::error::ProgramError;
use crate::program::settings::{Clearance, ProgramSettings};
use deflex_model::{Pose, ToolLoad};
use nalgebra::Vector3;
use std::ops::Range;

/// A program ready to write: the checked input, converted point by point as it is written
/// ([`Plan::point`]: a million-point path is not copied).
pub(crate) struct Plan<'a> {
    input: &'a ProgramInput,
    settings: &'a ProgramSettings,
    /// The clearance points above the start and the end (speed: the approach speed).
    pub clear: [Checked; 2],
    /// The parts: ranges of `points` after the first (which the approach reaches); one range
    /// when the path is not split.
    pub parts: Vec<Range<usize>>,
    /// The tool load, centre of mass in the flange frame, when known.
    pub tool_load_in_flange: Option<ToolLoad>,
}

impl Plan<'_> {
    /// The path is written in more than one file.
    pub fn split(&self) -> bool {
        self.parts.len() > 1
    }

    /// Number of path points.
    pub fn len(&self) -> usize {
        self.input.points.len()
    }

    /// Path point `i` as written (with its configuration when the caller gave them).
    pub fn point(&self, i: usize) -> Checked {
        let mut p = checked(&self.input.points[i], self.settings);
        p.config = self.input.configurations.get(i).copied();
        p
    }

    /// The path points from `from` on.
    pub fn points_from(&self, from: usize) -> impl Iterator<Item = Checked> + '_ {
        (from..self.len()).map(|i| self.point(i))
    }

    /// The blend radius at point `i` (see [`crate::program::common::blend_radius`]).
    pub fn blend_radius(&self, i: usize, blend_mm: f64) -> f64 {
        crate::program::common::blend_radius(
            i,
            self.len(),
            |k| self.input.points[k].pose.translation.vector * 1e3,
            blend_mm,
        )
    }
}

/// The clearance poses (see [`crate::program::ProgramInput::clearance_poses`]).
pub(crate) fn clearance_poses(
    input: &ProgramInput,
    settings: &ProgramSettings,
) -> Option<[Pose; 2]> {
    let first = input.points.first()?;
    let last = input.points.last()?;
    let c = settings.program.clearance_mm * 1e-3;
    Some(match settings.program.clearance {
        Clearance::Height => {
            let top = input
                .points
                .iter()
                .map(|p| p.pose.translation.vector.z)
                .fold(f64::MIN, f64::max);
            let above = |p: &Pose| {
                let t = p.translation.vector;
                Pose::from_parts(Vector3::new(t.x, t.y, top + c).into(), p.rotation)
            };
            [above(&first.pose), above(&last.pose)]
        }
        Clearance::ToolAxis => {
            let back = |p: &Pose| {
                let axis = p.rotation * Vector3::z();
                Pose::from_parts((p.translation.vector - axis * c).into(), p.rotation)
            };
            [back(&first.pose), back(&last.pose)]
        }
    })
}

/// The tool load (centre of mass in the flange frame): the template's, else the caller's.
fn tool_load_in_flange(input: &ProgramInput, settings: &ProgramSettings) -> Option<ToolLoad> {
    match settings.program.tool_mass_kg {
        Some(mass_kg) => Some(ToolLoad {
            mass_kg,
            centre_of_mass_m: Vector3::from(
                settings
                    .program
                    .tool_cog_mm
                    .unwrap_or([0.0; 3])
                    .map(|v| v * 1e-3),
            ),
        }),
        None => input.tool_load_in_flange,
    }
}

/// Check and plan a program; `line_bytes` is the longest motion line of the format (sizes the
/// parts under `max_part_kb`).
pub(crate) fn plan<'a>(
    format: &'static str,
    input: &'a ProgramInput,
    settings: &'a ProgramSettings,
    line_bytes: usize,
) -> Result<Plan<'a>, ProgramError> {
    plan_within(format, input, settings, line_bytes, usize::MAX)
}

/// [`plan`] for a format with a part limit of its own: at most `format_max_points` moves per
/// part, or `program.max_points_per_part` when lower (FANUC TP, Yaskawa INFORM).
pub(crate) fn plan_within<'a>(
    format: &'static str,
    input: &'a ProgramInput,
    settings: &'a ProgramSettings,
    line_bytes: usize,
    format_max_points: usize,
) -> Result<Plan<'a>, ProgramError> {
    check_input(format, input, settings)?;
    let count = input.points.len();
    if !input.configurations.is_empty() && input.configurations.len() != count {
        return Err(ProgramError::Mismatch {
            format,
            what: "arm configurations",
            got: input.configurations.len(),
            expected: count,
        });
    }
    let poses = clearance_poses(input, settings).expect("check_points refuses an empty path");
    let configs = input.clearance_configurations;
    let clear = [0, 1].map(|k| Checked {
        position_mm: poses[k].translation.vector * 1e3,
        rotation: poses[k].rotation,
        speed_mm_s: settings.program.approach_speed_mm_s,
        rapid: false,
        config: configs.map(|c| c[k]),
    });
    for (k, c) in clear.iter().enumerate() {
        if c.position_mm
            .iter()
            .any(|v| !v.is_finite() || v.abs() > 1e5)
        {
            return Err(ProgramError::BadValue {
                format,
                index: k * (count - 1),
                field: "clearance point",
                value: c.position_mm.norm(),
                limit: 1e5,
            });
        }
    }
    let per_part = settings
        .program
        .max_points_per_part
        .min(format_max_points)
        .min(settings.program.max_part_kb * 1024 / line_bytes.max(1))
        .max(1);
    let moves = count - 1;
    let parts: Vec<Range<usize>> = if moves <= per_part {
        std::iter::once(1..count).collect()
    } else {
        (1..count)
            .step_by(per_part)
            .map(|start| start..(start + per_part).min(count))
            .collect()
    };
    if parts.len() > 999 {
        return Err(ProgramError::PointCount {
            format,
            points: count,
            max: 999 * per_part,
        });
    }
    Ok(Plan {
        input,
        settings,
        clear,
        parts,
        tool_load_in_flange: tool_load_in_flange(input, settings),
    })
}

/// The name of part `k` (0-based) of program `name`: `NAME_p01` ….
pub(crate) fn part_name(name: &str, k: usize) -> String {
    format!("{name}_p{:02}", k + 1)
}
