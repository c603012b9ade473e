use crate::{png_pixels, sine_series};
use deflex_plot::{
    ImageFormat, MAX_TITLE_LINES, MIN_TITLE_PX, PlotSpec, finite_extent, line_plot, padded,
    text_width_px, tick_formatter, title_layout,
};
use std::path::Path;

#[test]
fn tick_labels_snap_rounding_noise_to_zero() {
    let f = tick_formatter((-0.45, 0.45));
    assert_eq!(f(&-5.55e-17), "0");
    assert_eq!(f(&0.2), "0.2");
    assert_eq!(f(&-0.4), "-0.4");
    let g = tick_formatter((400.0, 700.0));
    assert_eq!(g(&450.0), "450");
    let h = tick_formatter((0.0, 2e-5));
    assert_eq!(h(&1.5e-5), "1.5e-5");
}

#[test]
fn padding_and_extents() {
    assert_eq!(
        finite_extent(&[f64::NAN, 2.0, -1.0, f64::INFINITY]),
        Some((-1.0, 2.0))
    );
    assert_eq!(finite_extent(&[f64::NAN]), None);
    assert_eq!(padded((0.0, 10.0), 0.1), (-1.0, 11.0));
    assert_eq!(padded((0.0, 0.0), 0.1), (-1.0, 1.0));
    assert_eq!(padded((5.0, 5.0), 0.1), (4.5, 5.5));
}

#[test]
fn format_by_extension() {
    assert_eq!(
        ImageFormat::from_path(Path::new("a/b.PNG")).unwrap(),
        ImageFormat::Png
    );
    assert_eq!(
        ImageFormat::from_path(Path::new("b.svg")).unwrap(),
        ImageFormat::Svg
    );
    assert!(ImageFormat::from_path(Path::new("b")).is_err());
}

/// Titles of every length, on images from narrow panels to wide figures: never below the
/// minimum size, every line inside the image, at most `MAX_TITLE_LINES` lines, and nothing
/// dropped unless the title had to be shortened.
#[test]
fn titles_are_never_drawn_below_the_minimum_size() {
    let words = "SIMULATED Staubli TX200 (Johra 2022, Table 1) — improvement of the max path error \
                 [%]: delay × model compliance scale, with every error source of the cell on";
    let mut titles: Vec<String> = (1..=words.len())
        .step_by(7)
        .map(|n| words.chars().take(n).collect())
        .collect();
    titles.push("x".repeat(150));
    titles.push(format!(
        "{} {}",
        "long_unbroken_file_name_".repeat(4),
        words
    ));
    for title in &titles {
        for width in [240u32, 300, 450, 600, 700, 900, 1100, 2000] {
            for preferred in [12u32, 24, 28] {
                let layout = title_layout(title, width, preferred);
                assert!(
                    layout.size_px >= MIN_TITLE_PX,
                    "{title:?} at {width} px: size {}",
                    layout.size_px
                );
                assert!(layout.size_px <= preferred.max(MIN_TITLE_PX));
                assert!(!layout.lines.is_empty() && layout.lines.len() <= MAX_TITLE_LINES);
                for line in &layout.lines {
                    let w = text_width_px(line, layout.size_px);
                    assert!(
                        w + 20 <= width,
                        "{title:?}: line {line:?} is {w} px on a {width} px image"
                    );
                }
                let joined: String = layout.lines.concat();
                let letters = |s: &str| s.chars().filter(|c| !c.is_whitespace()).count();
                if !joined.ends_with('…') {
                    assert_eq!(letters(&joined), letters(title), "{title:?} lost text");
                }
            }
        }
    }
    // A title that fits keeps the preferred size on one line; one that does not is wrapped
    // before it is shrunk below the minimum.
    let short = title_layout("Residual per load case", 900, 24);
    assert_eq!((short.size_px, short.lines.len()), (24, 1));
    let long = title_layout(words, 900, 24);
    assert!(long.lines.len() >= 2, "{long:?}");
}

/// The title of a narrow plot takes two lines at a legible size: dark pixels in two bands
/// above the chart, where a shrunk one-line title would leave one thin band.
#[test]
fn a_long_title_is_wrapped_in_the_image() {
    let title = "SIMULATED cell — a title far too long to fit on one line of a narrow plot";
    let layout = title_layout(title, 500, 24);
    assert_eq!(layout.lines.len(), 2, "{layout:?}");
    let image = line_plot(
        Path::new("w.png"),
        &PlotSpec::new(title, "x", "y").size(500, 400),
        &sine_series(),
    )
    .unwrap();
    let px = png_pixels(&image);
    let dark_rows: Vec<usize> = (0..layout.height_px() as usize)
        .filter(|&y| (0..500).any(|x| px[y * 500 + x].0 < 100))
        .collect();
    let bands = dark_rows.windows(2).filter(|w| w[1] > w[0] + 1).count() + 1;
    assert!(bands >= 2, "title rows {dark_rows:?}");
    assert!(
        dark_rows.len() >= 2 * MIN_TITLE_PX as usize * 6 / 10,
        "two lines of ≥ {MIN_TITLE_PX} px: {} dark rows",
        dark_rows.len()
    );
}
