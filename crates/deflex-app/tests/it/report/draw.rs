//! Plots and pages written to their files ([`deflex_app::report::draw`]): the bytes drawn by
//! `deflex-plot`, written whole or not at all, every error naming the file. (The drawing itself
//! is tested in deflex-plot's tests.)

use deflex_app::report::DrawError;
use deflex_app::report::draw::{heatmap, line_plot, write_page};
use deflex_plot::{HtmlReport, PlotError, PlotSpec, Series};
use std::path::{Path, PathBuf};
use std::sync::atomic::{AtomicUsize, Ordering};

/// A fresh, unique directory under the system temp dir.
fn temp_dir(name: &str) -> PathBuf {
    static COUNTER: AtomicUsize = AtomicUsize::new(0);
    let n = COUNTER.fetch_add(1, Ordering::Relaxed);
    let dir =
        std::env::temp_dir().join(format!("deflex-app-draw-{}-{n}-{name}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(&dir).unwrap();
    dir
}

/// Two series over 0 ≤ x < 10: `sin` as a line, `cos` as points.
fn sine_series() -> Vec<Series> {
    let x: Vec<f64> = (0..100).map(|i| i as f64 * 0.1).collect();
    vec![
        Series::line("sin", x.clone(), x.iter().map(|v| v.sin()).collect()),
        Series::points("cos", x.clone(), x.iter().map(|v| v.cos()).collect()),
    ]
}

/// The names in `dir`, sorted.
fn names(dir: &Path) -> Vec<String> {
    let mut names: Vec<String> = std::fs::read_dir(dir)
        .unwrap()
        .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
        .collect();
    names.sort();
    names
}

/// The file holds exactly the bytes `deflex-plot` draws, PNG and SVG, and nothing else is left
/// in the folder (no temporary sibling).
#[test]
fn plots_are_written_with_the_drawn_bytes() {
    let dir = temp_dir("bytes");
    let spec = PlotSpec::new("Sine", "t [s]", "u [mm]").size(640, 400);
    for name in ["line.png", "line.svg"] {
        let path = dir.join(name);
        line_plot(&path, &spec, &sine_series()).unwrap();
        let drawn = deflex_plot::line_plot(&path, &spec, &sine_series()).unwrap();
        assert_eq!(std::fs::read(&path).unwrap(), drawn.bytes, "{name}");
    }
    assert_eq!(names(&dir), ["line.png", "line.svg"]);
    std::fs::remove_dir_all(&dir).unwrap();
}

#[test]
fn series_input_errors_write_nothing() {
    let dir = temp_dir("errs");
    let path = dir.join("e.png");
    let spec = PlotSpec::new("t", "x", "y");
    let e = line_plot(
        &path,
        &spec,
        &[Series::line("a", vec![1.0, 2.0], vec![1.0])],
    )
    .unwrap_err();
    assert!(e.to_string().contains("x has 2 values but y has 1"), "{e}");
    assert_eq!(e.path(), path.as_path());
    assert!(line_plot(&path, &spec, &[]).is_err());
    assert!(line_plot(&path, &spec, &[Series::line("a", vec![], vec![])]).is_err());
    let nan = Series::line("a", vec![f64::NAN, 1.0], vec![1.0, f64::INFINITY]);
    assert!(line_plot(&path, &spec, &[nan]).is_err());
    let bad_size = spec.clone().size(0, 100);
    assert!(line_plot(&path, &bad_size, &sine_series()).is_err());
    let bad_range = spec.clone().y_range(1.0, 0.0);
    assert!(line_plot(&path, &bad_range, &sine_series()).is_err());
    assert!(!path.exists());
    assert!(names(&dir).is_empty(), "{:?}", names(&dir));
    std::fs::remove_dir_all(&dir).unwrap();
}

#[test]
fn bad_heatmap_grids_write_nothing() {
    let dir = temp_dir("heatbad");
    let path = dir.join("h.png");
    let spec = PlotSpec::new("t", "x", "y");
    let e = heatmap(&path, &spec, &[0.0, 1.0], &[0.0, 1.0], &[1.0; 3], "v").unwrap_err();
    assert!(e.to_string().contains("values has 3 entries"), "{e}");
    assert!(e.to_string().contains("h.png"), "error names the file: {e}");
    assert!(heatmap(&path, &spec, &[1.0, 0.0], &[0.0], &[1.0; 2], "v").is_err());
    assert!(heatmap(&path, &spec, &[], &[0.0], &[], "v").is_err());
    assert!(heatmap(&path, &spec, &[0.0], &[0.0], &[f64::NAN], "v").is_err());
    let bad_range = spec.clone().color_range(1.0, 1.0);
    assert!(heatmap(&path, &bad_range, &[0.0], &[0.0], &[1.0], "v").is_err());
    assert!(!path.exists(), "nothing written on error");
    std::fs::remove_dir_all(&dir).unwrap();
}

/// A failed drawing leaves the image already there as it was.
#[test]
fn a_failed_plot_keeps_the_previous_image() {
    let dir = temp_dir("keep");
    let path = dir.join("p.png");
    let spec = PlotSpec::new("t", "x", "y").size(300, 200);
    line_plot(&path, &spec, &sine_series()).unwrap();
    let before = std::fs::read(&path).unwrap();
    assert!(line_plot(&path, &spec.clone().y_range(1.0, 0.0), &sine_series()).is_err());
    assert_eq!(std::fs::read(&path).unwrap(), before);
    assert_eq!(names(&dir), ["p.png"]);
    std::fs::remove_dir_all(&dir).unwrap();
}

#[test]
fn format_and_io_errors_name_the_file() {
    let dir = temp_dir("fmt");
    let spec = PlotSpec::new("t", "x", "y");
    let e = line_plot(&dir.join("plot.jpg"), &spec, &sine_series()).unwrap_err();
    assert!(
        matches!(e, DrawError::Plot(PlotError::UnsupportedFormat { .. })),
        "{e}"
    );
    assert!(e.to_string().contains("plot.jpg"));
    let missing = dir.join("no-such-dir").join("plot.png");
    let e = line_plot(&missing, &spec, &sine_series()).unwrap_err();
    assert!(matches!(e, DrawError::Plot(PlotError::Draw { .. })), "{e}");
    assert!(e.to_string().contains("no-such-dir"), "{e}");
    // An output that is not a file deflex may replace is refused before anything is written.
    let folder = dir.join("folder.png");
    std::fs::create_dir(&folder).unwrap();
    let e = line_plot(&folder, &spec, &sine_series()).unwrap_err();
    assert!(matches!(e, DrawError::Io(_)), "{e}");
    assert!(e.to_string().contains("folder.png"), "{e}");
    std::fs::remove_dir_all(&dir).unwrap();
}

/// The page written embeds each image as its file holds it: it is the page rendered from the
/// files' bytes.
#[test]
fn page_embeds_the_image_files() {
    let dir = temp_dir("page");
    let png = dir.join("fig.png");
    line_plot(
        &png,
        &PlotSpec::new("Fig", "x", "y").size(300, 200),
        &sine_series(),
    )
    .unwrap();
    let bytes = std::fs::read(&png).unwrap();
    let mut r = HtmlReport::new("Report & co");
    r.note("SIMULATED")
        .section("Plots")
        .image(&png, "Figure 1: <sine>");
    let out = dir.join("report.html");
    write_page(&r, &out).unwrap();
    let html = std::fs::read_to_string(&out).unwrap();
    let expected = r
        .render(|path| {
            assert_eq!(path, png.as_path());
            Ok(bytes.clone())
        })
        .unwrap();
    assert_eq!(html, expected);
    assert!(html.contains("data:image/png;base64,iVBORw0KGgo"));
    assert!(html.contains("<figcaption>Figure 1: &lt;sine&gt;</figcaption>"));
    assert_eq!(names(&dir), ["fig.png", "report.html"]);
    std::fs::remove_dir_all(&dir).unwrap();
}

/// An image that cannot be read is an I/O error naming it, and no page is written.
#[test]
fn missing_image_error_names_the_file() {
    let dir = temp_dir("missing");
    let mut r = HtmlReport::new("t");
    r.image("/nonexistent/deflex/fig.png", "c");
    let out = dir.join("index.html");
    let e = write_page(&r, &out).unwrap_err();
    assert!(matches!(e, DrawError::Plot(PlotError::Io { .. })), "{e}");
    assert!(e.to_string().contains("/nonexistent/deflex/fig.png"), "{e}");
    assert!(!out.exists());
    std::fs::remove_dir_all(&dir).unwrap();
}
