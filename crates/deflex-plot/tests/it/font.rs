#[test]
fn embedded_font_is_a_truetype_file() {
    // TrueType files start with the sfnt version 0x00010000.
    assert_eq!(&deflex_plot::DEJAVU_SANS[..4], &[0, 1, 0, 0]);
}
