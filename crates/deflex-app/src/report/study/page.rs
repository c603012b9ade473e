//! The study's page (`index.html`): self-contained (figures embedded), every simulated quantity
//! labelled, the paper's numbers beside ours. One function per section.

use super::Figure;
use crate::report::DrawError;
use crate::report::draw::write_page;
use crate::study::compensation::CompensationStudy;
use crate::study::contact::StiffContactNumbers;
use crate::study::{BASELINE, DemoSummary, IDENTIFIED, paper};
use deflex_calibrate::stiffness::SearchResult;
use deflex_calibrate::stiffness::plan::Plan;
use deflex_plot::{FileLink, HtmlReport};
use std::path::Path;

/// What the page shows.
pub(crate) struct Page<'a> {
    pub summary: &'a DemoSummary,
    pub search: &'a SearchResult,
    pub plan: &'a Plan,
    pub grid: &'a deflex_sim::twin_campaign::GridParams,
    pub spiral: &'a deflex_sim::twin_campaign::SpiralParams,
    pub figures: &'a super::StudyFigures,
    /// Descriptions of the data files not in [`FILE_DESCRIPTIONS`]: `(name, description)`.
    pub file_descriptions: Vec<(String, String)>,
}

/// A stiffness in 10⁶ N·m/rad, or a centre shift in mm (each in its own table: one unit per
/// column).
fn fmt_k(v: Option<f64>, is_shift: bool) -> String {
    match v {
        None => "–".into(),
        Some(v) if v.is_infinite() => "∞".into(),
        Some(v) if is_shift => format!("{:.1}", v * 1e3),
        Some(v) => format!("{:.3}", v / 1e6),
    }
}

/// What each file the study writes beside the page holds (paths relative to the page).
const FILE_DESCRIPTIONS: [(&str, &str); 21] = [
    (
        "summary.json",
        "every number of the study (SI and labelled units), for scripts",
    ),
    (
        "paper_vs_deflex.csv",
        "the paper's numbers beside the SIMULATED cell's",
    ),
    (
        "plan.csv",
        "the calibration campaign plan: load cases, joint values, loads, points (SI units)",
    ),
    (
        "campaign.csv",
        "the campaign measured on the twin: displacement of every planned point (SIMULATED tracker)",
    ),
    (
        "search_iterations.csv",
        "the structure search step by step (the identification table)",
    ),
    (
        "stiffness.csv",
        "identified stiffnesses (N·m/rad) and centre shifts (m) beside Table 1 and the twin's plant",
    ),
    (
        "identified.toml",
        "the identified robot model (deflex robot file)",
    ),
    (
        "baseline-1edof.toml",
        "the one-eDoF-per-joint model calibrated on the same campaign",
    ),
    (
        "fig7_points.csv",
        "Figs. 8–9: M1–M3 and the TCP at the Fig. 7 configuration, measured (SIMULATED) and predicted by each model",
    ),
    (
        "grid.csv",
        "the validation grid measured on the twin (dead weights, SIMULATED tracker)",
    ),
    (
        "grid_predictions.csv",
        "the grid's measured and predicted displacements, every model",
    ),
    (
        "spiral.csv",
        "the spiral measured on the twin at the tracker rate (SIMULATED)",
    ),
    (
        "spiral_predictions.csv",
        "the spiral's measured and predicted displacements, every model",
    ),
    (
        "forming_open/log.csv",
        "cone without correction: 50 Hz log of the desired, commanded, true and tracked TCP, error, contact wrench, sensor, correction",
    ),
    (
        "forming_open/profile.csv",
        "cone without correction: formed and programmed profile along θ = 0 (mm)",
    ),
    (
        "forming_open/summary.json",
        "cone without correction: the twin's summary of the run",
    ),
    (
        "forming_closed/log.csv",
        "cone with correction: 50 Hz log, same columns as without",
    ),
    (
        "forming_closed/profile.csv",
        "cone with correction: formed and programmed profile along θ = 0 (mm)",
    ),
    (
        "forming_closed/summary.json",
        "cone with correction: the twin's summary of the run",
    ),
    (
        "forming_closed/controller_log.csv",
        "cone with correction: every control cycle (100 Hz) of the controller: wrench, δŝ, ξ, ε, loop gain, state flags (SI units)",
    ),
    (
        "sensitivity.csv",
        "the closed loop's sensitivity runs: condition, errors, improvement, force",
    ),
];

/// The data files beside the page (`.csv`, `.json`, `.toml`, up to two folders deep), each with
/// its description: from [`FILE_DESCRIPTIONS`], else from `more` (files whose names depend on the
/// run), else a plain "data file" (never the file's own first line: that is a provenance note,
/// not a description).
fn data_files(out: &Path, more: &[(String, String)]) -> Vec<FileLink> {
    fn walk(dir: &Path, prefix: &str, depth: usize, found: &mut Vec<String>) {
        let Ok(entries) = std::fs::read_dir(dir) else {
            return;
        };
        let mut entries: Vec<_> = entries.flatten().collect();
        entries.sort_by_key(|e| e.file_name());
        for entry in entries {
            let name = entry.file_name().to_string_lossy().into_owned();
            let path = entry.path();
            if path.is_dir() {
                if depth < 2 {
                    walk(&path, &format!("{prefix}{name}/"), depth + 1, found);
                }
            } else if name.ends_with(".csv") || name.ends_with(".json") || name.ends_with(".toml") {
                found.push(format!("{prefix}{name}"));
            }
        }
    }
    let mut found = Vec::new();
    walk(out, "", 0, &mut found);
    // The study's own files in the order of the page, then any other.
    let rank = |f: &String| {
        FILE_DESCRIPTIONS
            .iter()
            .position(|(n, _)| n == f)
            .unwrap_or(FILE_DESCRIPTIONS.len())
    };
    found.sort_by_key(|f| (rank(f), f.clone()));
    found
        .into_iter()
        .map(|f| {
            let description = FILE_DESCRIPTIONS
                .iter()
                .find(|(n, _)| *n == f)
                .map(|(_, d)| d.to_string())
                .or_else(|| more.iter().find(|(n, _)| *n == f).map(|(_, d)| d.clone()))
                .unwrap_or_else(|| "data file".to_string());
            FileLink::new(f, description)
        })
        .collect()
}

/// Write `index.html` into `out`.
pub(crate) fn write(out: &Path, page: &Page) -> Result<(), DrawError> {
    let s = page.summary;
    let f = page.figures;
    let mut html = HtmlReport::new(format!(
        "deflex — the paper's study on the simulated {} cell",
        s.robot
    ));
    introduction(&mut html, s);
    headline_section(&mut html, s);
    if s.paper_comparison {
        paper_vs_deflex_section(&mut html, s);
    }
    plan_section(&mut html, s, page.plan);
    identification_section(&mut html, s, page.search);
    if !s.fig7.is_empty() {
        fig7_section(&mut html, s, &f.fig7);
    }
    validation_section(&mut html, page);
    forming_section(&mut html, s, &f.forming, &f.controller);
    contact_section(
        &mut html,
        &s.stiff_contact,
        &s.stiff_contact_sweep,
        &f.contact,
    );
    sensitivity_section(&mut html, s, &f.sensitivity);
    compensation_section(&mut html, &s.compensation, &f.compensation);
    files_and_run_sections(&mut html, s, out, &page.file_descriptions);
    write_page(&html, &out.join("index.html"))
}

/// The SIMULATED note, how to reproduce the page, and the contents.
fn introduction(html: &mut HtmlReport, s: &DemoSummary) {
    html.note(
        "SIMULATED: every deflex number on this page was measured on the digital twin of a \
         robotised ISF cell (deflex-sim), not on a real robot. The paper's numbers are from \
         Johra et al., Robotics 2022, 11, 48 (a real Stäubli TX200).",
    );
    html.paragraph(format!(
        "Robot: {} (`{}`). Seed {}{}. Reproduce with: deflex demo --robot {} --seed {}{}. Data \
         behind every number: the CSV files beside this page, listed under \"Data files\".",
        s.robot,
        s.robot_spec,
        s.seed,
        if s.quick {
            ", shortened study (--quick)"
        } else {
            ""
        },
        s.robot_spec,
        s.seed,
        if s.quick { " --quick" } else { "" }
    ));
    html.contents();
}

/// The headline's first paragraph: the cone with and without correction (also what the README's
/// screenshot of the page shows; a test compares the two).
pub fn headline_text(s: &DemoSummary) -> String {
    format!(
        "Forming the paper's cone, the maximum path error norm goes from {:.2} mm without \
         correction to {:.2} mm with it: {:.1} % better (paper, on the real TX200: 3.84 → 1.13 mm, \
         70 %). The largest contact force norm rises from {:.0} N to {:.0} N as the corrected \
         tool reaches the programmed depth (paper, Figs. 18–19: about 1300 → 1500 N). Conditions \
         of the twin, each documented with its source in deflex-sim and switchable in its TOML \
         ([cell.errors]):",
        s.forming_open.max_error_norm_mm,
        s.forming_closed.max_error_norm_mm,
        s.improvement_percent,
        s.forming_open.max_force_norm_N,
        s.forming_closed.max_force_norm_N,
    )
}

/// The headline: the cone with and without correction, and the twin's conditions.
fn headline_section(html: &mut HtmlReport, s: &DemoSummary) {
    html.section("Headline: the closed loop with every error source on");
    html.paragraph(headline_text(s));
    let conditions: Vec<Vec<String>> = s
        .conditions
        .iter()
        .map(|(name, level, on)| {
            vec![
                name.clone(),
                level.clone(),
                if *on { "on" } else { "off" }.to_string(),
            ]
        })
        .collect();
    html.table(
        &["error source / effect", "level", "in this run"],
        &conditions,
    );
}

/// Section 1: the calibration campaign and its expected standard errors.
fn plan_section(html: &mut HtmlReport, s: &DemoSummary, plan: &Plan) {
    html.section("1. Calibration campaign plan");
    html.paragraph(format!(
        "{} load cases ({} measured points: the TCP, points on links 2 and 3 and a reflector on the \
         base casting, like the paper's M1–M3), chosen axis by axis and then D-optimally from random reachable poses and load \
         directions. Expected standard error of each stiffness at 15 µm tracker noise:",
        s.campaign_load_cases, s.campaign_rows
    ));
    html.table(
        &crate::report::plan_tables::EXPECTED_SE_HEADERS,
        &crate::report::plan_tables::expected_se_rows(plan),
    );
    if !plan.expected_shifts.is_empty() {
        html.table(
            &crate::report::plan_tables::EXPECTED_SHIFT_HEADERS,
            &crate::report::plan_tables::expected_shift_rows(plan),
        );
    }
}

/// Sections 2–3: the structure search and the identified stiffnesses and centre shifts beside
/// Table 1 and the twin's plant.
fn identification_section(html: &mut HtmlReport, s: &DemoSummary, search: &SearchResult) {
    html.section("2–3. Identification (structure search, Section 3)");
    html.paragraph(format!(
        "Start: one z-eDoF per joint (the paper's start). Each step tries every refinement (an x/y \
         eDoF on any joint, a base tilt eDoF, a free centre shift) and keeps the one that lowers \
         BIC most. The last column is the cross-validated RMS: each of 5 folds of load cases \
         predicted by the model fitted on the other four. Stopped: {}. Result: {} (RMS residual \
         {:.1} µm, χ²/dof {:.2}).",
        s.search_stop_reason,
        s.identified_structure,
        s.identification_rms_um,
        s.identification_reduced_chi2
    ));
    html.table(
        &crate::report::calibration_tables::ITERATION_HEADERS,
        &crate::report::calibration_tables::iteration_rows(&search.steps),
    );
    let row = |r: &crate::study::StiffnessRow, shift: bool| {
        vec![
            r.name.trim_end_matches(" [m]").to_string(),
            fmt_k(r.identified, shift),
            fmt_k(r.se, shift),
            r.interval95
                .map(|(lo, _)| fmt_k(Some(lo), shift))
                .unwrap_or_else(|| "–".into()),
            r.interval95
                .map(|(_, hi)| fmt_k(Some(hi), shift))
                .unwrap_or_else(|| "–".into()),
            r.status.clone(),
            fmt_k(r.table1, shift),
            fmt_k(r.plant, shift),
        ]
    };
    let is_shift = |r: &&crate::study::StiffnessRow| r.name.starts_with('δ');
    let stiffness: Vec<Vec<String>> = s
        .stiffness
        .iter()
        .filter(|r| !is_shift(r))
        .map(|r| row(r, false))
        .collect();
    let shifts: Vec<Vec<String>> = s
        .stiffness
        .iter()
        .filter(is_shift)
        .map(|r| row(r, true))
        .collect();
    html.paragraph(
        "\"Twin plant\" is the simulated robot's hidden linear truth, shown only to judge the \
         identification. The 95 % intervals account for measurement noise, not for model-form \
         error: the twin also has a J2/J3 coupling and wrist lost motion that no VJM model \
         represents, and a base tilt that TCP-side data cannot separate from J1.x/y, so some \
         identified values lie outside their interval around the plant value while the model \
         still predicts well (validation below).",
    );
    html.table(
        &[
            "eDoF",
            "identified [10⁶ N·m/rad]",
            "SE [10⁶ N·m/rad]",
            "95 % low [10⁶ N·m/rad]",
            "95 % high [10⁶ N·m/rad]",
            "status",
            "paper Table 1 [10⁶ N·m/rad]",
            "twin plant (SIMULATED truth) [10⁶ N·m/rad]",
        ],
        &stiffness,
    );
    if !shifts.is_empty() {
        html.table(
            &[
                "centre shift",
                "identified [mm]",
                "SE [mm]",
                "95 % low [mm]",
                "95 % high [mm]",
                "status",
                "paper [mm]",
                "twin plant (SIMULATED truth) [mm]",
            ],
            &shifts,
        );
    }
}

/// Section 4: validation on the grid and along the spiral.
fn validation_section(html: &mut HtmlReport, page: &Page) {
    let s = page.summary;
    html.section("4. Validation on a grid and a spiral (Section 3.2)");
    let g = page.grid;
    let loads: Vec<String> = g.loads_n.iter().map(|l| format!("{l:.0} N")).collect();
    html.paragraph(format!(
        "{} TCP poses on a {:.2} × {:.2} m grid at z = {:.3} m centred on ({:.3}, {:.3}) m, tool \
         down, {} dead weights (the paper's grid for the TX200), measured by the simulated laser \
         tracker (noise 10 µm + 5 µm/m); then a {:.2} m spiral at z = {:.3} m with {:.0} N. \
         Errors are measured − predicted, in mm. The one-eDoF model is calibrated on the same \
         campaign; \"{}\" is the robot file's model used as is.",
        g.points_xy[0] * g.points_xy[1],
        g.size_xy_m[0],
        g.size_xy_m[1],
        g.height_m,
        g.center_xy_m[0],
        g.center_xy_m[1],
        loads.join(" and "),
        page.spiral.length_m,
        page.spiral.center_m[2],
        page.spiral.load_n,
        crate::study::TABLE1,
    ));
    let validation: Vec<Vec<String>> = s
        .validation
        .iter()
        .map(|v| {
            vec![
                v.data.clone(),
                v.model.clone(),
                v.points.to_string(),
                format!("{:.3}", v.rms_z_mm),
                format!("{:.3}", v.max_z_mm),
                format!("{:.3}", v.rms_norm_mm),
                format!("{:.3}", v.max_norm_mm),
                format!("{:.3}", v.measured_rms_z_mm),
            ]
        })
        .collect();
    html.table(
        &[
            "data (SIMULATED)",
            "model",
            "points",
            "RMS δz error [mm]",
            "max |δz error| [mm]",
            "RMS |error| [mm]",
            "max |error| [mm]",
            "RMS measured δz [mm]",
        ],
        &validation,
    );
    for (path, caption) in page.figures.grid.iter().chain(&page.figures.spiral) {
        html.image(path, caption.clone());
    }
}

/// Section 5: forming the cone without and with correction, and the controller's correction
/// and state.
fn forming_section(
    html: &mut HtmlReport,
    s: &DemoSummary,
    forming_figures: &[Figure],
    controller: &[Figure],
) {
    html.section("5. Forming the paper's cone (Section 4)");
    let f = [
        (&s.forming_open, "without correction"),
        (&s.forming_closed, "with correction"),
    ];
    let forming: Vec<Vec<String>> = f
        .iter()
        .map(|(n, label)| {
            vec![
                label.to_string(),
                format!("{:.3}", n.max_error_norm_mm),
                format!("{:.3}", n.rms_error_norm_mm),
                format!("{:.0}", n.max_force_norm_N),
                format!("{:.0}", n.max_fz_N),
                format!("{:.0}", n.max_fxy_N),
                format!("{:.2}", n.final_part_depth_mm),
                format!("{:.2}", n.target_depth_mm),
            ]
        })
        .collect();
    html.table(
        &[
            "run (SIMULATED)",
            "max |error| [mm]",
            "RMS |error| [mm]",
            "max |F| [N]",
            "max Fz [N]",
            "max in-plane F [N]",
            "part depth [mm]",
            "programmed depth [mm]",
        ],
        &forming,
    );
    html.paragraph(format!(
        "Improvement of the maximum error norm: {:.1} % (paper: 70 %). Controller: {}.",
        s.improvement_percent, s.controller_status
    ));
    for (path, caption) in forming_figures {
        html.image(path, caption.clone());
    }
    if !controller.is_empty() {
        html.subsection("The correction ξ and the controller's state");
        html.paragraph(
            "What the controller sent the robot during the corrected run, cycle by cycle \
             (forming_closed/controller_log.csv): the correction ξ added to the programmed \
             path (eq. 7) and the state flags of every cycle: active (the law drives ξ), \
             ramping in or out, taring the sensor out of contact, ξ held at its size or rate \
             limit, a reused (stale) F/T sample, the runaway guard holding ξ, a fault detected \
             or latched.",
        );
        for (path, caption) in controller {
            html.image(path, caption.clone());
        }
    }
}

/// Section 7: the sensitivity of the closed loop, one table per factor.
fn sensitivity_section(html: &mut HtmlReport, s: &DemoSummary, figures: &[Figure]) {
    if let Some(sens) = &s.sensitivity {
        html.section("7. Sensitivity of the closed loop");
        html.paragraph(format!(
            "{} runs on the sensitivity cone (the paper's cone with a 1 mm step-down, sheet \
             strength scaled to the same force level), every error source on; one factor varied \
             at a time around the cell's values, and the correction delay crossed with the \
             compliance scale of the controller's model (1.3: the model is 30 % too soft).",
            sens.runs
        ));
        // One table per factor, its condition in columns of one unit each.
        let mut factors: Vec<&str> = Vec::new();
        for r in &sens.rows {
            if !factors.contains(&r.factor.as_str()) {
                factors.push(&r.factor);
            }
        }
        for (index, factor) in factors.into_iter().enumerate() {
            let group: Vec<&crate::study::sensitivity::SensitivityRow> =
                sens.rows.iter().filter(|r| r.factor == factor).collect();
            let mut headers: Vec<String> = group[0]
                .condition_columns
                .iter()
                .map(|(h, _)| h.clone())
                .collect();
            headers.extend(
                [
                    "open max |e| [mm]",
                    "closed max |e| [mm]",
                    "improvement [%]",
                    "closed max |F| [N]",
                    "fault",
                ]
                .map(String::from),
            );
            let rows: Vec<Vec<String>> = group
                .iter()
                .map(|r| {
                    let mut row: Vec<String> =
                        r.condition_columns.iter().map(|(_, v)| v.clone()).collect();
                    row.extend([
                        format!("{:.3}", r.open_max_mm),
                        format!("{:.3}", r.closed_max_mm),
                        format!("{:.1}", r.improvement_percent),
                        format!("{:.0}", r.closed_max_force_N),
                        r.fault.clone().unwrap_or_else(|| "–".into()),
                    ]);
                    row
                })
                .collect();
            html.subsection(factor_title(factor));
            let header_refs: Vec<&str> = headers.iter().map(String::as_str).collect();
            html.table(&header_refs, &rows);
            if index == 0 {
                // The heatmap shows the first (crossed) factor.
                for (path, caption) in figures {
                    html.image(path, caption.clone());
                }
            }
        }
    }
}

/// The data files beside the page, and the stage timings of the run.
fn files_and_run_sections(
    html: &mut HtmlReport,
    s: &DemoSummary,
    out: &Path,
    descriptions: &[(String, String)],
) {
    html.section("Data files");
    html.paragraph(
        "Beside this page (open the folder the page is in; every file of a SIMULATED run says so \
         in its header):",
    );
    html.files(&data_files(out, descriptions));

    html.section("Run");
    let timings: Vec<Vec<String>> = s
        .stage_seconds
        .iter()
        .map(|(stage, seconds)| vec![stage.clone(), format!("{seconds:.2}")])
        .collect();
    html.table(&["stage", "wall time [s]"], &timings);
}

/// The paper's numbers beside the SIMULATED cell's, one unit per column: the validation errors
/// (mm) in one table, the forming errors (mm) and forces (N) in another, the improvement (%) in
/// the text.
fn paper_vs_deflex_section(html: &mut HtmlReport, s: &DemoSummary) {
    html.section("Paper vs deflex");
    html.paragraph(
        "The paper's numbers are measured on a real TX200; deflex's on the SIMULATED cell. δz \
         error over the validation grid (Section 3.2, Figs. 11 and 13):",
    );
    let mut validation = Vec::new();
    for (i, load) in ["600", "1100"].iter().enumerate() {
        let data = format!("grid {load} N");
        for (model, label, max_mm, rms_mm) in [
            (
                BASELINE,
                "one eDoF per joint",
                paper::ONE_EDOF_MAX_MM[i],
                paper::ONE_EDOF_RMS_MM[i],
            ),
            (
                IDENTIFIED,
                "identified model",
                paper::MODEL_MAX_MM[i],
                paper::MODEL_RMS_MM[i],
            ),
        ] {
            if let Some(e) = s.errors(model, &data) {
                validation.push(vec![
                    label.to_string(),
                    load.to_string(),
                    format!("{max_mm:.2}"),
                    format!("{:.3}", e.max_z_mm),
                    format!("{rms_mm:.2}"),
                    format!("{:.3}", e.rms_z_mm),
                ]);
            }
        }
    }
    html.table(
        &[
            "model",
            "load [N]",
            "max |δz error|, paper [mm]",
            "max |δz error|, deflex [mm]",
            "RMS δz error, paper [mm]",
            "RMS δz error, deflex [mm]",
        ],
        &validation,
    );
    html.paragraph(format!(
        "Forming the cone (Section 4.3, Figs. 17–19); the paper gives its forces without \
         correction only. Improvement of the max error norm: paper {:.0} %, deflex {:.1} %.",
        paper::FORMING_IMPROVEMENT_PERCENT,
        s.improvement_percent
    ));
    let forming = vec![
        vec![
            "without correction".to_string(),
            format!("{:.2}", paper::FORMING_OPEN_MAX_MM),
            format!("{:.3}", s.forming_open.max_error_norm_mm),
            format!("{:.0}", paper::FORMING_OPEN_FZ_N),
            format!("{:.0}", s.forming_open.max_fz_N),
            format!("{:.0}", paper::FORMING_OPEN_FXY_N),
            format!("{:.0}", s.forming_open.max_fxy_N),
        ],
        vec![
            "with correction".to_string(),
            format!("{:.2}", paper::FORMING_CLOSED_MAX_MM),
            format!("{:.3}", s.forming_closed.max_error_norm_mm),
            "–".into(),
            format!("{:.0}", s.forming_closed.max_fz_N),
            "–".into(),
            format!("{:.0}", s.forming_closed.max_fxy_N),
        ],
    ];
    html.table(
        &[
            "run",
            "max |error|, paper [mm]",
            "max |error|, deflex [mm]",
            "max Fz, paper [N]",
            "max Fz, deflex [N]",
            "max in-plane F, paper [N]",
            "max in-plane F, deflex [N]",
        ],
        &forming,
    );
}

/// Figs. 7–9: the displacements of M1–M3 and the TCP under the lateral load, measured on the
/// twin and predicted by each model.
fn fig7_section(html: &mut HtmlReport, s: &DemoSummary, figures: &[Figure]) {
    html.section("Figs. 7–9: points along the arm under a lateral load");
    let sigma_mm = s.fig7.iter().map(|p| p.sigma_mm).fold(0.0, f64::max);
    let m1 = s.fig7.iter().find(|p| p.point == "M1");
    html.paragraph(format!(
        "The paper's structure test (Section 3.1): the TX200 at q = (0, 90°, 0, 0, 0, 0), arm \
         stretched along x0, loaded by f_y = {:.0} N at the end effector (here the TCP of the \
         cell's forming tool), displacements of points along the arm measured by the laser \
         tracker, here the twin's (SIMULATED; 1σ of each displacement about {sigma_mm:.3} mm). \
         The paper does not give where M1–M3 sit; deflex puts M1 on the upper arm (40 % from \
         joint 2 to joint 3), M2 on the forearm 15 cm past the elbow, M3 a quarter of the \
         forearm before the wrist centre. The x-displacement of M2, M3 and the TCP is what the \
         one-eDoF model cannot produce and the joint-3 x-eDoF with its shifted centre (δr3) \
         does. The paper saw M1 move along x0 as well and traced it to the baseplate tilting \
         about y0, which neither of its models represents{}.",
        crate::study::fig7::FIG7_FY_N,
        m1.map(|p| format!("; on the twin M1 moves {:.3} mm along x0", p.measured_mm[0]))
            .unwrap_or_default()
    ));
    let models: Vec<String> = s
        .fig7
        .first()
        .map(|p| p.predicted_mm.iter().map(|(m, _)| m.clone()).collect())
        .unwrap_or_default();
    let mut headers = vec![
        "point".to_string(),
        "x0 [mm]".to_string(),
        "measured δx [mm]".to_string(),
    ];
    headers.extend(models.iter().map(|m| format!("{m} δx [mm]")));
    headers.push("measured δy [mm]".to_string());
    headers.extend(models.iter().map(|m| format!("{m} δy [mm]")));
    let rows: Vec<Vec<String>> = s
        .fig7
        .iter()
        .map(|p| {
            let mut row = vec![
                p.point.clone(),
                format!("{:.0}", p.x_mm),
                format!("{:.3}", p.measured_mm[0]),
            ];
            row.extend(p.predicted_mm.iter().map(|(_, d)| format!("{:.3}", d[0])));
            row.push(format!("{:.3}", p.measured_mm[1]));
            row.extend(p.predicted_mm.iter().map(|(_, d)| format!("{:.3}", d[1])));
            row
        })
        .collect();
    let header_refs: Vec<&str> = headers.iter().map(String::as_str).collect();
    html.table(&header_refs, &rows);
    for (path, caption) in figures {
        html.image(path, caption.clone());
    }
}

/// A sensitivity factor as a subsection heading.
fn factor_title(factor: &str) -> String {
    match factor {
        "delay × model scale" => "Correction delay × model compliance scale".into(),
        "gain error" => "F/T gain error".into(),
        "bias drift" => "F/T bias drift".into(),
        "contact stiffness" => "Contact stiffness of the sheet".into(),
        other => other.to_string(),
    }
}

/// The rows of the stiff-contact table: per stiffness, without correction, unguarded, guarded.
pub fn contact_table_rows(comparisons: &[&StiffContactNumbers]) -> Vec<Vec<String>> {
    let mut rows = Vec::new();
    for n in comparisons {
        let k = format!("{:.0e}", n.stiffness_n_m);
        rows.push(vec![
            k.clone(),
            "without correction".into(),
            format!("{:.0}", n.open_max_force_N),
            "1.00".into(),
            "–".into(),
            format!("rigid-robot force k·δ {:.0} N", n.rigid_robot_force_N),
        ]);
        for l in [&n.unguarded, &n.guarded] {
            let outcome = match (&l.fault, &l.first_runaway) {
                (Some(f), _) => f.clone(),
                (None, Some(w)) => format!("warning {w}"),
                (None, None) if l.runaway_at_s.is_some() => "force more than doubled".into(),
                (None, None) => "settles".into(),
            };
            rows.push(vec![
                k.clone(),
                if l.guard {
                    "correction + runaway guard".into()
                } else {
                    "correction, no guard".into()
                },
                format!("{:.0}", l.max_force_N),
                format!("{:.2}", l.force_ratio_to_uncorrected),
                format!("{:.2}", l.max_correction_mm),
                outcome,
            ]);
        }
    }
    rows
}

/// Section 6 of the report page: the plunge at `main` (its figures in `figures`) and the sweep.
fn contact_section(
    html: &mut HtmlReport,
    main: &StiffContactNumbers,
    sweep: &[StiffContactNumbers],
    figures: &[Figure],
) {
    html.section("6. Stiff contact: a plunge into a fixture");
    let (u, g) = (&main.unguarded, &main.guarded);
    html.paragraph(format!(
        "SIMULATED. The tool plunges {:.1} mm into a fixture of contact stiffness {:.0e} N/m and \
         traverses at that depth. Without correction the robot and the contact share the \
         interference as springs in series: the force reaches {:.0} N. With correction the loop is \
         positive feedback (the correction pushes further in, the force and the estimated \
         deflection rise, the correction grows): an exact correction would take the force to the \
         rigid-robot {:.0} N, a model softer than the robot has no equilibrium at all. Without the \
         runaway guard: {:.0} N at most ({:.2}× the uncorrected force), correction up to {:.2} mm{}{}. \
         With the controller's runaway guard (deflex-control `runaway.rs`: it estimates the loop \
         gain through the contact online, withdraws the correction along the runaway direction and \
         latches until the contact goes away): {:.0} N at most ({:.2}×){}{}.",
        main.interference_mm,
        main.stiffness_n_m,
        main.open_max_force_N,
        main.rigid_robot_force_N,
        u.max_force_N,
        u.force_ratio_to_uncorrected,
        u.max_correction_mm,
        u.runaway_at_s
            .map(|t| format!(", twice the uncorrected force at t = {t:.2} s"))
            .unwrap_or_default(),
        u.fault
            .as_ref()
            .map(|f| format!("; the controller stopped on {f}"))
            .unwrap_or_default(),
        g.max_force_N,
        g.force_ratio_to_uncorrected,
        g.first_runaway
            .as_ref()
            .map(|w| format!(", warning {w}"))
            .unwrap_or_default(),
        g.fault
            .as_ref()
            .map(|f| format!("; fault {f}"))
            .unwrap_or_default(),
    ));
    let comparisons: Vec<&StiffContactNumbers> = if sweep.is_empty() {
        vec![main]
    } else {
        sweep.iter().collect()
    };
    html.table(
        &[
            "fixture stiffness [N/m]",
            "controller",
            "max |F| [N]",
            "× uncorrected",
            "max correction [mm]",
            "outcome",
        ],
        &contact_table_rows(&comparisons),
    );
    for (path, caption) in figures {
        html.image(path, caption.clone());
    }
}

/// The compensation comparison's section.
fn compensation_section(html: &mut HtmlReport, study: &CompensationStudy, figures: &[Figure]) {
    html.section("Compensation without a real-time option: offline, online and both");
    html.paragraph(format!(
        "For cells without a real-time correction option, deflex compensate gives the robot a \
         compensated program (commanded = desired − predicted deflection, with the identified \
         model) from forces predicted by a process model or logged in a previous run; where the \
         option exists, the same table is the online controller's feed-forward, or the \
         controller runs on top of the compensated program knowing what it already applies. \
         SIMULATED: the twin's robot with every error source on; the process model is the twin's \
         own forming law (optimistic), driven by the identified robot model, not the plant; the \
         compensations are position only (the twin holds the tool orientation); feed-forward \
         lead {:.3} s. The controller runs with its defaults, the contact-runaway guard on; \
         on the CAM part each plunge's elastic onset into the sheet reads as a loop gain of \
         0.8–1.2 and trips it (the guard cannot tell that onset from a fixture), so the part \
         also shows the online correction with the guard off. In contact: the rows whose \
         contact force is at least {:.0} N (the error that forms the part, without the \
         transients in the air after a retract, where a correction still ramping out at its \
         rate limit moves the tool). Lag: {}.",
        study.lead_s,
        crate::study::compensation::lag::CONTACT_FORCE_N,
        study.lag_definition
    ));
    for part in &study.parts {
        let p = &part.offline_process;
        html.paragraph(format!(
            "{} ({} points, {:.0} mm, {} force ramp(s)). Process-model compensation: {} \
             iteration(s){}, predicted error {:.3} → {:.4} mm, largest compensation {:.3} mm, \
             force {:.0} N, {:.2} s. Log compensation: predicted error {:.3} → {:.4} mm.",
            part.part,
            part.points,
            part.length_mm,
            part.ramps,
            p.iterations,
            if p.converged { "" } else { " (not converged)" },
            p.predicted_error_before_mm,
            p.predicted_error_after_mm,
            p.max_compensation_mm,
            p.max_force_N,
            p.seconds,
            part.offline_log.predicted_error_before_mm,
            part.offline_log.predicted_error_after_mm,
        ));
        let rows: Vec<Vec<String>> = part
            .ways
            .iter()
            .map(|w| {
                let n = &w.numbers;
                vec![
                    w.way.clone(),
                    format!("{:.3}", n.max_error_mm),
                    format!("{:.3}", n.rms_error_mm),
                    n.max_contact_error_mm
                        .map_or("–".into(), |v| format!("{v:.3}")),
                    n.rms_contact_error_mm
                        .map_or("–".into(), |v| format!("{v:.3}")),
                    n.ramp_error_integral_mm_s
                        .map_or("– (no force ramp)".into(), |v| format!("{v:.4}")),
                    match n.ramp_settle_s {
                        None => "–".into(),
                        Some(v) if n.ramps_not_settled > 0 => {
                            format!("{v:.2} ({} not settled)", n.ramps_not_settled)
                        }
                        Some(v) => format!("{v:.2}"),
                    },
                    format!("{:.0}", n.max_force_N),
                ]
            })
            .collect();
        html.table(
            &[
                "way",
                "max |e| [mm]",
                "RMS |e| [mm]",
                "max |e| in contact [mm]",
                "RMS |e| in contact [mm]",
                "ramp ∫|e|dt [mm·s]",
                "ramp settle [s]",
                "max |F| [N]",
            ],
            &rows,
        );
    }
    for (path, caption) in figures {
        html.image(path, caption.clone());
    }
}
