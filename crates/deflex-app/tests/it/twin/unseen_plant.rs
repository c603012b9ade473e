//! A held-out check of offline compensation on plants no built-in cell has (issue 23): a
//! KR 210-like arm whose twin has a strong J2/J3 coupling (a non-diagonal compliance no VJM
//! model represents), a hardening wrist (lost motion taken up over a large torque: the
//! stiffness rises with the load), a compliant tool holder (J6 bending springs whose centre sits
//! down the tool), its geometry errors and every other error source on. A part is formed at
//! about 1 kN without correction; its log, with 200 rows appended at rest at the end with the
//! force fading (what `deflex run` logs while the robot waits at the end of its program), is the
//! source of the compensation; the compensated program runs on the same twin.
//!
//! The robot model is either the plant's own linear spring chain (`PlantConfig::linear_robot`:
//! the springs without the coupling, the hardening and the large rotations) or, as a user has
//! it, a model **identified from a loaded campaign** measured on the plant's twin
//! ([`campaign_models`]: the structure search, then the J2.z–J3.z off-diagonal compliance). Ways
//! to use the log:
//! * **fixed**: the logged wrenches (one pass). The compensated tool reaches the programmed
//!   depth and the sheet pushes harder than the log says (846 → 998 N on the first plant).
//! * **law**: the force–depth law identified from the log ([`LoggedProcess`]), the depths from
//!   the robot model's deflection (all a `deflex run` log allows).
//! * **law + measured TCP**: the same, with the laser tracker's positions of the sim log: the
//!   deflection the robot model misses in the logged run is added, scaled with the force.
//!
//! **Measured (max path error in contact on the feed moves):**
//!
//! | part, plant | uncorrected | fixed | law | law + measured TCP | law, campaign model (diagonal / coupled) |
//! | --- | --- | --- | --- | --- | --- |
//! | 60 mm circle, 10 × 0.5 mm levels, plant 1 | 1.637 mm | 0.654 (60.0 %) | 0.477 (70.9 %) | 0.189 (88.4 %) | 0.208 (87.3 %) / 0.170 (89.6 %) |
//! | 50 mm circle clockwise, 12 × 0.4 mm levels on a 50° wall, plant 2 | 1.500 mm | 0.487 (67.5 %) | 0.317 (78.9 %) | 0.148 (90.1 %) | 0.161 (89.3 %) / 0.137 (90.9 %) |
//!
//! Plant 1: coupling 0.3, 0.4 mrad of wrist lost motion over 600 N·m, tool holder 4e5 N·m/rad
//! centred 80 mm down the tool. Plant 2: 0.2, 0.3 mrad over 400 N·m, 6e5 N·m/rad at 60 mm.
//!
//! **Why the law with the plant's springs stops near 75 %.** Compensating the first circle from
//! the log of the *compensated* run (its forces at the programmed depth: what a perfect process
//! law gives) cuts the error to 0.39 mm (76 %, printed by the first test): the rest is what the
//! plant's linear spring chain does not represent, and taking the effects out of the plant one
//! at a time shows it is the J2/J3 coupling ([`the_plain_log_gap_is_the_j2_j3_coupling`]). A
//! model fitted to a loaded campaign on the plant represents where its tool goes under load,
//! coupling included, and reaches 89.6 % / 90.9 % from the plain log.
//!
//! **The error measure.** Rows with a contact force of at least 20 N (as the README's "in
//! contact" numbers) whose desired TCP is on a feed move: the retract at the end is a rapid
//! that starts in contact, and while it lifts the tool its command blends from the last point's
//! compensation to none (up to 1 mm from the retract line while the force fades), which is not
//! part of the formed path. The whole-run numbers, retract included, are printed.
//!
//! SIMULATED.

use super::common::{plant_1, plant_2};
use deflex_app::load::parse_wrench_log;
use deflex_compensate::log::{ResampleOptions, Resampled, resample_on_path};
use deflex_compensate::{
    Compensation, CompensationOptions, LoggedProcess, LoggedProcessOptions, TcpPath, WrenchSource,
    commanded_pose, compensate,
};
use deflex_model::Robot;
use deflex_sim::gcode::parse_gcode;
use deflex_sim::{
    CellConfig, FormingRun, ToolPath, compensated_tool_path, run_forming,
    run_program_with_progress, tcp_path,
};

/// A 60 mm circle formed down a 45° wall in 0.5 mm levels (each a full G3 circle), so the force
/// rises to the sheet's ≈ 1.2 kN level.
fn circle_program() -> String {
    let mut text = String::from(
        "%\nO60 (60 MM CIRCLE LEVELS)\nG17 G21 G40 G90 G54\nG0 X30 Y0 Z2\nG1 Z0 F300\n",
    );
    for k in 1..=10 {
        let z = -0.5 * k as f64;
        let r = 30.0 + z;
        text.push_str(&format!("G1 X{r} Z{z} F600\nG3 X{r} Y0 I{} J0\n", -r));
    }
    text.push_str("G0 Z5\nM30\n%\n");
    text
}

/// A 50 mm circle formed clockwise down a 50° wall in 0.4 mm levels, at 8 mm/s.
fn second_program() -> String {
    let mut text =
        String::from("%\nO61 (50 MM CW LEVELS)\nG17 G21 G40 G90 G54\nG0 X25 Y0 Z2\nG1 Z0 F300\n");
    for k in 1..=12 {
        let z = -0.4 * k as f64;
        let r = 25.0 + z / 50f64.to_radians().tan();
        text.push_str(&format!(
            "G1 X{r:.4} Z{z:.4} F480\nG2 X{r:.4} Y0 I{:.4} J0\n",
            -r
        ));
    }
    text.push_str("G0 Z5\nM30\n%\n");
    text
}

/// The run's log as CSV with 200 rows at rest at the end, the force fading out.
fn log_with_standstill(run: &FormingRun) -> String {
    let mut text = run.log.to_csv();
    let last = text.lines().last().unwrap().to_string();
    let header_line = text
        .lines()
        .find(|l| l.starts_with("time_s,"))
        .unwrap()
        .to_string();
    let header: Vec<&str> = header_line.split(',').collect();
    let fields: Vec<f64> = last.split(',').map(|v| v.parse().unwrap_or(0.0)).collect();
    for k in 1..=200 {
        let fade = 1.0 - k as f64 / 200.0;
        let row: Vec<String> = header
            .iter()
            .zip(&fields)
            .map(|(name, v)| match *name {
                "time_s" => format!("{}", v + 0.02 * k as f64),
                "fx_N" | "fy_N" | "fz_N" | "mx_Nm" | "my_Nm" | "mz_Nm" => format!("{}", v * fade),
                _ => format!("{v}"),
            })
            .collect();
        text.push_str(&row.join(","));
        text.push('\n');
    }
    text
}

/// One part on one plant: the uncorrected run, its log, and the compensated runs.
struct HeldOut {
    cell: CellConfig,
    model: Robot,
    part: ToolPath,
    path: TcpPath,
    open: FormingRun,
    resampled: Resampled,
}

impl HeldOut {
    fn new(cell: CellConfig, program: &str) -> HeldOut {
        let nominal = cell.nominal_robot().unwrap();
        // The plant's own linear spring chain: what a perfect VJM identification finds, without
        // the coupling, the hardening and the large rotations.
        let model = cell.plant.linear_robot(&nominal).unwrap();
        HeldOut::with_model(cell, program, model)
    }

    /// The same with another robot model (e.g. one identified from a campaign).
    fn with_model(cell: CellConfig, program: &str, model: Robot) -> HeldOut {
        let part = parse_gcode(program, "part.nc").unwrap();
        let open = run_forming(&cell, part.clone(), 3, None).unwrap();
        assert!(open.summary.max_force_norm_N > 700.0, "{:?}", open.summary);
        let rotation = model.tcp_pose(&cell.seed_q_rad()).unwrap().rotation;
        let path = tcp_path(
            &part,
            &cell.part_frame(),
            &rotation,
            cell.controller.rapid_feed_mm_s,
        )
        .unwrap();
        let text = log_with_standstill(&open);
        let log = parse_wrench_log(&text, "open/log.csv", &model, &cell.part_frame()).unwrap();
        assert!(log.measured, "the sim log carries the tracker's TCP");
        let resampled = resample_on_path(&log, &path, &ResampleOptions::default()).unwrap();
        assert!(
            resampled.standstill_rows >= 200,
            "{}",
            resampled.standstill_rows
        );
        HeldOut {
            cell,
            model,
            part,
            path,
            open,
            resampled,
        }
    }

    fn compensate(&self, source: WrenchSource) -> Compensation {
        let result = compensate(
            &self.model,
            &self.path,
            &self.cell.seed_q_rad(),
            source,
            &CompensationOptions {
                orientation: false,
                ..CompensationOptions::default()
            },
            &mut |_| {},
        )
        .unwrap();
        assert!(result.converged);
        assert_eq!(result.failure_count(), 0);
        result
    }

    fn fixed(&self, wrenches: &[deflex_model::Wrench]) -> Compensation {
        self.compensate(WrenchSource::Fixed {
            label: "log".into(),
            simulated: true,
            wrenches,
        })
    }

    fn law(&self, measured: bool) -> Compensation {
        let mut process = LoggedProcess::new(
            "open/log.csv",
            true,
            self.resampled.clone(),
            LoggedProcessOptions {
                use_measured: measured,
                ..LoggedProcessOptions::default()
            },
        )
        .unwrap();
        let result = self.compensate(WrenchSource::Process(&mut process));
        let id = process.identification().unwrap();
        assert!(id.sloped_bins > 0, "{id:?}");
        assert_eq!(id.measured, measured);
        // `--log-forces auto` would choose the law on these logs too (issue 33).
        let evidence = id.evidence.as_ref().unwrap();
        println!(
            "SIMULATED evidence (measured TCP {measured}): R² depth {:.3}, position {:.3}, loop gain {:.2}, falling {:.2}: {:?}",
            evidence.r2_depth,
            evidence.r2_position,
            evidence.loop_gain,
            evidence.falling_share,
            evidence.rejection()
        );
        assert!(evidence.supported(), "{evidence:?}");
        result
    }

    /// The compensated program on the twin.
    fn run(&self, result: &Compensation) -> FormingRun {
        let commanded: Vec<_> = self
            .path
            .points()
            .iter()
            .zip(&result.points)
            .map(|(p, c)| commanded_pose(&p.pose, &c.compensation).translation.vector)
            .collect();
        let program =
            compensated_tool_path(&self.part, &commanded, &self.cell.part_frame()).unwrap();
        run_program_with_progress(&self.cell, program, Some(&self.part), 3, None, &mut |_| {})
            .unwrap()
    }

    /// Improvement of the compensated run over the uncorrected one, printed.
    fn improvement(&self, name: &str, run: &FormingRun, predicted_n: f64) -> f64 {
        let (before, after) = (
            super::common::max_contact_error_mm(&self.open, Some(&self.part)),
            super::common::max_contact_error_mm(run, Some(&self.part)),
        );
        let improvement = 1.0 - after / before;
        println!(
            "SIMULATED {name}: max path error in contact {before:.3} → {after:.3} mm ({:.1} %); every row, the retract through the air included, {:.3} → {:.3} mm; max force {:.0} N uncorrected, {:.0} N compensated ({predicted_n:.0} N predicted)",
            improvement * 100.0,
            super::common::max_contact_error_mm(&self.open, None),
            super::common::max_contact_error_mm(run, None),
            self.open.summary.max_force_norm_N,
            run.summary.max_force_norm_N,
        );
        improvement
    }

    /// Fixed, law and law + measured TCP: their improvements.
    fn compare(&self, name: &str) -> [f64; 3] {
        let fixed = self.fixed(&self.resampled.wrenches);
        let law = self.law(false);
        let measured = self.law(true);
        [
            ("fixed", &fixed),
            ("law", &law),
            ("law + measured TCP", &measured),
        ]
        .map(|(way, result)| {
            self.improvement(
                &format!("{name}, {way}"),
                &self.run(result),
                result.final_max_force_n,
            )
        })
    }
}

#[test]
fn a_circle_compensated_from_its_own_log_on_an_unseen_plant() {
    let case = HeldOut::new(plant_1(), &circle_program());
    let [fixed, law, measured] = case.compare("60 mm circle, plant 1");
    // The ceiling of a process law alone: the forces of the compensated run itself.
    let first = case.run(&case.fixed(&case.resampled.wrenches));
    let text = first.log.to_csv();
    let log =
        parse_wrench_log(&text, "fixed/log.csv", &case.model, &case.cell.part_frame()).unwrap();
    let own = resample_on_path(&log, &case.path, &ResampleOptions::default()).unwrap();
    let oracle = case.fixed(&own.wrenches);
    case.improvement(
        "60 mm circle, plant 1, the compensated run's own forces",
        &case.run(&oracle),
        oracle.final_max_force_n,
    );
    // Measured 60.0 %, 70.9 %, 88.4 % (the issue asks for 85 %).
    assert!(fixed >= 0.58, "fixed: {:.1} %", fixed * 100.0);
    assert!(law >= 0.68, "law: {:.1} %", law * 100.0);
    assert!(
        measured >= 0.85,
        "law + measured TCP: {:.1} %",
        measured * 100.0
    );
}

#[test]
fn a_second_part_on_a_second_unseen_plant() {
    let case = HeldOut::new(plant_2(), &second_program());
    let [fixed, law, measured] = case.compare("50 mm clockwise circle, plant 2");
    // Measured 67.5 %, 78.9 %, 90.1 %.
    assert!(fixed >= 0.64, "fixed: {:.1} %", fixed * 100.0);
    assert!(law >= 0.75, "law: {:.1} %", law * 100.0);
    assert!(
        measured >= 0.85,
        "law + measured TCP: {:.1} %",
        measured * 100.0
    );
}

/// Which of the unseen plant's effects the plain-log law misses: the same held-out check with
/// one effect taken out of the plant at a time (the robot model stays the plant's linear spring
/// chain). Measured (max error in contact, law from a plain `deflex run`-like log, no measured
/// TCP): plant 1 70.9 % → **88.5 %** without the J2/J3 coupling, 71.7 % without the wrist lost
/// motion; plant 2 78.9 % → **90.1 %** without the coupling, 90.2 % without the coupling and
/// the lost motion, and the same with the large rotations and the floor pivot of the base taken
/// out too. The gap to 85 % is the coupling (a non-diagonal joint compliance), not the
/// hardening wrist, the large rotations or the base pivot: a model class with off-diagonal
/// compliances between adjacent joints, identified from a loaded campaign, is what closes it
/// (README, "Offline compensation from a log on a plant deflex never saw").
#[test]
fn the_plain_log_gap_is_the_j2_j3_coupling() {
    let law_only = |cell: CellConfig, program: &str, name: &str| {
        let case = HeldOut::new(cell, program);
        let result = case.law(false);
        case.improvement(name, &case.run(&result), result.final_max_force_n)
    };
    let mut uncoupled = plant_1();
    uncoupled.plant.j2_j3_coupling = 0.0;
    let without_coupling = law_only(
        uncoupled,
        &circle_program(),
        "60 mm circle, plant 1 without the J2/J3 coupling, law (plain log)",
    );
    let mut no_lost_motion = plant_1();
    no_lost_motion.plant.wrist_lost_motion_rad = [0.0; 3];
    let without_lost_motion = law_only(
        no_lost_motion,
        &circle_program(),
        "60 mm circle, plant 1 without the wrist lost motion, law (plain log)",
    );
    let mut plant_2_uncoupled = plant_2();
    plant_2_uncoupled.plant.j2_j3_coupling = 0.0;
    let second = law_only(
        plant_2_uncoupled,
        &second_program(),
        "50 mm clockwise circle, plant 2 without the J2/J3 coupling, law (plain log)",
    );
    // Measured 88.5 %, 71.7 % (70.9 % with every effect), 90.1 %.
    assert!(
        without_coupling >= 0.85,
        "plant 1 without the coupling: {:.1} %",
        without_coupling * 100.0
    );
    assert!(
        second >= 0.85,
        "plant 2 without the coupling: {:.1} %",
        second * 100.0
    );
    assert!(
        without_lost_motion < 0.80,
        "plant 1 without the lost motion: {:.1} % (the hardening wrist was not the gap)",
        without_lost_motion * 100.0
    );
}

/// The stiffness identification a user makes once on their robot, SIMULATED: a loaded campaign
/// planned for the robot's nominal model (40 load cases, every eDoF family), measured on the
/// unseen plant's twin with the laser tracker (25 samples per reading), the model structure
/// searched from it (diagonal VJM), then the J2.z–J3.z off-diagonal compliance fitted with the
/// eDoF compliances by weighted least squares ([`deflex_calibrate::stiffness::fit_couplings`], what
/// `deflex calibrate --couplings J2.z:J3.z` runs; the CLI's test
/// `couplings_are_fitted_from_a_simulated_campaign` runs this plant's campaign through the
/// commands). Never from the plant's parameters. Returns the diagonal and the coupled model.
fn campaign_models(cell: &CellConfig) -> (Robot, deflex_calibrate::stiffness::CouplingFit) {
    use deflex_calibrate::stiffness::fit_couplings;
    use deflex_model::{Axis, EdofSite};
    let nominal = cell.nominal_robot().unwrap();
    let (rows, search) = super::common::careful_campaign(&nominal, cell);
    let diagonal = search.calibration.to_robot(&nominal);
    let pair = ((EdofSite::Joint(2), Axis::Z), (EdofSite::Joint(3), Axis::Z));
    let fit = fit_couplings(&diagonal, &rows, &[pair]).unwrap();
    println!(
        "SIMULATED campaign on the unseen plant: structure {}, RMS residual {:.1} µm (diagonal) → {:.1} µm with J2.z–J3.z, correlation {:.3} (plant {:.3}), χ²/dof {:.1} → {:.1}",
        search.calibration.structure.label(),
        fit.rms_before_m * 1e6,
        fit.rms_m * 1e6,
        fit.correlations[0],
        cell.plant.j2_j3_coupling,
        fit.reduced_chi2_before,
        fit.reduced_chi2,
    );
    (diagonal, fit)
}

/// The user's workflow, SIMULATED end to end: the robot model identified once from a loaded
/// campaign on the unseen plant ([`campaign_models`]), then a production run without a tracker
/// whose plain log (joint values and forces, no measured TCP) is the compensation's only
/// source. Measured (campaign seed 1): plant 1 87.3 % with the diagonal model, **89.6 %** with
/// the J2.z–J3.z coupling (correlation 0.275 found, 0.30 in the plant); plant 2 89.3 %,
/// **90.9 %** (0.177 found, 0.20 in the plant). (Before the coupling's transfer to a marker on a
/// link between the two joints was corrected, the fit found 0.15 and 0.10, and 88.7 %, 90.2 %.)
/// The campaign-identified diagonal
/// model already does much better than the plant's own spring chain (70.9 %, 78.9 %): fitted
/// to where the plant's tool actually goes under load, its stiffnesses absorb most of the
/// coupling over the workspace the campaign covers.
#[test]
fn a_plain_log_with_a_campaign_identified_model() {
    for (cell, program, name) in [
        (plant_1(), circle_program(), "60 mm circle, plant 1"),
        (
            plant_2(),
            second_program(),
            "50 mm clockwise circle, plant 2",
        ),
    ] {
        let (diagonal, fit) = campaign_models(&cell);
        assert!(fit.rms_m < fit.rms_before_m, "{fit:?}");
        // The plant's coupling is positive; the fit finds it so, and a spring (|ρ| < 1).
        assert!(
            fit.correlations[0] > 0.05 && fit.correlations[0] < 1.0,
            "{:?}",
            fit.correlations
        );
        let [diagonal, coupled] =
            [("diagonal", diagonal), ("with J2.z–J3.z", fit.robot)].map(|(model_name, model)| {
                let case = HeldOut::with_model(cell.clone(), &program, model);
                let law = case.law(false);
                case.improvement(
                    &format!("{name}, campaign-identified model {model_name}, law (plain log)"),
                    &case.run(&law),
                    law.final_max_force_n,
                )
            });
        // Measured 87.3 / 89.6 % and 89.3 / 90.9 % (the issue asks for 85 %).
        assert!(coupled >= 0.85, "{name}: {:.1} %", coupled * 100.0);
        assert!(
            coupled >= diagonal,
            "{name}: coupled {:.1} %, diagonal {:.1} %",
            coupled * 100.0,
            diagonal * 100.0
        );
    }
}
