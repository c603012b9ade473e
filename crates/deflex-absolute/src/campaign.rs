//! A calibration campaign: absolute readings (any number of set-ups and targets) and loaded
//! displacement readings, resolved against a model, with the per-reading residuals and
//! Jacobian blocks the solver consumes.

use crate::data::{AbsoluteRow, configuration_index};
use crate::model::Loads;
use crate::params::{EgModel, Param};
use deflex_stiffness::MeasurementRow;
use deflex_model::MAX_EDOFS;
use nalgebra::Vector3;

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
}

/// Default standard deviation of a loaded displacement component (m), as `deflex calibrate`.
pub const DEFAULT_LOADED_SIGMA_M: f64 = deflex_stiffness::DEFAULT_SIGMA_M;

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
        })
    }

    /// Number of readings (absolute + loaded); each has three equations.
    pub fn len(&self) -> usize {
        self.absolute.len() + self.loaded.len()
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

    /// Configuration of reading `i` (absolute first, then loaded).
    pub fn config(&self, i: usize) -> usize {
        if i < self.absolute.len() {
            self.config_of[i]
        } else {
            self.loaded_config_of[i - self.absolute.len()]
        }
    }

    /// Whether reading `i` is absolute.
    pub fn is_absolute(&self, i: usize) -> bool {
        i < self.absolute.len()
    }

    /// Standard deviation of reading `i` (m).
    pub fn sigma(&self, i: usize) -> f64 {
        if i < self.absolute.len() {
            self.absolute[i].sigma()
        } else {
            self.loaded[i - self.absolute.len()]
                .sigma_m
                .unwrap_or(DEFAULT_LOADED_SIGMA_M)
        }
    }

    /// Loads of absolute reading `i`: its payload (or the robot's) and its wrench.
    pub fn loads(&self, model: &EgModel, i: usize) -> Loads {
        let row = &self.absolute[i];
        let payload = match row.payload {
            Some(p) => (p.mass_kg > 0.0).then(|| (p.mass_kg, Vector3::from(p.com_m))),
            None => model
                .robot
                .payload
                .filter(|p| p.mass_kg > 0.0)
                .map(|p| (p.mass_kg, p.com)),
        };
        Loads {
            payload,
            wrench: row.wrench,
        }
    }

    /// Measured minus predicted of reading `i` (m; tracker frame for absolute readings, world
    /// axes for loaded ones) and, when `columns` is given, the column of each of `params`.
    pub fn residual(
        &self,
        model: &EgModel,
        i: usize,
        params: &[Param],
        columns: Option<&mut Vec<Vector3<f64>>>,
    ) -> Vector3<f64> {
        if i < self.absolute.len() {
            let row = &self.absolute[i];
            let (s, t) = (self.setup_of[i], self.target_of[i]);
            let ev = model.evaluate(&row.q_rad, t, &self.loads(model, i));
            let predicted = model.setups[s]
                .pose
                .transform_point(&(ev.target_world + ev.sag_world).into())
                .coords;
            if let Some(columns) = columns {
                columns.clear();
                columns.extend(params.iter().map(|&p| model.tracker_column(&ev, s, p)));
            }
            Vector3::from(row.position_m) - predicted
        } else {
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
    }
}
