//! The figures of a run, or of two runs overlaid (`deflex plot`): forces, correction, estimated
//! deflection, path error when known, controller state and loop timing, against the position
//! along the desired path (its arc length) when every run knows it — so that an open-loop and a
//! closed-loop run of the same path line up whatever their timing — else against time. Plain
//! data in ([`RunTrace`]), PNG files and a self-contained page out ([`write_run_figures`]).

use crate::report::DrawError;
use crate::report::RunFigures;
use crate::report::draw::{panels_plot, timeline_plot, write_page};
use deflex_plot::{
    FileLink, HtmlReport, Lane, LineStyle, PanelLayout, PlotError, PlotSpec, Series,
};
use deflex_record::trace::{RunTrace, Xyz};
use std::path::{Path, PathBuf};

/// Most points drawn per series (longer series keep each block's lowest and highest point).
pub const MAX_POINTS: usize = 20_000;

/// Keeps at most about [`MAX_POINTS`] points of the series `(x, y)`: each block of rows is
/// replaced by its lowest and highest point, in order, so that spikes stay visible; a block
/// with no finite value becomes one NaN, a break in the line. A shorter series is returned as it
/// is. [`write_run_figures`] draws every column of a long log thinned so.
pub fn thin_series(x: &[f64], y: &[f64]) -> (Vec<f64>, Vec<f64>) {
    let n = x.len().min(y.len());
    if n <= MAX_POINTS {
        return (x[..n].to_vec(), y[..n].to_vec());
    }
    let block = n.div_ceil(MAX_POINTS / 2);
    let (mut xs, mut ys) = (
        Vec::with_capacity(MAX_POINTS + 2),
        Vec::with_capacity(MAX_POINTS + 2),
    );
    for start in (0..n).step_by(block) {
        let end = (start + block).min(n);
        let (mut lo, mut hi) = (None::<usize>, None::<usize>);
        for i in start..end {
            if !y[i].is_finite() {
                continue;
            }
            if lo.is_none_or(|l| y[i] < y[l]) {
                lo = Some(i);
            }
            if hi.is_none_or(|h| y[i] > y[h]) {
                hi = Some(i);
            }
        }
        match (lo, hi) {
            (Some(a), Some(b)) => {
                for i in if a <= b { [a, b] } else { [b, a] } {
                    xs.push(x[i]);
                    ys.push(y[i]);
                }
            }
            // A block with no finite value breaks the line.
            _ => {
                xs.push(x[start]);
                ys.push(f64::NAN);
            }
        }
    }
    (xs, ys)
}

const DASHES: [LineStyle; 2] = [LineStyle::Solid, LineStyle::Dashed];
const RUN_COLORS: [(u8, u8, u8); 2] = [(31, 119, 180), (214, 39, 40)];

fn check(trace: &RunTrace, path: &Path) -> Result<(), PlotError> {
    let n = trace.time_s.len();
    let bad = |what: &str| {
        PlotError::invalid(
            path,
            format!(
                "run {:?} ({}): {what} does not have one value per row ({n} rows)",
                trace.label, trace.file
            ),
        )
    };
    if n == 0 {
        return Err(PlotError::invalid(
            path,
            format!("run {:?} ({}) has no rows", trace.label, trace.file),
        ));
    }
    if trace.path_s_m.as_ref().is_some_and(|s| s.len() != n) {
        return Err(bad("path position"));
    }
    if !trace.force_n.len_ok(n) {
        return Err(bad("force"));
    }
    for (name, v) in [
        ("correction", &trace.correction_m),
        ("deflection", &trace.deflection_m),
        ("path error", &trace.path_error_m),
    ] {
        if v.as_ref().is_some_and(|v| !v.len_ok(n)) {
            return Err(bad(name));
        }
    }
    if trace.cycle_time_s.as_ref().is_some_and(|c| c.len() != n) {
        return Err(bad("cycle time"));
    }
    for (name, on) in &trace.states {
        if on.len() != n {
            return Err(bad(&format!("state {name:?}")));
        }
    }
    Ok(())
}

/// One panel per component, each run one line (first solid, second dashed).
fn component_panels(
    traces: &[RunTrace],
    xs: &[Vec<f64>],
    x_label: &str,
    unit: &str,
    scale: f64,
    pick: impl Fn(&RunTrace) -> Option<Vec<(String, Vec<f64>)>>,
) -> Vec<(PlotSpec, Vec<Series>)> {
    let mut panels: Vec<(PlotSpec, Vec<Series>)> = Vec::new();
    for (k, trace) in traces.iter().enumerate() {
        let Some(components) = pick(trace) else {
            continue;
        };
        for (c, (name, values)) in components.into_iter().enumerate() {
            if panels.len() <= c {
                panels.push((
                    PlotSpec::new(name.clone(), x_label, format!("{name} [{unit}]"))
                        .size(1000, 260),
                    Vec::new(),
                ));
            }
            let y: Vec<f64> = values.iter().map(|v| v * scale).collect();
            if !y.iter().any(|v| v.is_finite()) {
                continue; // nothing known: no line (and no panel if no run has one)
            }
            let (x, y) = thin_series(&xs[k], &y);
            panels[c].1.push(
                Series::line(trace.label.clone(), x, y)
                    .with_line(DASHES[k])
                    .with_color(RUN_COLORS[k]),
            );
        }
    }
    panels.retain(|(_, series)| !series.is_empty());
    panels
}

fn xyz(v: &Xyz, names: [&str; 3], norm: Option<&str>) -> Vec<(String, Vec<f64>)> {
    let mut out = vec![
        (names[0].to_string(), v.x.clone()),
        (names[1].to_string(), v.y.clone()),
        (names[2].to_string(), v.z.clone()),
    ];
    if let Some(n) = norm {
        out.push((n.to_string(), v.norm()));
    }
    out
}

fn max_abs(v: &[f64]) -> f64 {
    v.iter()
        .filter(|x| x.is_finite())
        .fold(0.0, |m, x| m.max(x.abs()))
}

fn rms(v: &[f64]) -> f64 {
    let finite: Vec<f64> = v.iter().copied().filter(|x| x.is_finite()).collect();
    if finite.is_empty() {
        return f64::NAN;
    }
    (finite.iter().map(|x| x * x).sum::<f64>() / finite.len() as f64).sqrt()
}

/// Draws the figures of one run, or of two runs overlaid, into `dir` (which must exist), and
/// a self-contained `index.html` embedding them.
pub fn write_run_figures(dir: &Path, traces: &[RunTrace]) -> Result<RunFigures, DrawError> {
    let page = dir.join("index.html");
    if traces.is_empty() || traces.len() > 2 {
        return Err(PlotError::invalid(
            &page,
            format!("{} runs given, expected 1 or 2", traces.len()),
        )
        .into());
    }
    for t in traces {
        check(t, &page)?;
    }
    let by_path = traces.iter().all(|t| t.path_s_m.is_some());
    let (x_label, xs): (&str, Vec<Vec<f64>>) = if by_path {
        (
            "position along the desired path [mm]",
            traces
                .iter()
                .map(|t| t.path_s_m.iter().flatten().map(|s| s * 1e3).collect())
                .collect(),
        )
    } else {
        (
            "time [s]",
            traces.iter().map(|t| t.time_s.clone()).collect(),
        )
    };
    let names = traces
        .iter()
        .map(|t| t.label.as_str())
        .collect::<Vec<_>>()
        .join(" vs ");
    let simulated = traces.iter().any(|t| t.simulated);
    let sim = if simulated { "SIMULATED: " } else { "" };
    let mut figures: Vec<(PathBuf, String)> = Vec::new();

    let mut figure = |file: &str,
                      title: String,
                      caption: String,
                      panels: Vec<(PlotSpec, Vec<Series>)>|
     -> Result<(), DrawError> {
        if panels.is_empty() {
            return Ok(());
        }
        let path = dir.join(file);
        panels_plot(&path, &title, PanelLayout::Column, &panels)?;
        figures.push((path, caption));
        Ok(())
    };
    let axes = &traces[0].axes;
    figure(
        "forces.png",
        format!("{sim}Force on the tool at the TCP, {axes}: {names}"),
        format!("Force components and norm at the TCP ({axes}), N."),
        component_panels(traces, &xs, x_label, "N", 1.0, |t| {
            Some(xyz(&t.force_n, ["Fx", "Fy", "Fz"], Some("|F|")))
        }),
    )?;
    figure(
        "correction.png",
        format!("{sim}Correction ξ: {names}"),
        "Applied correction ξ, position part, mm.".into(),
        component_panels(traces, &xs, x_label, "mm", 1e3, |t| {
            t.correction_m
                .as_ref()
                .map(|v| xyz(v, ["ξx", "ξy", "ξz"], Some("|ξ|")))
        }),
    )?;
    figure(
        "deflection.png",
        format!("{sim}Estimated deflection δŝ: {names}"),
        "Estimated deflection δŝ (eq. 15), position part, mm.".into(),
        component_panels(traces, &xs, x_label, "mm", 1e3, |t| {
            t.deflection_m
                .as_ref()
                .map(|v| xyz(v, ["δŝx", "δŝy", "δŝz"], None))
        }),
    )?;
    figure(
        "path_error.png",
        format!("{sim}Path error, true − desired TCP: {names}"),
        "Path error (true minus desired TCP, known on the twin only), mm.".into(),
        component_panels(traces, &xs, x_label, "mm", 1e3, |t| {
            t.path_error_m
                .as_ref()
                .map(|v| xyz(v, ["error x", "error y", "error z"], Some("error norm")))
        }),
    )?;
    figure(
        "cycle_time.png",
        format!("{sim}Control cycle computation time: {names}"),
        "Computation time of the control cycle, µs.".into(),
        component_panels(traces, &xs, x_label, "µs", 1e6, |t| {
            t.cycle_time_s
                .as_ref()
                .map(|c| vec![("cycle time".to_string(), c.clone())])
        }),
    )?;
    if let Some(state) = state_figure(
        dir,
        traces,
        &xs,
        x_label,
        &format!("{sim}Controller and process state: {names}"),
    )? {
        figures.push(state);
    }
    let html = run_page(
        traces,
        &figures,
        simulated,
        by_path,
        &format!("{sim}deflex plot: {names}"),
    );
    write_page(&html, &page)?;
    Ok(RunFigures {
        figures: figures.into_iter().map(|(p, _)| p).collect(),
        page,
        by_path_position: by_path,
    })
}

/// The state lanes of every run (`state.png`), if any state was ever on.
fn state_figure(
    dir: &Path,
    traces: &[RunTrace],
    xs: &[Vec<f64>],
    x_label: &str,
    title: &str,
) -> Result<Option<(PathBuf, String)>, DrawError> {
    let mut lanes = Vec::new();
    for (k, t) in traces.iter().enumerate() {
        for (name, on) in &t.states {
            if on.iter().any(|b| *b) {
                let label = if traces.len() > 1 {
                    format!("{}: {name}", t.label)
                } else {
                    name.clone()
                };
                lanes.push(Lane::from_samples(label, &xs[k], on).with_color(RUN_COLORS[k]));
            }
        }
    }
    if lanes.is_empty() {
        return Ok(None);
    }
    let path = dir.join("state.png");
    let height = 120 + 34 * lanes.len() as u32;
    let spec = PlotSpec::new(title, x_label, "").size(1000, height);
    timeline_plot(&path, &spec, &lanes)?;
    Ok(Some((
        path,
        "Controller and process states (on where drawn).".into(),
    )))
}

/// The page of `deflex plot`: the runs' table, the figures and the logs.
fn run_page(
    traces: &[RunTrace],
    figures: &[(PathBuf, String)],
    simulated: bool,
    by_path: bool,
    title: &str,
) -> HtmlReport {
    let mut report = HtmlReport::new(title);
    if simulated {
        report.note("SIMULATED: at least one of these runs is the digital twin or a simulated cell, not a measurement.");
    }
    report.paragraph(if by_path {
        "Every run is drawn against its position along the desired path (the arc length of the \
         program's TCP path), so that runs of the same path line up whatever their timing."
            .to_string()
    } else {
        "At least one run does not give its position along the desired path, so the runs are \
         drawn against time."
            .to_string()
    });
    let rows: Vec<Vec<String>> = traces
        .iter()
        .map(|t| {
            let err = t.path_error_m.as_ref().map(|e| e.norm());
            let len = t
                .path_s_m
                .as_ref()
                .map_or("–".into(), |s| format!("{:.1}", max_abs(s) * 1e3));
            vec![
                t.label.clone(),
                t.kind.clone(),
                t.time_s.len().to_string(),
                format!("{:.2}", t.time_s.last().unwrap_or(&0.0) - t.time_s[0]),
                len,
                format!("{:.1}", max_abs(&t.force_n.norm())),
                t.correction_m
                    .as_ref()
                    .map_or("–".into(), |c| format!("{:.3}", max_abs(&c.norm()) * 1e3)),
                err.as_ref()
                    .map_or("–".into(), |e| format!("{:.3}", max_abs(e) * 1e3)),
                err.as_ref()
                    .map_or("–".into(), |e| format!("{:.3}", rms(e) * 1e3)),
            ]
        })
        .collect();
    report.section("Runs").table(
        &[
            "run",
            "log",
            "rows",
            "duration (s)",
            "path length (mm)",
            "max |F| (N)",
            "max |ξ| (mm)",
            "max error (mm)",
            "RMS error (mm)",
        ],
        &rows,
    );
    report.section("Figures");
    for (path, caption) in figures {
        report.image(path, caption.clone());
    }
    let links: Vec<FileLink> = traces
        .iter()
        .map(|t| FileLink::new(t.file.clone(), format!("{} ({})", t.label, t.kind)))
        .collect();
    report.section("Logs").paragraph(
        links
            .iter()
            .map(|l| format!("{}: {}", l.description, l.href))
            .collect::<Vec<_>>()
            .join("; "),
    );
    report
}
