//! The study's figures, after the paper's: validation heatmaps and parity plots (Figs. 10–13),
//! the spiral (Fig. 14), the forming comparisons (Figs. 17, A1, 18, 19), the programmed versus
//! formed profile and the controller's correction and state over time. Every title says
//! SIMULATED.

use super::Figure;
use super::csv_files::column_tag;
use crate::report::DrawError;
use crate::report::draw::{
    cloud_3d, heatmap, line_plot, panels_plot, parity_plot, scatter_heatmap, timeline_plot,
};
use crate::report::forming_run::{FULL_WIDTH_PX, force_panels, profile_panels};
use crate::study::compensation::PartRuns;
use crate::study::contact::StiffContactRuns;
use crate::study::fig7::Fig7Point;
use crate::study::sensitivity::SensitivityResult;
use crate::study::{BASELINE, IDENTIFIED};
use deflex_calibrate::measurements::MeasurementRow;
use deflex_control::CycleOutput;
use deflex_plot::{Cloud3, Lane, LineStyle, PALETTE, PanelLayout, Plot3Spec, PlotSpec, Series};
use deflex_sim::FormingRun;
use deflex_sim::twin::ClosedLoopRun;
use deflex_telemetry::{FaultKind, Flags};
use std::path::Path;

/// Colour and stroke of the x, y, z components of a vector quantity, the same on every figure.
const AXES: [(&str, usize, LineStyle); 3] = [
    ("x", 0, LineStyle::Solid),
    ("y", 1, LineStyle::Dashed),
    ("z", 2, LineStyle::Dotted),
];

/// Heatmaps of the δz prediction error over the grid for the baseline and the identified model
/// for each dead weight (the paper's 600 N and 1100 N: Figs. 11, 13), and predicted-vs-measured
/// δz (Figs. 10, 12).
pub fn grid_figures(
    out: &Path,
    grid: &[MeasurementRow],
    loads_n: &[f64],
    predictions: &[(&'static str, Vec<[f64; 3]>)],
) -> Result<Vec<Figure>, DrawError> {
    let mut figures = Vec::new();
    for (index, &load) in loads_n.iter().enumerate() {
        let selected = crate::study::numbers::grid_rows(grid, load);
        let x: Vec<f64> = selected.iter().map(|&i| grid[i].point_m[0] * 1e3).collect();
        let y: Vec<f64> = selected.iter().map(|&i| grid[i].point_m[1] * 1e3).collect();
        let measured: Vec<f64> = selected
            .iter()
            .map(|&i| {
                grid[i]
                    .displacement_m
                    .map(|d| d[2] * 1e3)
                    .unwrap_or(f64::NAN)
            })
            .collect();
        // One colour scale for both models so the heatmaps compare at a glance.
        let errors: Vec<(&str, Vec<f64>)> = predictions
            .iter()
            .filter(|(name, _)| *name == BASELINE || *name == IDENTIFIED)
            .map(|(name, p)| {
                let e = selected
                    .iter()
                    .zip(&measured)
                    .map(|(&i, m)| (m - p[i][2] * 1e3).abs())
                    .collect();
                (*name, e)
            })
            .collect();
        let top = errors
            .iter()
            .flat_map(|(_, e)| e.iter().cloned())
            .fold(0.0f64, f64::max)
            .max(1e-6);
        for (name, error) in &errors {
            let tag = column_tag(name);
            let path = out.join(format!("grid_error_{tag}_{load:.0}N.png"));
            let spec = PlotSpec::new(
                format!(
                    "SIMULATED cell — |δz error| of the {name} model, {load:.0} N (cf. Fig. {})",
                    if index == 0 { 11 } else { 13 }
                ),
                "x [mm]",
                "y [mm]",
            )
            .size(900, 700)
            .color_range(0.0, top);
            scatter_heatmap(
                &path,
                &spec,
                &x,
                &y,
                error,
                "|measured − predicted δz| [mm]",
            )?;
            figures.push((path, format!("|δz error| of the {name} model over the grid, {load:.0} N dead weight (SIMULATED)")));
        }
        for (name, p) in predictions
            .iter()
            .filter(|(name, _)| *name == BASELINE || *name == IDENTIFIED)
        {
            let tag = column_tag(name);
            let predicted: Vec<f64> = selected.iter().map(|&i| p[i][2] * 1e3).collect();
            let path = out.join(format!("grid_parity_{tag}_{load:.0}N.png"));
            let spec = PlotSpec::new(
                format!(
                    "SIMULATED cell — δz predicted vs measured, {name}, {load:.0} N (cf. Fig. {})",
                    if index == 0 { 10 } else { 12 }
                ),
                "measured δz [mm]",
                "predicted δz [mm]",
            )
            .size(700, 650);
            parity_plot(&path, &spec, &predicted, &measured, name)?;
            figures.push((
                path,
                format!("Predicted vs measured δz, {name} model, {load:.0} N (SIMULATED)"),
            ));
        }
    }
    Ok(figures)
}

/// The spiral trajectory (Fig. 14a) and δz measured vs predicted along it (Fig. 14b).
pub fn spiral_figures(
    out: &Path,
    rows: &[MeasurementRow],
    params: &deflex_sim::twin_campaign::SpiralParams,
    predictions: &[(&'static str, Vec<[f64; 3]>)],
) -> Result<Vec<Figure>, DrawError> {
    let mut figures = Vec::new();
    let x: Vec<f64> = rows.iter().map(|r| r.point_m[0] * 1e3).collect();
    let y: Vec<f64> = rows.iter().map(|r| r.point_m[1] * 1e3).collect();
    let path = out.join("spiral_path.png");
    let spec = PlotSpec::new(
        format!(
            "SIMULATED cell — spiral trajectory at z = {:.0} mm (cf. Fig. 14a)",
            params.center_m[2] * 1e3
        ),
        "x [mm]",
        "y [mm]",
    )
    .size(700, 700);
    line_plot(&path, &spec, &[Series::line("TCP path", x, y)])?;
    figures.push((
        path,
        format!(
            "Spiral trajectory, {:.0} N dead weight (SIMULATED)",
            params.load_n
        ),
    ));
    let per_sample_mm = params.speed_m_s * 1e3 / 50.0;
    let length: Vec<f64> = (0..rows.len()).map(|i| i as f64 * per_sample_mm).collect();
    let mut series = vec![Series::line(
        "measured (SIMULATED tracker)",
        length.clone(),
        rows.iter()
            .map(|r| r.displacement_m.map(|d| d[2] * 1e3).unwrap_or(f64::NAN))
            .collect(),
    )];
    for (name, p) in predictions
        .iter()
        .filter(|(name, _)| *name == BASELINE || *name == IDENTIFIED)
    {
        series.push(Series::line(
            format!("{name} model"),
            length.clone(),
            p.iter().map(|d| d[2] * 1e3).collect(),
        ));
    }
    let path = out.join("spiral_dz.png");
    let spec = PlotSpec::new(
        format!(
            "SIMULATED cell — δz along the spiral, {:.0} N (cf. Fig. 14b)",
            params.load_n
        ),
        "path length [mm]",
        "δz [mm]",
    )
    .size(1100, 500);
    line_plot(&path, &spec, &series)?;
    figures.push((
        path,
        "δz along the spiral: measured and predicted (SIMULATED)".to_string(),
    ));
    Ok(figures)
}

/// Forming without vs with correction: deviation clouds (Fig. 17), error per axis and norm along
/// the path (Fig. A1), forces (Fig. 18) and error vs force norm (Fig. 19).
pub fn forming_figures(
    out: &Path,
    open: &FormingRun,
    closed: &FormingRun,
) -> Result<Vec<Figure>, DrawError> {
    let mut figures = Vec::new();
    let runs = [("without correction", open), ("with correction", closed)];
    let cloud: Vec<Cloud3> = runs
        .iter()
        .map(|(label, run)| {
            Cloud3::new(
                *label,
                run.log
                    .rows
                    .iter()
                    .map(|r| {
                        let e = r.truth.path_error_m();
                        [e.x * 1e3, e.y * 1e3, e.z * 1e3]
                    })
                    .collect(),
            )
        })
        .collect();
    let path = out.join("forming_cloud.png");
    cloud_3d(
        &path,
        &Plot3Spec::new(
            "SIMULATED cell — TCP deviation during cone forming (cf. Fig. 17)",
            "x_p [mm]",
            "y_p [mm]",
            "z_p [mm]",
        )
        .size(900, 750),
        &cloud,
    )?;
    figures.push((
        path,
        "Deviation from the desired path, without and with correction (SIMULATED)".to_string(),
    ));

    let axis_names = ["x_p", "y_p", "z_p", "norm"];
    let panels: Vec<(PlotSpec, Vec<Series>)> = axis_names
        .iter()
        .enumerate()
        .map(|(k, axis)| {
            let series = runs
                .iter()
                .map(|(label, run)| {
                    let t = run.log.column(|r| r.time_s);
                    let v = run.log.column(|r| {
                        let e = r.truth.path_error_m();
                        if k < 3 { e[k] * 1e3 } else { e.norm() * 1e3 }
                    });
                    Series::line(*label, t, v)
                })
                .collect();
            (
                PlotSpec::new(format!("deviation {axis}"), "time [s]", "deviation [mm]")
                    .size(FULL_WIDTH_PX, 300),
                series,
            )
        })
        .collect();
    let path = out.join("forming_error_along_path.png");
    panels_plot(
        &path,
        "SIMULATED cell — deviation along the path (cf. Fig. A1)",
        PanelLayout::Column,
        &panels,
    )?;
    figures.push((
        path,
        "Deviation per axis and in norm along the path (SIMULATED)".to_string(),
    ));

    let path = out.join("forming_forces.png");
    panels_plot(
        &path,
        "SIMULATED cell — contact force on the tool at the TCP, part axes (cf. Fig. 18)",
        PanelLayout::Column,
        &force_panels(&runs),
    )?;
    figures.push((
        path,
        "Contact forces without and with correction (SIMULATED), every panel on the same force \
         scale: each run whole, then the last seconds of each run, where F_x (solid) and F_y \
         (dashed), a quarter turn apart, follow the tool around the cone; last, F_z of both runs"
            .to_string(),
    ));

    let series: Vec<Series> = runs
        .iter()
        .map(|(label, run)| {
            Series::points(
                *label,
                run.log.column(|r| r.truth.force_norm_n()),
                run.log.column(|r| r.truth.path_error_m().norm() * 1e3),
            )
        })
        .collect();
    let path = out.join("forming_error_vs_force.png");
    line_plot(
        &path,
        &PlotSpec::new(
            "SIMULATED cell — deviation norm vs force norm (cf. Fig. 19)",
            "|F| [N]",
            "|deviation| [mm]",
        )
        .size(900, 560),
        &series,
    )?;
    figures.push((
        path,
        "Deviation norm as a function of the force norm (SIMULATED)".to_string(),
    ));

    let panels = profile_panels(&runs);
    if !panels.is_empty() {
        let path = out.join("forming_profile.png");
        panels_plot(
            &path,
            "SIMULATED cell — the part's cross-section: programmed and formed",
            PanelLayout::Column,
            &panels,
        )?;
        figures.push((
            path,
            "Programmed versus formed profile along θ = 0 (SIMULATED): the programmed profile is \
             what a rigid robot on the desired path would form (the tool sphere swept along it), \
             the formed ones are the twin's sheet after each run; below, their difference"
                .to_string(),
        ));
    }
    Ok(figures)
}

/// The states of the controller's flags shown over time, in lane order: the flag bit(s) and
/// the lane's name.
const STATE_LANES: [(u32, &str); 8] = [
    (Flags::ACTIVE, "active"),
    (Flags::RAMPING, "ramping"),
    (Flags::TARING, "taring"),
    (Flags::SATURATED_SIZE, "saturated (size)"),
    (Flags::SATURATED_RATE, "saturated (rate)"),
    (Flags::STALE_WRENCH, "stale wrench"),
    (Flags::RUNAWAY_HOLD, "runaway hold"),
    (Flags::LATCHED, "fault latched"),
];

/// The correction ξ the controller sent (position in mm, rotation in mrad when any rotation
/// axis is used) and its state flags over time, for the corrected run, from its per-cycle log
/// (`trace`, the rows of `controller_log.csv`).
pub fn controller_figures(out: &Path, trace: &[CycleOutput]) -> Result<Vec<Figure>, DrawError> {
    let mut figures = Vec::new();
    if trace.len() < 2 {
        return Ok(figures);
    }
    let t: Vec<f64> = trace.iter().map(|c| c.time_s).collect();
    // 1 % of margin on the left, so that what happens in the first cycles (taring, the ramp
    // in) is not hidden under the axis.
    let (t0, t1) = (t[0] - 0.01 * (t[t.len() - 1] - t[0]), t[t.len() - 1]);
    let component =
        |k: usize, scale: f64| -> Vec<f64> { trace.iter().map(|c| c.xi[k] * scale).collect() };
    let mut panels = vec![(
        PlotSpec::new(
            "correction ξ, position (robot base axes)",
            "time [s]",
            "ξ [mm]",
        )
        .size(FULL_WIDTH_PX, 340)
        .x_range(t0, t1),
        AXES.iter()
            .map(|&(name, k, line)| {
                Series::line(format!("ξ_{name}"), t.clone(), component(k, 1e3))
                    .with_line(line)
                    .with_color(PALETTE[k])
            })
            .collect::<Vec<_>>(),
    )];
    let rotations = trace.iter().any(|c| c.xi[3..].iter().any(|v| *v != 0.0));
    if rotations {
        panels.push((
            PlotSpec::new(
                "correction ξ, rotation (robot base axes)",
                "time [s]",
                "ξ [mrad]",
            )
            .size(FULL_WIDTH_PX, 300)
            .x_range(t0, t1),
            AXES.iter()
                .map(|&(name, k, line)| {
                    Series::line(format!("ξ_r{name}"), t.clone(), component(3 + k, 1e3))
                        .with_line(line)
                        .with_color(PALETTE[k])
                })
                .collect(),
        ));
    }
    let path = out.join("controller_correction.png");
    panels_plot(
        &path,
        "SIMULATED cell — the correction ξ the controller sent, corrected run",
        PanelLayout::Column,
        &panels,
    )?;
    figures.push((
        path,
        if rotations {
            "Correction ξ over the corrected run (SIMULATED): position in mm, rotation in mrad"
        } else {
            "Correction ξ over the corrected run (SIMULATED), in mm; the rotation axes are not \
             corrected (ξ_rx = ξ_ry = ξ_rz = 0 throughout)"
        }
        .to_string(),
    ));

    let fault_bits: u32 = FaultKind::ALL
        .iter()
        .map(|k| k.flag())
        .fold(0, |a, b| a | b);
    let cycles = trace.len() as f64;
    let mut lanes: Vec<Lane> = Vec::new();
    let mut lane = |name: &str, on: Vec<bool>| {
        let count = on.iter().filter(|v| **v).count();
        let share = 100.0 * count as f64 / cycles;
        let label = match count {
            0 => format!("{name} (never)"),
            n if n == trace.len() => format!("{name} (always)"),
            n if share < 0.1 => format!("{name} ({n} cycles)"),
            n if share >= 99.95 => format!("{name} (all but {} cycles)", trace.len() - n),
            _ => format!("{name} ({share:.1} % of cycles)"),
        };
        lanes.push(Lane::from_samples(label, &t, &on));
    };
    for (bit, name) in STATE_LANES {
        lane(name, trace.iter().map(|c| c.flags.has(bit)).collect());
    }
    lane(
        "fault detected",
        trace.iter().map(|c| c.flags.0 & fault_bits != 0).collect(),
    );
    let path = out.join("controller_state.png");
    timeline_plot(
        &path,
        &PlotSpec::new(
            "SIMULATED cell — controller state per cycle, corrected run",
            "time [s]",
            "",
        )
        .size(FULL_WIDTH_PX, 420)
        .x_range(t0, t1),
        &lanes,
    )?;
    figures.push((
        path,
        "Controller state over the corrected run (SIMULATED), from the flags of every control \
         cycle in forming_closed/controller_log.csv; each lane gives the share of cycles it held"
            .to_string(),
    ));
    Ok(figures)
}

/// Figs. 8 and 9 in one image: δp_x and δp_y against the points' position along x0, the
/// SIMULATED measurement as markers, each model as a line with markers (identified solid,
/// one-eDoF dashed, the robot file's model dotted).
pub fn fig7_figure(path: &Path, points: &[Fig7Point]) -> Result<(), DrawError> {
    let x: Vec<f64> = points.iter().map(|p| p.x_mm).collect();
    let styles = [LineStyle::Solid, LineStyle::Dashed, LineStyle::Dotted];
    let panel = |axis: usize, name: &str, figure: u32| {
        let mut series = vec![
            Series::points(
                "measured (SIMULATED tracker)",
                x.clone(),
                points.iter().map(|p| p.measured_mm[axis]).collect(),
            )
            .with_color((0, 0, 0)),
        ];
        if let Some(first) = points.first() {
            for (k, (model, _)) in first.predicted_mm.iter().enumerate() {
                series.push(
                    Series::line_and_points(
                        format!("{model} model"),
                        x.clone(),
                        points.iter().map(|p| p.predicted_mm[k].1[axis]).collect(),
                    )
                    .with_line(styles[k % styles.len()])
                    .with_color(PALETTE[k % PALETTE.len()]),
                );
            }
        }
        (
            PlotSpec::new(
                format!("δp_{name} of M1, M2, M3 and the TCP (cf. Fig. {figure})"),
                "position of the point along x0 [mm]",
                format!("δp_{name} [mm]"),
            )
            .size(FULL_WIDTH_PX, 420),
            series,
        )
    };
    panels_plot(
        path,
        "SIMULATED cell — q = (0, 90°, 0, 0, 0, 0), f_y = 1400 N at the TCP (cf. Figs. 7–9)",
        PanelLayout::Column,
        &[panel(0, "x", 8), panel(1, "y", 9)],
    )
}

/// Force over time along the plunge without correction, with it unguarded and guarded (PNG).
pub fn contact_figure(
    path: &std::path::Path,
    runs: &StiffContactRuns,
    stiffness_n_m: f64,
) -> Result<(), DrawError> {
    let series = |run: &FormingRun, label: &str| {
        deflex_plot::Series::line(
            label,
            run.log.column(|r| r.time_s),
            run.log.column(|r| r.truth.force_norm_n()),
        )
    };
    let outcome = |run: &ClosedLoopRun| match (run.fault, run.first_runaway) {
        (Some(f), _) => format!(", stopped by {}", f.kind.name()),
        (None, Some(_)) => ", contact_runaway reported".to_string(),
        (None, None) => String::new(),
    };
    crate::report::draw::line_plot(
        path,
        &PlotSpec::new(
            format!(
                "SIMULATED — plunge into a {stiffness_n_m:.0e} N/m fixture: contact force over time"
            ),
            "time [s]",
            "contact force norm [N]",
        )
        .size(1000, 500),
        &[
            series(&runs.open, "without correction"),
            series(
                &runs.unguarded.forming,
                &format!(
                    "with correction, no runaway guard{}",
                    outcome(&runs.unguarded)
                ),
            ),
            series(
                &runs.guarded.forming,
                &format!(
                    "with correction and runaway guard{}",
                    outcome(&runs.guarded)
                ),
            ),
        ],
    )
}

/// The delay × model-scale heatmap of the improvement (PNG).
pub fn sensitivity_heatmap(result: &SensitivityResult, path: &Path) -> Result<(), DrawError> {
    if result.heatmap_delays_s.len() < 2 || result.heatmap_scales.len() < 2 {
        return Ok(());
    }
    let spec = PlotSpec::new(
        format!(
            "SIMULATED {} — improvement of the max path error [%]: delay × model compliance scale",
            result.robot
        ),
        "correction delay [ms]",
        "model compliance scale (1.3 = 30 % too soft)",
    )
    .size(900, 650);
    let x: Vec<f64> = result.heatmap_delays_s.iter().map(|d| d * 1e3).collect();
    heatmap(
        path,
        &spec,
        &x,
        &result.heatmap_scales,
        &result.heatmap_improvement_percent,
        "improvement [%]",
    )
}

/// Ways drawn in the figures (the double correction and the log compensation are in the table).
const DRAWN: [&str; 5] = [
    crate::study::compensation::UNCORRECTED,
    crate::study::compensation::OFFLINE_PROCESS,
    crate::study::compensation::ONLINE,
    crate::study::compensation::FEED_FORWARD,
    crate::study::compensation::PRECOMPENSATED,
];

/// The path error along the path for each part, and one force ramp of the CAM part up close:
/// all against the position along the desired path, so that the ways line up.
pub fn compensation_figures(out: &Path, runs: &[PartRuns]) -> Result<Vec<Figure>, DrawError> {
    let mut figures = Vec::new();
    for (i, part) in runs.iter().enumerate() {
        let tag = super::csv_files::part_tag(i);
        let series: Vec<Series> = part
            .runs
            .iter()
            .filter(|(way, _)| DRAWN.contains(&way.as_str()))
            .map(|(way, run)| {
                let (s, e) = super::csv_files::error_along_path(run, 1)
                    .into_iter()
                    .map(|(s, _, e)| (s, e * 1e3))
                    .unzip();
                Series::line(way.clone(), s, e)
            })
            .collect();
        let path = out.join(format!("compensation_{tag}_error.png"));
        let name = &part.runs[0].1.summary.path;
        let spec = PlotSpec::new(
            format!("SIMULATED cell — path error norm, {name}: offline, online and both"),
            "position along the desired path [m]",
            "|error| [mm]",
        )
        .size(1100, 500);
        line_plot(&path, &spec, &series)?;
        figures.push((
            path,
            format!(
                "Path error norm along {name} without correction, with the offline compensation \
                 (process model), the online correction, and both, against the position along \
                 the desired path (SIMULATED)"
            ),
        ));
    }
    // A ramp of the CAM part up close: the middle one, over the stretch of path the first way
    // covers from 0.5 s before its 50 % point to the settling window after it; every way is
    // drawn over that same stretch, against the position from that point.
    if let Some(part) = runs.get(1)
        && let Some(&s) = part.ramps.get(part.ramps.len() / 2)
        && let Some((_, first)) = part.runs.first()
    {
        let along = super::csv_files::error_along_path(first, 1);
        let t0 = along
            .get(along.partition_point(|a| a.0 < s))
            .map_or(0.0, |a| a.1);
        let position_at = |t: f64| {
            along
                .get(
                    along
                        .partition_point(|a| a.1 < t)
                        .min(along.len().saturating_sub(1)),
                )
                .map_or(s, |a| a.0)
        };
        let (from, to) = (
            position_at(t0 - 0.5),
            position_at(t0 + crate::study::compensation::lag::SETTLE_WINDOW_S),
        );
        let series: Vec<Series> = part
            .runs
            .iter()
            .filter(|(way, _)| DRAWN.contains(&way.as_str()))
            .map(|(way, run)| {
                let (x, e) = super::csv_files::error_along_path(run, 1)
                    .into_iter()
                    .filter(|(a, _, _)| (from..=to).contains(a))
                    .map(|(a, _, e)| ((a - s) * 1e3, e * 1e3))
                    .unzip();
                Series::line(way.clone(), x, e)
            })
            // A way that stopped before this stretch has nothing to draw here.
            .filter(|series| !series.x.is_empty())
            .collect();
        let path = out.join("compensation_ramp.png");
        let spec = PlotSpec::new(
            "SIMULATED cell — path error at a force ramp of the CAM part (0: the force at 50 % of its step)",
            "position along the desired path from the 50 % point [mm]",
            "|error| [mm]",
        )
        .size(1100, 500);
        line_plot(&path, &spec, &series)?;
        figures.push((
            path,
            format!(
                "The lag at a force ramp (ramp {} of {}, after a plunge): the online correction \
                 catches up with the deflection after the force has risen; the feed-forward and \
                 the pre-compensated program do not wait for it (SIMULATED)",
                part.ramps.len() / 2 + 1,
                part.ramps.len()
            ),
        ));
    }
    Ok(figures)
}
