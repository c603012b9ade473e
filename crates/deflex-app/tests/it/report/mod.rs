//! deflex-report's tests, through its public API. Here: rendering, files are written to a
//! unique temp dir, decoded back and inspected; a module per report and per piece.

use std::path::{Path, PathBuf};
use std::sync::atomic::{AtomicUsize, Ordering};

use deflex_plot::*;
use deflex_app::report::*;

mod base64;
mod calibration;
mod colormap;
mod font;
mod forming_folder;
mod heatmap;
mod html;
mod plan;
mod plot;
mod render;
mod run_figures;
mod study;
mod timeline;
mod validation;

/// A fresh, unique directory under the system temp dir.
fn temp_dir(name: &str) -> PathBuf {
    static COUNTER: AtomicUsize = AtomicUsize::new(0);
    let n = COUNTER.fetch_add(1, Ordering::Relaxed);
    let nanos = std::time::SystemTime::now()
        .duration_since(std::time::UNIX_EPOCH)
        .map(|d| d.subsec_nanos())
        .unwrap_or(0);
    let dir = std::env::temp_dir().join(format!(
        "deflex-report-test-{}-{n}-{nanos}-{name}",
        std::process::id()
    ));
    std::fs::create_dir_all(&dir).unwrap();
    dir
}

/// Checks the PNG signature and returns the IHDR width and height.
fn png_dims(path: &Path) -> (u32, u32) {
    let b = std::fs::read(path).unwrap();
    assert!(b.len() > 33, "{} too short", path.display());
    assert_eq!(&b[..8], b"\x89PNG\r\n\x1a\n", "PNG signature");
    assert_eq!(&b[12..16], b"IHDR", "first chunk is IHDR");
    let w = u32::from_be_bytes([b[16], b[17], b[18], b[19]]);
    let h = u32::from_be_bytes([b[20], b[21], b[22], b[23]]);
    (w, h)
}

/// Decodes a PNG fully and returns its RGB pixels.
fn png_pixels(path: &Path) -> Vec<(u8, u8, u8)> {
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

fn count(pixels: &[(u8, u8, u8)], c: (u8, u8, u8)) -> usize {
    pixels.iter().filter(|&&p| p == c).count()
}

fn sine_series() -> Vec<Series> {
    let x: Vec<f64> = (0..100).map(|i| i as f64 * 0.1).collect();
    vec![
        Series::line("sin", x.clone(), x.iter().map(|v| v.sin()).collect()),
        Series::points("cos", x.clone(), x.iter().map(|v| v.cos()).collect()),
    ]
}

#[test]
fn line_plot_png_decodes_with_requested_size_and_colours() {
    let dir = temp_dir("line");
    let path = dir.join("line.png");
    let spec = PlotSpec::new("Sine", "t [s]", "u [mm]").size(640, 400);
    line_plot(&path, &spec, &sine_series()).unwrap();
    assert_eq!(png_dims(&path), (640, 400));
    let px = png_pixels(&path);
    assert_eq!(px.len(), 640 * 400);
    assert!(
        count(&px, palette_color(0)) > 50,
        "first series colour drawn"
    );
    assert!(
        count(&px, palette_color(1)) > 50,
        "second series colour drawn"
    );
    assert!(
        count(&px, (255, 255, 255)) > px.len() / 2,
        "white background"
    );
}

#[test]
fn svg_contains_title_and_labels() {
    let dir = temp_dir("svg");
    let path = dir.join("line.svg");
    let spec = PlotSpec::new("Deflection along path", "time [s]", "deflection [mm]");
    line_plot(&path, &spec, &sine_series()).unwrap();
    let svg = std::fs::read_to_string(&path).unwrap();
    assert!(svg.starts_with("<svg"), "{}", &svg[..svg.len().min(80)]);
    for text in [
        "Deflection along path",
        "time [s]",
        "deflection [mm]",
        "sin",
        "cos",
    ] {
        assert!(svg.contains(text), "SVG lacks {text:?}");
    }
}

#[test]
fn panels_plot_sizes_the_grid() {
    let dir = temp_dir("panels");
    let x: Vec<f64> = (0..50).map(f64::from).collect();
    let panel = |t: &str| {
        (
            PlotSpec::new(t, "point", "error [mm]").size(500, 220),
            vec![Series::line(
                t,
                x.clone(),
                x.iter().map(|v| v * 0.01).collect(),
            )],
        )
    };
    let panels = vec![panel("x"), panel("y"), panel("z"), panel("norm")];
    let col = dir.join("col.png");
    panels_plot(&col, "Errors", PanelLayout::Column, &panels).unwrap();
    assert_eq!(png_dims(&col), (500, 4 * 220 + 50));
    let row = dir.join("row.png");
    panels_plot(&row, "", PanelLayout::Row, &panels[..2]).unwrap();
    assert_eq!(png_dims(&row), (1000, 220));
    let grid = dir.join("grid.png");
    panels_plot(&grid, "G", PanelLayout::Grid { columns: 3 }, &panels).unwrap();
    assert_eq!(png_dims(&grid), (1500, 2 * 220 + 50));
    let e = panels_plot(&grid, "G", PanelLayout::Grid { columns: 0 }, &panels).unwrap_err();
    assert!(matches!(e, PlotError::InvalidInput { .. }));
    assert!(panels_plot(&grid, "G", PanelLayout::Row, &[]).is_err());
}

#[test]
fn heatmap_uses_colormap_endpoints_and_blank_nan_cells() {
    let dir = temp_dir("heat");
    let path = dir.join("heat.png");
    let xs = [0.0, 1.0, 2.0, 3.0];
    let ys = [10.0, 20.0, 30.0];
    let mut values: Vec<f64> = (0..12).map(f64::from).collect();
    values[5] = f64::NAN;
    let spec = PlotSpec::new("Error", "x [mm]", "y [mm]").size(700, 450);
    heatmap(&path, &spec, &xs, &ys, &values, "error [mm]").unwrap();
    assert_eq!(png_dims(&path), (700, 450));
    let px = png_pixels(&path);
    // Min cell and max cell take the exact colour-map endpoints.
    assert!(count(&px, viridis(0.0)) > 500, "min colour present");
    assert!(count(&px, viridis(1.0)) > 500, "max colour present");
    // The SVG variant carries the colour-bar label.
    let svg = dir.join("heat.svg");
    heatmap(&svg, &spec, &xs, &ys, &values, "error [mm]").unwrap();
    let text = std::fs::read_to_string(&svg).unwrap();
    assert!(text.contains("error [mm]") && text.contains("Error"));
}

#[test]
fn heatmap_rejects_bad_grids() {
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
}

#[test]
fn scatter_heatmap_renders_and_checks_lengths() {
    let dir = temp_dir("scatter");
    let path = dir.join("s.png");
    let x: Vec<f64> = (0..40)
        .map(|i| (i % 8) as f64 * 50.0 + (i as f64 * 0.7).sin() * 10.0)
        .collect();
    let y: Vec<f64> = (0..40).map(|i| (i / 8) as f64 * 40.0).collect();
    let v: Vec<f64> = x
        .iter()
        .zip(&y)
        .map(|(a, b)| (a * a + b * b).sqrt() / 100.0)
        .collect();
    let spec = PlotSpec::new("Scatter", "x [mm]", "y [mm]").size(600, 420);
    scatter_heatmap(&path, &spec, &x, &y, &v, "|e| [mm]").unwrap();
    assert_eq!(png_dims(&path), (600, 420));
    let e = scatter_heatmap(&path, &spec, &x, &y[..3], &v, "v").unwrap_err();
    assert!(e.to_string().contains("equal lengths"), "{e}");
    assert!(scatter_heatmap(&path, &spec, &[], &[], &[], "v").is_err());
}

#[test]
fn parity_plot_renders_and_checks_inputs() {
    let dir = temp_dir("parity");
    let path = dir.join("p.png");
    let measured: Vec<f64> = (0..30).map(|i| i as f64 * 0.02).collect();
    let predicted: Vec<f64> = measured.iter().map(|m| m * 1.05 + 0.01).collect();
    let spec = PlotSpec::new("Parity", "measured [mm]", "predicted [mm]").size(500, 500);
    parity_plot(&path, &spec, &predicted, &measured, "z").unwrap();
    assert_eq!(png_dims(&path), (500, 500));
    let svg = dir.join("p.svg");
    parity_plot(&svg, &spec, &predicted, &measured, "z").unwrap();
    let text = std::fs::read_to_string(&svg).unwrap();
    assert!(
        text.contains("y = x") && text.contains("n = 30"),
        "legend text"
    );
    let e = parity_plot(&path, &spec, &predicted[..2], &measured, "z").unwrap_err();
    assert!(matches!(e, PlotError::InvalidInput { .. }));
    assert!(parity_plot(&path, &spec, &[f64::NAN], &[1.0], "z").is_err());
}

#[test]
fn cloud_3d_renders_png_and_svg() {
    let dir = temp_dir("cloud");
    let pts: Vec<[f64; 3]> = (0..200)
        .map(|i| {
            let t = i as f64 * 0.1;
            [t.cos(), t.sin(), t * 0.05]
        })
        .collect();
    let spec = Plot3Spec::new("Deviation", "dx [mm]", "dy [mm]", "dz [mm]").size(640, 560);
    let clouds = [
        Cloud3::new("spiral", pts),
        Cloud3::new("origin", vec![[0.0; 3]]),
    ];
    let png = dir.join("c.png");
    cloud_3d(&png, &spec, &clouds).unwrap();
    assert_eq!(png_dims(&png), (640, 560));
    let svg = dir.join("c.svg");
    cloud_3d(&svg, &spec, &clouds).unwrap();
    let text = std::fs::read_to_string(&svg).unwrap();
    for t in ["Deviation", "dx [mm]", "dy [mm]", "dz [mm]", "spiral"] {
        assert!(text.contains(t), "SVG lacks {t:?}");
    }
    assert!(cloud_3d(&png, &spec, &[]).is_err());
    assert!(cloud_3d(&png, &spec, &[Cloud3::new("e", vec![])]).is_err());
    assert!(cloud_3d(&png, &spec, &[Cloud3::new("n", vec![[f64::NAN; 3]])]).is_err());
}

#[test]
fn series_input_errors() {
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
}

#[test]
fn non_finite_points_are_skipped() {
    let dir = temp_dir("gaps");
    let path = dir.join("g.png");
    let y = vec![0.0, 1.0, f64::NAN, 3.0, 4.0, f64::INFINITY, 6.0];
    let s = Series::indexed("gappy", y, SeriesStyle::LineAndPoints);
    line_plot(&path, &PlotSpec::new("Gaps", "i", "y"), &[s]).unwrap();
    assert_eq!(png_dims(&path), (900, 560));
}

#[test]
fn format_and_io_errors_name_the_file() {
    let dir = temp_dir("fmt");
    let spec = PlotSpec::new("t", "x", "y");
    let e = line_plot(&dir.join("plot.jpg"), &spec, &sine_series()).unwrap_err();
    assert!(matches!(e, PlotError::UnsupportedFormat { .. }), "{e}");
    assert!(e.to_string().contains("plot.jpg"));
    let missing = dir.join("no-such-dir").join("plot.png");
    let e = line_plot(&missing, &spec, &sine_series()).unwrap_err();
    assert!(matches!(e, PlotError::Draw { .. }), "{e}");
    assert!(e.to_string().contains("no-such-dir"), "{e}");
}

#[test]
fn html_report_embeds_png_as_data_uri() {
    let dir = temp_dir("html");
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
        .paragraph("See below.")
        .image(&png, "Figure 1: <sine>");
    let out = dir.join("report.html");
    r.write(&out).unwrap();
    let html = std::fs::read_to_string(&out).unwrap();
    let uri = format!("data:image/png;base64,{}", base64_encode(&bytes));
    assert!(html.contains(&uri), "whole PNG embedded");
    assert!(
        html.contains("data:image/png;base64,iVBORw0KGgo"),
        "PNG magic in base64"
    );
    assert!(html.contains("<figcaption>Figure 1: &lt;sine&gt;</figcaption>"));
    assert!(html.contains("<title>Report &amp; co</title>"));
    assert!(
        !html.contains("http://") && !html.contains("https://"),
        "no network"
    );
}

#[test]
fn rendering_is_deterministic() {
    let dir = temp_dir("det");
    let (a, b) = (dir.join("a.png"), dir.join("b.png"));
    let spec = PlotSpec::new("Same", "x", "y").size(400, 300);
    line_plot(&a, &spec, &sine_series()).unwrap();
    line_plot(&b, &spec, &sine_series()).unwrap();
    assert_eq!(std::fs::read(a).unwrap(), std::fs::read(b).unwrap());
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
    let dir = temp_dir("wrap");
    let path = dir.join("w.png");
    let title = "SIMULATED cell — a title far too long to fit on one line of a narrow plot";
    let layout = title_layout(title, 500, 24);
    assert_eq!(layout.lines.len(), 2, "{layout:?}");
    line_plot(
        &path,
        &PlotSpec::new(title, "x", "y").size(500, 400),
        &sine_series(),
    )
    .unwrap();
    let px = png_pixels(&path);
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

/// A dashed series leaves gaps along its line that a solid one does not: the colours are
/// counted along the horizontal line each draws.
#[test]
fn dashed_and_dotted_series_are_drawn_with_gaps() {
    let dir = temp_dir("dash");
    let x = vec![0.0, 10.0];
    let series = [
        Series::line("solid", x.clone(), vec![1.0, 1.0]),
        Series::line("dashed", x.clone(), vec![2.0, 2.0]).with_line(LineStyle::Dashed),
        Series::line("dotted", x.clone(), vec![3.0, 3.0])
            .with_line(LineStyle::Dotted)
            .with_color((200, 0, 200)),
    ];
    let path = dir.join("d.png");
    let spec = PlotSpec::new("Dashes", "x", "y")
        .size(600, 400)
        .y_range(0.0, 4.0);
    line_plot(&path, &spec, &series).unwrap();
    let px = png_pixels(&path);
    // Runs of a colour along the row where it is densest.
    let runs = |c: (u8, u8, u8)| -> usize {
        (0..400)
            .map(|y| {
                let row = &px[y * 600..(y + 1) * 600];
                row.windows(2).filter(|w| w[0] != c && w[1] == c).count()
            })
            .max()
            .unwrap_or(0)
    };
    let (solid, dashed, dotted) = (
        runs(palette_color(0)),
        runs(palette_color(1)),
        runs((200, 0, 200)),
    );
    assert!(solid <= 3, "solid line is continuous: {solid} runs");
    assert!(dashed >= 20, "dashed line: {dashed} runs");
    assert!(dotted > dashed, "dotted {dotted} vs dashed {dashed}");
}

#[test]
fn timeline_draws_lanes_and_checks_intervals() {
    let dir = temp_dir("timeline");
    let path = dir.join("t.png");
    let t: Vec<f64> = (0..1000).map(|k| k as f64 * 0.01).collect();
    let on: Vec<bool> = t.iter().map(|v| (2.0..6.0).contains(v)).collect();
    let lanes = [
        Lane::from_samples("active", &t, &on),
        Lane::new("fault (never)", vec![]),
        Lane::new("one cycle", vec![(5.0, 5.0)]).with_color((200, 0, 200)),
    ];
    let spec = PlotSpec::new("Controller state", "time [s]", "").size(800, 300);
    timeline_plot(&path, &spec, &lanes).unwrap();
    assert_eq!(png_dims(&path), (800, 300));
    let px = png_pixels(&path);
    assert!(count(&px, palette_color(0)) > 1000, "active bar drawn");
    assert!(
        count(&px, (200, 0, 200)) > 10,
        "a zero-length interval stays visible"
    );
    let svg = dir.join("t.svg");
    timeline_plot(&svg, &spec, &lanes).unwrap();
    let text = std::fs::read_to_string(&svg).unwrap();
    assert!(text.contains("fault (never)") && text.contains("time [s]"));
    assert!(timeline_plot(&path, &spec, &[]).is_err());
    let bad = [Lane::new("b", vec![(2.0, 1.0)])];
    assert!(timeline_plot(&path, &spec, &bad).is_err());
    let empty = [Lane::new("e", vec![])];
    assert!(timeline_plot(&path, &spec, &empty).is_err());
    assert!(timeline_plot(&path, &spec.clone().x_range(0.0, 1.0), &empty).is_ok());
}

#[test]
fn html_contents_and_file_links() {
    let mut r = HtmlReport::new("t");
    r.contents()
        .section("1. Plan & campaign")
        .subsection("Points")
        .section("Data files")
        .files(&[
            FileLink::new("plan.csv", "the plan <rows>"),
            FileLink::new("forming_open/log.csv", "the log"),
        ])
        .section("Data files");
    let html = r.render().unwrap();
    assert!(html.contains("<h2 id=\"1-plan-campaign\">1. Plan &amp; campaign</h2>"));
    assert!(html.contains("<h3 id=\"points\">Points</h3>"));
    assert!(html.contains("<h2 id=\"data-files-2\">"), "unique ids");
    assert!(html.contains("<a href=\"#1-plan-campaign\">1. Plan &amp; campaign</a>"));
    assert!(html.contains("<a href=\"#points\">"));
    assert!(html.contains("<a href=\"#data-files-2\">"));
    assert!(html.contains("<a href=\"plan.csv\"><code>plan.csv</code></a>: the plan &lt;rows&gt;"));
    assert!(html.contains("<a href=\"forming_open/log.csv\">"));
    for bad in [
        "/etc/passwd",
        "../x.csv",
        "a/../../x.csv",
        "http://x/y.csv",
        "javascript:alert(1)",
        "a b.csv",
        "",
    ] {
        let mut r = HtmlReport::new("t");
        r.files(&[FileLink::new(bad, "d")]);
        assert!(r.render().is_err(), "{bad:?} accepted");
    }
}

/// Red pixels outside the plotting area of a chart drawn by `line_plot` with no title (margin
/// 14 px, y label area 86 px, x label area 58 px; 2 px of slack for the stroke).
fn red_outside_plot_area(path: &Path) -> usize {
    let (w, h) = png_dims(path);
    let pixels = png_pixels(path);
    let (left, right, top, bottom) = (14 + 86 - 2, w - 14 + 2, 14 - 2, h - 14 - 58 + 2);
    pixels
        .iter()
        .enumerate()
        .filter(|&(i, &p)| {
            let (col, row) = (i as u32 % w, i as u32 / w);
            p == (255, 0, 0) && (col < left || col > right || row < top || row > bottom)
        })
        .count()
}

/// A dense series that reverses sharply at every point (a path error with spikes, 10 ms rows
/// over a long run) is drawn inside the plotting area: the stroke's joins never reach into the
/// tick labels (plotters' wide-line joins grow without bound at near-reversals), and data past
/// a given y range is clipped at the frame.
#[test]
fn spiky_series_stay_inside_the_plotting_area() {
    let dir = temp_dir("spikes");
    let n = 6000;
    let x: Vec<f64> = (0..n).map(|i| i as f64 * 0.013).collect();
    // Small values with a spike every few rows, as |error| of a corrected run.
    let y: Vec<f64> = (0..n)
        .map(|i| match i % 7 {
            3 => 0.5 + 0.4 * ((i as f64) * 0.37).sin().abs(),
            5 => 0.2 + 0.1 * ((i as f64) * 0.11).cos(),
            _ => 0.02 + 0.01 * ((i as f64) * 0.5).sin(),
        })
        .collect();
    let series = vec![Series::line("", x, y).with_color((255, 0, 0))];
    let spec = PlotSpec::new("", "time [s]", "|error| [mm]").size(1100, 500);
    let auto = dir.join("auto.png");
    line_plot(&auto, &spec, &series).unwrap();
    let drawn = count(&png_pixels(&auto), (255, 0, 0));
    assert!(drawn > 10_000, "the series is drawn ({drawn} red pixels)");
    assert_eq!(red_outside_plot_area(&auto), 0, "autoscaled y range");
    let fixed = dir.join("fixed.png");
    line_plot(&fixed, &spec.clone().y_range(0.0, 0.3), &series).unwrap();
    assert_eq!(red_outside_plot_area(&fixed), 0, "y range (0, 0.3 mm)");
    std::fs::remove_dir_all(&dir).unwrap();
}
