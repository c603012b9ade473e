//! Renders one sample of every plot kind, plus an HTML report embedding them,
//! from synthetic data.
//!
//! `cargo run -p deflex-plot --example samples [OUT_DIR]`
//! (default OUT_DIR: `/tmp/deflex-plot-samples`).

use std::path::{Path, PathBuf};

use deflex_plot::*;

/// Tiny deterministic noise source (xorshift), so samples are reproducible.
struct Noise(u64);
impl Noise {
    fn next(&mut self) -> f64 {
        self.0 ^= self.0 << 13;
        self.0 ^= self.0 >> 7;
        self.0 ^= self.0 << 17;
        (self.0 >> 11) as f64 / (1u64 << 53) as f64 - 0.5
    }
}

/// Writes an image drawn into memory to its file (a sample: a plain write; deflex's own outputs
/// are written whole or not at all by `deflex_app::report::draw`).
fn save(path: &Path, image: Image) -> Result<(), PlotError> {
    std::fs::write(path, image.bytes).map_err(|source| PlotError::Io {
        path: path.to_path_buf(),
        source,
    })
}

// One sample of every plot kind, drawn in sequence: a script of independent steps, kept as one
// function (≈ 275 lines) so that it reads top to bottom like the gallery it writes.
fn main() -> Result<(), PlotError> {
    let out = std::env::args()
        .nth(1)
        .map(PathBuf::from)
        .unwrap_or_else(|| PathBuf::from("/tmp/deflex-plot-samples"));
    std::fs::create_dir_all(&out).map_err(|source| PlotError::Io {
        path: out.clone(),
        source,
    })?;
    let mut rng = Noise(0x2545_f491_4f6c_dd1d);

    // Spiral trajectory (Fig. 14).
    let t: Vec<f64> = (0..400).map(|i| i as f64 * 0.05).collect();
    let sx: Vec<f64> = t.iter().map(|t| 600.0 + 8.0 * t * t.cos()).collect();
    let sy: Vec<f64> = t.iter().map(|t| 8.0 * t * t.sin()).collect();
    let spiral = out.join("spiral.png");
    save(
        &spiral,
        line_plot(
            &spiral,
            &PlotSpec::new("Spiral trajectory", "x [mm]", "y [mm]").size(700, 640),
            &[Series::line("commanded path", sx.clone(), sy.clone())],
        )?,
    )?;

    // Per-axis error and norm along a path (Fig. A1).
    let n = 120;
    let idx: Vec<f64> = (0..n).map(f64::from).collect();
    let mut axes = Vec::new();
    for (k, a) in ["x", "y", "z"].iter().enumerate() {
        let before: Vec<f64> = idx
            .iter()
            .map(|i| 0.4 * (i * 0.05 + k as f64).sin() + 0.05 * rng.next())
            .collect();
        let after: Vec<f64> = before.iter().map(|v| 0.2 * v + 0.02 * rng.next()).collect();
        axes.push((a.to_string(), before, after));
    }
    let norm = |after: bool| -> Vec<f64> {
        (0..n as usize)
            .map(|i| {
                axes.iter()
                    .map(|a| if after { a.2[i] } else { a.1[i] }.powi(2))
                    .sum::<f64>()
                    .sqrt()
            })
            .collect()
    };
    let (norm_b, norm_a) = (norm(false), norm(true));
    let mut panels: Vec<(PlotSpec, Vec<Series>)> = axes
        .iter()
        .map(|(a, b, c)| {
            (
                PlotSpec::new(
                    format!("{a} error"),
                    "point along path",
                    format!("e{a} [mm]"),
                )
                .size(900, 240),
                vec![
                    Series::line("uncompensated", idx.clone(), b.clone()),
                    Series::line("compensated", idx.clone(), c.clone()),
                ],
            )
        })
        .collect();
    panels.push((
        PlotSpec::new("error norm", "point along path", "|e| [mm]").size(900, 240),
        vec![
            Series::line("uncompensated", idx.clone(), norm_b.clone()),
            Series::line("compensated", idx.clone(), norm_a.clone()),
        ],
    ));
    let per_axis = out.join("error_per_axis.png");
    save(
        &per_axis,
        panels_plot(
            &per_axis,
            "Position error along the path",
            PanelLayout::Column,
            &panels,
        )?,
    )?;

    // Forces along a path, without and with compensation side by side (Fig. 18).
    let force = |scale: f64, rng: &mut Noise| -> Vec<Series> {
        ["Fx", "Fy", "Fz"]
            .iter()
            .enumerate()
            .map(|(k, f)| {
                let y = idx
                    .iter()
                    .map(|i| scale * (40.0 * (i * 0.04 + k as f64 * 2.0).cos() + 3.0 * rng.next()))
                    .collect();
                Series::line(*f, idx.clone(), y)
            })
            .collect()
    };
    let forces = out.join("forces.png");
    save(
        &forces,
        panels_plot(
            &forces,
            "Contact forces along the path",
            PanelLayout::Row,
            &[
                (
                    PlotSpec::new("without compensation", "point", "force [N]")
                        .size(640, 420)
                        .y_range(-50.0, 50.0),
                    force(1.0, &mut rng),
                ),
                (
                    PlotSpec::new("with compensation", "point", "force [N]")
                        .size(640, 420)
                        .y_range(-50.0, 50.0),
                    force(0.6, &mut rng),
                ),
            ],
        )?,
    )?;

    // Error vs force norm (Fig. 19).
    let fnorm: Vec<f64> = (0..150).map(|_| 10.0 + 90.0 * (rng.next() + 0.5)).collect();
    let err_b: Vec<f64> = fnorm
        .iter()
        .map(|f| 0.006 * f + 0.05 * rng.next())
        .collect();
    let err_a: Vec<f64> = fnorm
        .iter()
        .map(|f| 0.001 * f + 0.02 * rng.next())
        .collect();
    let err_force = out.join("error_vs_force.png");
    save(
        &err_force,
        line_plot(
            &err_force,
            &PlotSpec::new("Error vs force norm", "|F| [N]", "|e| [mm]"),
            &[
                Series::points("uncompensated", fnorm.clone(), err_b),
                Series::points("compensated", fnorm.clone(), err_a),
            ],
        )?,
    )?;

    // Prediction error heatmap over a grid (Fig. 11, 13), one NaN cell.
    let xs: Vec<f64> = (0..7).map(|i| 400.0 + 50.0 * i as f64).collect();
    let ys: Vec<f64> = (0..5).map(|j| -100.0 + 50.0 * j as f64).collect();
    let mut vals = Vec::new();
    for y in &ys {
        for x in &xs {
            vals.push(0.05 + 0.0004 * (x - 400.0) + 0.0003 * y.abs() + 0.01 * rng.next());
        }
    }
    vals[9] = f64::NAN;
    let heat = out.join("heatmap.png");
    let heat_spec = PlotSpec::new("Prediction error over the grid", "x [mm]", "y [mm]");
    save(
        &heat,
        heatmap(&heat, &heat_spec, &xs, &ys, &vals, "error norm [mm]")?,
    )?;
    save(
        &out.join("heatmap.svg"),
        heatmap(
            &out.join("heatmap.svg"),
            &heat_spec,
            &xs,
            &ys,
            &vals,
            "error norm [mm]",
        )?,
    )?;
    // A finer grid (no in-cell numbers).
    let fx: Vec<f64> = (0..40).map(|i| i as f64 * 10.0).collect();
    let fy: Vec<f64> = (0..25).map(|j| j as f64 * 10.0).collect();
    let fine: Vec<f64> = fy
        .iter()
        .flat_map(|y| {
            fx.iter()
                .map(move |x| ((x / 60.0).sin() * (y / 40.0).cos()).abs())
        })
        .collect();
    let heat_fine = out.join("heatmap_fine.png");
    save(
        &heat_fine,
        heatmap(
            &heat_fine,
            &PlotSpec::new("Fine grid", "x [mm]", "y [mm]"),
            &fx,
            &fy,
            &fine,
            "|e| [mm]",
        )?,
    )?;

    // Scattered measurement points coloured by error.
    let px: Vec<f64> = (0..60)
        .map(|i| 400.0 + 300.0 * (rng.next() + 0.5) + i as f64 * 0.0)
        .collect();
    let py: Vec<f64> = (0..60)
        .map(|_| -100.0 + 200.0 * (rng.next() + 0.5))
        .collect();
    let pv: Vec<f64> = px
        .iter()
        .zip(&py)
        .map(|(x, y)| 0.0004 * (x - 400.0) + 0.0003 * y.abs())
        .collect();
    let scatter = out.join("scatter_heatmap.png");
    save(
        &scatter,
        scatter_heatmap(
            &scatter,
            &PlotSpec::new("Error at measured points", "x [mm]", "y [mm]"),
            &px,
            &py,
            &pv,
            "error norm [mm]",
        )?,
    )?;

    // Predicted vs measured displacement (Fig. 8–10, 12).
    let measured: Vec<f64> = (0..80).map(|_| 1.2 * (rng.next() + 0.5)).collect();
    let predicted: Vec<f64> = measured
        .iter()
        .map(|m| 0.97 * m + 0.03 * rng.next())
        .collect();
    let parity = out.join("parity.png");
    save(
        &parity,
        parity_plot(
            &parity,
            &PlotSpec::new(
                "Predicted vs measured deflection",
                "measured [mm]",
                "predicted [mm]",
            )
            .size(640, 640),
            &predicted,
            &measured,
            "z displacement",
        )?,
    )?;

    // 3D deviation cloud (Fig. 17).
    let before: Vec<[f64; 3]> = (0..300)
        .map(|_| {
            [
                0.3 * rng.next() + 0.2,
                0.3 * rng.next() - 0.1,
                0.4 * rng.next() - 0.3,
            ]
        })
        .collect();
    let after: Vec<[f64; 3]> = (0..300)
        .map(|_| [0.08 * rng.next(), 0.08 * rng.next(), 0.1 * rng.next()])
        .collect();
    let cloud = out.join("cloud.png");
    save(
        &cloud,
        cloud_3d(
            &cloud,
            &Plot3Spec::new("Deviation cloud", "dx [mm]", "dy [mm]", "dz [mm]"),
            &[
                Cloud3::new("uncompensated", before),
                Cloud3::new("compensated", after),
            ],
        )?,
    )?;

    let mut r = HtmlReport::new("deflex sample report");
    r.note("SIMULATED: synthetic data, for checking the report layout only.")
        .section("Summary")
        .paragraph("Every plot kind of deflex-plot, rendered from synthetic data.")
        .table(
            &["axis", "RMSE before [mm]", "RMSE after [mm]"],
            &[
                vec!["x".into(), "0.283".into(), "0.057".into()],
                vec!["y".into(), "0.291".into(), "0.059".into()],
                vec!["z".into(), "0.279".into(), "0.056".into()],
            ],
        );
    for (heading, path, caption) in [
        ("Trajectory", &spiral, "Spiral trajectory"),
        (
            "Errors along the path",
            &per_axis,
            "Per-axis error and norm",
        ),
        ("Forces", &forces, "Forces without and with compensation"),
        (
            "Error vs force",
            &err_force,
            "Error norm against force norm",
        ),
        ("Error maps", &heat, "Prediction error over the grid"),
        ("Error maps (fine)", &heat_fine, "Fine grid"),
        ("Scattered points", &scatter, "Error at measured points"),
        ("Model validation", &parity, "Predicted vs measured"),
        ("Deviation", &cloud, "3D deviation cloud"),
    ] {
        r.section(heading).image(path, caption);
    }
    let page = out.join("report.html");
    let html = r.render(|image| std::fs::read(image))?;
    std::fs::write(&page, html).map_err(|source| PlotError::Io { path: page, source })?;
    println!("samples written to {}", out.display());
    Ok(())
}
