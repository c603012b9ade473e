//! The embedded font (DejaVu Sans, see `assets/DejaVu-LICENSE.txt`),
//! registered with plotters once per process.

use std::sync::Once;

/// The font family name under which the embedded font is registered. It is
/// also the name SVG output asks the viewer for.
pub(crate) const FAMILY: &str = "sans-serif";

static DEJAVU_SANS: &[u8] = include_bytes!("../assets/DejaVuSans.ttf");
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

#[cfg(test)]
mod tests {
    #[test]
    fn embedded_font_is_a_truetype_file() {
        // TrueType files start with the sfnt version 0x00010000.
        assert_eq!(&super::DEJAVU_SANS[..4], &[0, 1, 0, 0]);
    }
}
