//! Tests of `CELL.toml` parsing and validation ([`deflex_app::cell::config`]).

use deflex_app::cell::config::*;
use deflex_control::{FeedForwardMode, PathIndex, PidGains};
use std::path::PathBuf;

const MINIMAL: &str = r#"
[robot]
kind = "kuka-rsi"
bind = "127.0.0.1:59152"
[sensor]
kind = "netft"
address = "127.0.0.1:49152"
[model]
file = "tx200"
"#;

/// `text` parsed as `cell.toml`.
fn parse(text: &str) -> Result<CellFile, ConfigError> {
    CellFile::parse(text, "cell.toml", PathBuf::new())
}

/// `parsed` (a valid file with `case` added or changed) is refused, naming the file and `field`.
fn refused_naming<T>(parsed: Result<T, ConfigError>, case: &str, field: &str) {
    let e = parsed
        .err()
        .unwrap_or_else(|| panic!("accepted: {case}"))
        .to_string();
    assert!(e.contains("cell.toml") && e.contains(field), "{case} → {e}");
}

#[test]
fn minimal_file_gets_paper_defaults() {
    let cell = parse(MINIMAL).unwrap();
    let c = cell.controller_config();
    assert_eq!(c.period_s, 0.01);
    assert_eq!(c.gains, PidGains::default());
    assert_eq!(c.limiter.enabled, [true; 6]);
    assert_eq!(cell.model_spec(), "tx200");
}

#[test]
fn the_documented_example_parses() {
    let text = include_str!("../../../../../docs/cell.example.toml");
    let cell = CellFile::parse(text, "cell.example.toml", PathBuf::new()).unwrap();
    assert_eq!(cell.robot.kind, RobotKind::KukaRsi);
}

#[test]
fn errors_name_file_and_field() {
    let bad = format!("{MINIMAL}[limits]\nsafe_action = \"explode\"\n");
    let e = parse(&bad).unwrap_err().to_string();
    assert!(
        e.contains("cell.toml") && e.contains("limits.safe_action"),
        "{e}"
    );
    let typo = format!("{MINIMAL}[control]\nkp = 1.0\n");
    let e = parse(&typo).unwrap_err().to_string();
    assert!(e.contains("cell.toml") && e.contains("kp"), "{e}");
    let axes = format!("{MINIMAL}[control]\naxes = [\"x\", \"w\"]\n");
    let e = parse(&axes).unwrap_err().to_string();
    assert!(e.contains("control.axes") && e.contains("\"w\""), "{e}");
    let e = parse(&MINIMAL.replace("kuka-rsi", "fanuc"))
        .unwrap_err()
        .to_string();
    assert!(e.contains("cell.toml") && e.contains("fanuc"), "{e}");
}

/// Every numeric field has a bound; absurd values are refused with the field named.
#[test]
fn every_number_is_bounded_and_named() {
    let cases = [
        ("[control]\nrate_hz = 1e-300\n", "control.rate_hz"),
        ("[control]\nrate_hz = 0.001\n", "control.rate_hz"),
        ("[control]\nrate_hz = 1e300\n", "control.rate_hz"),
        ("[control]\nrate_hz = nan\n", "control.rate_hz"),
        ("[control]\nkc = inf\n", "control.kc"),
        (
            "[log]\npath = \"x.csv\"\nring_capacity = 2000000000000000000\n",
            "log.ring_capacity",
        ),
        (
            "[log]\npath = \"x.csv\"\nring_capacity = 2e18\n",
            "ring_capacity",
        ),
        ("[limits]\nramp_out_s = 1e9\n", "limits.ramp_out_s"),
        (
            "[limits]\nmax_correction_m = 5.0\n",
            "limits.max_correction_m",
        ),
        ("[limits]\nmax_force_n = 0.0\n", "limits.max_force_n"),
        (
            "[limits]\nrunaway_gain_limit = 0.2\nrunaway_release_gain = 0.3\n",
            "limits.runaway_release_gain",
        ),
        (
            "[limits]\nrunaway_action = \"panic\"\n",
            "limits.runaway_action",
        ),
        ("[mounting]\ntare_s = 1e12\n", "mounting.tare_s"),
        (
            "[mounting]\nsensor_xyz_m = [0.0, 0.0, 1e300]\n",
            "mounting.sensor_xyz_m[2]",
        ),
        ("[mounting]\nlowpass_hz = 1e-9\n", "mounting.lowpass_hz"),
        (
            "[model_check]\nposition_tolerance_m = 5.0\n",
            "model_check.position_tolerance_m",
        ),
        (
            "[model_check]\norientation_tolerance_rad = 0.0\n",
            "model_check.orientation_tolerance_rad",
        ),
        (
            "[mounting]\nbias = [0.0, 0.0, nan, 0.0, 0.0, 0.0]\n",
            "mounting.bias[2]",
        ),
    ];
    for (extra, field) in cases {
        refused_naming(parse(&format!("{MINIMAL}{extra}")), extra, field);
    }
    for (robot_extra, field) in [
        ("cycle_s = 1e300\n", "robot.cycle_s"),
        ("cycle_s = 0.0\n", "robot.cycle_s"),
        ("timeout_s = nan\n", "robot.timeout_s"),
        ("cycle_s = 0.012\ntimeout_s = 0.004\n", "robot.timeout_s"),
        ("egm_frame = \"flange\"\n", "robot.egm_frame"),
        ("rsi_answer = \"both\"\n", "robot.rsi_answer"),
        ("rsi_joint_tag = \"AX\"\n", "robot.rsi_joint_tag"),
        ("sen_type = \"Im Free\"\n", "robot.sen_type"),
    ] {
        let text = MINIMAL.replace(
            "bind = \"127.0.0.1:59152\"\n",
            &format!("bind = \"127.0.0.1:59152\"\n{robot_extra}"),
        );
        refused_naming(parse(&text), robot_extra, field);
    }
    // The documented example stays inside every bound it states.
    for (field, lo, hi, _) in BOUNDS {
        assert!(lo < hi, "{field}");
    }
}

/// `[model_check]`: on by default at 5 mm and 10 mrad; the file's tolerances reach the
/// controller.
#[test]
fn the_model_check_follows_the_file() {
    let default = parse(MINIMAL).unwrap().controller_config().model_check;
    assert_eq!(default, deflex_control::ModelCheckConfig::default());
    assert!(default.enabled);
    assert_eq!(
        (
            default.position_tolerance_m,
            default.orientation_tolerance_rad
        ),
        (0.005, 0.01)
    );
    let text = format!(
        "{MINIMAL}[model_check]\nenabled = false\nposition_tolerance_m = 0.002\n\
         orientation_tolerance_rad = 0.004\n"
    );
    let c = parse(&text).unwrap().controller_config().model_check;
    assert!(!c.enabled);
    assert_eq!(
        (c.position_tolerance_m, c.orientation_tolerance_rad),
        (0.002, 0.004)
    );
}

#[test]
fn link_settings_follow_the_file() {
    let text = MINIMAL.replace(
        "bind = \"127.0.0.1:59152\"\n",
        "bind = \"127.0.0.1:0\"\nrsi_answer = \"joint\"\nrsi_joint_tag = \"AKorr\"\n\
         egm_frame = \"work-object\"\negm_work_object_rpy_rad = [0.0, 0.0, 1.5707963267948966]\n",
    );
    let cell = parse(&text).unwrap();
    assert_eq!(
        cell.rsi_config().answer,
        deflex_io::rsi::RsiAnswer::Joint(deflex_io::rsi::JointTag::AKorr)
    );
    let egm = cell.egm_config(7);
    assert!(egm.seven_axis);
    assert_eq!(egm.frame, deflex_io::egm::EgmFrame::WorkObject);
    // Yaw 90°: the work object's x is the base's y.
    assert!((egm.work_object_in_base[(1, 0)] - 1.0).abs() < 1e-12);
    assert!(cell.open_robot_link(6).unwrap().answers_in_joint_space());
}

/// A compensated-path table (the columns `deflex compensate` writes), `rows` rows along x.
fn table_text(rows: usize, status_of_row_2: &str) -> String {
    let mut t = String::from(
        "# SIMULATED\nindex,s_m,t_s,x_m,y_m,z_m,rx_rad,ry_rad,rz_rad,dx_m,dy_m,dz_m,drx_rad,dry_rad,\
         drz_rad,fx_N,fy_N,fz_N,mx_Nm,my_Nm,mz_Nm,defl_x_m,defl_y_m,defl_z_m,defl_rx_rad,\
         defl_ry_rad,defl_rz_rad,status\n",
    );
    for i in 0..rows {
        let s = i as f64 * 1e-3;
        let status = if i == 2 { status_of_row_2 } else { "ok" };
        t.push_str(&format!(
            "{i},{s},{},{},0,-0.18,0,0,0,0,0,-1e-4,0,0,0,0,0,100,0,0,0,0,0,1e-4,0,0,0,{status}\n",
            s / 0.01,
            1.5 + s
        ));
    }
    t
}

#[test]
fn feedforward_section_reads_its_table() {
    let dir = std::env::temp_dir().join(format!("deflex-ff-config-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    std::fs::write(dir.join("good.csv"), table_text(5, "ok")).unwrap();
    std::fs::write(
        dir.join("failed.csv"),
        table_text(5, "compensated:out_of_reach"),
    )
    .unwrap();
    let robot = deflex_model::builtin("tx200").unwrap();
    let with = |extra: &str| {
        CellFile::parse(
            &format!("{MINIMAL}[feedforward]\n{extra}"),
            "cell.toml",
            dir.clone(),
        )
    };
    let cell = with("table = \"good.csv\"\nmode = \"precompensated\"\nindex = \"time\"\n").unwrap();
    let ff = cell.feedforward(&robot).unwrap().unwrap();
    assert_eq!(ff.table().len(), 5);
    assert!((ff.table().length_m() - 0.004).abs() < 1e-12);
    let c = ff.config();
    assert_eq!(
        (c.mode, c.index),
        (FeedForwardMode::Precompensated, PathIndex::Time)
    );
    assert_eq!(c.window_m, 0.005);
    // Without the section: none.
    let plain = CellFile::parse(MINIMAL, "cell.toml", dir.clone()).unwrap();
    assert!(plain.feedforward(&robot).unwrap().is_none());
    // Failed points, a missing file: the file and the line or the field named.
    let e = with("table = \"failed.csv\"\n")
        .unwrap()
        .feedforward(&robot)
        .unwrap_err()
        .to_string();
    assert!(
        e.contains("feedforward.table") && e.contains("failed.csv:5") && e.contains("out_of_reach"),
        "{e}"
    );
    let e = with("table = \"missing.csv\"\n")
        .unwrap()
        .feedforward(&robot)
        .unwrap_err()
        .to_string();
    assert!(e.contains("missing.csv"), "{e}");
    for (extra, field) in [
        (
            "table = \"good.csv\"\nmode = \"twice\"\n",
            "feedforward.mode",
        ),
        (
            "table = \"good.csv\"\nindex = \"angle\"\n",
            "feedforward.index",
        ),
        ("table = \"good.csv\"\nlead_s = 5.0\n", "feedforward.lead_s"),
        ("table = \"good.csv\"\nlead_s = nan\n", "feedforward.lead_s"),
        (
            "table = \"good.csv\"\nmax_offset_m = 0.0\n",
            "feedforward.max_offset_m",
        ),
        (
            "table = \"good.csv\"\nwindow_m = 1e9\n",
            "feedforward.window_m",
        ),
        (
            "table = \"good.csv\"\ntime_offset_s = -1.0\n",
            "feedforward.time_offset_s",
        ),
        (
            "table = \"good.csv\"\nmode = \"precompensated\"\nlead_s = 0.02\n",
            "feedforward.lead_s",
        ),
        ("table = \" \"\n", "feedforward.table"),
        ("mode = \"feed-forward\"\n", "table"),
    ] {
        refused_naming(with(extra), extra, field);
    }
    let _ = std::fs::remove_dir_all(&dir);
}

/// docs/cell.example.toml documents every key of every section (read from the sections'
/// struct definitions, so a new key without documentation fails here).
#[test]
fn the_example_documents_every_key() {
    let source = include_str!("../../../src/cell/config/sections.rs");
    let example = include_str!("../../../../../docs/cell.example.toml");
    let mut in_section = false;
    let mut checked = 0;
    for line in source.lines() {
        if line.starts_with("pub struct ") && line.contains("Section") {
            in_section = true;
        } else if line.starts_with('}') {
            in_section = false;
        } else if in_section
            && let Some(rest) = line.trim().strip_prefix("pub ")
            && let Some((name, _)) = rest.split_once(':')
        {
            let documented = example
                .lines()
                .any(|l| l.trim_start_matches("# ").starts_with(&format!("{name} =")));
            assert!(
                documented,
                "docs/cell.example.toml does not document `{name}`"
            );
            checked += 1;
        }
    }
    assert!(checked > 40, "{checked}");
}

/// Issue 18, item 10: a network `bind` without `peer` is refused unless `allow_any_peer`; an
/// unspecified peer is refused; both name the field. A loopback bind without a peer is served
/// with a warning.
#[test]
fn robot_peer_rules_name_the_field() {
    let network = MINIMAL.replace("127.0.0.1:59152", "0.0.0.0:59152");
    let e = parse(&network).unwrap_err().to_string();
    assert!(
        e.contains("cell.toml") && e.contains("robot.bind") && e.contains("allow_any_peer"),
        "{e}"
    );
    let allowed = network.replace(
        "bind = \"0.0.0.0:59152\"",
        "bind = \"0.0.0.0:59152\"\nallow_any_peer = true",
    );
    let cell = parse(&allowed).unwrap();
    assert!(cell.peer_policy().unwrap().warning().is_some());
    let unspecified = network.replace(
        "bind = \"0.0.0.0:59152\"",
        "bind = \"0.0.0.0:59152\"\npeer = \"0.0.0.0:0\"",
    );
    let e = parse(&unspecified).unwrap_err().to_string();
    assert!(e.contains("robot.peer") && e.contains("unspecified"), "{e}");
    let locked = network.replace(
        "bind = \"0.0.0.0:59152\"",
        "bind = \"0.0.0.0:59152\"\npeer = \"192.168.1.147:0\"",
    );
    let cell = parse(&locked).unwrap();
    assert!(cell.peer_policy().unwrap().warning().is_none());
    let cell = parse(MINIMAL).unwrap();
    assert!(cell.peer_policy().unwrap().warning().is_some());
}

/// `[ros2]` and `sensor.kind = "ros2"`: no address needed, the section required, every field
/// checked and named.
#[test]
fn ros2_section_and_sensor() {
    let ros2 = "[robot]\nkind = \"kuka-rsi\"\nbind = \"127.0.0.1:59152\"\n[sensor]\nkind = \"ros2\"\n\
                topic = \"/ati/wrench\"\n[model]\nfile = \"tx200\"\n";
    let e = parse(ros2).unwrap_err().to_string();
    assert!(e.contains("sensor.kind") && e.contains("[ros2]"), "{e}");
    let with = |extra: &str| parse(&format!("{ros2}[ros2]\n{extra}"));
    let cell = with("").unwrap();
    assert_eq!(cell.sensor.kind, SensorKind::Ros2);
    let r = cell.ros2.as_ref().unwrap();
    assert_eq!(
        (r.domain_id, r.namespace.as_str(), r.qos),
        (0, "/deflex", Ros2Qos::SensorData)
    );
    assert_eq!(r.topics, Ros2Topic::ALL.to_vec());
    let cell = with("topics = [\"joint_states\", \"diagnostics\"]\nqos = \"reliable\"\n").unwrap();
    assert_eq!(
        cell.ros2.unwrap().topics,
        vec![Ros2Topic::JointStates, Ros2Topic::Diagnostics]
    );
    for (extra, field) in [
        ("domain_id = 233\n", "ros2.domain_id"),
        ("namespace = \"deflex\"\n", "ros2.namespace"),
        ("namespace = \"/a//b\"\n", "ros2.namespace"),
        ("namespace = \"/1a\"\n", "ros2.namespace"),
        ("node_name = \"a/b\"\n", "ros2.node_name"),
        ("qos = \"fast\"\n", "ros2.qos"),
        ("depth = 0\n", "ros2.depth"),
        ("publish_rate_hz = 200.0\n", "ros2.publish_rate_hz"),
        ("publish_rate_hz = nan\n", "ros2.publish_rate_hz"),
        ("diagnostics_rate_hz = 0.0\n", "ros2.diagnostics_rate_hz"),
        ("topics = [\"wrenches\"]\n", "ros2.topics"),
        ("sensor_frame = \"\"\n", "ros2.sensor_frame"),
        ("base_frame = \"base link\"\n", "ros2.base_frame"),
        ("colour = 1\n", "colour"),
    ] {
        refused_naming(with(extra), extra, field);
    }
    for (sensor, field) in [
        ("topic = \"ati/wrench\"", "sensor.topic"),
        ("max_age_s = 0.0", "sensor.max_age_s"),
        ("queue_depth = 100000", "sensor.queue_depth"),
    ] {
        let text = format!(
            "{}[ros2]\n",
            ros2.replace("topic = \"/ati/wrench\"", sensor)
        );
        refused_naming(parse(&text), sensor, field);
    }
    // A Net F/T still needs its address.
    let e = parse(&MINIMAL.replace("address = \"127.0.0.1:49152\"\n", ""))
        .unwrap_err()
        .to_string();
    assert!(e.contains("sensor.address"), "{e}");
}

const UR_RTDE: &str = r#"
[robot]
kind = "ur-rtde"
peer = "127.0.0.1:0"
cycle_s = 0.002
[sensor]
kind = "ur-rtde"
address = "127.0.0.1:0"
[model]
file = "ur10e"
"#;

/// Issue 34: a UR over RTDE is connected to, not listened for: `robot.peer` is required (port 0
/// means 30004), `robot.bind` is not; the registers and the alpha filter are bounded; the
/// twin's path offset follows the file.
#[test]
fn ur_rtde_needs_the_controller_s_address_and_bounds_its_registers() {
    let cell = parse(UR_RTDE).unwrap();
    assert_eq!(cell.robot.kind, RobotKind::UrRtde);
    assert_eq!(cell.sensor.kind, SensorKind::UrRtde);
    assert_eq!(cell.robot_link_address().to_string(), "127.0.0.1:30004");
    assert_eq!(
        (cell.robot.rtde_register, cell.robot.ur_alpha_filter),
        (24, 0.5)
    );
    let side = cell.robot_side(6);
    assert_eq!(side.controller.to_string(), "127.0.0.1:30004");
    assert_eq!(side.rtde_register, 24);
    let m = side.path_offset;
    assert_eq!(m.alpha, 0.5);
    assert!((m.max_offset_m - cell.limits.max_correction_m * 3f64.sqrt()).abs() < 1e-15);
    // robot.timeout_s (0.05 s by default) in 2 ms controller cycles.
    assert_eq!(m.watchdog_cycles, 25);

    let no_peer = UR_RTDE.replace("peer = \"127.0.0.1:0\"\n", "");
    let e = parse(&no_peer).unwrap_err().to_string();
    assert!(e.contains("robot.peer") && e.contains("ur-rtde"), "{e}");
    refused_naming(
        parse(&UR_RTDE.replace("127.0.0.1:0\"\ncycle", "0.0.0.0:30004\"\ncycle")),
        "unspecified peer",
        "robot.peer",
    );
    for (key, value) in [
        ("rtde_register", "23"),
        ("rtde_register", "43"),
        ("ur_alpha_filter", "0.0"),
        ("ur_alpha_filter", "1.5"),
    ] {
        let text = UR_RTDE.replace(
            "cycle_s = 0.002",
            &format!("cycle_s = 0.002\n{key} = {value}"),
        );
        refused_naming(parse(&text), value, &format!("robot.{key}"));
    }
    // The other robots still need their bind.
    let rsi = MINIMAL.replace("bind = \"127.0.0.1:59152\"\n", "");
    refused_naming(parse(&rsi), "kuka-rsi without bind", "robot.bind");
}

/// The simulated cell streams the flange sensor from its UR controller only.
#[test]
fn the_twin_plays_the_arm_s_sensor_only_with_its_ur_controller() {
    let twin = deflex_sim::CellConfig::for_robot("ur10e").unwrap();
    let sides = parse(UR_RTDE).unwrap().cell_sides(&twin).unwrap();
    assert!(sides.sensor_over_rtde);
    let with_rsi = UR_RTDE.replace(
        "kind = \"ur-rtde\"\npeer = \"127.0.0.1:0\"",
        "kind = \"kuka-rsi\"\nbind = \"127.0.0.1:59152\"",
    );
    let elsewhere = UR_RTDE.replace("address = \"127.0.0.1:0\"", "address = \"127.0.0.2:0\"");
    for text in [with_rsi, elsewhere] {
        let e = parse(&text)
            .unwrap()
            .cell_sides(&twin)
            .unwrap_err()
            .to_string();
        assert!(e.contains("ur-rtde") && e.contains("robot.peer"), "{e}");
    }
}
