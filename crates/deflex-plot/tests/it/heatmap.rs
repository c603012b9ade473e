use crate::{count, png_dims, png_pixels, svg_text};
use deflex_plot::{PlotSpec, cell_edges, cell_value_text, heatmap, scatter_heatmap, viridis};
use std::path::Path;

#[test]
fn edges_are_midpoints() {
    assert_eq!(cell_edges(&[0.0, 1.0, 3.0]), vec![-0.5, 0.5, 2.0, 4.0]);
    assert_eq!(cell_edges(&[2.0]), vec![1.9, 2.1]);
}

#[test]
fn value_labels_have_three_significant_digits() {
    assert_eq!(cell_value_text(0.12345), "0.123");
    assert_eq!(cell_value_text(1.2345), "1.23");
    assert_eq!(cell_value_text(123.45), "123");
    assert_eq!(cell_value_text(0.0), "0.000");
}

#[test]
fn heatmap_uses_colormap_endpoints_and_blank_nan_cells() {
    let path = Path::new("heat.png");
    let xs = [0.0, 1.0, 2.0, 3.0];
    let ys = [10.0, 20.0, 30.0];
    let mut values: Vec<f64> = (0..12).map(f64::from).collect();
    values[5] = f64::NAN;
    let spec = PlotSpec::new("Error", "x [mm]", "y [mm]").size(700, 450);
    let image = heatmap(path, &spec, &xs, &ys, &values, "error [mm]").unwrap();
    assert_eq!(png_dims(&image), (700, 450));
    let px = png_pixels(&image);
    // Min cell and max cell take the exact colour-map endpoints.
    assert!(count(&px, viridis(0.0)) > 500, "min colour present");
    assert!(count(&px, viridis(1.0)) > 500, "max colour present");
    // The SVG variant carries the colour-bar label.
    let svg = heatmap(
        Path::new("heat.svg"),
        &spec,
        &xs,
        &ys,
        &values,
        "error [mm]",
    )
    .unwrap();
    let text = svg_text(svg);
    assert!(text.contains("error [mm]") && text.contains("Error"));
}

/// Bad grids are refused, the error naming the image (that nothing is written then is tested
/// where images are written: deflex-app's `report::draw`).
#[test]
fn heatmap_rejects_bad_grids() {
    let path = Path::new("h.png");
    let spec = PlotSpec::new("t", "x", "y");
    let e = heatmap(path, &spec, &[0.0, 1.0], &[0.0, 1.0], &[1.0; 3], "v").unwrap_err();
    assert!(e.to_string().contains("values has 3 entries"), "{e}");
    assert!(e.to_string().contains("h.png"), "error names the file: {e}");
    assert!(heatmap(path, &spec, &[1.0, 0.0], &[0.0], &[1.0; 2], "v").is_err());
    assert!(heatmap(path, &spec, &[], &[0.0], &[], "v").is_err());
    assert!(heatmap(path, &spec, &[0.0], &[0.0], &[f64::NAN], "v").is_err());
    let bad_range = spec.clone().color_range(1.0, 1.0);
    assert!(heatmap(path, &bad_range, &[0.0], &[0.0], &[1.0], "v").is_err());
}

#[test]
fn scatter_heatmap_renders_and_checks_lengths() {
    let path = Path::new("s.png");
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
    let image = scatter_heatmap(path, &spec, &x, &y, &v, "|e| [mm]").unwrap();
    assert_eq!(png_dims(&image), (600, 420));
    let e = scatter_heatmap(path, &spec, &x, &y[..3], &v, "v").unwrap_err();
    assert!(e.to_string().contains("equal lengths"), "{e}");
    assert!(scatter_heatmap(path, &spec, &[], &[], &[], "v").is_err());
}
