//! The tool path of a forming run on the twin from its name (`deflex sim isf --path`, Python's
//! `deflex.sim.form(path)`): a built-in path or a G-code file, with the feed and the length the
//! user asked for.

use crate::OptionNames;
use crate::error::{Result, bounded};
use crate::load::gcode_file::read_gcode;
use crate::twin::FormConflict;
use deflex_sim::{ConeParams, PlungeParams, PyramidParams, ToolPath};
use std::path::PathBuf;

/// A built-in tool path or a G-code file.
#[derive(Clone, Debug, Default, PartialEq, Eq)]
pub enum PathChoice {
    /// The paper's helical cone.
    #[default]
    Cone,
    /// The cone in contours.
    ConeContour,
    /// The pyramid.
    Pyramid,
    /// 1 mm into a stiff fixture, then 20 mm along x.
    Plunge,
    /// A G-code file.
    Gcode(PathBuf),
}

impl std::str::FromStr for PathChoice {
    type Err = std::convert::Infallible;

    /// `cone`, `cone-contour`, `pyramid`, `plunge`, or else a G-code file.
    fn from_str(text: &str) -> Result<PathChoice, std::convert::Infallible> {
        Ok(match text {
            "cone" => PathChoice::Cone,
            "cone-contour" => PathChoice::ConeContour,
            "pyramid" => PathChoice::Pyramid,
            "plunge" => PathChoice::Plunge,
            file => PathChoice::Gcode(PathBuf::from(file)),
        })
    }
}

/// Smallest and largest feed of the built-in paths (mm/s).
pub const FEED_RANGE_MM_S: (f64, f64) = (0.1, 1000.0);
/// Smallest and largest length a path is cut to (mm of travel).
pub const LENGTH_RANGE_MM: (f64, f64) = (1e-3, 1e6);

/// The tool path `choice`, with the feed of the built-in paths (`feed_mm_s`; a G-code file sets
/// its own F) and only its first `length_mm` of travel. The tool-path generator works in mm
/// (`deflex_sim::ConeParams`, `ToolPath::truncated`), so these two are in mm: a front end
/// converting from its unit would round them. A feed given for a G-code file is refused naming
/// the options in the words of `names`.
pub fn tool_path(
    choice: &PathChoice,
    feed_mm_s: Option<f64>,
    length_mm: Option<f64>,
    names: OptionNames,
) -> Result<ToolPath> {
    let feed = match feed_mm_s {
        Some(f) => Some(bounded(
            "feed_mm_s",
            f,
            FEED_RANGE_MM_S.0,
            FEED_RANGE_MM_S.1,
            "mm/s",
        )?),
        None => None,
    };
    let path = match choice {
        PathChoice::Cone | PathChoice::ConeContour => {
            let mut p = ConeParams {
                helical: *choice == PathChoice::Cone,
                ..ConeParams::default()
            };
            if let Some(f) = feed {
                p.feed_mm_s = f;
            }
            ToolPath::cone(&p)?
        }
        PathChoice::Pyramid => {
            let mut p = PyramidParams::default();
            if let Some(f) = feed {
                p.feed_mm_s = f;
            }
            ToolPath::pyramid(&p)?
        }
        PathChoice::Plunge => {
            let mut p = PlungeParams::default();
            if let Some(f) = feed {
                p.traverse_feed_mm_s = f;
            }
            ToolPath::plunge(&p)?
        }
        PathChoice::Gcode(file) => {
            if feed.is_some() {
                return Err(FormConflict::FeedWithGcode.named(names));
            }
            read_gcode(file)?
        }
    };
    Ok(match length_mm {
        Some(l) => path.truncated(bounded(
            "length_mm",
            l,
            LENGTH_RANGE_MM.0,
            LENGTH_RANGE_MM.1,
            "mm",
        )?),
        None => path,
    })
}
