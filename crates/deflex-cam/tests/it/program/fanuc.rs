//! FANUC TP (`.ls`): the header and what it asks the user to set, the motions and their
//! terminations, the `/POS` records with the configuration from the IK branch, the split at
//! [`FANUC_MAX_POINTS_PER_PART`] with a main program that calls the parts, and the reader's
//! refusals. The pose round trip of every format (FANUC included) is in `round_trip.rs`.

use super::arm;
use deflex_cam::program::readback::{read_fanuc, read_files};
use deflex_cam::program::settings::{CommonSettings, ProgramSettings};
use deflex_cam::program::{
    Coordinates, FANUC_MAX_POINTS_PER_PART, Format, ProgramInput, ProgramPoint, export,
};
use deflex_model::conventions::rotation_distance;

/// The FANUC test line: 0.1 mm steps at 10 mm/s ([`super::tilted_line`]).
fn line_path(points: usize) -> Vec<ProgramPoint> {
    super::tilted_line(points, 1e-4, 0.010)
}

fn input(points: Vec<ProgramPoint>) -> ProgramInput {
    super::tool_input(points, "FANUC")
}

/// The `/MN` lines of a TP text, without their numbers.
fn mn_lines(text: &str) -> Vec<String> {
    let start = text.find("/MN\n").unwrap() + 4;
    let end = text.find("/POS\n").unwrap();
    text[start..end]
        .lines()
        .map(|l| l.split_once(':').unwrap().1.to_string())
        .collect()
}

#[test]
fn a_tp_program_has_the_header_motions_and_positions_fanuc_loads() {
    let files = export(
        Format::Fanuc,
        &input(line_path(20)),
        &ProgramSettings::default(),
    )
    .unwrap();
    assert_eq!(files.len(), 1);
    assert_eq!(files[0].path, "DEFLEX_PATH.ls");
    let text = &files[0].contents;
    assert!(text.starts_with("/PROG  DEFLEX_PATH\n/ATTR\nOWNER\t\t= MNEDITOR;\n"));
    assert!(text.contains("\nDEFAULT_GROUP\t= 1,*,*,*,*;\n"));
    assert!(text.contains("\nPROTECT\t\t= READ_WRITE;\n"));
    assert!(text.contains("\nCOMMENT\t\t= \"deflex path\";\n"));
    assert!(text.trim_end().ends_with("/END"));
    let mn = mn_lines(text);
    assert!(text.contains(&format!("\nLINE_COUNT\t= {};\n", mn.len())));
    // Every /MN line ends with " ;" and every comment fits an old pendant's 32 characters.
    for line in &mn {
        assert!(line.ends_with(" ;"), "{line}");
        if let Some(c) = line.trim().strip_prefix("! ") {
            assert!(c.len() <= 32, "{line}");
        }
    }
    let header: String = mn
        .iter()
        .filter_map(|l| l.trim().strip_prefix("! "))
        .map(|c| c.trim_end_matches(" ;").to_string() + " ")
        .collect();
    for needed in [
        "ASCII upload option",
        "maketp",
        "Set UTOOL 1 to the model's TCP",
        "Set UFRAME 1 to the program frame",
        "Select PAYLOAD[1] with the tool load: 2.500 kg",
    ] {
        assert!(header.contains(needed), "{needed}: {header}");
    }
    let motions: Vec<&String> = mn
        .iter()
        .filter(|l| l.starts_with("J ") || l.starts_with("L "))
        .collect();
    // Clearance point, approach, 19 path moves, retract.
    assert_eq!(motions.len(), 22);
    assert_eq!(motions[0], "J P[1] 20% FINE ;");
    assert_eq!(motions[1], "L P[2] 10mm/sec FINE ;", "the approach");
    assert_eq!(motions[2], "L P[3] 10mm/sec CNT100 ;", "inside the path");
    assert_eq!(
        motions[20], "L P[21] 10mm/sec FINE ;",
        "the last path point"
    );
    assert_eq!(motions[21], "L P[22] 10mm/sec FINE ;", "the retract");
    let frame = mn.iter().position(|l| l == "  UFRAME_NUM=1 ;").unwrap();
    assert_eq!(mn[frame + 1], "  UTOOL_NUM=1 ;");
    assert!(frame < mn.iter().position(|l| l.starts_with("J ")).unwrap());
    // The /POS record of the first path point: 400 mm, -100 mm, 300 mm, tool down (turned 180°
    // about y: Rz(180°)·Rx(180°), W = R = 180).
    assert!(
        text.contains(
            "P[2]{\n   GP1:\n\tUF : 1, UT : 1,\t\tCONFIG : 'N U T, 0, 0, 0',\n\
             \tX =     400.0000  mm,\tY =    -100.0000  mm,\tZ =     300.0000  mm,\n\
             \tW =   180.000000 deg,\tP =     0.000000 deg,\tR =   180.000000 deg\n};\n"
        ),
        "{text}"
    );
    // Every pose and speed reads back (the clearance points around the path).
    let read = read_fanuc(text, "DEFLEX_PATH.ls").unwrap();
    assert_eq!(read.len(), 22);
    assert_eq!(read[0].speed_m_s, None, "the joint move has no path speed");
    let input = input(line_path(20));
    for (p, back) in input.points.iter().zip(&read[1..21]) {
        assert!((p.pose.translation.vector - back.position_m).norm() < 1e-7);
        assert!(rotation_distance(&p.pose.rotation, &back.rotation.unwrap()) < 1e-7);
        assert_eq!(back.speed_m_s, Some(0.010));
    }
}

#[test]
fn the_configuration_comes_from_the_ik_branch_and_robot_coordinates_use_uframe_0() {
    let mut input = input(line_path(5));
    input.coordinates = Coordinates::Robot;
    // Path: J5 < 0 (flip), wrist behind axis 1 (back), elbow short of stretched (down), J6 at
    // 200° (turn 1), J1 at -190° (turn -1).
    input.configurations = vec![arm([-3.3, 0.5, 0.2, 0.0, -0.4, 3.49], true, false); 5];
    input.clearance_configurations = Some([arm([0.1, 0.5, 1.2, 0.0, 0.7, -0.2], false, true); 2]);
    let settings = ProgramSettings {
        fanuc: deflex_cam::program::settings::FanucSettings {
            utool: 3,
            uframe: 5,
            joint_percent: 35,
            cnt: 50,
            payload: 2,
        },
        ..Default::default()
    };
    let text = &export(Format::Fanuc, &input, &settings).unwrap()[0].contents;
    assert!(
        text.contains("  UFRAME_NUM=0 ;"),
        "robot coordinates: the world frame"
    );
    assert!(text.contains("  UTOOL_NUM=3 ;"));
    assert!(text.contains("J P[1] 35% FINE ;"));
    assert!(text.contains("mm/sec CNT50 ;"));
    assert!(text.contains("PAYLOAD[2]"));
    assert!(text.contains("UF : 0, UT : 3,\t\tCONFIG : 'N U T, 0, 0, 0',"));
    assert!(text.contains("UF : 0, UT : 3,\t\tCONFIG : 'F D B, -1, 0, 1',"));
    read_fanuc(text, "DEFLEX_PATH.ls").unwrap();
}

#[test]
fn long_paths_split_at_the_fanuc_limit_into_called_parts() {
    // A path of the largest size (1 000 000 points) fits the 999 parts a program may call.
    let max_points = deflex_cam::program::settings::MAX_POINTS_LIMIT;
    assert!(max_points.div_ceil(FANUC_MAX_POINTS_PER_PART) <= 999);
    // The template allows 5000 moves a part; FANUC parts stop at 2000.
    let n = 2 * FANUC_MAX_POINTS_PER_PART + 500;
    let input = input(line_path(n));
    let settings = ProgramSettings {
        program: CommonSettings {
            name: "a long name for a fanuc program".into(),
            ..Default::default()
        },
        ..Default::default()
    };
    let files = export(Format::Fanuc, &input, &settings).unwrap();
    let paths: Vec<&str> = files.iter().map(|f| f.path.as_str()).collect();
    assert_eq!(
        paths,
        [
            "A_LONG_NAME_.ls",
            "A_LONG_NAME__P01.ls",
            "A_LONG_NAME__P02.ls",
            "A_LONG_NAME__P03.ls"
        ]
    );
    let main = &files[0].contents;
    let calls: Vec<String> = mn_lines(main)
        .into_iter()
        .filter(|l| l.contains("CALL"))
        .collect();
    assert_eq!(
        calls,
        [
            "  CALL A_LONG_NAME__P01 ;",
            "  CALL A_LONG_NAME__P02 ;",
            "  CALL A_LONG_NAME__P03 ;"
        ]
    );
    for part in &files[1..] {
        let records = part.contents.matches("   GP1:").count();
        assert!(records <= FANUC_MAX_POINTS_PER_PART, "{}", part.path);
        assert!(part.contents.contains("\nDEFAULT_GROUP\t= 1,*,*,*,*;\n"));
        assert!(part.contents.contains("  UFRAME_NUM=1 ;") && part.contents.contains("P[1]{"));
    }
    let read = read_files(Format::Fanuc, &files).unwrap();
    assert_eq!(read.len(), n + 2);
    for (p, back) in input.points.iter().zip(&read[1..=n]) {
        assert!((p.pose.translation.vector - back.position_m).norm() < 1e-7);
    }
    // The last path point of the last part ends exactly.
    assert!(files[3].contents.contains("10mm/sec FINE ;\n/POS"));
}

#[test]
fn the_reader_refuses_what_a_controller_would_refuse() {
    let files = export(
        Format::Fanuc,
        &input(line_path(5)),
        &ProgramSettings::default(),
    )
    .unwrap();
    let text = &files[0].contents;
    for (broken, why) in [
        (text.replace("/END\n", ""), "no /END"),
        (
            text.replace("'N U T, 0, 0, 0'", "'X U T, 0, 0, 0'"),
            "CONFIG",
        ),
        (text.replace("P[3]{", "P[30]{"), "P[3] not in /POS"),
        (text.replace("mm/sec", "cm/min"), "L without n mm/sec"),
        (
            text.replace("DEFAULT_GROUP\t= 1,*,*,*,*;\n", ""),
            "DEFAULT_GROUP",
        ),
        (text.replacen("  mm,", "  deg,", 1), "unit"),
    ] {
        let e = read_fanuc(&broken, "x.ls").unwrap_err().to_string();
        assert!(e.contains(why), "{why}: {e}");
    }
}

#[test]
fn long_header_paragraphs_are_wrapped_whole_within_the_pendant_width() {
    let mut input = input(line_path(5));
    let long: String = (0..60).map(|k| format!("word{k} ")).collect();
    input.description = vec![long.clone() + "END-OF-PARAGRAPH; with a semicolon (°)"];
    let text = &export(Format::Fanuc, &input, &ProgramSettings::default()).unwrap()[0].contents;
    let comments: Vec<String> = mn_lines(text)
        .iter()
        .filter_map(|l| {
            l.trim()
                .strip_prefix("! ")
                .map(|c| c.trim_end_matches(" ;").to_string())
        })
        .collect();
    assert!(comments.iter().all(|c| c.len() <= 30), "{comments:?}");
    let joined = comments.join(" ");
    assert!(
        joined.contains("word59 END-OF-PARAGRAPH, with a semicolon ( deg)"),
        "{joined}"
    );
    read_fanuc(text, "x.ls").unwrap();
}
