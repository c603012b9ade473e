//! End-to-end tests of `deflex sim` and `deflex demo` through the real binary: the twin plays
//! the robot it is given and says so in every output, and bad input (issue 12) gets a clear error
//! naming the option or field, with nothing written or overwritten.

use crate::support::{Run, deflex, scratch};
use std::path::Path;

/// `args` fail with an error that mentions `needle`, and the output `out` keeps its old content.
fn refused(args: &[&str], needle: &str, out: &Path) {
    let Run {
        ok, stdout, stderr, ..
    } = deflex(args);
    assert!(!ok, "deflex {args:?} should fail; stdout: {stdout}");
    assert!(
        stderr.contains(needle),
        "deflex {args:?}: the error should name {needle:?}: {stderr}"
    );
    assert!(!stderr.contains("panicked"), "{stderr}");
    if out.is_file() {
        assert_eq!(
            std::fs::read_to_string(out).unwrap(),
            "old",
            "{} overwritten",
            out.display()
        );
    } else if out.is_dir() {
        assert_eq!(
            std::fs::read_to_string(out.join("keep.txt")).unwrap(),
            "old",
            "{} replaced",
            out.display()
        );
    }
}

/// Flags a command refuses, and what its error must name.
type Refusal<'a> = (&'a [&'a str], &'a str);

#[test]
fn every_numeric_option_of_sim_is_checked() {
    let dir = scratch("sim-flags");
    let out = dir.join("run");
    std::fs::create_dir_all(&out).unwrap();
    std::fs::write(out.join("keep.txt"), "old").unwrap();
    // An earlier deflex output folder (a foreign one is refused whole, before the flags).
    std::fs::write(out.join(".deflex-output"), "").unwrap();
    let csv = dir.join("meas.csv");
    std::fs::write(&csv, "old").unwrap();
    // Each command with the output it must not touch, and its flags with what the error must
    // name.
    let commands: [(&[&str], &Path, &[Refusal]); 4] = [
        (
            &["sim", "isf"],
            &out,
            &[
                // Issue 12: a 180 TB allocation before.
                (&["--feed-mm-s", "1e-9"], "--feed-mm-s"),
                (&["--feed-mm-s", "nan"], "--feed-mm-s"),
                (&["--feed-mm-s", "1e300"], "--feed-mm-s"),
                (&["--length-mm", "nan"], "--length-mm"),
                (&["--length-mm=-5"], "--length-mm"),
                (&["--length-mm", "inf"], "--length-mm"),
                (
                    &["--path", "plunge", "--fixture-stiffness-n-m", "1e20"],
                    "--fixture-stiffness-n-m",
                ),
                (
                    &["--path", "plunge", "--fixture-stiffness-n-m", "nan"],
                    "--fixture-stiffness-n-m",
                ),
                (&["--robot", "no-such-robot"], "no-such-robot"),
            ],
        ),
        (
            &["sim", "campaign"],
            &csv,
            &[
                (&["--grid", "--grid-step-m", "1e-9"], "--grid-step-m"),
                (&["--grid", "--grid-step-m", "nan"], "--grid-step-m"),
                (&["--grid", "--grid-loads-n", "nan"], "--grid-loads-n"),
                (&["--grid", "--grid-loads-n", "1e9"], "grid loads"),
                (&["--grid", "--grid-size-m", "0"], "--grid-size-m"),
                (&["--grid", "--grid-height-m", "inf"], "--grid-height-m"),
                (&["--grid", "--grid-center-m", "1,nan"], "--grid-center-m"),
                (
                    &["--spiral", "--spiral-length-m", "1e9"],
                    "--spiral-length-m",
                ),
                (
                    &["--spiral", "--spiral-speed-m-s", "0"],
                    "--spiral-speed-m-s",
                ),
                (
                    &["--spiral", "--spiral-radius-m", "nan"],
                    "--spiral-radius-m",
                ),
                (&["--spiral", "--spiral-load-n=-1"], "--spiral-load-n"),
                (&["--spiral", "--spiral-pitch-m", "1e9"], "--spiral-pitch-m"),
                (
                    &["--spiral", "--spiral-center-m", "1,2"],
                    "--spiral-center-m",
                ),
                (&["--grid-step-m", "0.1"], "need --grid"),
            ],
        ),
        (
            &["sim", "sensitivity"],
            &out,
            &[
                (&["--delays-ms", "nan"], "--delays-ms"),
                (&["--delays-ms", "8,1e9"], "--delays-ms"),
                (&["--model-scales", "0"], "--model-scales"),
                (&["--gain-errors-percent", "500"], "--gain-errors"),
                (&["--drift-factors=-1"], "--drift-factors"),
                (&["--contact-stiffness-n-m", "1"], "--contact-stiffness-n-m"),
                (&["--threads", "0"], "--threads"),
                (&["--length-mm", "nan"], "--length-mm"),
            ],
        ),
        (
            &["demo"],
            &out,
            &[(&["--robot", "no-such-robot"], "no-such-robot")],
        ),
    ];
    for (command, target, cases) in commands {
        for (flags, needle) in cases {
            let mut args = command.to_vec();
            args.extend_from_slice(flags);
            args.extend_from_slice(&["--out", target.to_str().unwrap()]);
            refused(&args, needle, target);
        }
    }
    let _ = std::fs::remove_dir_all(&dir);
}

#[test]
fn bad_twin_files_and_gcode_name_the_field_or_line() {
    let dir = scratch("sim-files");
    let out = dir.join("run");
    std::fs::create_dir_all(&out).unwrap();
    std::fs::write(out.join("keep.txt"), "old").unwrap();
    // An earlier deflex output folder (a foreign one is refused whole, before the flags).
    std::fs::write(out.join(".deflex-output"), "").unwrap();
    let o = out.to_str().unwrap();
    let cases = [
        ("[cell.controller]\nrate_hz = 1e300\n", "controller.rate_hz"),
        (
            "[cell.tracker]\nsamples_per_reading = 1000000000000\n",
            "samples_per_reading",
        ),
        (
            "[cell.sensor]\nbias = [nan, 0.0, 0.0, 0.0, 0.0, 0.0]\n",
            "sensor.bias[0]",
        ),
        (
            "[cell.sensor]\nsensor_in_flange_xyz_m = [0.0, 0.0, nan]\n",
            "sensor.sensor_in_flange_xyz_m[2]",
        ),
        (
            "[cell.tracker]\nposition_m = [2.8, nan, 0.3]\n",
            "tracker.position_m[1]",
        ),
        ("[cell.log]\nrate_hz = 1e12\n", "log.rate_hz"),
    ];
    for (i, (text, field)) in cases.iter().enumerate() {
        let twin = dir.join(format!("twin{i}.toml"));
        std::fs::write(&twin, text).unwrap();
        let t = twin.to_str().unwrap();
        refused(&["sim", "isf", "--config", t, "--out", o], field, &out);
        // `sim campaign` writes a file (a folder given for it is refused before the settings).
        let csv = dir.join("campaign.csv");
        std::fs::write(&csv, "old").unwrap();
        refused(
            &[
                "sim",
                "campaign",
                "--spiral",
                "--config",
                t,
                "--out",
                csv.to_str().unwrap(),
            ],
            field,
            &csv,
        );
    }
    // Issue 12: a feed of 1e-42 (out of memory after 39 s before), in the decimal form G-code has.
    let gcode = dir.join("slow.nc");
    std::fs::write(
        &gcode,
        "G21 G90\nG0 X20 Y0 Z1\nG1 Z0 F0.000000000000000000000000000000000000000001\nG1 X0 Y20\n",
    )
    .unwrap();
    let g = gcode.to_str().unwrap();
    refused(&["sim", "isf", "--path", g, "--out", o], "slow.nc:3", &out);
    std::fs::write(&gcode, "G21 G90\nG0 X20 Y0 Z1\nG1 Z0 F1e-42\n").unwrap();
    refused(&["sim", "isf", "--path", g, "--out", o], "slow.nc:3", &out);
    // A legal but very slow feed: the run (22 000 s) would take longer than the twin's 4 h.
    std::fs::write(&gcode, "G21 G90\nG0 X20 Y0 Z1\nG1 Z0 F0.6\nG1 X-200 F0.6\n").unwrap();
    refused(&["sim", "isf", "--path", g, "--out", o], "at most", &out);
    let _ = std::fs::remove_dir_all(&dir);
}

#[test]
fn the_twin_plays_the_robot_it_is_given_and_names_it() {
    let dir = scratch("sim-robot");
    let csv = dir.join("grid.csv");
    let Run {
        ok, stdout, stderr, ..
    } = deflex(&[
        "sim",
        "campaign",
        "--robot",
        "ur10e",
        "--grid",
        "--grid-step-m",
        "0.1",
        "--out",
        csv.to_str().unwrap(),
    ]);
    assert!(ok, "{stderr}");
    assert!(stdout.contains("UR10e"), "{stdout}");
    let text = std::fs::read_to_string(&csv).unwrap();
    let header: Vec<&str> = text.lines().take(3).collect();
    assert!(header[0].starts_with("# SIMULATED"), "{header:?}");
    assert!(
        header[1].starts_with("# robot: ") && header[1].contains("UR10e"),
        "{header:?}"
    );
    // The fingerprint of the robot the twin played, its cell's tool included.
    let fingerprint = header[2].strip_prefix("# geometry: ").unwrap();
    assert!(
        fingerprint.len() == 16 && fingerprint.chars().all(|c| c.is_ascii_hexdigit()),
        "{header:?}"
    );
    // The UR cell's grid: loads sized to its forming force (≈ 0.5 and 0.9 × 170 N), not 600 N.
    assert!(!text.contains("grid600N"), "the TX200's loads on a UR10e");
    let out = dir.join("run");
    let Run {
        ok, stdout, stderr, ..
    } = deflex(&[
        "--json",
        "sim",
        "isf",
        "--robot",
        "ur10e",
        "--length-mm",
        "40",
        "--out",
        out.to_str().unwrap(),
    ]);
    assert!(ok, "{stderr}");
    let v: serde_json::Value = serde_json::from_str(&stdout).unwrap();
    assert_eq!(v["simulated"], true);
    assert!(v["robot"].as_str().unwrap().contains("UR10e"), "{v}");
    assert_eq!(v["robot_spec"], "ur10e");
    let log = std::fs::read_to_string(out.join("log.csv")).unwrap();
    assert!(log.lines().next().unwrap().contains("UR10e"));
    // The plunge into a fixture, open loop.
    let Run {
        ok, stdout, stderr, ..
    } = deflex(&[
        "sim",
        "isf",
        "--path",
        "plunge",
        "--fixture-stiffness-n-m",
        "1e6",
        "--out",
        out.to_str().unwrap(),
    ]);
    assert!(ok, "{stderr}");
    assert!(stdout.contains("fixture"), "{stdout}");
    let _ = std::fs::remove_dir_all(&dir);
}

/// A campaign measured from a plan names the robot the plan was made for (its coordinates are
/// the plan's), so `calibrate --robot` with that robot sees no fingerprint mismatch.
#[test]
fn a_campaign_from_a_plan_carries_the_plans_robot_lines() {
    let dir = scratch("sim-plan-header");
    let plan = dir.join("plan.csv");
    let meas = dir.join("meas.csv");
    let Run { ok, stderr, .. } = deflex(&[
        "plan",
        "--robot",
        "ur10e",
        "--load-cases",
        "6",
        "--out",
        plan.to_str().unwrap(),
    ]);
    assert!(ok, "{stderr}");
    let Run { ok, stderr, .. } = deflex(&[
        "sim",
        "campaign",
        "--robot",
        "ur10e",
        "--plan",
        plan.to_str().unwrap(),
        "--out",
        meas.to_str().unwrap(),
    ]);
    assert!(ok, "{stderr}");
    let text = std::fs::read_to_string(&meas).unwrap();
    let fingerprint = deflex_model::builtin("ur10e")
        .unwrap()
        .geometry_fingerprint();
    assert!(
        text.contains(&format!("# geometry: {fingerprint}\n")),
        "{}",
        &text[..400]
    );
    assert!(text.starts_with("# SIMULATED"));
}

/// `sim isf` records its run in MCAP beside its log and writes its `deflex plot` page (unless
/// `--no-plot`); `deflex plot` on the open- and closed-loop logs overlays them on path position
/// (issue 21's acceptance), and reads the recordings too.
#[test]
fn sim_isf_records_and_plots_and_two_runs_overlay() {
    let dir = scratch("sim-record");
    let (open, closed, model) = (dir.join("open"), dir.join("closed"), dir.join("robot.toml"));
    let Run {
        ok, stdout, stderr, ..
    } = deflex(&[
        "--json",
        "sim",
        "isf",
        "--length-mm",
        "150",
        "--out",
        open.to_str().unwrap(),
    ]);
    assert!(ok, "{stderr}");
    let v: serde_json::Value = serde_json::from_str(&stdout).unwrap();
    assert_eq!(v["mcap"]["source"], "twin-cell", "{v}");
    let mcap = std::fs::read(open.join("run.mcap")).unwrap();
    assert!(mcap.starts_with(b"\x89MCAP0\r\n"));
    let page = std::fs::read_to_string(open.join("plot/index.html")).unwrap();
    assert!(page.contains("SIMULATED"));
    let Run { ok, stderr, .. } = deflex(&["sim", "robot", "--out", model.to_str().unwrap()]);
    assert!(ok, "{stderr}");
    let Run {
        ok, stdout, stderr, ..
    } = deflex(&[
        "sim",
        "isf",
        "--length-mm",
        "150",
        "--correction",
        "on",
        "--model",
        model.to_str().unwrap(),
        "--no-plot",
        "--out",
        closed.to_str().unwrap(),
    ]);
    assert!(ok, "{stderr}");
    assert!(
        stdout.contains("recording:") && stdout.contains("path error"),
        "{stdout}"
    );
    assert!(closed.join("run.mcap").is_file() && !closed.join("plot").exists());

    let plots = dir.join("plots");
    let Run {
        ok, stdout, stderr, ..
    } = deflex(&[
        "--json",
        "plot",
        open.join("log.csv").to_str().unwrap(),
        closed.join("log.csv").to_str().unwrap(),
        "--labels",
        "open loop,closed loop",
        "--out",
        plots.to_str().unwrap(),
    ]);
    assert!(ok, "{stderr}");
    let v: serde_json::Value = serde_json::from_str(&stdout).unwrap();
    assert_eq!(v["by_path_position"], true, "{v}");
    for f in [
        "forces.png",
        "correction.png",
        "path_error.png",
        "index.html",
    ] {
        assert!(plots.join(f).is_file(), "{f}");
    }
    let html = std::fs::read_to_string(plots.join("index.html")).unwrap();
    assert!(html.contains("open loop vs closed loop"), "overlaid page");
    // The recordings plot as well (the controller's stream and the twin's own).
    let Run { ok, stderr, .. } = deflex(&[
        "plot",
        closed.join("run.mcap").to_str().unwrap(),
        open.join("run.mcap").to_str().unwrap(),
        "--out",
        dir.join("from-mcap").to_str().unwrap(),
    ]);
    assert!(ok, "{stderr}");
    assert!(dir.join("from-mcap/path_error.png").is_file());

    // `--speed` is for watching; a bad `--view` address is named.
    let o = dir.join("never");
    refused(
        &["sim", "isf", "--speed", "5", "--out", o.to_str().unwrap()],
        "--view",
        &o,
    );
    refused(
        &[
            "sim",
            "isf",
            "--view",
            "nowhere:x",
            "--out",
            o.to_str().unwrap(),
        ],
        "--view",
        &o,
    );
    assert!(!o.exists());
    let _ = std::fs::remove_dir_all(&dir);
}
