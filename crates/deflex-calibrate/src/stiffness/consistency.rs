//! Do a file's rows belong to this robot? Every measurement row gives joint values *and* the
//! world coordinates of its measured point and load point (unloaded pose). Forward kinematics
//! of the joint values must put those points where the file says, up to the tracker's noise:
//!
//! * a `TCP` point on the last link is compared directly with the TCP of the joint values, a
//!   point named after one of the robot's flange targets (`[[target]]`) with that target;
//! * any other measured point (M1–M3 on links, the base reflector M0) is not known to the robot
//!   file, but it is fixed to its link: its coordinates in its link's frame must be the same in
//!   every load case. Rows are grouped by (point label, link); each row is compared with the
//!   component-wise median of its group in the link frame. A group whose link frame is the
//!   same in all its rows (one configuration of the joints before it, or the base) cannot be
//!   checked and is reported as such;
//! * a load point that coincides (within the tolerance) with a point measured in the same load
//!   case is covered by that point's check; one at the TCP of its joint values agrees directly;
//!   the others are grouped by load link and checked for consistency like measured points.
//!
//! A measurement of one robot given with another robot's file fails this at almost every row
//! (hundreds of millimetres at the TCP), while a good file passes with the tracker's noise and
//! the robot's geometric errors well inside the default tolerance, [`DEFAULT_FK_TOLERANCE_M`]
//! (1 mm). The file's header (`# robot:`, `# geometry:`) is compared with the robot too.

use crate::measurements::{FileHeader, MeasurementRow};
use crate::stiffness::{CalibError, RowsError};
use deflex_model::{Data, Robot};
use nalgebra::{Point3, Vector3};
use std::collections::BTreeMap;

/// Default largest distance between a row's coordinates and forward kinematics (m): 1 mm, far
/// above a tracker's noise (tens of µm) and a nominal model's geometric error (tenths of a
/// millimetre), far below what another robot's file gives (hundreds of millimetres).
pub const DEFAULT_FK_TOLERANCE_M: f64 = 1e-3;
/// Smallest tolerance accepted (m).
pub const MIN_FK_TOLERANCE_M: f64 = 1e-6;
/// Largest tolerance accepted (m).
pub const MAX_FK_TOLERANCE_M: f64 = 1.0;
/// How many disagreeing rows a message names.
pub const ROWS_NAMED: usize = 5;

/// What a row's coordinates were compared with.
#[derive(Clone, Debug, PartialEq)]
pub enum Reference {
    /// The TCP of the row's joint values.
    Tcp,
    /// A flange target of the robot file, by name.
    FlangeTarget(String),
    /// The median position of the same point in its link's frame over the file.
    LinkPoint {
        /// Link carrying the point.
        link: usize,
    },
    /// The median position of the load points of this link in its frame over the file.
    LoadPoint {
        /// Link carrying the load.
        link: usize,
    },
}

/// A row whose coordinates disagree with forward kinematics.
#[derive(Clone, Debug, PartialEq)]
pub struct Disagreement {
    /// Row index (0-based, in file order).
    pub row: usize,
    /// Line in the file, when known.
    pub line: Option<u64>,
    /// Load case of the row.
    pub load_case: String,
    /// The measured point's label (for a load point too: the row's point).
    pub point: String,
    /// What the coordinates were compared with.
    pub reference: Reference,
    /// Distance to the reference (m).
    pub distance_m: f64,
}

impl std::fmt::Display for Disagreement {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        let at = match self.line {
            Some(line) => format!("line {line}"),
            None => format!("row {}", self.row + 1),
        };
        let mm = self.distance_m * 1e3;
        match &self.reference {
            Reference::Tcp => write!(
                f,
                "{at} (load case {}, point {}): {mm:.3} mm from the TCP its joint values give",
                self.load_case, self.point
            ),
            Reference::FlangeTarget(name) => write!(
                f,
                "{at} (load case {}, point {}): {mm:.3} mm from flange target {name} at its joint values",
                self.load_case, self.point
            ),
            Reference::LinkPoint { link } => write!(
                f,
                "{at} (load case {}, point {} on link {link}): {mm:.3} mm from where the other load cases put it in link {link}'s frame",
                self.load_case, self.point
            ),
            Reference::LoadPoint { link } => write!(
                f,
                "{at} (load case {}, load point on link {link}): {mm:.3} mm from where the other load cases put it in link {link}'s frame",
                self.load_case
            ),
        }
    }
}

/// The outcome of [`check_geometry`].
#[derive(Clone, Debug, PartialEq)]
pub struct GeometryCheck {
    /// The robot checked against.
    pub robot: String,
    /// Its geometry fingerprint.
    pub geometry: String,
    /// Tolerance used (m).
    pub tolerance_m: f64,
    /// Rows in the file.
    pub rows: usize,
    /// Measured points checked (directly or by consistency).
    pub checked_points: usize,
    /// Load points checked (directly, through a measured point, or by consistency).
    pub checked_loads: usize,
    /// Every disagreement above the tolerance, in row order (measured point before load point).
    pub disagreements: Vec<Disagreement>,
    /// Point groups that could not be checked, with the reason.
    pub unchecked: Vec<String>,
    /// Largest distance seen, checked rows only (m).
    pub max_distance_m: f64,
    /// The header names another robot or geometry: what it says.
    pub header_mismatch: Option<String>,
}

impl GeometryCheck {
    /// No row disagrees.
    pub fn passed(&self) -> bool {
        self.disagreements.is_empty()
    }

    /// Rows with at least one disagreement.
    pub fn disagreeing_rows(&self) -> usize {
        let mut rows: Vec<usize> = self.disagreements.iter().map(|d| d.row).collect();
        rows.dedup();
        rows.len()
    }

    /// A message naming the first disagreeing rows and their distances (and the header's robot
    /// when it names another one).
    pub fn describe(&self, origin: &str) -> String {
        let mut out = format!(
            "{origin}: {} of {} rows disagree with the forward kinematics of robot \"{}\" (geometry {}) by more than {:.3} mm (largest {:.3} mm); first rows:",
            self.disagreeing_rows(),
            self.rows,
            self.robot,
            self.geometry,
            self.tolerance_m * 1e3,
            self.max_distance_m * 1e3
        );
        for d in self.disagreements.iter().take(ROWS_NAMED) {
            out.push_str(&format!("\n  {d}"));
        }
        if let Some(header) = &self.header_mismatch {
            out.push_str(&format!("\n{header}"));
        }
        out
    }
}

/// A file refused by [`enforce`]: its rows do not match the robot.
#[derive(Clone, Debug, PartialEq)]
pub struct GeometryMismatch {
    /// File name.
    pub origin: String,
    /// The check.
    pub check: GeometryCheck,
    /// How the user can override (e.g. the CLI's flags), appended to the message.
    pub hint: String,
}

impl std::fmt::Display for GeometryMismatch {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(f, "{}", self.check.describe(&self.origin))?;
        if !self.hint.is_empty() {
            write!(f, "\n{}", self.hint)?;
        }
        Ok(())
    }
}

/// The part of a robot name before " — calibrated …" (a calibrated model keeps its geometry).
fn base_name(name: &str) -> &str {
    name.split(" — calibrated").next().unwrap_or(name).trim()
}

/// What the header says when it names another robot or geometry, `None` when it agrees or says
/// nothing. The fingerprint decides when present; the name is compared only without one.
pub fn header_mismatch(robot: &Robot, header: &FileHeader) -> Option<String> {
    let fingerprint = robot.geometry_fingerprint();
    let named = header.robot.as_deref().unwrap_or("(no name)");
    match (&header.geometry, &header.robot) {
        (Some(geometry), _) if geometry.trim() != fingerprint => Some(format!(
            "The file's header names robot \"{named}\" with geometry {geometry}; robot \"{}\" has geometry {fingerprint}.",
            robot.name
        )),
        (None, Some(name)) if base_name(name) != base_name(&robot.name) => Some(format!(
            "The file's header names robot \"{name}\", not \"{}\".",
            robot.name
        )),
        _ => None,
    }
}

/// Check every row's point and load point against forward kinematics (see the module
/// documentation). `lines` gives each row's line in the file (for messages), `header` the
/// file's header comments.
// One pass over the rows fills shared tallies (points and loads checked, the largest distance,
// the disagreements, the groups to compare): kept as one function (≈ 165 lines) so that every
// tally is updated in one visible place.
pub fn check_geometry(
    robot: &Robot,
    rows: &[MeasurementRow],
    lines: Option<&[u64]>,
    header: Option<&FileHeader>,
    tolerance_m: f64,
) -> Result<GeometryCheck, CalibError> {
    if !(MIN_FK_TOLERANCE_M..=MAX_FK_TOLERANCE_M).contains(&tolerance_m) {
        return Err(RowsError::FkTolerance {
            got_mm: tolerance_m * 1e3,
        }
        .into());
    }
    if !rows.is_empty() {
        crate::stiffness::design::check_row_set(robot, rows, false)?;
    }
    let n = robot.joint_count();
    let mut data = Data::new();
    let mut last_q: Option<&[f64]> = None;
    let mut disagreements = Vec::new();
    let mut max_distance = 0.0_f64;
    let (mut checked_points, mut checked_loads) = (0, 0);
    let mut point_groups: BTreeMap<(String, usize), Group> = BTreeMap::new();
    let mut load_groups: BTreeMap<usize, Group> = BTreeMap::new();
    let line_of = |i: usize| lines.and_then(|l| l.get(i).copied());
    let mut cases: BTreeMap<&str, Vec<usize>> = BTreeMap::new();
    for (i, row) in rows.iter().enumerate() {
        cases.entry(row.load_case.as_str()).or_default().push(i);
    }
    let mut disagree = |row: usize, point: &str, reference: Reference, distance_m: f64| {
        disagreements.push(Disagreement {
            row,
            line: line_of(row),
            load_case: rows[row].load_case.clone(),
            point: point.to_string(),
            reference,
            distance_m,
        });
    };
    for (i, row) in rows.iter().enumerate() {
        if last_q != Some(row.q_rad.as_slice()) {
            robot.forward_kinematics(&mut data, &row.q_rad)?;
            last_q = Some(row.q_rad.as_slice());
        }
        // The joints a link frame depends on, as exact bit patterns.
        let frame_key =
            |link: usize| -> Vec<u64> { row.q_rad[..link].iter().map(|q| q.to_bits()).collect() };
        let local = |link: usize, p: &[f64; 3]| -> Vector3<f64> {
            data.link_frame(link)
                .inverse_transform_point(&Point3::from(*p))
                .coords
        };
        // The measured point.
        let p = Vector3::from(row.point_m);
        let target = robot
            .targets
            .iter()
            .find(|t| t.name == row.point && row.point_link == n);
        if row.point == "TCP" && row.point_link == n {
            let d = (p - data.tcp_position()).norm();
            checked_points += 1;
            max_distance = max_distance.max(d);
            if d > tolerance_m {
                disagree(i, &row.point, Reference::Tcp, d);
            }
        } else if let Some(target) = target {
            let world = data
                .flange
                .transform_point(&Point3::from(target.position))
                .coords;
            let d = (p - world).norm();
            checked_points += 1;
            max_distance = max_distance.max(d);
            if d > tolerance_m {
                disagree(
                    i,
                    &row.point,
                    Reference::FlangeTarget(target.name.clone()),
                    d,
                );
            }
        } else {
            point_groups
                .entry((row.point.clone(), row.point_link))
                .or_default()
                .push((
                    i,
                    local(row.point_link, &row.point_m),
                    frame_key(row.point_link),
                ));
        }
        // The load point (loads of zero carry no information about their point).
        if row.wrench.iter().all(|w| *w == 0.0) {
            continue;
        }
        let a = Vector3::from(row.load_point_m);
        let at_measured_point = cases[row.load_case.as_str()].iter().any(|&j| {
            rows[j].point_link == row.load_link
                && (Vector3::from(rows[j].point_m) - a).norm() <= tolerance_m
        });
        if at_measured_point
            || (row.load_link == n && (a - data.tcp_position()).norm() <= tolerance_m)
        {
            checked_loads += 1;
        } else {
            load_groups.entry(row.load_link).or_default().push((
                i,
                local(row.load_link, &row.load_point_m),
                frame_key(row.load_link),
            ));
        }
    }
    let groups = check_groups(
        &point_groups,
        &load_groups,
        tolerance_m,
        &mut |row, reference, d| disagree(row, &rows[row].point, reference, d),
    );
    checked_points += groups.points;
    checked_loads += groups.loads;
    max_distance = max_distance.max(groups.max_distance_m);
    let unchecked = groups.unchecked;
    disagreements.sort_by_key(|d| (d.row, matches!(d.reference, Reference::LoadPoint { .. })));
    Ok(GeometryCheck {
        robot: robot.name.clone(),
        geometry: robot.geometry_fingerprint(),
        tolerance_m,
        rows: rows.len(),
        checked_points,
        checked_loads,
        disagreements,
        unchecked,
        max_distance_m: max_distance,
        header_mismatch: header.and_then(|h| header_mismatch(robot, h)),
    })
}

/// Rows of one point (or the load points of one link) whose coordinates are known only in their
/// link frame: (row, local coordinates, the joints the link frame depends on, as bit patterns).
type Group = Vec<(usize, Vector3<f64>, Vec<u64>)>;

/// What the consistency of the groups found.
struct GroupCheck {
    /// Measured points checked.
    points: usize,
    /// Load points checked.
    loads: usize,
    /// Largest distance of a local point from its group's median (m).
    max_distance_m: f64,
    /// Groups that could not be checked (one link frame only), said in words.
    unchecked: Vec<String>,
}

/// Each group's local coordinates against their median: a point (or load point) fixed on its
/// link has the same local coordinates in every configuration. A group seen in one link frame
/// only cannot be checked. `disagree(row, reference, distance)` records a row farther than
/// `tolerance_m` from its group's median.
fn check_groups(
    point_groups: &BTreeMap<(String, usize), Group>,
    load_groups: &BTreeMap<usize, Group>,
    tolerance_m: f64,
    disagree: &mut dyn FnMut(usize, Reference, f64),
) -> GroupCheck {
    let mut max_distance = 0.0_f64;
    let (mut checked_points, mut checked_loads) = (0, 0);
    let mut unchecked = Vec::new();
    let mut consistency = |group: &Group, what: String, reference: &dyn Fn() -> Reference| {
        let mut frames: Vec<&Vec<u64>> = group.iter().map(|g| &g.2).collect();
        frames.sort();
        frames.dedup();
        if frames.len() < 2 {
            unchecked.push(what);
            return 0;
        }
        let median = median_point(group.iter().map(|g| &g.1));
        for (row, local, _) in group {
            let d = (local - median).norm();
            max_distance = max_distance.max(d);
            if d > tolerance_m {
                disagree(*row, reference(), d);
            }
        }
        group.len()
    };
    for ((label, link), group) in point_groups {
        let link = *link;
        checked_points += consistency(
            group,
            format!(
                "point {label} on link {link}: its link frame is the same in every row ({}), so its coordinates cannot be checked",
                if link == 0 {
                    "the base"
                } else {
                    "one configuration"
                }
            ),
            &|| Reference::LinkPoint { link },
        );
    }
    for (link, group) in load_groups {
        let link = *link;
        checked_loads += consistency(
            group,
            format!(
                "load points on link {link}: one configuration of the joints before it, so they cannot be checked"
            ),
            &|| Reference::LoadPoint { link },
        );
    }
    GroupCheck {
        points: checked_points,
        loads: checked_loads,
        max_distance_m: max_distance,
        unchecked,
    }
}

/// Apply the policy: a file whose rows disagree is refused ([`CalibError::GeometryMismatch`],
/// naming the first rows and the header's robot) unless `allow_mismatch`, which turns the
/// refusal into a warning; a header that names another robot or geometry while the rows agree
/// gives a warning. Returns the warnings.
pub fn enforce(
    check: &GeometryCheck,
    origin: &str,
    allow_mismatch: bool,
    hint: &str,
) -> Result<Vec<String>, CalibError> {
    if !check.passed() {
        if allow_mismatch {
            return Ok(vec![format!(
                "{} (going on as asked)",
                check.describe(origin)
            )]);
        }
        return Err(CalibError::GeometryMismatch(Box::new(GeometryMismatch {
            origin: origin.to_string(),
            check: check.clone(),
            hint: hint.to_string(),
        })));
    }
    Ok(check
        .header_mismatch
        .iter()
        .map(|h| {
            format!(
                "{origin}: {h} Its coordinates agree with this robot's forward kinematics within {:.3} mm, so it is used.",
                check.tolerance_m * 1e3
            )
        })
        .collect())
}

/// The per-axis median of `points` (robust to the few rows of a group that disagree).
fn median_point<'p>(points: impl Iterator<Item = &'p Vector3<f64>> + Clone) -> Vector3<f64> {
    Vector3::from_fn(|axis, _| {
        let mut values: Vec<f64> = points.clone().map(|p| p[axis]).collect();
        values.sort_by(f64::total_cmp);
        let m = values.len();
        if m % 2 == 1 {
            values[m / 2]
        } else {
            0.5 * (values[m / 2 - 1] + values[m / 2])
        }
    })
}
