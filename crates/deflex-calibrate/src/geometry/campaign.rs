//! A calibration campaign: absolute readings (any number of set-ups and targets), loaded
//! displacement readings and, when asked, the absolute readings' measured orientations,
//! resolved against a model, with the per-reading residuals and Jacobian blocks the solver
//! consumes.
//!
//! **Readings.** Every reading has three equations: reading `i` is the position of absolute
//! row `i` (`0 ≤ i < A`), then loaded row `i − A` (`A ≤ i < A + L`), then, after
//! [`Campaign::use_orientations`], the orientation of an absolute row that has one
//! (residual `log(R_measured · R_predictedᵀ)`, a rotation vector in the tracker frame).

use crate::geometry::data::{AbsoluteRow, DEFAULT_ORIENTATION_SIGMA_RAD, configuration_index};
use crate::geometry::model::Conditions;
use crate::geometry::params::{EgModel, Param};
use crate::measurements::{DEFAULT_SIGMA_M, MeasurementRow};
use deflex_model::spatial::rotation_log;
use deflex_model::{MAX_EDOFS, MAX_JOINTS};
use nalgebra::{Rotation3, Vector3};

/// What a reading measures.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum ReadingKind {
    /// An absolute target position (tracker frame).
    Position,
    /// A loaded − unloaded displacement (world axes).
    Loaded,
    /// An absolute target orientation (tracker frame).
    Orientation,
}

impl ReadingKind {
    /// Index for per-kind tables (robust scales).
    pub fn index(self) -> usize {
        match self {
            ReadingKind::Position => 0,
            ReadingKind::Loaded => 1,
            ReadingKind::Orientation => 2,
        }
    }
}

/// Why a campaign cannot be built.
#[derive(Debug, thiserror::Error)]
pub enum CampaignError {
    /// A reading's joint count differs from the robot's.
    #[error("{what} reading {index}: {got} joint values, the robot has {expected} joints")]
    JointCount {
        /// `absolute` or `loaded`.
        what: &'static str,
        /// Row index (0-based).
        index: usize,
        /// Joint values given.
        got: usize,
        /// Robot joints.
        expected: usize,
    },
    /// Nothing to fit.
    #[error("the campaign has no readings")]
    Empty,
    /// A loaded reading names a link the robot does not have.
    #[error("loaded reading {index}: link {link} does not exist (robot has {joints} joints)")]
    Link {
        /// Row index.
        index: usize,
        /// Link named.
        link: usize,
        /// Robot joints.
        joints: usize,
    },
}

/// Readings resolved against a model's set-ups and targets.
#[derive(Clone, Debug)]
pub struct Campaign {
    /// Absolute readings.
    pub absolute: Vec<AbsoluteRow>,
    /// Set-up index of each absolute reading.
    pub setup_of: Vec<usize>,
    /// Target index of each absolute reading.
    pub target_of: Vec<usize>,
    /// Configuration index of each absolute reading.
    pub config_of: Vec<usize>,
    /// Number of configurations among the absolute readings.
    pub config_count: usize,
    /// Loaded displacement readings (the stiffness campaign's format).
    pub loaded: Vec<MeasurementRow>,
    /// Configuration index of each loaded reading (its load case), after the absolute ones.
    pub loaded_config_of: Vec<usize>,
    /// Absolute row of each orientation reading (empty unless [`Campaign::use_orientations`]).
    pub orientation_rows: Vec<usize>,
    /// Standard deviation of an orientation component when its row gives none (rad).
    pub default_sigma_rad: f64,
}

impl Campaign {
    /// Resolve `absolute` and `loaded` readings against `model`, adding set-ups and targets the
    /// model does not know yet (at identity / the flange origin: registration initialises them).
    pub fn new(
        model: &mut EgModel,
        absolute: Vec<AbsoluteRow>,
        loaded: Vec<MeasurementRow>,
    ) -> Result<Campaign, CampaignError> {
        if absolute.is_empty() && loaded.is_empty() {
            return Err(CampaignError::Empty);
        }
        let n = model.robot.joint_count();
        let mut setup_of = Vec::with_capacity(absolute.len());
        let mut target_of = Vec::with_capacity(absolute.len());
        for (index, row) in absolute.iter().enumerate() {
            if row.q_rad.len() != n {
                return Err(CampaignError::JointCount {
                    what: "absolute",
                    index,
                    got: row.q_rad.len(),
                    expected: n,
                });
            }
            let s = model.setup_index(&row.setup).unwrap_or_else(|| {
                model.setups.push(deflex_model::NamedPose {
                    name: row.setup.clone(),
                    pose: deflex_model::Pose::identity(),
                });
                model.setups.len() - 1
            });
            let t = model.target_index(&row.target).unwrap_or_else(|| {
                model.targets.push(deflex_model::NamedPoint {
                    name: row.target.clone(),
                    position: Vector3::zeros(),
                    rotation: None,
                });
                model.targets.len() - 1
            });
            setup_of.push(s);
            target_of.push(t);
        }
        for (index, row) in loaded.iter().enumerate() {
            if row.q_rad.len() != n {
                return Err(CampaignError::JointCount {
                    what: "loaded",
                    index,
                    got: row.q_rad.len(),
                    expected: n,
                });
            }
            for link in [row.point_link, row.load_link] {
                if link > n {
                    return Err(CampaignError::Link {
                        index,
                        link,
                        joints: n,
                    });
                }
            }
        }
        let (config_of, config_count) = configuration_index(&absolute);
        let mut cases: std::collections::BTreeMap<&str, usize> = Default::default();
        let loaded_config_of = loaded
            .iter()
            .map(|r| {
                let next = config_count + cases.len();
                *cases.entry(r.load_case.as_str()).or_insert(next)
            })
            .collect();
        Ok(Campaign {
            absolute,
            setup_of,
            target_of,
            config_of,
            config_count,
            loaded,
            loaded_config_of,
            orientation_rows: Vec::new(),
            default_sigma_rad: DEFAULT_ORIENTATION_SIGMA_RAD,
        })
    }

    /// Add the measured orientation of every absolute row that has one as a reading, with
    /// `default_sigma_rad` for rows that state no `sigma_rad`.
    pub fn use_orientations(&mut self, default_sigma_rad: f64) {
        self.default_sigma_rad = default_sigma_rad;
        self.orientation_rows = (0..self.absolute.len())
            .filter(|&i| self.absolute[i].orientation.is_some())
            .collect();
    }

    /// Number of readings (positions, loaded, orientations); each has three equations.
    pub fn len(&self) -> usize {
        self.absolute.len() + self.loaded.len() + self.orientation_rows.len()
    }

    /// What reading `i` measures.
    pub fn kind(&self, i: usize) -> ReadingKind {
        let (a, l) = (self.absolute.len(), self.loaded.len());
        if i < a {
            ReadingKind::Position
        } else if i < a + l {
            ReadingKind::Loaded
        } else {
            ReadingKind::Orientation
        }
    }

    /// Indices of the loaded readings.
    pub fn loaded_readings(&self) -> std::ops::Range<usize> {
        self.absolute.len()..self.absolute.len() + self.loaded.len()
    }

    /// Indices of the orientation readings.
    pub fn orientation_readings(&self) -> std::ops::Range<usize> {
        let start = self.absolute.len() + self.loaded.len();
        start..start + self.orientation_rows.len()
    }

    /// Absolute row of reading `i` (position or orientation), `None` for a loaded reading.
    pub fn absolute_row(&self, i: usize) -> Option<usize> {
        match self.kind(i) {
            ReadingKind::Position => Some(i),
            ReadingKind::Loaded => None,
            ReadingKind::Orientation => {
                Some(self.orientation_rows[i - self.absolute.len() - self.loaded.len()])
            }
        }
    }

    /// Whether there is no reading.
    pub fn is_empty(&self) -> bool {
        self.len() == 0
    }

    /// Number of configurations (absolute configurations + loaded load cases).
    pub fn total_configs(&self) -> usize {
        self.config_count
            + self
                .loaded_config_of
                .iter()
                .map(|c| c + 1 - self.config_count)
                .max()
                .unwrap_or(0)
    }

    /// Configuration of reading `i`.
    pub fn config(&self, i: usize) -> usize {
        match self.absolute_row(i) {
            Some(row) => self.config_of[row],
            None => self.loaded_config_of[i - self.absolute.len()],
        }
    }

    /// Whether reading `i` is an absolute position.
    pub fn is_absolute(&self, i: usize) -> bool {
        i < self.absolute.len()
    }

    /// Standard deviation of each component of reading `i` (m, or rad for an orientation).
    pub fn sigma(&self, i: usize) -> f64 {
        match self.kind(i) {
            ReadingKind::Position => self.absolute[i].sigma(),
            ReadingKind::Loaded => self.loaded[i - self.absolute.len()]
                .sigma_m
                .unwrap_or(DEFAULT_SIGMA_M),
            ReadingKind::Orientation => self.absolute[self.absolute_row(i).unwrap_or(0)]
                .orientation
                .and_then(|o| o.sigma_rad)
                .unwrap_or(self.default_sigma_rad),
        }
    }

    /// Conditions of absolute row `i`: its payload (or the robot's), its wrench and its
    /// approach motion.
    pub fn conditions(&self, model: &EgModel, i: usize) -> Conditions {
        let row = &self.absolute[i];
        let mut approach_rad = [0.0; MAX_JOINTS];
        if let Some(a) = &row.approach_rad {
            for (slot, v) in approach_rad.iter_mut().zip(a) {
                *slot = *v;
            }
        }
        let payload = match row.payload {
            Some(p) => (p.mass_kg > 0.0).then(|| (p.mass_kg, Vector3::from(p.com_m))),
            None => model
                .robot
                .payload
                .filter(|p| p.mass_kg > 0.0)
                .map(|p| (p.mass_kg, p.com)),
        };
        Conditions {
            payload,
            wrench: row.wrench,
            approach_rad,
        }
    }

    /// Measured orientation of absolute row `i` (tracker frame), if any.
    pub fn measured_orientation(&self, i: usize) -> Option<Rotation3<f64>> {
        self.absolute[i]
            .orientation
            .map(|o| Rotation3::from_scaled_axis(Vector3::from(o.rotation_vector_rad)))
    }

    /// Measured minus predicted of reading `i` (m, tracker frame, for a position; m, world
    /// axes, for a loaded reading; the rotation vector `log(R_m R_pᵀ)`, tracker frame, for an
    /// orientation) and, when `columns` is given, the column of each of `params`.
    pub fn residual(
        &self,
        model: &EgModel,
        i: usize,
        params: &[Param],
        columns: Option<&mut Vec<Vector3<f64>>>,
    ) -> Vector3<f64> {
        match self.kind(i) {
            ReadingKind::Loaded => {
                let row = &self.loaded[i - self.absolute.len()];
                let mut compliance_columns = [Vector3::zeros(); MAX_EDOFS];
                let predicted = model.loaded_displacement(row, &mut compliance_columns);
                if let Some(columns) = columns {
                    columns.clear();
                    columns.extend(params.iter().map(|&p| match p {
                        Param::Compliance(e) => compliance_columns[e],
                        _ => Vector3::zeros(),
                    }));
                }
                let measured = row.displacement_m.unwrap_or([0.0; 3]);
                Vector3::from(measured) - predicted
            }
            kind => {
                let r = self.absolute_row(i).unwrap_or(i);
                let (s, t) = (self.setup_of[r], self.target_of[r]);
                let row = &self.absolute[r];
                let ev = model.evaluate(&row.q_rad, t, &self.conditions(model, r));
                let orientation = kind == ReadingKind::Orientation;
                if let Some(columns) = columns {
                    columns.clear();
                    columns.extend(params.iter().map(|&p| {
                        let c = model.tracker_column(&ev, s, p);
                        if orientation { c.rotation } else { c.position }
                    }));
                }
                if orientation {
                    let measured = self
                        .measured_orientation(r)
                        .unwrap_or_else(Rotation3::identity);
                    rotation_log(&(measured * model.tracker_orientation(&ev, s).inverse()))
                } else {
                    Vector3::from(row.position_m) - model.tracker_position(&ev, s)
                }
            }
        }
    }
}
