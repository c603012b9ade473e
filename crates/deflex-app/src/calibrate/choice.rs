//! The choices of a stiffness calibration and of a measurement plan, one type each for the CLI
//! (`clap::ValueEnum` with the `clap` feature) and Python (`FromStr` on the same names).

use std::path::PathBuf;
use thiserror::Error;

/// A name that is not one of a choice's values.
#[derive(Clone, Debug, PartialEq, Eq, Error)]
#[error("expected {expected}, got \"{got}\"")]
pub struct UnknownChoice {
    /// The values accepted, in words (`"auto" or "fixed"`).
    pub expected: &'static str,
    /// The name given.
    pub got: String,
}

/// How the calibrated structure is found (`--structure`, `structure=`): `auto`, the structure
/// search from one z-eDoF per joint (Fig. 6 of the paper, automated); `fixed`, the start model's
/// eDoFs and centre shifts as given.
// The variants carry plain comments: a doc comment would become the value's help and change
// the CLI's `--help`.
#[allow(missing_docs)]
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
#[cfg_attr(feature = "clap", derive(clap::ValueEnum))]
pub enum StructureChoice {
    // Structure search from one z-eDoF per joint.
    Auto,
    // The start model's eDoFs and centre shifts.
    Fixed,
}

impl StructureChoice {
    /// The name the CLI and Python use.
    pub fn name(self) -> &'static str {
        match self {
            StructureChoice::Auto => "auto",
            StructureChoice::Fixed => "fixed",
        }
    }
}

impl std::str::FromStr for StructureChoice {
    type Err = UnknownChoice;

    fn from_str(text: &str) -> Result<Self, UnknownChoice> {
        match text {
            "auto" => Ok(StructureChoice::Auto),
            "fixed" => Ok(StructureChoice::Fixed),
            other => Err(UnknownChoice {
                expected: "\"auto\" or \"fixed\"",
                got: other.to_string(),
            }),
        }
    }
}

/// How the structure search ranks structures (`--criterion`, `criterion=`): `bic`, the Bayesian
/// information criterion; `cv`, the held-out χ² of k-fold cross-validation by load case.
// Plain comments on the variants, as for `StructureChoice`.
#[allow(missing_docs)]
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
#[cfg_attr(feature = "clap", derive(clap::ValueEnum))]
pub enum CriterionChoice {
    // Bayesian information criterion.
    Bic,
    // Held-out χ² of k-fold cross-validation by load case.
    Cv,
}

impl CriterionChoice {
    /// The name the CLI and Python use.
    pub fn name(self) -> &'static str {
        match self {
            CriterionChoice::Bic => "bic",
            CriterionChoice::Cv => "cv",
        }
    }
}

impl std::str::FromStr for CriterionChoice {
    type Err = UnknownChoice;

    fn from_str(text: &str) -> Result<Self, UnknownChoice> {
        match text {
            "bic" => Ok(CriterionChoice::Bic),
            "cv" => Ok(CriterionChoice::Cv),
            other => Err(UnknownChoice {
                expected: "\"bic\" or \"cv\"",
                got: other.to_string(),
            }),
        }
    }
}

/// How a plan's loads are applied (`--load`): `cable`, a cable's tension along chosen world
/// axes; `dead-weight`, masses hanging along gravity.
// Plain comments on the variants, as for `StructureChoice`.
#[allow(missing_docs)]
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
#[cfg_attr(feature = "clap", derive(clap::ValueEnum))]
pub enum LoadChoice {
    // A cable.
    Cable,
    // Dead weights.
    DeadWeight,
}

/// The points a plan measures besides the TCP (`--points`).
#[derive(Clone, Debug, PartialEq, Eq)]
pub enum PointsChoice {
    /// Two mid-arm points.
    Standard,
    /// None.
    None,
    /// The points of a CSV file (columns `name, link, x_m, y_m, z_m`).
    File(PathBuf),
}

impl std::str::FromStr for PointsChoice {
    type Err = std::convert::Infallible;

    /// `standard`, `none`, or a file name.
    fn from_str(text: &str) -> Result<Self, Self::Err> {
        Ok(match text {
            "standard" => PointsChoice::Standard,
            "none" => PointsChoice::None,
            file => PointsChoice::File(PathBuf::from(file)),
        })
    }
}
