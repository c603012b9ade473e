//! A forming run of the twin (SIMULATED) on disk: its folder (`log.csv`, `summary.json`,
//! `profile.csv` and the plots, swapped in whole) and the PNG plots after the paper's figures:
//! the 3D deviation cloud (Fig. 17), the error per axis and in norm along the path (Fig. A1), the
//! forces (Fig. 18), the error versus the force norm (Fig. 19), and the programmed versus formed
//! profile. Every title says SIMULATED.
//!
//! [`force_panels`] and [`profile_panels`] are shared with the study's page, which compares the
//! runs without and with correction on the same panels.

use crate::report::DrawError;
use crate::report::draw::{cloud_3d, line_plot, panels_plot, write_text};
use deflex_plot::{Cloud3, LineStyle, PALETTE, PanelLayout, Plot3Spec, PlotSpec, Series};
use deflex_sim::FormingRun;
use std::path::{Path, PathBuf};

/// Width (px) of a full-width panel: the report pages show it at (nearly) its own size, so its
/// text is not scaled down.
pub const FULL_WIDTH_PX: u32 = 1100;

/// Colour and stroke of each force component, the same on every panel: F_x blue solid, F_y
/// orange dashed (the two in-plane components turn with the tool and cross all the time), F_z
/// green solid.
const COMPONENTS: [(&str, usize, LineStyle); 3] = [
    ("F_x", 0, LineStyle::Solid),
    ("F_y", 1, LineStyle::Dashed),
    ("F_z", 2, LineStyle::Solid),
];

/// Grey of the uncorrected run where both runs share a panel.
const OPEN_RUN_GREY: (u8, u8, u8) = PALETTE[7];

/// Length (s) of the close-up at the end of the run: about three turns of the paper cone's last
/// contours, where the in-plane force is largest; at most a quarter of the run.
fn close_up_s(duration_s: f64) -> f64 {
    12.0f64.min(0.25 * duration_s)
}

/// `base` followed by `, label` when the label is not empty.
fn tagged(base: &str, label: &str) -> String {
    if label.is_empty() {
        base.to_string()
    } else {
        format!("{base}, {label}")
    }
}

/// Common y range of the force components of `runs` (N), padded by 6 %.
fn force_range(runs: &[(&str, &FormingRun)]) -> (f64, f64) {
    let (mut lo, mut hi) = (0.0f64, 0.0f64);
    for (_, run) in runs {
        for r in &run.log.rows {
            for k in 0..3 {
                let v = r.truth.wrench[k];
                if v.is_finite() {
                    lo = lo.min(v);
                    hi = hi.max(v);
                }
            }
        }
    }
    let pad = 0.06 * (hi - lo).max(1.0);
    (lo - pad, hi + pad)
}

/// The force panels of Fig. 18 for one or more runs (`(label, run)`), full width, one under the
/// other, every panel on the same force range so that the runs compare directly: per run the
/// whole run, then per run a close-up of its last seconds (where F_x and F_y, a quarter turn
/// apart, can be told apart cycle by cycle; no legend there, where every corner holds data: the
/// lines are those of the whole-run panels), and, with two runs, F_z of both on one panel.
/// Units in the axis labels (s, N); contact force on the tool at the TCP, part axes.
pub fn force_panels(runs: &[(&str, &FormingRun)]) -> Vec<(PlotSpec, Vec<Series>)> {
    let range = force_range(runs);
    let components = |run: &FormingRun, keep: &dyn Fn(f64) -> bool, legend: bool| -> Vec<Series> {
        let rows: Vec<_> = run.log.rows.iter().filter(|r| keep(r.time_s)).collect();
        let t: Vec<f64> = rows.iter().map(|r| r.time_s).collect();
        COMPONENTS
            .iter()
            .map(|&(name, k, line)| {
                Series::line(
                    if legend { name } else { "" },
                    t.clone(),
                    rows.iter().map(|r| r.truth.wrench[k]).collect(),
                )
                .with_line(line)
                .with_color(PALETTE[k])
            })
            .collect()
    };
    let mut panels = Vec::new();
    for (label, run) in runs {
        panels.push((
            PlotSpec::new(
                tagged("F_x, F_y, F_z over the whole run", label),
                "time [s]",
                "force [N]",
            )
            .size(FULL_WIDTH_PX, 340)
            .y_range(range.0, range.1),
            components(run, &|_| true, true),
        ));
    }
    for (label, run) in runs {
        let end = run.log.rows.last().map_or(0.0, |r| r.time_s);
        let from = end - close_up_s(end);
        panels.push((
            PlotSpec::new(
                format!(
                    "{}, lines as above",
                    tagged(&format!("close-up of the last {:.0} s", end - from), label)
                ),
                "time [s]",
                "force [N]",
            )
            .size(FULL_WIDTH_PX, 300)
            .x_range(from, end.max(from + 1e-3))
            .y_range(range.0, range.1),
            components(run, &|t| t >= from, false),
        ));
    }
    if runs.len() == 2 {
        let fz = |(label, run): &(&str, &FormingRun)| {
            Series::line(
                tagged("F_z", label),
                run.log.column(|r| r.time_s),
                run.log.column(|r| r.truth.wrench[2]),
            )
        };
        panels.push((
            PlotSpec::new("F_z of both runs", "time [s]", "force [N]")
                .size(FULL_WIDTH_PX, 340)
                .y_range(-0.06 * range.1.max(1.0), range.1),
            vec![
                fz(&runs[0])
                    .with_line(LineStyle::Dashed)
                    .with_color(OPEN_RUN_GREY),
                fz(&runs[1]).with_color(PALETTE[2]),
            ],
        ));
    }
    panels
}

/// The part's cross-section along the ray θ = 0: the programmed profile (a rigid robot on the
/// desired path) and the formed sheet of each run, as height of the surface (mm, 0 = the
/// undeformed sheet) against the radius (mm); below it, formed − programmed (mm, positive =
/// shallower than programmed). Empty when no run has a profile (a fixture run).
pub fn profile_panels(runs: &[(&str, &FormingRun)]) -> Vec<(PlotSpec, Vec<Series>)> {
    let Some((_, first)) = runs
        .iter()
        .find(|(_, r)| !r.programmed_profile_mm.is_empty())
    else {
        return Vec::new();
    };
    let programmed = &first.programmed_profile_mm;
    // Up to just beyond the last radius any profile reaches down to.
    let touched = |p: &[(f64, f64)]| {
        p.iter()
            .rev()
            .find(|(_, d)| *d > 1e-3)
            .map_or(0.0, |(r, _)| *r)
    };
    let r_max = runs
        .iter()
        .map(|(_, run)| touched(&run.profile_mm))
        .fold(touched(programmed), f64::max)
        * 1.15
        + 1.0;
    let within = |p: &[(f64, f64)]| -> Vec<(f64, f64)> {
        p.iter().copied().filter(|(r, _)| *r <= r_max).collect()
    };
    let height = |label: String, p: &[(f64, f64)]| {
        let p = within(p);
        Series::line(
            label,
            p.iter().map(|q| q.0).collect(),
            p.iter().map(|q| -q.1).collect(),
        )
    };
    let mut section = vec![
        height("programmed".into(), programmed)
            .with_line(LineStyle::Dashed)
            .with_color((0, 0, 0)),
    ];
    let mut difference = Vec::new();
    for (k, (label, run)) in runs.iter().enumerate() {
        if run.profile_mm.is_empty() {
            continue;
        }
        let color = PALETTE[k % PALETTE.len()];
        section.push(height(tagged("formed", label), &run.profile_mm).with_color(color));
        let formed = within(&run.profile_mm);
        let reference = &run.programmed_profile_mm;
        difference.push(
            Series::line(
                tagged("formed − programmed", label),
                formed.iter().map(|q| q.0).collect(),
                formed
                    .iter()
                    .enumerate()
                    .map(|(i, q)| reference.get(i).map_or(f64::NAN, |p| p.1 - q.1))
                    .collect(),
            )
            .with_color(color),
        );
    }
    vec![
        (
            PlotSpec::new(
                "cross-section along θ = 0: programmed and formed",
                "radius [mm]",
                "surface height [mm]",
            )
            .size(FULL_WIDTH_PX, 420),
            section,
        ),
        (
            PlotSpec::new(
                "formed − programmed (positive: shallower than programmed)",
                "radius [mm]",
                "height difference [mm]",
            )
            .size(FULL_WIDTH_PX, 300),
            difference,
        ),
    ]
}

/// Draw every plot of a run into `dir`; returns the files.
pub fn forming_plots(run: &FormingRun, dir: &Path) -> Result<Vec<PathBuf>, DrawError> {
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
    let norm = log.column(|r| r.truth.path_error_m().norm() * 1e3);
    let force_norm = log.column(|r| r.truth.force_norm_n());

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
    )?;
    files.push(path);

    // Fig. A1: per-axis and norm.
    let path = dir.join("error_along_path.png");
    let panel = |title: &str, y: Vec<f64>| {
        (
            PlotSpec::new(title, "time [s]", "deviation [mm]").size(FULL_WIDTH_PX, 300),
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
    )?;
    files.push(path);

    // Fig. 18: forces, the whole run and a close-up of its end.
    let path = dir.join("forces.png");
    panels_plot(
        &path,
        &format!("SIMULATED — contact force on the tool, part axes ({mode}) (cf. Fig. 18)"),
        PanelLayout::Column,
        &force_panels(&[("", run)]),
    )?;
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
    )?;
    files.push(path);

    // Programmed versus formed profile.
    let panels = profile_panels(&[("", run)]);
    if !panels.is_empty() {
        let path = dir.join("profile.png");
        panels_plot(
            &path,
            &format!("SIMULATED — programmed and formed part profile ({mode})"),
            PanelLayout::Column,
            &panels,
        )?;
        files.push(path);
    }
    Ok(files)
}

/// Write `log.csv`, `summary.json`, `profile.csv` and the PNG plots of `run` into the existing
/// folder `dir`; returns their names, in that order.
pub fn write_run_files(run: &FormingRun, dir: &Path) -> Result<Vec<String>, DrawError> {
    let summary = run
        .summary_json()
        .map_err(DrawError::content_of(&dir.join("summary.json")))?;
    let mut names = Vec::new();
    for (name, text) in [
        ("log.csv", run.log.to_csv()),
        ("summary.json", summary),
        ("profile.csv", run.profile_csv()),
    ] {
        write_text(&dir.join(name), &text)?;
        names.push(name.to_string());
    }
    for plot in forming_plots(run, dir)? {
        if let Some(name) = plot.file_name() {
            names.push(name.to_string_lossy().into_owned());
        }
    }
    Ok(names)
}

/// Write `log.csv`, `summary.json`, `profile.csv` and the PNG plots of `run` into the folder
/// `dir`, whole or not at all: the folder is built aside and swapped in at the end (an existing
/// `dir` is replaced only then). Returns the files written.
pub fn write_forming_run(run: &FormingRun, dir: &Path) -> Result<Vec<PathBuf>, DrawError> {
    let building = deflex_files::AtomicDir::create(dir).map_err(DrawError::io_on(dir))?;
    let names = write_run_files(run, building.path())?;
    building.commit().map_err(DrawError::io_on(dir))?;
    Ok(names.into_iter().map(|n| dir.join(n)).collect())
}
