//! Every exporter's output read back ([`deflex_cam::program::readback`]) agrees with the path:
//! positions within 1 µm, orientations within 1e-6 rad (the printed precision), speeds as
//! programmed (capped by the settings, rapid moves at the rapid speed). Plus the bounds:
//! point counts, bad values, line lengths and names.

use deflex_cam::program::readback::read_files;
use deflex_cam::program::settings::ProgramSettings;
use deflex_cam::program::{
    Coordinates, Format, ProgramError, ProgramInput, ProgramPoint, export, names,
};
use deflex_model::Pose;
use deflex_model::conventions::{rotation_distance, rotation_from_kuka_abc_deg};
use nalgebra::{Rotation3, Translation3, Vector3};

/// A helical cone like the paper's (20 mm radius, 45°, in the part frame), the tool pointing
/// down with a millirad wobble (what a compensated orientation looks like), a rapid start, a
/// speed change and a feed above the settings' cap.
fn cone_path(points: usize) -> Vec<ProgramPoint> {
    let down = Rotation3::from_axis_angle(&Vector3::y_axis(), std::f64::consts::PI);
    (0..points)
        .map(|i| {
            let t = i as f64 / points as f64;
            let theta = 2.0 * std::f64::consts::PI * 3.0 * t;
            let depth = 0.015 * t;
            let r = 0.020 - depth;
            let wobble = Rotation3::from_scaled_axis(Vector3::new(
                1e-3 * theta.sin(),
                -1.5e-3 * theta.cos(),
                2e-4 * t,
            ));
            let speed = match i {
                0 => None,
                _ if i < points / 2 => Some(0.010),
                _ if i < points * 3 / 4 => Some(0.012_345),
                _ => Some(0.5), // capped at max_speed_mm_s
            };
            ProgramPoint {
                pose: Pose::from_parts(
                    Translation3::new(r * theta.cos(), r * theta.sin(), -depth),
                    wobble * down,
                ),
                speed_m_s: speed,
            }
        })
        .collect()
}

fn input(points: Vec<ProgramPoint>) -> ProgramInput {
    ProgramInput {
        tool_load_in_flange: Some(deflex_model::ToolLoad {
            mass_kg: 2.5,
            centre_of_mass_m: Vector3::new(0.0, 0.0, 0.08),
        }),
        tool_load_source: "test".into(),
        coordinates: Coordinates::Part,
        frame_name: None,
        configurations: Vec::new(),
        clearance_configurations: None,
        description: vec![
            "SIMULATED test path: cone Ø40 mm, 45° — δ ≤ 3 mm (µm-level check)".into(),
            "second line (with parentheses) and ; semicolons".into(),
        ],
        frame_in_robot: Pose::from_parts(
            Translation3::new(1.5, 0.0, -0.183),
            Rotation3::from_axis_angle(&Vector3::z_axis(), 0.3),
        ),
        tool_in_flange: Pose::from_parts(
            Translation3::new(0.0, 0.0, 0.25),
            Rotation3::from_axis_angle(&Vector3::x_axis(), 0.1),
        ),
        points,
    }
}

fn expected_speed_m_s(point: &ProgramPoint, settings: &ProgramSettings) -> f64 {
    match point.speed_m_s {
        Some(v) => (v * 1e3).min(settings.program.max_speed_mm_s) * 1e-3,
        None => settings.program.rapid_speed_mm_s * 1e-3,
    }
}

fn check_round_trip(format: Format, input: &ProgramInput, settings: &ProgramSettings) {
    let files = export(format, input, settings).unwrap();
    for file in &files {
        assert!(
            file.contents.is_ascii(),
            "{format:?}: {} is not ASCII",
            file.path
        );
    }
    let read = read_files(format, &files).unwrap();
    let n = input.points.len();
    // The clearance point above the start, the path, the clearance point above the end.
    assert_eq!(read.len(), n + 2, "{format:?}");
    let clear = input.clearance_poses(settings).unwrap();
    for (k, back) in [(0, &read[0]), (1, &read[n + 1])] {
        let dp = (clear[k].translation.vector - back.position_m).norm();
        assert!(dp <= 1e-6, "{format:?}: clearance point {k} off by {dp} m");
    }
    // The first motion after the start reaches the clearance point from above the part: the
    // approach and the retract stay outside the path's bounding box but for their ends.
    let mut worst_position: f64 = 0.0;
    let mut worst_rotation: f64 = 0.0;
    for (i, (written, back)) in input.points.iter().zip(&read[1..=n]).enumerate() {
        let dp = (written.pose.translation.vector - back.position_m).norm();
        worst_position = worst_position.max(dp);
        if let Some(rotation) = back.rotation {
            worst_rotation =
                worst_rotation.max(rotation_distance(&written.pose.rotation, &rotation));
        } else {
            assert_eq!(format, Format::Gcode);
        }
        let want = if i == 0 {
            settings.program.approach_speed_mm_s * 1e-3
        } else {
            expected_speed_m_s(written, settings)
        };
        match back.speed_m_s {
            None => {
                assert_eq!(format, Format::Gcode, "only G-code keeps rapids as G0");
                assert!(written.speed_m_s.is_none() && i > 0);
            }
            Some(v) => {
                // Speeds are written to 0.01 mm/s; FANUC's `mm/sec` takes whole mm/s.
                let tolerance = match format {
                    Format::Fanuc => 0.5e-3,
                    // INFORM's `V=` takes 0.1 mm/s.
                    Format::Inform => 0.5e-4,
                    _ => 0.5e-5,
                };
                assert!(
                    (v - want).abs() <= tolerance + 1e-12,
                    "{format:?} point {i}: {v} vs {want}"
                );
            }
        }
    }
    assert!(
        worst_position <= 1e-6,
        "{format:?}: position {worst_position} m"
    );
    assert!(
        worst_rotation <= 1e-6,
        "{format:?}: orientation {worst_rotation} rad"
    );
}

#[test]
fn every_format_round_trips_a_compensated_cone() {
    let settings = ProgramSettings::default();
    let mut points = cone_path(2000);
    // A rapid move in the middle.
    points[1000].speed_m_s = None;
    let input = input(points);
    for format in Format::ALL {
        check_round_trip(format, &input, &settings);
    }
}

#[test]
fn orientations_at_and_near_gimbal_lock_round_trip() {
    // KUKA B = ±90° and Stäubli ry = ±90°, exactly and within 1e-9 … 1e-3 degree.
    let mut points = Vec::new();
    for (k, offset) in [0.0, 1e-9, 1e-6, 1e-3].iter().enumerate() {
        for sign in [1.0, -1.0] {
            let kuka = rotation_from_kuka_abc_deg([35.0, sign * (90.0 - offset), -20.0]);
            let staubli = deflex_model::conventions::rotation_from_staubli_rxryrz_deg([
                15.0,
                sign * (90.0 - offset),
                -65.0,
            ]);
            for rotation in [kuka, staubli] {
                points.push(ProgramPoint {
                    pose: Pose::from_parts(
                        Translation3::new(0.001 * points.len() as f64, 0.0, 0.002 * k as f64),
                        rotation,
                    ),
                    speed_m_s: Some(0.02),
                });
            }
        }
    }
    let mut input = ProgramInput::new(points);
    input.tool_load_in_flange = Some(deflex_model::ToolLoad {
        mass_kg: 1.0,
        centre_of_mass_m: Vector3::zeros(),
    });
    input.tool_load_source = "test".into();
    for format in Format::ALL {
        check_round_trip(format, &input, &ProgramSettings::default());
    }
}

#[test]
fn programs_carry_the_vendor_keywords_units_and_frames() {
    let settings = ProgramSettings::default();
    let input = input(cone_path(50));
    let text = |format| {
        export(format, &input, &settings)
            .unwrap()
            .into_iter()
            .map(|f| format!("== {}\n{}", f.path, f.contents))
            .collect::<String>()
    };
    let krl = text(Format::Krl);
    assert!(krl.contains("== deflex_path.src") && krl.contains("== deflex_path.dat"));
    assert!(krl.contains("DEF deflex_path( )") && krl.contains("DEFDAT deflex_path"));
    assert!(krl.contains("$TOOL = TOOL_DATA[1]") && krl.contains("$BASE = BASE_DATA[1]"));
    assert!(krl.contains("PTP $H_POS") && krl.contains("$LOAD = LOAD_DATA[1]"));
    assert!(krl.contains("; approach") && krl.contains("; retract"));
    assert!(krl.contains("$VEL.CP = 0.01000"), "10 mm/s written in m/s");
    assert!(krl.contains("} C_DIS\r\n") && krl.contains("DECL REAL DEFLEX_CDIS = 0.200"));
    // The expected base: X 1500 mm, turned 0.3 rad = 17.188734° about z.
    assert!(
        krl.contains("{X 1500.0000, Y 0.0000, Z -183.0000, A 17.188734, B 0.000000, C 0.000000}"),
        "{krl}"
    );
    let rapid = text(Format::Rapid);
    assert!(rapid.contains("MODULE deflex_path") && rapid.contains("PROC main()"));
    assert!(rapid.contains("CONST speeddata deflex_v1 := [10.00,30.00,5000,1000];"));
    assert!(rapid.contains("\\WObj:=deflex_wobj;"));
    assert!(rapid.contains("PERS tooldata deflex_tool := [TRUE,[[0.0000,0.0000,250.0000],"));
    assert!(
        rapid.contains("[2.500,[0.000,0.000,80.000],"),
        "the tool load"
    );
    assert!(
        rapid.contains("fine, deflex_tool"),
        "the last move ends exactly"
    );
    let val3 = text(Format::Val3);
    for part in [
        "deflex_path/deflex_path.pjx",
        "deflex_path/deflex_path.dtx",
        "deflex_path/start.pgx",
        "deflex_path/stop.pgx",
    ] {
        assert!(val3.contains(&format!("== {part}")), "{part}");
    }
    assert!(val3.contains("movel(pPath1[l_i], tTool, mPath[nSpeed1[l_i]])"));
    assert!(
        val3.contains("call part1()") && val3.contains("movel(pClear[1], tTool, mApproach[1])")
    );
    assert!(val3.contains("fatherId=\"fPart[0]\"") && val3.contains("fatherId=\"flange[0]\""));
    assert!(val3.contains("millimeterUnit=\"true\""));
    let ur = text(Format::UrScript);
    assert!(ur.contains("def deflex_path():") && ur.contains("\ndeflex_path()\n"));
    assert!(ur.contains(
        "set_tcp(p[0.0000000, 0.0000000, 0.2500000, 0.10000000, 0.00000000, 0.00000000])"
    ));
    assert!(ur.contains(
        "deflex_frame = p[1.5000000, 0.0000000, -0.1830000, 0.00000000, 0.00000000, 0.30000000]"
    ));
    assert!(ur.contains("v=0.01000"));
    let gcode = text(Format::Gcode);
    assert!(gcode.contains("G17 G40 G49 G80 G90 G21 G54\nG0 X20.0000 Y0.0000 Z20.0000 ( clearance point )\nG1 X20.0000 Y0.0000 Z0.0000 F600.00 ( approach )\n"), "{gcode}");
    assert!(gcode.contains(" F600.00\n"));
    assert!(gcode.trim_end().ends_with("M30\n%"));
    // Comments never break the language: no parentheses inside G-code comments.
    for line in gcode.lines().filter(|l| l.starts_with('(')) {
        assert_eq!(line.matches('(').count(), 1, "{line}");
        assert_eq!(line.matches(')').count(), 1, "{line}");
    }
}

#[test]
fn blends_shrink_on_short_segments_and_vanish_at_the_end() {
    let mut points: Vec<ProgramPoint> = (0..5)
        .map(|i| ProgramPoint {
            pose: Pose::translation(0.0001 * f64::from(i), 0.0, 0.0), // 0.1 mm segments
            speed_m_s: Some(0.01),
        })
        .collect();
    points[0].speed_m_s = None;
    let files = export(
        Format::UrScript,
        &ProgramInput::new(points),
        &ProgramSettings::default(),
    )
    .unwrap();
    let radii: Vec<&str> = files[0]
        .contents
        .lines()
        .filter_map(|l| l.split("r=").nth(1))
        .collect();
    // The approach has none; 45 % of 0.1 mm = 0.045 mm < the 0.2 mm setting; the last move and
    // the retract have none.
    assert_eq!(
        radii,
        [
            "0.0000000)",
            "0.0000450)",
            "0.0000450)",
            "0.0000450)",
            "0.0000000)",
            "0.0000000)"
        ]
    );
}

#[test]
fn bounds_and_bad_values_are_refused_with_the_point_named() {
    let settings = ProgramSettings {
        program: deflex_cam::program::settings::CommonSettings {
            max_points: 10,
            ..Default::default()
        },
        ..Default::default()
    };
    for format in Format::ALL {
        let e = export(format, &ProgramInput::new(cone_path(11)), &settings).unwrap_err();
        assert!(
            matches!(
                e,
                ProgramError::PointCount {
                    points: 11,
                    max: 10,
                    ..
                }
            ),
            "{e}"
        );
        let e = export(format, &ProgramInput::new(Vec::new()), &settings).unwrap_err();
        assert!(
            matches!(e, ProgramError::PointCount { points: 0, .. }),
            "{e}"
        );
        let mut points = cone_path(5);
        points[3].pose.translation.vector.y = f64::NAN;
        let e = export(format, &ProgramInput::new(points), &settings).unwrap_err();
        assert!(e.to_string().contains("point 3: y_m"), "{e}");
        let mut points = cone_path(5);
        points[2].pose.translation.vector.x = 1e4;
        assert!(export(format, &ProgramInput::new(points), &settings).is_err());
        let mut points = cone_path(5);
        points[4].speed_m_s = Some(-1.0);
        let e = export(format, &ProgramInput::new(points), &settings).unwrap_err();
        assert!(e.to_string().contains("point 4: speed_m_s"), "{e}");
        let mut bad_tool = ProgramInput::new(cone_path(5));
        bad_tool.tool_in_flange.translation.vector.z = f64::INFINITY;
        let e = export(format, &bad_tool, &settings).unwrap_err();
        assert!(e.to_string().contains("tool: z_m"), "{e}");
    }
}

#[test]
fn names_are_made_valid_per_language_and_lines_stay_short() {
    let settings = ProgramSettings {
        program: deflex_cam::program::settings::CommonSettings {
            name: "Cone for the TX200 — compensated, run #7 (seed 1) with a very long name".into(),
            ..Default::default()
        },
        ..Default::default()
    };
    let input = input(cone_path(100));
    for format in Format::ALL {
        let files = export(format, &input, &settings).unwrap();
        for file in &files {
            for line in file.contents.lines() {
                assert!(line.len() <= 250, "{format:?} {}: {line}", file.path);
            }
        }
        let stem = files[0].path.split(['/', '.']).next().unwrap().to_string();
        let rule = match format {
            Format::Krl => names::KRL,
            Format::Rapid => names::RAPID,
            Format::Val3 => names::VAL3,
            Format::UrScript => names::URSCRIPT,
            Format::Gcode => names::GCODE_FILE,
            Format::Fanuc => names::FANUC,
            Format::Inform => names::INFORM,
        };
        assert!(names::is_valid(&stem, &rule), "{format:?}: {stem}");
    }
    let files = export(Format::Krl, &input, &settings).unwrap();
    assert_eq!(files[0].path, "Cone_for_the_TX200___com.src");
    assert!(
        files[0]
            .contents
            .contains("DEF Cone_for_the_TX200___com( )")
    );
}

#[test]
fn robot_coordinates_and_world_poses_convert_consistently() {
    // A TCP pose in the world, a robot base placed in the world and a part frame: the program
    // pose composed with the declared frame gives back the TCP in the robot base frame.
    let base = Pose::from_parts(
        Translation3::new(0.1, -0.2, 0.5),
        Rotation3::from_axis_angle(&Vector3::z_axis(), 0.7),
    );
    let part = Pose::from_parts(
        Translation3::new(1.5, 0.3, -0.2),
        Rotation3::from_axis_angle(&Vector3::x_axis(), 0.05),
    );
    let tcp = Pose::from_parts(
        Translation3::new(1.52, 0.31, -0.21),
        Rotation3::from_axis_angle(&Vector3::y_axis(), 3.0),
    );
    for coordinates in [Coordinates::Part, Coordinates::Robot] {
        let input = ProgramInput::from_world_poses(
            [(tcp, Some(0.01))],
            &base,
            &part,
            coordinates,
            &Pose::identity(),
            Vec::new(),
        );
        let in_robot = input.frame_in_robot * input.points[0].pose;
        let want = base.inverse() * tcp;
        assert!((in_robot.translation.vector - want.translation.vector).norm() < 1e-12);
        assert!(rotation_distance(&in_robot.rotation, &want.rotation) < 1e-12);
    }
}

#[test]
fn the_template_file_documents_the_defaults() {
    let path =
        std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("../../docs/program.example.toml");
    let parsed = ProgramSettings::load(&path).unwrap();
    assert_eq!(parsed, ProgramSettings::default());
    let e = ProgramSettings::from_toml_str("[kuka]\ntool = 40\n", "t.toml").unwrap_err();
    assert!(e.to_string().contains("t.toml: kuka.tool"), "{e}");
    let e =
        ProgramSettings::from_toml_str("[abb]\ntool_name = \"my tool\"\n", "t.toml").unwrap_err();
    assert!(e.to_string().contains("abb.tool_name"), "{e}");
    let e = ProgramSettings::from_toml_str("[program]\nspeed = 1\n", "t.toml").unwrap_err();
    assert!(e.to_string().contains("speed"), "{e}");
    let e = ProgramSettings::from_toml_str("[program]\nblend_mm = nan\n", "t.toml").unwrap_err();
    assert!(e.to_string().contains("program.blend_mm"), "{e}");
}

/// The configuration of a TX200-like arm at joint values (the sides written out for the
/// test: in front of axis 1, in front of the lower arm, elbow short of stretched).
fn arm(q: [f64; 6]) -> deflex_cam::program::ArmConfiguration {
    deflex_cam::program::ArmConfiguration {
        joints_rad: q,
        wrist_behind_axis_1: false,
        wrist_behind_lower_arm: false,
        elbow_beyond_stretched: q[2] > 0.3,
        elbow_up: q[2] > 0.3,
    }
}

#[test]
fn long_paths_are_split_into_parts_that_read_back_in_order() {
    let settings = ProgramSettings {
        program: deflex_cam::program::settings::CommonSettings {
            max_points_per_part: 300,
            ..Default::default()
        },
        ..Default::default()
    };
    let mut input = input(cone_path(1000));
    input.configurations = (0..1000)
        .map(|i| arm([0.1, 0.8, 1.5 - 1e-4 * i as f64, 0.0, 0.7, -0.2]))
        .collect();
    input.clearance_configurations = Some([arm([0.1, 0.8, 1.4, 0.0, 0.7, -0.2]); 2]);
    for format in Format::ALL {
        check_round_trip(format, &input, &settings);
        let files = export(format, &input, &settings).unwrap();
        let parts: Vec<&str> = files
            .iter()
            .map(|f| f.path.as_str())
            .filter(|p| p.to_ascii_lowercase().contains("_p0") || p.contains("/part"))
            .collect();
        match format {
            // 999 moves after the first point in parts of 300: 4 parts.
            Format::Krl
            | Format::Rapid
            | Format::UrScript
            | Format::Val3
            | Format::Fanuc
            | Format::Inform => {
                assert_eq!(parts.len(), 4, "{format:?}: {parts:?}")
            }
            Format::Gcode => assert!(parts.is_empty()),
        }
    }
    let text = |format| -> String {
        export(format, &input, &settings)
            .unwrap()
            .iter()
            .map(|f| f.contents.clone())
            .collect()
    };
    let krl = text(Format::Krl);
    for k in 1..=4 {
        assert!(
            krl.contains(&format!("deflex_path_p0{k}( )\r\n")),
            "call {k}"
        );
        assert!(
            krl.contains(&format!("DEF deflex_path_p0{k}( )")),
            "part {k}"
        );
    }
    // KUKA Status/Turn on the PTP to the clearance point: S 2 (A3 beyond stretched), T 32
    // (A6 negative).
    assert!(
        krl.contains(", S 2, T 32} ; clearance point"),
        "{}",
        &krl[..2000]
    );
    // ABB: robconf at every target, configuration monitoring on, the start joint move.
    let rapid = text(Format::Rapid);
    assert!(rapid.contains("ConfJ \\On;") && rapid.contains("ConfL \\On;"));
    assert!(
        rapid.contains("],[0,0,-1,0],[9E9"),
        "robconf of A6 = -0.2 rad"
    );
    assert!(rapid.contains("MoveAbsJ deflex_start,"));
    assert!(rapid.contains(
        "CONST jointtarget deflex_start := [[5.7296,45.8366,80.2141,0.0000,40.1070,-11.4592]"
    ));
    let val3 = text(Format::Val3);
    assert!(val3.contains("shoulder=\"righty\" elbow=\"epositive\" wrist=\"wpositive\""));
    assert!(val3.contains("movej(jStart[0], tTool, mApproach[0])"));
    let ur = text(Format::UrScript);
    assert!(ur.contains(
        "movej([0.100000, 0.800000, 1.400000, 0.000000, 0.700000, -0.200000], a=0.500, v=0.200)"
    ));
    assert!(ur.contains("set_payload(2.500, [0.0000, 0.0000, 0.0800])"));
}

#[test]
fn robot_coordinates_write_no_base_and_headers_wrap_at_words() {
    let settings = ProgramSettings {
        program: deflex_cam::program::settings::CommonSettings {
            coordinates: Coordinates::Robot,
            ..Default::default()
        },
        ..Default::default()
    };
    let mut input = input(cone_path(20));
    input.coordinates = Coordinates::Robot;
    input.description = vec![format!(
        "SIMULATED deflex offline compensation {} end",
        "of a rather long description line with many words ".repeat(4)
    )];
    let krl = &export(Format::Krl, &input, &settings).unwrap()[0].contents;
    assert!(krl.contains("$BASE = $NULLFRAME"), "{krl}");
    assert!(!krl.contains("$BASE = BASE_DATA"));
    let comments: Vec<&str> = krl
        .lines()
        .filter_map(|l| l.strip_prefix("; "))
        .take(4)
        .collect();
    assert!(comments.iter().all(|l| l.len() <= 90), "{comments:?}");
    let joined = comments.join(" ");
    let words: Vec<&str> = joined.split_whitespace().take(8).collect();
    assert_eq!(
        words,
        [
            "SIMULATED",
            "deflex",
            "offline",
            "compensation",
            "of",
            "a",
            "rather",
            "long"
        ]
    );
    // RAPID refuses to guess a tool load.
    input.tool_load_in_flange = None;
    let e = export(Format::Rapid, &input, &settings).unwrap_err();
    assert!(e.to_string().contains("program.tool_mass_kg"), "{e}");
}
