//! PNG plots of a forming run, after the paper's figures: the 3D deviation cloud (Fig. 17), the
//! error per axis and in norm along the path (Fig. A1), the forces (Fig. 18), the error versus
//! the force norm (Fig. 19), and the formed profile. Every title says SIMULATED.

use crate::error::SimError;
use crate::forming::FormingRun;
use deflex_report::{
    Cloud3, PanelLayout, Plot3Spec, PlotSpec, Series, cloud_3d, line_plot, panels_plot,
};
use std::path::{Path, PathBuf};

fn report_error(path: &Path, e: deflex_report::ReportError) -> SimError {
    SimError::output(path, e)
}

/// Draw every plot of a run into `dir`; returns the files.
pub fn forming_plots(run: &FormingRun, dir: &Path) -> Result<Vec<PathBuf>, SimError> {
    let log = &run.log;
    let mut files = Vec::new();
    if log.rows.len() < 2 {
        return Ok(files);
    }
    let mode = format!(
        "{}, {}",
        run.summary.robot,
        if run.summary.correction {
            "with correction"
        } else {
            "without correction"
        }
    );
    let mode = mode.as_str();
    let t = log.column(|r| r.time_s);
    let err = |i: usize| log.column(move |r| (r.truth.true_m[i] - r.truth.desired_m[i]) * 1e3);
    let norm = log.column(|r| (r.truth.true_m - r.truth.desired_m).norm() * 1e3);
    let force = |i: usize| log.column(move |r| r.truth.wrench[i]);
    let force_norm = log.column(|r| r.truth.wrench.fixed_rows::<3>(0).norm());

    // Fig. 17: deviation cloud.
    let path = dir.join("deviation_cloud.png");
    let points: Vec<[f64; 3]> = (0..t.len())
        .map(|k| {
            let e = log.rows[k].truth.true_m - log.rows[k].truth.desired_m;
            [e.x * 1e3, e.y * 1e3, e.z * 1e3]
        })
        .collect();
    cloud_3d(
        &path,
        &Plot3Spec::new(
            format!("SIMULATED — deviation from the desired path ({mode}) (cf. Fig. 17)"),
            "x_p deviation [mm]",
            "y_p deviation [mm]",
            "z_p deviation [mm]",
        ),
        &[Cloud3::new(mode, points)],
    )
    .map_err(|e| report_error(&path, e))?;
    files.push(path);

    // Fig. A1: per-axis and norm.
    let path = dir.join("error_along_path.png");
    let panel = |title: &str, y: Vec<f64>| {
        (
            PlotSpec::new(title, "time [s]", "deviation [mm]").size(1000, 300),
            vec![Series::line(title, t.clone(), y)],
        )
    };
    panels_plot(
        &path,
        &format!("SIMULATED — deviation from the nominal path ({mode}) (cf. Fig. A1)"),
        PanelLayout::Column,
        &[
            panel("x_p", err(0)),
            panel("y_p", err(1)),
            panel("z_p", err(2)),
            panel("norm", norm.clone()),
        ],
    )
    .map_err(|e| report_error(&path, e))?;
    files.push(path);

    // Fig. 18: forces.
    let path = dir.join("forces.png");
    line_plot(
        &path,
        &PlotSpec::new(
            format!("SIMULATED — contact force on the tool ({mode}) (cf. Fig. 18)"),
            "time [s]",
            "force [N]",
        )
        .size(1000, 560),
        &[
            Series::line("F x_p", t.clone(), force(0)),
            Series::line("F y_p", t.clone(), force(1)),
            Series::line("F z_p", t.clone(), force(2)),
        ],
    )
    .map_err(|e| report_error(&path, e))?;
    files.push(path);

    // Fig. 19: error vs force norm.
    let path = dir.join("error_vs_force.png");
    line_plot(
        &path,
        &PlotSpec::new(
            format!("SIMULATED — error norm vs force norm ({mode}) (cf. Fig. 19)"),
            "force norm [N]",
            "error norm [mm]",
        ),
        &[Series::points(mode, force_norm, norm)],
    )
    .map_err(|e| report_error(&path, e))?;
    files.push(path);

    // Formed profile.
    if run.profile_mm.len() > 1 {
        let path = dir.join("profile.png");
        let r: Vec<f64> = run.profile_mm.iter().map(|p| p.0).collect();
        let d: Vec<f64> = run.profile_mm.iter().map(|p| -p.1).collect();
        line_plot(
            &path,
            &PlotSpec::new(
                format!("SIMULATED — formed part profile at θ = 0 ({mode})"),
                "radius [mm]",
                "height of the formed surface [mm]",
            ),
            &[Series::line("formed sheet", r, d)],
        )
        .map_err(|e| report_error(&path, e))?;
        files.push(path);
    }
    Ok(files)
}
