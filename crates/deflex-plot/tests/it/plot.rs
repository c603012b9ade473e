use crate::{count, png_dims, png_pixels, sine_series, svg_text};
use deflex_plot::{
    Image, LineStyle, PanelLayout, PlotError, PlotSpec, Series, SeriesStyle, clip_segment,
    line_plot, palette_color, panels_plot, parity_plot, strokable_pieces,
};
use std::path::Path;

#[test]
fn clipping_keeps_the_part_inside_the_rectangle() {
    let (xr, yr) = ((0.0, 10.0), (0.0, 1.0));
    // Crosses the bottom edge half-way, and a segment wholly below.
    assert_eq!(
        clip_segment((0.0, 1.0), (2.0, -1.0), xr, yr),
        Some((0.0, 0.5))
    );
    assert_eq!(clip_segment((0.0, -1.0), (2.0, -0.5), xr, yr), None);
    let pieces = strokable_pieces(
        &[(0.0, 0.5), (1.0, 0.5), (2.0, -1.0), (3.0, 0.5), (4.0, 0.5)],
        xr,
        yr,
        (1000, 100),
    );
    assert_eq!(pieces.len(), 2, "{pieces:?}");
    for p in &pieces {
        assert!(
            p.iter()
                .all(|&(x, y)| (0.0..=10.0).contains(&x) && (0.0..=1.0).contains(&y))
        );
    }
    assert!((pieces[0].last().unwrap().1).abs() < 1e-12, "{pieces:?}");
}

#[test]
fn sharp_turns_end_the_stroke_and_gentle_ones_do_not() {
    let (xr, yr) = ((0.0, 100.0), (0.0, 100.0));
    // A spike up and down one pixel apart: cut at its tip; a 45° bend: kept whole.
    let spike = strokable_pieces(
        &[(10.0, 0.0), (11.0, 90.0), (12.0, 0.0)],
        xr,
        yr,
        (100, 100),
    );
    assert_eq!(
        spike,
        vec![
            vec![(10.0, 0.0), (11.0, 90.0)],
            vec![(11.0, 90.0), (12.0, 0.0)]
        ]
    );
    let bend = strokable_pieces(&[(0.0, 0.0), (50.0, 0.0), (90.0, 40.0)], xr, yr, (100, 100));
    assert_eq!(bend.len(), 1);
    assert_eq!(bend[0].len(), 3);
}

/// Red pixels outside the plotting area of a chart drawn by `line_plot` with no title (margin
/// 14 px, y label area 86 px, x label area 58 px; 2 px of slack for the stroke).
fn red_outside_plot_area(image: &Image) -> usize {
    let (w, h) = png_dims(image);
    let pixels = png_pixels(image);
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

#[test]
fn line_plot_png_decodes_with_requested_size_and_colours() {
    let path = Path::new("line.png");
    let spec = PlotSpec::new("Sine", "t [s]", "u [mm]").size(640, 400);
    let image = line_plot(path, &spec, &sine_series()).unwrap();
    assert_eq!(png_dims(&image), (640, 400));
    let px = png_pixels(&image);
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
    let path = Path::new("line.svg");
    let spec = PlotSpec::new("Deflection along path", "time [s]", "deflection [mm]");
    let svg = svg_text(line_plot(path, &spec, &sine_series()).unwrap());
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
    let col = panels_plot(Path::new("col.png"), "Errors", PanelLayout::Column, &panels).unwrap();
    assert_eq!(png_dims(&col), (500, 4 * 220 + 50));
    let row = panels_plot(Path::new("row.png"), "", PanelLayout::Row, &panels[..2]).unwrap();
    assert_eq!(png_dims(&row), (1000, 220));
    let grid = Path::new("grid.png");
    let image = panels_plot(grid, "G", PanelLayout::Grid { columns: 3 }, &panels).unwrap();
    assert_eq!(png_dims(&image), (1500, 2 * 220 + 50));
    let e = panels_plot(grid, "G", PanelLayout::Grid { columns: 0 }, &panels).unwrap_err();
    assert!(matches!(e, PlotError::InvalidInput { .. }));
    assert!(panels_plot(grid, "G", PanelLayout::Row, &[]).is_err());
}

#[test]
fn parity_plot_renders_and_checks_inputs() {
    let path = Path::new("p.png");
    let measured: Vec<f64> = (0..30).map(|i| i as f64 * 0.02).collect();
    let predicted: Vec<f64> = measured.iter().map(|m| m * 1.05 + 0.01).collect();
    let spec = PlotSpec::new("Parity", "measured [mm]", "predicted [mm]").size(500, 500);
    let image = parity_plot(path, &spec, &predicted, &measured, "z").unwrap();
    assert_eq!(png_dims(&image), (500, 500));
    let svg = parity_plot(Path::new("p.svg"), &spec, &predicted, &measured, "z").unwrap();
    let text = svg_text(svg);
    assert!(
        text.contains("y = x") && text.contains("n = 30"),
        "legend text"
    );
    let e = parity_plot(path, &spec, &predicted[..2], &measured, "z").unwrap_err();
    assert!(matches!(e, PlotError::InvalidInput { .. }));
    assert!(parity_plot(path, &spec, &[f64::NAN], &[1.0], "z").is_err());
}

/// Bad series are refused, the error naming the image (that nothing is written then is tested
/// where images are written: deflex-app's `report::draw`).
#[test]
fn series_input_errors() {
    let path = Path::new("e.png");
    let spec = PlotSpec::new("t", "x", "y");
    let e = line_plot(path, &spec, &[Series::line("a", vec![1.0, 2.0], vec![1.0])]).unwrap_err();
    assert!(e.to_string().contains("x has 2 values but y has 1"), "{e}");
    assert_eq!(e.path(), path);
    assert!(line_plot(path, &spec, &[]).is_err());
    assert!(line_plot(path, &spec, &[Series::line("a", vec![], vec![])]).is_err());
    let nan = Series::line("a", vec![f64::NAN, 1.0], vec![1.0, f64::INFINITY]);
    assert!(line_plot(path, &spec, &[nan]).is_err());
    let bad_size = spec.clone().size(0, 100);
    assert!(line_plot(path, &bad_size, &sine_series()).is_err());
    let bad_range = spec.clone().y_range(1.0, 0.0);
    assert!(line_plot(path, &bad_range, &sine_series()).is_err());
}

#[test]
fn non_finite_points_are_skipped() {
    let y = vec![0.0, 1.0, f64::NAN, 3.0, 4.0, f64::INFINITY, 6.0];
    let s = Series::indexed("gappy", y, SeriesStyle::LineAndPoints);
    let image = line_plot(Path::new("g.png"), &PlotSpec::new("Gaps", "i", "y"), &[s]).unwrap();
    assert_eq!(png_dims(&image), (900, 560));
}

/// An image path of another format is refused, naming the file. (A folder that does not exist
/// is the writer's error: deflex-app's `report::draw` checks it names the file.)
#[test]
fn format_and_io_errors_name_the_file() {
    let spec = PlotSpec::new("t", "x", "y");
    let e = line_plot(Path::new("out/plot.jpg"), &spec, &sine_series()).unwrap_err();
    assert!(matches!(e, PlotError::UnsupportedFormat { .. }), "{e}");
    assert!(e.to_string().contains("plot.jpg"));
}

#[test]
fn rendering_is_deterministic() {
    let spec = PlotSpec::new("Same", "x", "y").size(400, 300);
    let a = line_plot(Path::new("a.png"), &spec, &sine_series()).unwrap();
    let b = line_plot(Path::new("b.png"), &spec, &sine_series()).unwrap();
    assert_eq!(a.bytes, b.bytes);
}

/// A dashed series leaves gaps along its line that a solid one does not: the colours are
/// counted along the horizontal line each draws.
#[test]
fn dashed_and_dotted_series_are_drawn_with_gaps() {
    let x = vec![0.0, 10.0];
    let series = [
        Series::line("solid", x.clone(), vec![1.0, 1.0]),
        Series::line("dashed", x.clone(), vec![2.0, 2.0]).with_line(LineStyle::Dashed),
        Series::line("dotted", x.clone(), vec![3.0, 3.0])
            .with_line(LineStyle::Dotted)
            .with_color((200, 0, 200)),
    ];
    let spec = PlotSpec::new("Dashes", "x", "y")
        .size(600, 400)
        .y_range(0.0, 4.0);
    let px = png_pixels(&line_plot(Path::new("d.png"), &spec, &series).unwrap());
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

/// A dense series that reverses sharply at every point (a path error with spikes, 10 ms rows
/// over a long run) is drawn inside the plotting area: the stroke's joins never reach into the
/// tick labels (plotters' wide-line joins grow without bound at near-reversals), and data past
/// a given y range is clipped at the frame.
#[test]
fn spiky_series_stay_inside_the_plotting_area() {
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
    let auto = line_plot(Path::new("auto.png"), &spec, &series).unwrap();
    let drawn = count(&png_pixels(&auto), (255, 0, 0));
    assert!(drawn > 10_000, "the series is drawn ({drawn} red pixels)");
    assert_eq!(red_outside_plot_area(&auto), 0, "autoscaled y range");
    let fixed_spec = spec.clone().y_range(0.0, 0.3);
    let fixed = line_plot(Path::new("fixed.png"), &fixed_spec, &series).unwrap();
    assert_eq!(red_outside_plot_area(&fixed), 0, "y range (0, 0.3 mm)");
}
