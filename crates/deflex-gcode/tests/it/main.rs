//! Integration tests of `deflex-gcode`: one test binary (modules below). The corpus is CAM-style
//! programs written for the tests (`docs/parts/`, `tests/data/`); every expected point is
//! computed here from the part's analytic geometry (circle centres and radii, helix pitch,
//! unit conversions), independently of the reader's arc code.

mod corpus;
mod refusals;
