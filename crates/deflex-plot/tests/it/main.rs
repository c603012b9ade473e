//! The tests of `deflex-plot`, through its public API: one test binary (modules below), so the
//! library is compiled once (`[lib] test = false`). Plots are drawn into memory, decoded back
//! (PNG) or read as text (SVG, HTML) and inspected; a module per plot kind and per piece. (That
//! a plot or page is written whole or not at all is the application layer's, tested in
//! deflex-app's `report::draw`.)

use deflex_plot::{Image, ImageFormat, Series};

mod base64;
mod cloud;
mod colormap;
mod font;
mod heatmap;
mod html;
mod plot;
mod render;
mod timeline;

/// Checks that `image` is a PNG (format and signature) and returns its IHDR width and height.
pub fn png_dims(image: &Image) -> (u32, u32) {
    assert_eq!(image.format, ImageFormat::Png);
    let b = &image.bytes;
    assert!(b.len() > 33, "PNG of {} bytes too short", b.len());
    assert_eq!(&b[..8], b"\x89PNG\r\n\x1a\n", "PNG signature");
    assert_eq!(&b[12..16], b"IHDR", "first chunk is IHDR");
    let w = u32::from_be_bytes([b[16], b[17], b[18], b[19]]);
    let h = u32::from_be_bytes([b[20], b[21], b[22], b[23]]);
    (w, h)
}

/// Decodes a PNG fully and returns its RGB pixels.
pub fn png_pixels(image: &Image) -> Vec<(u8, u8, u8)> {
    assert_eq!(image.format, ImageFormat::Png);
    let decoder = png::Decoder::new(std::io::Cursor::new(&image.bytes));
    let mut reader = decoder.read_info().unwrap();
    let mut buf = vec![0; reader.output_buffer_size()];
    let info = reader.next_frame(&mut buf).unwrap();
    let bytes = &buf[..info.buffer_size()];
    let step = match info.color_type {
        png::ColorType::Rgb => 3,
        png::ColorType::Rgba => 4,
        other => panic!("unexpected colour type {other:?}"),
    };
    bytes.chunks(step).map(|p| (p[0], p[1], p[2])).collect()
}

/// The text of an SVG image.
pub fn svg_text(image: Image) -> String {
    assert_eq!(image.format, ImageFormat::Svg);
    String::from_utf8(image.bytes).unwrap()
}

/// How many of `pixels` are exactly the colour `c`.
pub fn count(pixels: &[(u8, u8, u8)], c: (u8, u8, u8)) -> usize {
    pixels.iter().filter(|&&p| p == c).count()
}

/// Two series over 0 ≤ x < 10: `sin` as a line, `cos` as points.
pub fn sine_series() -> Vec<Series> {
    let x: Vec<f64> = (0..100).map(|i| i as f64 * 0.1).collect();
    vec![
        Series::line("sin", x.clone(), x.iter().map(|v| v.sin()).collect()),
        Series::points("cos", x.clone(), x.iter().map(|v| v.cos()).collect()),
    ]
}
