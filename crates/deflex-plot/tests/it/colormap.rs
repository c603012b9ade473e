use deflex_plot::{PALETTE, palette_color, viridis};

#[test]
fn viridis_endpoints_and_clamping() {
    assert_eq!(viridis(0.0), (68, 1, 84));
    assert_eq!(viridis(1.0), (253, 231, 37));
    assert_eq!(viridis(-5.0), viridis(0.0));
    assert_eq!(viridis(7.0), viridis(1.0));
    assert_eq!(viridis(f64::NAN), viridis(0.0));
    assert_eq!(viridis(0.5), (0x21, 0x90, 0x8c));
}

#[test]
fn viridis_brightens_monotonically() {
    // Viridis is perceptually ordered: luminance rises with t.
    let lum = |(r, g, b): (u8, u8, u8)| 0.2126 * r as f64 + 0.7152 * g as f64 + 0.0722 * b as f64;
    let mut prev = -1.0;
    for k in 0..=100 {
        let l = lum(viridis(k as f64 / 100.0));
        assert!(l >= prev, "luminance fell at t = {}", k as f64 / 100.0);
        prev = l;
    }
}

#[test]
fn palette_cycles() {
    assert_eq!(palette_color(0), PALETTE[0]);
    assert_eq!(palette_color(PALETTE.len() + 3), PALETTE[3]);
}
