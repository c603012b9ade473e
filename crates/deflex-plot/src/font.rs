//! The embedded font (DejaVu Sans, see `assets/DejaVu-LICENSE.txt`),
//! registered with plotters once per process.

use std::sync::Once;

/// The font family name under which the embedded font is registered. It is
/// also the name SVG output asks the viewer for.
pub(crate) const FAMILY: &str = "sans-serif";

/// The embedded font, DejaVu Sans (a TrueType file; licence in `assets/DejaVu-LICENSE.txt`):
/// the text of every plot is drawn with it, so rendering needs no system fonts.
pub static DEJAVU_SANS: &[u8] = include_bytes!("../assets/DejaVuSans.ttf");
static REGISTER: Once = Once::new();

/// Registers the embedded font with plotters (idempotent, thread-safe).
pub(crate) fn ensure_registered() {
    REGISTER.call_once(|| {
        // The font is embedded at compile time and is known to parse; a
        // failure here would be caught by every rendering test.
        if plotters::style::register_font(FAMILY, plotters::style::FontStyle::Normal, DEJAVU_SANS)
            .is_err()
        {
            debug_assert!(false, "embedded DejaVu Sans failed to parse");
        }
    });
}
