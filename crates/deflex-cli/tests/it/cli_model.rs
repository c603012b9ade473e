//! End-to-end tests of the model commands through the real `deflex` binary.

use crate::support::{Run, deflex, json, s, scratch};
use std::path::{Path, PathBuf};

/// A two-joint URDF arm (`arm.urdf`) and its robot file (`arm.toml`, returned) in `dir`.
fn two_joint_arm(dir: &Path) -> PathBuf {
    std::fs::write(
        dir.join("arm.urdf"),
        r#"<robot name="a"><link name="b"/><link name="l1"/><link name="l2"/>
        <joint name="j1" type="revolute"><parent link="b"/><child link="l1"/><origin xyz="0 0 0.4"/><axis xyz="0 0 1"/><limit lower="-3" upper="3" effort="0" velocity="1"/></joint>
        <joint name="j2" type="revolute"><parent link="l1"/><child link="l2"/><origin xyz="0.25 0 0"/><axis xyz="0 1 0"/><limit lower="-2" upper="2" effort="0" velocity="1"/></joint></robot>"#,
    )
    .unwrap();
    let arm = dir.join("arm.toml");
    std::fs::write(
        &arm,
        "name = \"two-joint arm\"\nurdf = \"arm.urdf\"\n[[joint]]\nname = \"j1\"\n[[joint]]\nname = \"j2\"\n",
    )
    .unwrap();
    arm
}

#[test]
fn pose_json_reaches_the_paper_part_origin() {
    let v = json(&["pose", "--robot", "tx200", "--q-deg", "0,49.7,89.3,0,41,0"]);
    let tcp: Vec<f64> = serde_json::from_value(v["tcp_m"].clone()).unwrap();
    assert!(
        (tcp[0] - 1.4994).abs() < 5e-4 && tcp[1].abs() < 1e-9 && (tcp[2] + 0.1833).abs() < 5e-4
    );
    let rotation: Vec<Vec<f64>> = serde_json::from_value(v["rotation"].clone()).unwrap();
    assert!(
        (rotation[2][2] + 1.0).abs() < 1e-3,
        "tool axis down: {rotation:?}"
    );
}

#[test]
fn deflect_json_has_compliance_consistent_with_dp() {
    let v = json(&[
        "deflect",
        "--robot",
        "tx200",
        "--q-deg",
        "0,90,0,0,0,0",
        "--wrench",
        "0,1400,0,0,0,0",
    ]);
    let dp: Vec<f64> = serde_json::from_value(v["dp_m"].clone()).unwrap();
    let compliance: Vec<Vec<f64>> = serde_json::from_value(v["compliance"].clone()).unwrap();
    assert_eq!(compliance.len(), 6);
    for (r, value) in dp.iter().enumerate() {
        assert!((compliance[r][1] * 1400.0 - value).abs() < 1e-15);
    }
    assert!(
        dp[0] > 1e-4,
        "enhanced model shows the Figure 7 x-displacement"
    );
    let _: Vec<f64> = serde_json::from_value(v["dphi_rad"].clone()).unwrap();
}

#[test]
fn ik_round_trips_and_reports_unreachable() {
    let v = json(&[
        "ik",
        "--robot",
        "tx200",
        "--xyz-mm",
        "1450,80,-150",
        "--rpy-deg",
        "180,0,180",
    ]);
    let q: Vec<f64> = serde_json::from_value(v["q_rad"].clone()).unwrap();
    let q_text: Vec<String> = q.iter().map(|x| format!("{x}")).collect();
    let pose = json(&["pose", "--robot", "tx200", "--q-rad", &q_text.join(",")]);
    let tcp: Vec<f64> = serde_json::from_value(pose["tcp_m"].clone()).unwrap();
    assert!(
        (tcp[0] - 1.45).abs() < 1e-8
            && (tcp[1] - 0.08).abs() < 1e-8
            && (tcp[2] + 0.15).abs() < 1e-8
    );
    let Run { ok, stderr, .. } = deflex(&[
        "ik",
        "--robot",
        "tx200",
        "--xyz-mm",
        "5000,0,0",
        "--rpy-deg",
        "0,0,0",
    ]);
    assert!(!ok && stderr.contains("out of reach"), "{stderr}");
    // A reachable pose from a singular seed (stretched arm, straight wrist).
    let v = json(&[
        "ik",
        "--robot",
        "tx200",
        "--xyz-mm",
        "1450,80,-150",
        "--rpy-deg",
        "180,0,180",
        "--seed-deg",
        "0,0,0,0,0,0",
    ]);
    assert!(v["q_rad"].is_array(), "{v}");
}

#[test]
fn map_writes_csv_and_heatmaps_for_the_paper_grid() {
    let out = std::env::temp_dir().join(format!("deflex-cli-map-{}", std::process::id()));
    let v = json(&[
        "map",
        "--robot",
        "tx200",
        "--plane",
        "z=100mm",
        "--center",
        "1500,0",
        "--size",
        "600mm",
        "--step",
        "40mm",
        "--wrench",
        "0,0,-1100,0,0,0",
        "--out",
        out.to_str().unwrap(),
    ]);
    assert_eq!(v["nodes"], 256);
    assert_eq!(v["unreachable"], 0);
    let csv = std::fs::read_to_string(out.join("deflection_map.csv")).unwrap();
    assert!(csv.starts_with("x_m,y_m,z_m,q1_rad"));
    assert_eq!(csv.lines().count(), 257);
    for png in ["deflection_dz.png", "deflection_norm.png"] {
        let bytes = std::fs::read(out.join(png)).unwrap();
        assert_eq!(&bytes[..8], b"\x89PNG\r\n\x1a\n");
    }
}

#[test]
fn user_errors_are_clear() {
    let Run { ok, stderr, .. } = deflex(&["pose", "--robot", "tx200", "--q-deg", "0,1"]);
    assert!(
        !ok && stderr.contains("6 joints") && stderr.contains("2 joint values"),
        "{stderr}"
    );
    let Run { ok, stderr, .. } = deflex(&[
        "pose",
        "--robot",
        "no/such/robot.toml",
        "--q-deg",
        "0,0,0,0,0,0",
    ]);
    assert!(!ok && stderr.contains("no/such/robot.toml"), "{stderr}");
    let Run { ok, stderr, .. } = deflex(&[
        "deflect",
        "--robot",
        "tx200",
        "--q-deg",
        "0,0,0,0,0,0",
        "--wrench",
        "1,2,x,4,5,6",
    ]);
    assert!(
        !ok && stderr.contains("--wrench") && stderr.contains("\"x\""),
        "{stderr}"
    );
    let Run { ok, stderr, .. } = deflex(&[
        "deflect",
        "--robot",
        "tx200",
        "--q-deg",
        "0,0,0,0,0,0",
        "--wrench",
        "1,2,3",
    ]);
    assert!(!ok && stderr.contains("expected 6 values"), "{stderr}");
}

#[test]
fn model_show_prints_standard_dh_masses_and_urdf_geometry() {
    let Run {
        ok, stdout, stderr, ..
    } = deflex(&["model", "show", "--robot", "ur10"]);
    assert!(ok, "{stderr}");
    assert!(
        stdout.contains("standard DH") && stdout.contains("shoulder_pan_joint"),
        "{stdout}"
    );
    assert!(stdout.contains("12.70"), "link masses shown: {stdout}");
    let v = json(&["model", "show", "--robot", "kr210-r2700"]);
    assert_eq!(v["geometry"], "modified DH");
    assert_eq!(v["geometry_fingerprint"].as_str().unwrap().len(), 16);
    // A URDF robot shows its placements.
    let dir = scratch("model-urdf-show");
    let arm = two_joint_arm(&dir);
    let Run {
        ok, stdout, stderr, ..
    } = deflex(&["model", "show", "--robot", s(&arm)]);
    assert!(ok, "{stderr}");
    assert!(
        stdout.contains("URDF") && stdout.contains("xyz 250.0000 0.0000 0.0000 mm"),
        "{stdout}"
    );
}

#[test]
fn map_refuses_a_grid_too_fine_to_hold() {
    let out = std::env::temp_dir().join(format!("deflex-cli-map-fine-{}", std::process::id()));
    let Run { ok, stderr, .. } = deflex(&[
        "map",
        "--robot",
        "tx200",
        "--step",
        "1e-9mm",
        "--out",
        out.to_str().unwrap(),
    ]);
    assert!(
        !ok && stderr.contains("--step") && stderr.contains("nodes per side"),
        "{stderr}"
    );
    assert!(!out.exists(), "nothing written");
}

#[test]
fn pose_reports_the_sag_under_the_arms_own_weight_when_masses_are_known() {
    // UR10 stretched horizontally (q2 = 0): the gravity sag is downward and of the order of
    // m·g·L²/k over the links; the TX200 file has no masses and reports none.
    let v = json(&["pose", "--robot", "ur10", "--q-deg", "0,0,0,0,90,0"]);
    let sag: Vec<f64> = serde_json::from_value(v["gravity_sag_m"].clone()).unwrap();
    assert!(sag[2] < -1e-4 && sag[2] > -1e-2, "{sag:?}");
    let with: Vec<f64> = serde_json::from_value(v["tcp_with_gravity_m"].clone()).unwrap();
    let tcp: Vec<f64> = serde_json::from_value(v["tcp_m"].clone()).unwrap();
    assert!((with[2] - tcp[2] - sag[2]).abs() < 1e-15);
    let v = json(&["pose", "--robot", "tx200", "--q-deg", "0,0,0,0,0,0"]);
    assert!(v["gravity_sag_m"].is_null());
}

/// `model show` and `sim robot` print the robot's twin cell (issue 23), the same cell in both,
/// and the forming pose the summary computes by inverse kinematics puts the cell robot's TCP
/// (its tool included, `deflex pose` on the file `sim robot` wrote: forward kinematics) on the
/// part origin the summary prints.
#[test]
fn model_show_and_sim_robot_print_the_robots_twin_cell() {
    let Run {
        ok, stdout, stderr, ..
    } = deflex(&["model", "show", "--robot", "ur10e"]);
    assert!(ok, "{stderr}");
    for needle in [
        "twin cell of ur10e",
        "part frame origin (mm, R0 axes)",
        "--part-xyz-mm",
        "--seed-deg",
        "tool, flange → TCP (mm)",
        "sheet:",
    ] {
        assert!(stdout.contains(needle), "{needle:?} missing: {stdout}");
    }
    let shown = json(&["model", "show", "--robot", "ur10e"]);
    let cell = &shown["cell"];
    let dir = scratch("model-cell-show");
    let file = dir.join("ur10e_cell.toml");
    let sim = json(&[
        "sim",
        "robot",
        "--robot",
        "ur10e",
        "--out",
        file.to_str().unwrap(),
    ]);
    assert_eq!(
        &sim["cell"], cell,
        "sim robot and model show print one cell"
    );
    let Run {
        ok, stdout, stderr, ..
    } = deflex(&[
        "sim",
        "robot",
        "--robot",
        "ur10e",
        "--out",
        file.to_str().unwrap(),
    ]);
    assert!(
        ok && stdout.contains("twin cell of ur10e"),
        "{stdout}{stderr}"
    );

    let origin: Vec<f64> = serde_json::from_value(cell["part_origin_m"].clone()).unwrap();
    let forming: Vec<f64> = serde_json::from_value(cell["forming_q_rad"].clone()).unwrap();
    let q: Vec<String> = forming.iter().map(|v| v.to_string()).collect();
    let v = json(&[
        "pose",
        "--robot",
        file.to_str().unwrap(),
        "--q-rad",
        &q.join(","),
    ]);
    let tcp: Vec<f64> = serde_json::from_value(v["tcp_m"].clone()).unwrap();
    for i in 0..3 {
        assert!((tcp[i] - origin[i]).abs() < 1e-6, "{tcp:?} vs {origin:?}");
    }
    // The tool the cell prints is the tool of the robot file it writes.
    let tool: Vec<f64> = serde_json::from_value(cell["tool_xyz_m"].clone()).unwrap();
    let written: Vec<f64> = serde_json::from_value(sim["tool_xyz_m"].clone()).unwrap();
    assert_eq!(tool, written);

    // A robot no cell is built around says so and still shows its model.
    let arm = two_joint_arm(&dir);
    let Run {
        ok, stdout, stderr, ..
    } = deflex(&["model", "show", "--robot", arm.to_str().unwrap()]);
    assert!(
        ok && stdout.contains("twin cell: none ("),
        "{stdout}{stderr}"
    );
    let _ = std::fs::remove_dir_all(&dir);
}

/// `model fk` (issue 35: a controller's joint log checked with deflex's kinematics): the q
/// columns of a compensated_path.csv give back its commanded points; degrees read as `pose`.
#[test]
fn model_fk_reads_a_compensated_path_and_a_joint_log_in_degrees() {
    let dir = scratch("model-fk");
    let out = dir.join("run");
    let Run { ok, stderr, .. } = deflex(&[
        "compensate",
        "--robot",
        "ur10",
        "--path",
        "cone-contour",
        "--length-mm",
        "20",
        "--format",
        "none",
        "--out",
        s(&out),
    ]);
    assert!(ok, "{stderr}");
    let path = out.join("compensated_path.csv");
    let fk = dir.join("fk.csv");
    // The UR10 with its cell's 150 mm tool, the one compensate used.
    let cell_robot = dir.join("ur10_cell.toml");
    let Run { ok, stderr, .. } =
        deflex(&["sim", "robot", "--robot", "ur10", "--out", s(&cell_robot)]);
    assert!(ok, "{stderr}");
    let Run {
        ok, stdout, stderr, ..
    } = deflex(&[
        "model",
        "fk",
        "--robot",
        s(&cell_robot),
        "--joints",
        s(&path),
        "--out",
        s(&fk),
    ]);
    assert!(
        ok && stdout.contains("pose(s)") && stdout.contains("(0.0000, 0.0000, 150.0000) mm"),
        "{stdout} {stderr}"
    );
    let text = std::fs::read_to_string(&path).unwrap();
    let mut lines = text.lines().filter(|l| !l.starts_with('#'));
    let header: Vec<&str> = lines.next().unwrap().split(',').collect();
    let col = |name: &str| header.iter().position(|h| *h == name).unwrap();
    let rows: Vec<Vec<&str>> = lines.map(|l| l.split(',').collect()).collect();
    let poses = std::fs::read_to_string(&fk).unwrap();
    let poses: Vec<Vec<f64>> = poses
        .lines()
        .skip(1)
        .map(|l| l.split(',').map(|v| v.parse().unwrap()).collect())
        .collect();
    assert_eq!(poses.len(), rows.len());
    for (row, pose) in rows.iter().zip(&poses) {
        for (k, c) in ["cx_m", "cy_m", "cz_m"].iter().enumerate() {
            let want: f64 = row[col(c)].parse().unwrap();
            assert!(
                (pose[k + 1] - want).abs() < 2e-9,
                "{c}: {} vs {want}",
                pose[k + 1]
            );
        }
    }
    // A joint log in degrees (other columns ignored), to standard output.
    let log = dir.join("log.csv");
    std::fs::write(
        &log,
        "sample,q1_deg,q2_deg,q3_deg,q4_deg,q5_deg,q6_deg,line\n3,10,-50,80,20,90,0,7\n",
    )
    .unwrap();
    let Run { ok, stdout, .. } = deflex(&["model", "fk", "--robot", "ur10", "--joints", s(&log)]);
    assert!(ok);
    let v = json(&["pose", "--robot", "ur10", "--q-deg", "10,-50,80,20,90,0"]);
    let tcp: Vec<f64> = serde_json::from_value(v["tcp_m"].clone()).unwrap();
    let got: Vec<f64> = stdout
        .lines()
        .nth(1)
        .unwrap()
        .split(',')
        .skip(1)
        .map(|v| v.parse().unwrap())
        .collect();
    assert!(
        (0..3).all(|k| (got[k] - tcp[k]).abs() < 1e-9),
        "{got:?} vs {tcp:?}"
    );
    // A log without the robot's joint columns is refused, naming what is missing.
    std::fs::write(&log, "sample,q1_deg\n0,1\n").unwrap();
    let Run { ok, stderr, .. } = deflex(&["model", "fk", "--robot", "ur10", "--joints", s(&log)]);
    assert!(!ok && stderr.contains("q2_deg is missing"), "{stderr}");
}
