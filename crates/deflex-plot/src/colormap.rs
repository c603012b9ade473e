//! Fixed colours: a categorical palette for series and the viridis colour map
//! for heatmaps.

use plotters::style::RGBColor;

/// Categorical palette for series (matplotlib's "tab10"), in order of use.
pub const PALETTE: [(u8, u8, u8); 10] = [
    (0x1f, 0x77, 0xb4), // blue
    (0xff, 0x7f, 0x0e), // orange
    (0x2c, 0xa0, 0x2c), // green
    (0xd6, 0x27, 0x28), // red
    (0x94, 0x67, 0xbd), // purple
    (0x8c, 0x56, 0x4b), // brown
    (0xe3, 0x77, 0xc2), // pink
    (0x7f, 0x7f, 0x7f), // grey
    (0xbc, 0xbd, 0x22), // olive
    (0x17, 0xbe, 0xcf), // cyan
];

/// Colour of the `i`-th series (cycling through [`PALETTE`]).
pub fn palette_color(i: usize) -> (u8, u8, u8) {
    PALETTE[i % PALETTE.len()]
}

pub(crate) fn palette_rgb(i: usize) -> RGBColor {
    let (r, g, b) = palette_color(i);
    RGBColor(r, g, b)
}

/// Viridis sampled at 9 evenly spaced points (t = 0, 1/8, ..., 1; the
/// standard viridis(9) hex values #440154, #472D7B, #3B528B, #2C728E,
/// #21908C, #27AD81, #5DC863, #AADC32, #FDE725); intermediate values are
/// interpolated linearly in RGB.
const VIRIDIS: [(u8, u8, u8); 9] = [
    (0x44, 0x01, 0x54),
    (0x47, 0x2d, 0x7b),
    (0x3b, 0x52, 0x8b),
    (0x2c, 0x72, 0x8e),
    (0x21, 0x90, 0x8c),
    (0x27, 0xad, 0x81),
    (0x5d, 0xc8, 0x63),
    (0xaa, 0xdc, 0x32),
    (0xfd, 0xe7, 0x25),
];

/// The viridis colour of `t` in `[0, 1]` (clamped; NaN maps to 0).
/// `viridis(0.0)` is dark purple `(68, 1, 84)`, `viridis(1.0)` is yellow
/// `(253, 231, 37)`.
pub fn viridis(t: f64) -> (u8, u8, u8) {
    let t = if t.is_nan() { 0.0 } else { t.clamp(0.0, 1.0) };
    let n = (VIRIDIS.len() - 1) as f64;
    let pos = t * n;
    let i = (pos.floor() as usize).min(VIRIDIS.len() - 2);
    let f = pos - i as f64;
    let (a, b) = (VIRIDIS[i], VIRIDIS[i + 1]);
    let lerp = |x: u8, y: u8| (x as f64 + (y as f64 - x as f64) * f).round() as u8;
    (lerp(a.0, b.0), lerp(a.1, b.1), lerp(a.2, b.2))
}

pub(crate) fn viridis_rgb(t: f64) -> RGBColor {
    let (r, g, b) = viridis(t);
    RGBColor(r, g, b)
}
