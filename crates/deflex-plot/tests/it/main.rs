//! The tests of `deflex-plot`, through its public API: one test binary (modules below), so the
//! library is compiled once (`[lib] test = false`). Plots are written to a unique temp dir,
//! decoded back (PNG) or read (SVG, HTML) and inspected; a module per plot kind and per piece.

use std::path::{Path, PathBuf};
use std::sync::atomic::{AtomicUsize, Ordering};

use deflex_plot::Series;

mod base64;
mod cloud;
mod colormap;
mod font;
mod heatmap;
mod html;
mod plot;
mod render;
mod timeline;

/// A fresh, unique directory under the system temp dir.
pub fn temp_dir(name: &str) -> PathBuf {
    static COUNTER: AtomicUsize = AtomicUsize::new(0);
    let n = COUNTER.fetch_add(1, Ordering::Relaxed);
    let nanos = std::time::SystemTime::now()
        .duration_since(std::time::UNIX_EPOCH)
        .map(|d| d.subsec_nanos())
        .unwrap_or(0);
    let dir = std::env::temp_dir().join(format!(
        "deflex-plot-test-{}-{n}-{nanos}-{name}",
        std::process::id()
    ));
    std::fs::create_dir_all(&dir).unwrap();
    dir
}

/// Checks the PNG signature and returns the IHDR width and height.
pub fn png_dims(path: &Path) -> (u32, u32) {
    let b = std::fs::read(path).unwrap();
    assert!(b.len() > 33, "{} too short", path.display());
    assert_eq!(&b[..8], b"\x89PNG\r\n\x1a\n", "PNG signature");
    assert_eq!(&b[12..16], b"IHDR", "first chunk is IHDR");
    let w = u32::from_be_bytes([b[16], b[17], b[18], b[19]]);
    let h = u32::from_be_bytes([b[20], b[21], b[22], b[23]]);
    (w, h)
}

/// Decodes a PNG fully and returns its RGB pixels.
pub fn png_pixels(path: &Path) -> Vec<(u8, u8, u8)> {
    let decoder = png::Decoder::new(std::fs::File::open(path).unwrap());
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
