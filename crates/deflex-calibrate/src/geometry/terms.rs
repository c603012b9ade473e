//! What a calibration keeps beyond the robot file: joint-angle terms (harmonics, gear
//! periodic error, backlash, joint-angle error maps), nonlinear torsion of the eDoFs and the
//! residual model, which a robot description has no place for, and the calibration's own accuracy (what a later registration compares its residual
//! with). Serialised as JSON (SI units) beside the robot file; tied to it by the robot's
//! geometry fingerprint, so a terms file is never applied to another robot's geometry.

use crate::geometry::joint_maps::{
    JointMap, JointMaps, JointMapsHyper, MAX_MAP_COEFFICIENTS, MIN_SPACING_RAD,
};
use crate::geometry::outcome::FitResult;
use crate::geometry::params::{EgModel, HarmonicTerm, TorsionShape, TorsionTerm};
use crate::geometry::residual_model::{MAX_INDUCING, ResidualHyper, ResidualModel};
use deflex_model::MAX_JOINTS;
use serde::{Deserialize, Serialize};

/// Margin over the calibration's held-out RMS above which a registration residual says the
/// robot itself has changed ([`CalibrationTerms::recalibrate_above_m`]).
pub const RECALIBRATE_MARGIN: f64 = 1.5;

/// Version of the format written.
pub const FORMAT: u32 = 1;
/// Largest number of harmonic terms read.
pub const MAX_HARMONICS: usize = 4096;

/// One harmonic term as written.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct HarmonicRecord {
    /// Joint, 1-based.
    pub joint: usize,
    /// Cycles per joint turn.
    pub order: u16,
    /// `true` for the sine term.
    pub sine: bool,
    /// Coefficient (rad).
    pub value_rad: f64,
}

/// Largest number of torsion terms read.
pub const MAX_TORSION: usize = 64;

/// One nonlinear torsion term as written: the eDoF turns by `c τ + a g(τ)`.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct TorsionRecord {
    /// eDoF label (`J2.z`).
    pub edof: String,
    /// Shape: `cubic` (`g = τ³/(100 N·m)²`) or `soft` (`g = T tanh(τ/T)`).
    pub shape: String,
    /// T of the soft zone (N·m); 0 for the cubic shape.
    pub torque_scale_nm: u16,
    /// Coefficient a (rad/(N·m)).
    pub value_rad_per_nm: f64,
}

/// The residual model as written.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct ResidualRecord {
    /// Length scale (rad).
    pub length_scale_rad: f64,
    /// Ridge σ_n²/σ_f².
    pub ridge: f64,
    /// Joints the kernel looks at (1-based).
    pub joints: Vec<usize>,
    /// Inducing configurations (rad).
    pub inducing_q_rad: Vec<Vec<f64>>,
    /// Their weights per world axis (m).
    pub weights_m: Vec<[f64; 3]>,
}

/// One joint's angle-error map as written: `Δθ(q) = Σ_k c_k B_k((q − start)/spacing)`, B_k
/// the uniform cubic B-spline on knots `start + k·spacing … start + (k+4)·spacing`.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct JointMapRecord {
    /// Joint, 1-based.
    pub joint: usize,
    /// First knot (rad).
    pub start_rad: f64,
    /// Knot spacing (rad).
    pub spacing_rad: f64,
    /// Coefficients (rad).
    pub coefficients_rad: Vec<f64>,
}

/// The joint-angle error maps as written, with the hyper-parameters they were trained with.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct JointMapsRecord {
    /// Prior standard deviation of a coefficient (rad).
    pub value_sigma_rad: f64,
    /// Prior standard deviation of a coefficients' second difference (rad).
    pub curvature_sigma_rad: f64,
    /// One map per mapped joint.
    pub maps: Vec<JointMapRecord>,
}

/// The terms file.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct CalibrationTerms {
    /// Format version ([`FORMAT`]).
    pub format: u32,
    /// Geometry fingerprint of the robot file these terms belong to.
    pub geometry_fingerprint: String,
    /// Model steps kept.
    pub kept_steps: Vec<String>,
    /// Harmonic and gear-periodic terms.
    pub harmonics: Vec<HarmonicRecord>,
    /// Direction-dependent offset per joint (rad).
    pub backlash_rad: Vec<f64>,
    /// Nonlinear torsion terms (absent in files written before them).
    #[serde(default)]
    pub torsion: Vec<TorsionRecord>,
    /// Residual model, if kept.
    pub residual_model: Option<ResidualRecord>,
    /// Joint-angle error maps, if kept (absent in files written before them).
    #[serde(default)]
    pub joint_maps: Option<JointMapsRecord>,
    /// Position RMS of the fitted readings (m).
    pub fit_rms_m: f64,
    /// Largest position RMS of a held-out group (held-out configurations, held-out series, left-out
    /// sessions; m), when there were any: what the healthy robot showed on readings its fit did
    /// not see, the reference of `register`'s "re-calibrate" warning.
    pub held_out_rms_m: Option<f64>,
}

/// A terms file that cannot be used.
#[derive(Debug, thiserror::Error)]
pub enum TermsError {
    /// Not JSON of this format.
    #[error("not a deflex calibration terms file: {0}")]
    Json(#[from] serde_json::Error),
    /// Another version.
    #[error("format {found}, this deflex reads {FORMAT}")]
    Format {
        /// Version found.
        found: u32,
    },
    /// For another geometry.
    #[error(
        "written for the robot geometry {expected}, but the robot file's is {found}: the terms belong to another calibration"
    )]
    Fingerprint {
        /// In the terms file.
        expected: String,
        /// Of the robot.
        found: String,
    },
    /// A joint index or count out of range.
    #[error("{what}: {value} is outside 1…{joints} (the robot's joints)")]
    Joint {
        /// Field.
        what: &'static str,
        /// Value.
        value: usize,
        /// Robot joints.
        joints: usize,
    },
    /// A joint given a second map.
    #[error("joint_maps.maps.joint: joint {joint} has two maps (each joint at most one)")]
    DuplicateMap {
        /// The joint (1-based).
        joint: usize,
    },
    /// A torsion term on an eDoF the robot does not have.
    #[error("torsion.edof: `{label}` is not an eDoF of the robot (its eDoFs: {known})")]
    Edof {
        /// Label given.
        label: String,
        /// The robot's eDoFs.
        known: String,
    },
    /// A torsion shape that is not `cubic` or `soft` with a torque scale 1…1000 N·m.
    #[error(
        "torsion.shape: expected \"cubic\" or \"soft\" with torque_scale_nm 1…1000, got \"{shape}\" with {torque_scale_nm}"
    )]
    TorsionShape {
        /// Shape given.
        shape: String,
        /// Torque scale given.
        torque_scale_nm: u16,
    },
    /// Too many entries, or a non-finite value.
    #[error("{what}: {problem}")]
    Value {
        /// Field.
        what: &'static str,
        /// What is wrong.
        problem: ValueProblem,
    },
}

/// What is wrong with a value of a terms file.
#[derive(Debug, thiserror::Error)]
pub enum ValueProblem {
    /// More entries than allowed.
    #[error("{count} entries, at most {limit}")]
    TooMany {
        /// Entries.
        count: usize,
        /// Bound.
        limit: usize,
    },
    /// A value that is not finite or not positive where it must be.
    #[error("{0} is not a finite value in range")]
    Bad(f64),
    /// Inducing configurations and weights of different lengths.
    #[error("{inducing} inducing configurations, {weights} weights")]
    Shape {
        /// Inducing.
        inducing: usize,
        /// Weights.
        weights: usize,
    },
}

impl CalibrationTerms {
    /// The terms of a fit's final model.
    pub fn of(result: &FitResult) -> CalibrationTerms {
        let model = &result.model;
        // The largest group, not the pooled RMS: left-out sessions that revisit the fitted
        // configurations (a grid measured again) score far better than new configurations.
        let held_out_rms_m = result.steps.iter().rev().find_map(|s| {
            if s.acceptance.is_some_and(|a| !a.accepted) {
                return None;
            }
            s.test
                .iter()
                .chain(&s.cross_groups)
                .filter(|g| g.stats.count > 0)
                .map(|g| g.stats.rms)
                .reduce(f64::max)
        });
        CalibrationTerms {
            format: FORMAT,
            geometry_fingerprint: model.to_robot().geometry_fingerprint(),
            kept_steps: result.kept_steps.iter().map(|s| s.name()).collect(),
            harmonics: model
                .harmonics
                .iter()
                .map(|h| HarmonicRecord {
                    joint: h.joint + 1,
                    order: h.order,
                    sine: h.sine,
                    value_rad: h.value,
                })
                .collect(),
            backlash_rad: model.backlash.clone(),
            torsion: model
                .torsion
                .iter()
                .map(|t| TorsionRecord {
                    edof: model
                        .robot
                        .edofs()
                        .nth(t.edof)
                        .map_or_else(String::new, |e| e.label()),
                    shape: match t.shape {
                        TorsionShape::Cubic => "cubic".into(),
                        TorsionShape::Soft(_) => "soft".into(),
                    },
                    torque_scale_nm: match t.shape {
                        TorsionShape::Cubic => 0,
                        TorsionShape::Soft(scale) => scale,
                    },
                    value_rad_per_nm: t.value,
                })
                .collect(),
            residual_model: model.residual.as_ref().map(|r| ResidualRecord {
                length_scale_rad: r.hyper.length_scale_rad,
                ridge: r.hyper.ridge,
                joints: (0..model.robot.joint_count().min(16))
                    .filter(|j| r.hyper.joints & (1 << j) != 0)
                    .map(|j| j + 1)
                    .collect(),
                inducing_q_rad: r.inducing.clone(),
                weights_m: r.weights.clone(),
            }),
            joint_maps: model.joint_maps.as_ref().map(|m| JointMapsRecord {
                value_sigma_rad: m.hyper.value_sigma_rad,
                curvature_sigma_rad: m.hyper.curvature_sigma_rad,
                maps: m
                    .maps
                    .iter()
                    .map(|map| JointMapRecord {
                        joint: map.joint + 1,
                        start_rad: map.start_rad,
                        spacing_rad: map.spacing_rad,
                        coefficients_rad: map.coefficients.clone(),
                    })
                    .collect(),
            }),
            fit_rms_m: result
                .steps
                .iter()
                .rev()
                .find(|s| s.acceptance.is_none_or(|a| a.accepted))
                .map_or(0.0, |s| s.fit.rms),
            held_out_rms_m,
        }
    }

    /// The registration residual (m) above which the robot itself is deemed changed:
    /// [`RECALIBRATE_MARGIN`] × the held-out RMS the calibration recorded.
    pub fn recalibrate_above_m(&self) -> Option<f64> {
        self.held_out_rms_m.map(|r| r * RECALIBRATE_MARGIN)
    }

    /// The terms file's JSON text (pretty-printed). A serialisation failure is returned, never
    /// written as an empty file.
    pub fn to_json(&self) -> Result<String, serde_json::Error> {
        serde_json::to_string_pretty(self)
    }

    /// Parse JSON text (the caller bounds its size) and check every value.
    pub fn from_json(text: &str) -> Result<CalibrationTerms, TermsError> {
        let terms: CalibrationTerms = serde_json::from_str(text)?;
        if terms.format != FORMAT {
            return Err(TermsError::Format {
                found: terms.format,
            });
        }
        Ok(terms)
    }

    /// Whether the terms change any prediction.
    pub fn is_empty(&self) -> bool {
        self.harmonics.is_empty()
            && self.backlash_rad.iter().all(|b| *b == 0.0)
            && self.torsion.iter().all(|t| t.value_rad_per_nm == 0.0)
            && self.residual_model.is_none()
            && self.joint_maps.is_none()
    }

    /// Put the terms into a model built from their robot file.
    pub fn apply(&self, model: &mut EgModel) -> Result<(), TermsError> {
        let found = model.robot.geometry_fingerprint();
        if found != self.geometry_fingerprint {
            return Err(TermsError::Fingerprint {
                expected: self.geometry_fingerprint.clone(),
                found,
            });
        }
        let joints = model.robot.joint_count();
        let finite = |what: &'static str, v: f64, limit: f64| {
            if v.is_finite() && v.abs() <= limit {
                Ok(())
            } else {
                Err(TermsError::Value {
                    what,
                    problem: ValueProblem::Bad(v),
                })
            }
        };
        if self.harmonics.len() > MAX_HARMONICS {
            return Err(TermsError::Value {
                what: "harmonics",
                problem: ValueProblem::TooMany {
                    count: self.harmonics.len(),
                    limit: MAX_HARMONICS,
                },
            });
        }
        let mut harmonics = Vec::new();
        for h in &self.harmonics {
            if h.joint == 0 || h.joint > joints {
                return Err(TermsError::Joint {
                    what: "harmonics.joint",
                    value: h.joint,
                    joints,
                });
            }
            finite("harmonics.value_rad", h.value_rad, 1.0)?;
            harmonics.push(HarmonicTerm {
                joint: h.joint - 1,
                order: h.order,
                sine: h.sine,
                value: h.value_rad,
            });
        }
        if self.backlash_rad.len() != joints {
            return Err(TermsError::Joint {
                what: "backlash_rad (entries)",
                value: self.backlash_rad.len(),
                joints,
            });
        }
        for b in &self.backlash_rad {
            finite("backlash_rad", *b, 1.0)?;
        }
        let torsion = torsion_terms(&self.torsion, model, &finite)?;
        let residual = match &self.residual_model {
            Some(r) => Some(residual_model(r, joints, &finite)?),
            None => None,
        };
        let maps = match &self.joint_maps {
            Some(m) => Some(joint_maps(m, joints, &finite)?),
            None => None,
        };
        model.harmonics = harmonics;
        model.backlash = self.backlash_rad.clone();
        model.torsion = torsion;
        model.residual = residual;
        model.joint_maps = maps;
        Ok(())
    }
}

/// Largest number of joint maps read.
pub const MAX_JOINT_MAPS: usize = MAX_JOINTS;

fn joint_maps(
    record: &JointMapsRecord,
    joints: usize,
    finite: &dyn Fn(&'static str, f64, f64) -> Result<(), TermsError>,
) -> Result<JointMaps, TermsError> {
    if record.maps.len() > MAX_JOINT_MAPS {
        return Err(TermsError::Value {
            what: "joint_maps.maps",
            problem: ValueProblem::TooMany {
                count: record.maps.len(),
                limit: MAX_JOINT_MAPS,
            },
        });
    }
    let positive = |what: &'static str, v: f64, low: f64, high: f64| {
        if v.is_finite() && (low..=high).contains(&v) {
            Ok(())
        } else {
            Err(TermsError::Value {
                what,
                problem: ValueProblem::Bad(v),
            })
        }
    };
    positive(
        "joint_maps.value_sigma_rad",
        record.value_sigma_rad,
        1e-9,
        1.0,
    )?;
    positive(
        "joint_maps.curvature_sigma_rad",
        record.curvature_sigma_rad,
        1e-9,
        1.0,
    )?;
    let mut mask = 0u16;
    let mut maps = Vec::with_capacity(record.maps.len());
    let mut spacing = f64::NAN;
    for m in &record.maps {
        if m.joint == 0 || m.joint > joints {
            return Err(TermsError::Joint {
                what: "joint_maps.maps.joint",
                value: m.joint,
                joints,
            });
        }
        if mask & (1 << (m.joint - 1)) != 0 {
            return Err(TermsError::DuplicateMap { joint: m.joint });
        }
        mask |= 1 << (m.joint - 1);
        finite("joint_maps.maps.start_rad", m.start_rad, 100.0)?;
        positive(
            "joint_maps.maps.spacing_rad",
            m.spacing_rad,
            MIN_SPACING_RAD,
            10.0,
        )?;
        if m.coefficients_rad.len() > MAX_MAP_COEFFICIENTS {
            return Err(TermsError::Value {
                what: "joint_maps.maps.coefficients_rad",
                problem: ValueProblem::TooMany {
                    count: m.coefficients_rad.len(),
                    limit: MAX_MAP_COEFFICIENTS,
                },
            });
        }
        for c in &m.coefficients_rad {
            finite("joint_maps.maps.coefficients_rad", *c, 0.1)?;
        }
        spacing = m.spacing_rad;
        maps.push(JointMap {
            joint: m.joint - 1,
            start_rad: m.start_rad,
            spacing_rad: m.spacing_rad,
            coefficients: m.coefficients_rad.clone(),
        });
    }
    Ok(JointMaps {
        hyper: JointMapsHyper {
            joints: mask,
            spacing_rad: spacing,
            value_sigma_rad: record.value_sigma_rad,
            curvature_sigma_rad: record.curvature_sigma_rad,
        },
        maps,
    })
}

fn torsion_terms(
    records: &[TorsionRecord],
    model: &EgModel,
    finite: &dyn Fn(&'static str, f64, f64) -> Result<(), TermsError>,
) -> Result<Vec<TorsionTerm>, TermsError> {
    if records.len() > MAX_TORSION {
        return Err(TermsError::Value {
            what: "torsion",
            problem: ValueProblem::TooMany {
                count: records.len(),
                limit: MAX_TORSION,
            },
        });
    }
    let labels: Vec<String> = model.robot.edofs().map(|e| e.label()).collect();
    records
        .iter()
        .map(|r| {
            let edof =
                labels
                    .iter()
                    .position(|l| *l == r.edof)
                    .ok_or_else(|| TermsError::Edof {
                        label: r.edof.clone(),
                        known: labels.join(", "),
                    })?;
            let shape = match (r.shape.as_str(), r.torque_scale_nm) {
                ("cubic", _) => TorsionShape::Cubic,
                ("soft", t) if (1..=1000).contains(&t) => TorsionShape::Soft(t),
                _ => {
                    return Err(TermsError::TorsionShape {
                        shape: r.shape.clone(),
                        torque_scale_nm: r.torque_scale_nm,
                    });
                }
            };
            finite("torsion.value_rad_per_nm", r.value_rad_per_nm, 1.0)?;
            Ok(TorsionTerm {
                edof,
                shape,
                value: r.value_rad_per_nm,
            })
        })
        .collect()
}

fn residual_model(
    r: &ResidualRecord,
    joints: usize,
    finite: &dyn Fn(&'static str, f64, f64) -> Result<(), TermsError>,
) -> Result<ResidualModel, TermsError> {
    if r.inducing_q_rad.len() > MAX_INDUCING {
        return Err(TermsError::Value {
            what: "residual_model.inducing_q_rad",
            problem: ValueProblem::TooMany {
                count: r.inducing_q_rad.len(),
                limit: MAX_INDUCING,
            },
        });
    }
    if r.inducing_q_rad.len() != r.weights_m.len() {
        return Err(TermsError::Value {
            what: "residual_model",
            problem: ValueProblem::Shape {
                inducing: r.inducing_q_rad.len(),
                weights: r.weights_m.len(),
            },
        });
    }
    finite("residual_model.length_scale_rad", r.length_scale_rad, 100.0)?;
    if r.length_scale_rad <= 0.0 {
        return Err(TermsError::Value {
            what: "residual_model.length_scale_rad",
            problem: ValueProblem::Bad(r.length_scale_rad),
        });
    }
    finite("residual_model.ridge", r.ridge, 1e12)?;
    for q in &r.inducing_q_rad {
        if q.len() != joints || joints > MAX_JOINTS {
            return Err(TermsError::Joint {
                what: "residual_model.inducing_q_rad (joint values)",
                value: q.len(),
                joints,
            });
        }
        for v in q {
            finite("residual_model.inducing_q_rad", *v, 100.0)?;
        }
    }
    for w in &r.weights_m {
        for v in w {
            finite("residual_model.weights_m", *v, 1e3)?;
        }
    }
    let mut mask = 0u16;
    for &j in &r.joints {
        if j == 0 || j > joints {
            return Err(TermsError::Joint {
                what: "residual_model.joints",
                value: j,
                joints,
            });
        }
        mask |= 1 << (j - 1);
    }
    Ok(ResidualModel {
        hyper: ResidualHyper {
            length_scale_rad: r.length_scale_rad,
            ridge: r.ridge,
            joints: mask,
        },
        inducing: r.inducing_q_rad.clone(),
        weights: r.weights_m.clone(),
    })
}
