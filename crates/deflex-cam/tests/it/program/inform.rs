//! Yaskawa INFORM (`.JBI`): the header and what it asks the user to set, the positions with
//! `///RCONF` from the IK branch, the steps and their position levels, the split at
//! [`INFORM_MAX_POINTS_PER_PART`] with a main job that calls the parts, and the reader's
//! refusals; and a 1 000 000-point path split by every format into parts within their limits.
//! The pose round trip of every format (INFORM included) is in `round_trip.rs`.

use deflex_cam::program::readback::{read_files, read_inform};
use deflex_cam::program::settings::{
    CommonSettings, InformPostype, InformSettings, MAX_POINTS_LIMIT, ProgramSettings,
};
use deflex_cam::program::{
    Coordinates, FANUC_MAX_POINTS_PER_PART, Format, INFORM_MAX_POINTS_PER_PART, ProgramError,
    ProgramInput, ProgramPoint, ProgramSink, export, export_to,
};
use deflex_model::Pose;
use deflex_model::conventions::rotation_distance;
use nalgebra::{Rotation3, Translation3, Vector3};

use super::arm;

/// The INFORM test line: 0.1 µm steps (a million points stay within the writers' coordinate
/// bounds) at 12.3 mm/s ([`super::tilted_line`]).
fn line_path(points: usize) -> Vec<ProgramPoint> {
    super::tilted_line(points, 1e-7, 0.0123)
}

/// [`super::tool_input`] in a user frame that is rotated and off the axes.
fn input(points: Vec<ProgramPoint>) -> ProgramInput {
    let mut input = super::tool_input(points, "INFORM");
    input.frame_in_robot = Pose::from_parts(
        Translation3::new(1.71363512, -0.01, 0.20764501),
        Rotation3::from_euler_angles(0.0, 0.0, 0.3),
    );
    input
}

/// The `//INST` lines of a job, after `NOP`.
fn instructions(text: &str) -> Vec<&str> {
    let start = text.find("\r\nNOP\r\n").unwrap() + 7;
    text[start..].lines().collect()
}

#[test]
fn a_job_has_the_header_positions_and_steps_a_controller_loads() {
    let input = input(line_path(20));
    let files = export(Format::Inform, &input, &ProgramSettings::default()).unwrap();
    assert_eq!(files.len(), 1);
    assert_eq!(files[0].path, "DEFLEX_PATH.JBI");
    let text = &files[0].contents;
    // Every line ends with CR LF.
    assert_eq!(text.matches('\n').count(), text.matches("\r\n").count());
    assert!(text.starts_with(
        "/JOB\r\n//NAME DEFLEX_PATH\r\n//POS\r\n///NPOS 22,0,0,0,0,0\r\n///USER 1\r\n\
         ///TOOL 1\r\n///POSTYPE USER\r\n///RECTAN\r\n///RCONF 0,0,0,0,0,0,0,0\r\nC00000="
    ));
    assert!(text.contains(
        "//INST\r\n///DATE 2000/01/01 00:00\r\n///COMM deflex path\r\n///ATTR SC,RW\r\n\
         ///GROUP1 RB1\r\nNOP\r\n"
    ));
    assert!(text.ends_with("\r\nEND\r\n"));
    let inst = instructions(text);
    let comments: Vec<&str> = inst.iter().filter_map(|l| l.strip_prefix('\'')).collect();
    assert!(comments.iter().all(|c| c.len() <= 32), "{comments:?}");
    let header = comments.join(" ");
    for needed in [
        "EX.MEMORY > LOAD > JOB",
        "MotoCom",
        "BEFORE loading",
        "Set TOOL 1 to the model TCP",
        "the vendors simulator",
        // The frames at the program's precision: 0.1 µm and 1e-6°.
        "X 1713.6351 Y -10.0000 Z 207.6450 Rx 0.000000 Ry 0.000000 Rz 17.188734",
        "Z 200.0000",
        "W 2.500 kg",
        "Zg 80.0000",
        "Set USER 1 to the program frame",
    ] {
        assert!(header.contains(needed), "{needed}: {header}");
    }
    let steps: Vec<&str> = inst
        .iter()
        .copied()
        .filter(|l| l.starts_with("MOV"))
        .collect();
    // Clearance point, approach, 19 path steps, retract.
    assert_eq!(steps.len(), 22);
    assert_eq!(steps[0], "MOVJ C00000 VJ=10.00");
    assert_eq!(steps[1], "MOVL C00001 V=10.0 PL=0", "the approach");
    assert_eq!(steps[2], "MOVL C00002 V=12.3 PL=1", "inside the path");
    assert_eq!(steps[20], "MOVL C00020 V=12.3 PL=0", "the last path point");
    assert_eq!(steps[21], "MOVL C00021 V=10.0 PL=0", "the retract");
    // The first path point: 400 mm, -100 mm, 300 mm, tool down (turned 180° about y:
    // Rz(180°)·Rx(180°), Rx = Rz = 180).
    assert!(
        text.contains("\r\nC00001=400.0000,-100.0000,300.0000,180.000000,0.000000,180.000000\r\n"),
        "{text}"
    );
    let read = read_inform(text, "DEFLEX_PATH.JBI").unwrap();
    assert_eq!(read.len(), 22);
    assert_eq!(read[0].speed_m_s, None, "the joint move has no path speed");
    for (p, back) in input.points.iter().zip(&read[1..21]) {
        assert!((p.pose.translation.vector - back.position_m).norm() < 0.5e-7 * 3f64.sqrt());
        assert!(rotation_distance(&p.pose.rotation, &back.rotation.unwrap()) < 1e-7);
    }
    assert_eq!(read[2].speed_m_s, Some(0.0123));
}

#[test]
fn rconf_comes_from_the_ik_branch_and_robot_coordinates_write_postype_base() {
    let mut input = input(line_path(5));
    input.coordinates = Coordinates::Robot;
    input.frame_in_robot = Pose::identity();
    // Path: B < 0 (no flip), elbow short of stretched (lower arm), wrist behind axis 1 (rear),
    // R at -200° (≥ 180), T at 200° (≥ 180), S at 10°.
    input.configurations = vec![
        arm(
            [
                0.17,
                0.5,
                0.2,
                -200f64.to_radians(),
                -0.4,
                200f64.to_radians()
            ],
            true,
            false
        );
        5
    ];
    input.clearance_configurations = Some([arm([0.1, 0.5, 1.2, 0.0, 0.7, -0.2], false, true); 2]);
    let settings = ProgramSettings {
        inform: InformSettings {
            user: 5,
            tool: 3,
            postype: InformPostype::User,
            joint_percent: 25.5,
            pl: 4,
        },
        ..Default::default()
    };
    let text = &export(Format::Inform, &input, &settings).unwrap()[0].contents;
    assert!(text.contains("///TOOL 3\r\n///POSTYPE BASE\r\n"), "{text}");
    assert!(!text.contains("///USER"));
    assert!(text.contains("MOVJ C00000 VJ=25.50"));
    assert!(text.contains(" PL=4\r\n"));
    // Flip, upper arm, front for the clearance point; then the path's branch, written once.
    assert!(text.contains("///RCONF 0,0,0,0,0,0,0,0\r\nC00000="));
    assert_eq!(text.matches("///RCONF 1,1,1,1,1,0,0,0\r\n").count(), 1);
    assert!(text.contains("///RCONF 1,1,1,1,1,0,0,0\r\nC00001="));
    // The retract's configuration is the clearance one again.
    assert!(text.contains("///RCONF 0,0,0,0,0,0,0,0\r\nC00006="));
    read_inform(text, "x.JBI").unwrap();
    // BASE with positions in the part frame is refused, naming the key.
    let mut part = input.clone();
    part.coordinates = Coordinates::Part;
    let base = ProgramSettings {
        inform: InformSettings {
            postype: InformPostype::Base,
            ..Default::default()
        },
        ..Default::default()
    };
    let e = export(Format::Inform, &part, &base)
        .unwrap_err()
        .to_string();
    assert!(e.contains("inform.postype"), "{e}");
    // The template's section parses and is range-checked.
    let parsed = ProgramSettings::from_toml_str(
        "[inform]\nuser = 2\ntool = 0\npostype = \"base\"\njoint_percent = 5\npl = 0\n",
        "t.toml",
    )
    .unwrap();
    assert_eq!(parsed.inform.postype, InformPostype::Base);
    let e = ProgramSettings::from_toml_str("[inform]\npl = 9\n", "t.toml")
        .unwrap_err()
        .to_string();
    assert!(e.contains("t.toml") && e.contains("inform.pl"), "{e}");
}

#[test]
fn long_paths_split_at_the_inform_limit_into_called_jobs() {
    let n = 2 * INFORM_MAX_POINTS_PER_PART + 500;
    let input = input(line_path(n));
    let settings = ProgramSettings {
        program: CommonSettings {
            name: "a long name for an inform job that goes on".into(),
            ..Default::default()
        },
        ..Default::default()
    };
    let files = export(Format::Inform, &input, &settings).unwrap();
    let paths: Vec<&str> = files.iter().map(|f| f.path.as_str()).collect();
    let stem = "A_LONG_NAME_FOR_AN_INFORM_J";
    assert_eq!(
        paths,
        [
            format!("{stem}.JBI"),
            format!("{stem}_P01.JBI"),
            format!("{stem}_P02.JBI"),
            format!("{stem}_P03.JBI")
        ]
    );
    let main = &files[0].contents;
    let calls: Vec<&str> = instructions(main)
        .into_iter()
        .filter(|l| l.starts_with("CALL"))
        .collect();
    assert_eq!(
        calls,
        [
            format!("CALL JOB:{stem}_P01"),
            format!("CALL JOB:{stem}_P02"),
            format!("CALL JOB:{stem}_P03")
        ]
    );
    for part in &files[1..] {
        let steps = part.contents.matches("\r\nMOVL ").count();
        assert!(steps <= INFORM_MAX_POINTS_PER_PART, "{}", part.path);
        assert!(
            part.contents
                .contains(&format!("///NPOS {steps},0,0,0,0,0\r\n"))
        );
        assert!(part.contents.contains("///USER 1\r\n") && part.contents.contains("\r\nC00000="));
    }
    let read = read_files(Format::Inform, &files).unwrap();
    assert_eq!(read.len(), n + 2);
    for (p, back) in input.points.iter().zip(&read[1..=n]) {
        assert!((p.pose.translation.vector - back.position_m).norm() < 1e-7);
    }
    assert!(files[3].contents.ends_with(" PL=0\r\nEND\r\n"));
}

#[test]
fn the_reader_refuses_what_a_controller_would_refuse() {
    let files = export(
        Format::Inform,
        &input(line_path(5)),
        &ProgramSettings::default(),
    )
    .unwrap();
    let text = &files[0].contents;
    for (broken, why) in [
        (text.replace("\r\nEND\r\n", "\r\n"), "no END"),
        (text.replace("///NPOS 7,", "///NPOS 8,"), "///NPOS says 8"),
        (text.replace("///RCONF 0,0,0", "///RCONF 0,2,0"), "RCONF"),
        (
            text.replace("MOVL C00003", "MOVL C00030"),
            "C00030 not in //POS",
        ),
        (text.replace(" V=", " S="), "MOVL without V="),
        (text.replace(" PL=1", " PL=9"), "PL=0"),
        (text.replace("///GROUP1 RB1\r\n", ""), "GROUP1"),
        (text.replace("/JOB\r\n", ""), "/JOB"),
        (
            text.replacen(",0.000000,", ",zero,", 1),
            "expected a number",
        ),
    ] {
        let e = read_inform(&broken, "x.JBI").unwrap_err().to_string();
        assert!(e.contains(why), "{why}: {e}");
        assert!(e.starts_with("x.JBI:"), "{e}");
    }
}

/// Counts, per file, the motion lines a format writes and the bytes, keeping nothing else.
struct Counter {
    format: Format,
    files: Vec<(String, usize, usize)>,
}

impl Counter {
    fn is_motion(&self, line: &str) -> bool {
        let line = line.trim_start();
        let line = line.split_once(':').map_or(line, |(n, rest)| {
            // FANUC's numbered /MN lines.
            if n.trim().chars().all(|c| c.is_ascii_digit()) {
                rest
            } else {
                line
            }
        });
        match self.format {
            Format::Krl => line.starts_with("LIN ") || line.starts_with("PTP "),
            Format::Rapid => line.starts_with("MoveL ") || line.starts_with("MoveJ "),
            Format::Val3 => line.contains("movel(") || line.contains("movej("),
            Format::UrScript => line.starts_with("movel(") || line.starts_with("movej("),
            Format::Gcode => line.starts_with("G1 ") || line.starts_with("G0 "),
            Format::Fanuc => line.starts_with("L P[") || line.starts_with("J P["),
            Format::Inform => line.starts_with("MOVL ") || line.starts_with("MOVJ "),
        }
    }
}

impl ProgramSink for Counter {
    fn begin(&mut self, path: &str) -> Result<(), ProgramError> {
        self.files.push((path.to_string(), 0, 0));
        Ok(())
    }
    fn write(&mut self, text: &str) -> Result<(), ProgramError> {
        let motions = if self.format == Format::Val3 {
            // A VAL3 part loops over its array of points: its comment names their range (part 1
            // holds point 0 too, which the approach in `start` reaches).
            text.lines()
                .filter_map(|l| l.split_once(": path points "))
                .filter_map(|(_, range)| {
                    let (a, b) = range.split_once(" to ")?;
                    let (a, b) = (
                        a.trim().parse::<usize>().ok()?,
                        b.trim().parse::<usize>().ok()?,
                    );
                    Some(b + usize::from(a > 0) - a)
                })
                .sum()
        } else {
            text.lines().filter(|l| self.is_motion(l)).count()
        };
        let file = self.files.last_mut().expect("begin before write");
        file.1 += motions;
        file.2 += text.len();
        Ok(())
    }
    fn end(&mut self) -> Result<(), ProgramError> {
        Ok(())
    }
}

#[test]
fn a_million_point_path_splits_into_parts_within_every_formats_limit() {
    let n = MAX_POINTS_LIMIT;
    let mut input = ProgramInput::new(line_path(n));
    input.tool_in_flange = Pose::translation(0.0, 0.0, 0.2);
    input.tool_load_in_flange = Some(deflex_model::ToolLoad {
        mass_kg: 2.5,
        centre_of_mass_m: Vector3::new(0.0, 0.0, 0.08),
    });
    let settings = ProgramSettings::default();
    let template_limit = settings.program.max_points_per_part;
    let bytes_limit = settings.program.max_part_kb * 1024;
    for format in Format::ALL {
        let mut counter = Counter {
            format,
            files: Vec::new(),
        };
        let paths = export_to(format, &input, &settings, &mut counter).unwrap();
        let limit = match format {
            Format::Fanuc => FANUC_MAX_POINTS_PER_PART,
            Format::Inform => INFORM_MAX_POINTS_PER_PART,
            _ => template_limit,
        };
        let is_part = |p: &str| {
            let stem = p.rsplit('/').next().unwrap().split('.').next().unwrap();
            stem.to_ascii_lowercase()
                .rsplit_once("_p")
                .is_some_and(|(_, k)| k.chars().all(|c| c.is_ascii_digit()))
                || stem.starts_with("part")
        };
        let parts: Vec<&(String, usize, usize)> =
            counter.files.iter().filter(|f| is_part(&f.0)).collect();
        if format == Format::Gcode {
            // One file, every point a motion (G-code is streamed by the CNC, not split).
            assert!(parts.is_empty());
            assert!(counter.files[0].1 >= n, "{format:?}");
            continue;
        }
        let motions: usize = parts.iter().map(|f| f.1).sum();
        assert!(
            motions >= n - 1,
            "{format:?}: {motions} motions in the parts for {n} points"
        );
        assert!(
            parts.len() >= (n - 1).div_ceil(limit),
            "{format:?}: {} parts",
            parts.len()
        );
        // URScript parts are whole scripts: the first also holds the start joint move and the
        // approach, the last the retract (the limit counts path moves).
        let extra = if format == Format::UrScript { 2 } else { 0 };
        for (path, count, bytes) in &parts {
            assert!(
                *count <= limit + extra,
                "{format:?} {path}: {count} > {limit}"
            );
            if format != Format::Val3 {
                assert!(*bytes <= bytes_limit, "{format:?} {path}: {bytes} bytes");
            }
        }
        assert_eq!(paths.len(), counter.files.len());
    }
}
