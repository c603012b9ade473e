//! Issue 36: every frame an operator types in is exact. For every built-in robot, `deflex
//! compensate` writes every program format; this test reads each program's frame **from its
//! printed text** as an operator would (the header line or the declaration the operator copies
//! onto the controller), reads the program's commanded positions with parsers of its own (not
//! deflex's readback), rebuilds the commanded positions in the robot's world from the two, and
//! finds every row of `compensated_path.csv` (`cx_m cy_m cz_m`) among them, in order, within
//! what the program's written decimals allow: 0.1 µm per axis for the formats written to
//! 0.1 µm (half a unit of the position's last decimal plus half of the frame's), plus the
//! table's own nanometre.
//!
//! The built-in cells place the part frame without rotation; the test checks that each program
//! says so (rotation zero in its frame), so a translation is all an operator enters.

use crate::support::{s, scratch, succeeds};
use std::path::Path;

/// Half a unit of the last written decimal of a position and of the frame, per axis (mm), for
/// programs written to 0.1 µm, and the CSV's nanometre.
const TOLERANCE_MM: f64 = 0.0001 + 0.000_001;

/// Every number of `text` that follows `key` (e.g. `X`, `x="`), in order.
fn numbers_after(text: &str, key: &str) -> Vec<f64> {
    text.match_indices(key)
        .filter_map(|(i, _)| {
            let rest = &text[i + key.len()..];
            let rest = rest.trim_start_matches([' ', '=']);
            let end = rest
                .find(|c: char| !(c.is_ascii_digit() || c == '.' || c == '-' || c == '+'))
                .unwrap_or(rest.len());
            rest[..end].parse().ok()
        })
        .collect()
}

/// The first three numbers of the comma-separated list after `key` in `line`.
fn list_after(line: &str, key: &str) -> [f64; 3] {
    let start = line
        .find(key)
        .unwrap_or_else(|| panic!("`{key}` in `{line}`"))
        + key.len();
    let v: Vec<f64> = line[start..]
        .split([',', ']', ' '])
        .filter(|t| !t.is_empty())
        .take(3)
        .map(|t| {
            t.parse()
                .unwrap_or_else(|_| panic!("number `{t}` in `{line}`"))
        })
        .collect();
    [v[0], v[1], v[2]]
}

/// The one line of `text` containing `needle`.
fn line_with<'a>(text: &'a str, needle: &str) -> &'a str {
    text.lines()
        .find(|l| l.contains(needle))
        .unwrap_or_else(|| panic!("no line with `{needle}`"))
}

/// `X… Y… Z…` of a line (mm), as the three numbers after `X`, `Y`, `Z`.
fn xyz_words(line: &str, sep: &str) -> [f64; 3] {
    let get = |k: &str| {
        numbers_after(line, &format!("{k}{sep}"))
            .first()
            .copied()
            .unwrap_or_else(|| panic!("{k} in `{line}`"))
    };
    [get("X"), get("Y"), get("Z")]
}

/// What an operator enters and what the program commands: the frame's translation (mm, robot
/// base) and every commanded position (mm, program frame), in program order.
struct OperatorView {
    frame_mm: [f64; 3],
    positions_mm: Vec<[f64; 3]>,
    tolerance_mm: f64,
}

/// Reads what an operator sees in one format's programs (in its `programs/` folder).
type ProgramReader = fn(&Path) -> OperatorView;

fn read(dir: &Path, file: &str) -> String {
    std::fs::read_to_string(dir.join(file)).unwrap_or_else(|e| panic!("{file}: {e}"))
}

/// G-code: the work offset from the header comment, the `G0`/`G1` positions.
fn gcode(dir: &Path) -> OperatorView {
    let text = read(dir, "deflex_path.gcode");
    let offset = line_with(&text, "must hold the part frame in the robot base frame");
    assert!(!offset.contains("rotated"), "{offset}");
    let frame_mm = xyz_words(offset.split("[mm]:").nth(1).unwrap(), "");
    let positions_mm = text
        .lines()
        .filter(|l| l.starts_with("G0 X") || l.starts_with("G1 X"))
        .map(|l| xyz_words(l, ""))
        .collect();
    OperatorView {
        frame_mm,
        positions_mm,
        tolerance_mm: TOLERANCE_MM,
    }
}

/// KRL: `BASE_DATA[n]` from the header comment, the `LIN {X …}` positions.
fn krl(dir: &Path) -> OperatorView {
    let text = read(dir, "deflex_path.src");
    let base = line_with(&text, "BASE_DATA[1] must hold");
    let frame = base.split('{').nth(1).unwrap();
    assert_eq!(numbers_after(frame, "A "), [0.0], "{base}");
    assert_eq!(numbers_after(frame, "B "), [0.0], "{base}");
    assert_eq!(numbers_after(frame, "C "), [0.0], "{base}");
    OperatorView {
        frame_mm: xyz_words(frame, " "),
        positions_mm: text
            .lines()
            .filter(|l| l.starts_with("LIN {"))
            .map(|l| xyz_words(l, " "))
            .collect(),
        tolerance_mm: TOLERANCE_MM,
    }
}

/// RAPID: the work object's user frame, the `MoveL [[x,y,z],…` positions.
fn rapid(dir: &Path) -> OperatorView {
    let text = read(dir, "deflex_path.mod");
    let wobj = line_with(&text, "PERS wobjdata deflex_wobj");
    assert!(
        wobj.contains("[1.000000000,0.000000000,0.000000000,0.000000000]"),
        "{wobj}"
    );
    OperatorView {
        frame_mm: list_after(wobj, "\"\",[["),
        positions_mm: text
            .lines()
            .filter(|l| l.trim_start().starts_with("MoveL [["))
            .map(|l| list_after(l, "MoveL [["))
            .collect(),
        tolerance_mm: TOLERANCE_MM,
    }
}

/// URScript: `deflex_frame = p[…]` (m), the `movel(pose_trans(deflex_frame, p[…` positions (m).
fn urscript(dir: &Path) -> OperatorView {
    let text = read(dir, "deflex_path.script");
    let frame = line_with(&text, "deflex_frame = p[");
    let rotation: Vec<f64> = frame
        .split('[')
        .nth(1)
        .unwrap()
        .split([',', ']'])
        .skip(3)
        .take(3)
        .map(|t| t.trim().parse().unwrap())
        .collect();
    assert_eq!(rotation, [0.0; 3], "{frame}");
    let mm = |v: [f64; 3]| v.map(|x| x * 1e3);
    OperatorView {
        frame_mm: mm(list_after(frame, "p[")),
        positions_mm: text
            .lines()
            .filter(|l| l.contains("movel(pose_trans(deflex_frame, p["))
            .map(|l| mm(list_after(l, "deflex_frame, p[")))
            .collect(),
        tolerance_mm: TOLERANCE_MM,
    }
}

/// VAL3: the `fPart` frame of the data file, the `pPath…` points (their `x= y= z=`).
fn val3(dir: &Path) -> OperatorView {
    let text = read(dir, "deflex_path/deflex_path.dtx");
    let mut frame = None;
    let mut positions_mm = Vec::new();
    let mut data = "";
    for line in text.lines() {
        if let Some(i) = line.find("<Data name=\"") {
            data = line[i + 12..].split('"').next().unwrap();
            continue;
        }
        if !line.contains("<Value ") || !line.contains(" x=\"") {
            continue;
        }
        let xyz = [
            numbers_after(line, " x=\"")[0],
            numbers_after(line, " y=\"")[0],
            numbers_after(line, " z=\"")[0],
        ];
        if data == "fPart" {
            for key in [" rx=\"", " ry=\"", " rz=\""] {
                assert_eq!(numbers_after(line, key), [0.0], "{line}");
            }
            frame = Some(xyz);
        } else if data.starts_with("pPath") {
            positions_mm.push(xyz);
        }
    }
    OperatorView {
        frame_mm: frame.expect("fPart in the .dtx"),
        positions_mm,
        tolerance_mm: TOLERANCE_MM,
    }
}

/// FANUC TP: the user frame from the comment lines (`Set UFRAME n to the program frame (mm,
/// deg): X … Y … Z … W … P … R …`, wrapped over several `!` lines), the `/POS` positions.
fn fanuc(dir: &Path) -> OperatorView {
    let text = read(dir, "DEFLEX_PATH.ls");
    let comments: String = text
        .lines()
        .filter_map(|l| l.split_once("! ").map(|(_, c)| c.trim_end_matches(" ;")))
        .collect::<Vec<_>>()
        .join(" ");
    let at = comments
        .find("to the program frame")
        .expect("the UFRAME comment");
    let frame = &comments[at..];
    for key in ["W ", "P ", "R "] {
        assert_eq!(numbers_after(frame, key)[0], 0.0, "{frame}");
    }
    let pos = &text[text.find("/POS").expect("/POS")..];
    let xs = numbers_after(pos, "X =");
    let ys = numbers_after(pos, "Y =");
    let zs = numbers_after(pos, "Z =");
    assert!(xs.len() == ys.len() && ys.len() == zs.len() && !xs.is_empty());
    OperatorView {
        frame_mm: xyz_words(frame, " "),
        positions_mm: (0..xs.len()).map(|i| [xs[i], ys[i], zs[i]]).collect(),
        tolerance_mm: TOLERANCE_MM,
    }
}

/// Yaskawa INFORM: the user frame from the header's `'` comment lines (`Set USER n to the program
/// frame … X … Y … Z … Rx … Ry … Rz …`, one value a line), the `C…=` positions in the order
/// the `MOVJ`/`MOVL` lines use them.
fn inform(dir: &Path) -> OperatorView {
    let text = read(dir, "DEFLEX_PATH.JBI");
    let comments: String = text
        .lines()
        .filter_map(|l| l.strip_prefix('\''))
        .collect::<Vec<_>>()
        .join(" ");
    let at = comments.find("Set USER").expect("the USER comment");
    let frame = &comments[at..];
    for key in ["Rx ", "Ry ", "Rz "] {
        assert_eq!(numbers_after(frame, key)[0], 0.0, "{frame}");
    }
    let positions: std::collections::HashMap<&str, [f64; 3]> = text
        .lines()
        .filter(|l| l.starts_with('C') && l.contains('='))
        .map(|l| {
            let (name, values) = l.split_once('=').unwrap();
            let v: Vec<f64> = values
                .split(',')
                .take(3)
                .map(|t| t.parse().unwrap())
                .collect();
            (name, [v[0], v[1], v[2]])
        })
        .collect();
    let positions_mm = text
        .lines()
        .filter(|l| l.starts_with("MOVJ C") || l.starts_with("MOVL C"))
        .map(|l| positions[l.split_whitespace().nth(1).unwrap()])
        .collect();
    OperatorView {
        frame_mm: xyz_words(frame, " "),
        positions_mm,
        tolerance_mm: TOLERANCE_MM,
    }
}

/// The commanded positions of `compensated_path.csv` (mm, world).
fn commanded_mm(dir: &Path) -> Vec<[f64; 3]> {
    let text = read(dir, "compensated_path.csv");
    let mut lines = text.lines().filter(|l| !l.starts_with('#'));
    let header: Vec<&str> = lines.next().unwrap().split(',').collect();
    let col = |name: &str| header.iter().position(|h| *h == name).unwrap();
    let (cx, cy, cz) = (col("cx_m"), col("cy_m"), col("cz_m"));
    lines
        .map(|l| {
            let v: Vec<&str> = l.split(',').collect();
            [cx, cy, cz].map(|c| v[c].parse::<f64>().unwrap() * 1e3)
        })
        .collect()
}

/// Every row of the table among the program's positions taken into the world with the frame
/// the operator entered, in order; the largest deviation per axis (mm).
fn check(format: &str, robot: &str, view: &OperatorView, table: &[[f64; 3]]) -> f64 {
    let world: Vec<[f64; 3]> = view
        .positions_mm
        .iter()
        .map(|p| [0, 1, 2].map(|i| p[i] + view.frame_mm[i]))
        .collect();
    let deviation =
        |a: &[f64; 3], b: &[f64; 3]| (0..3).map(|i| (a[i] - b[i]).abs()).fold(0.0, f64::max);
    let mut next = 0;
    let mut worst: f64 = 0.0;
    for row in table {
        let found = (next..world.len()).find(|&k| deviation(&world[k], row) <= view.tolerance_mm);
        let Some(k) = found else {
            let nearest = world
                .iter()
                .map(|w| deviation(w, row))
                .fold(f64::INFINITY, f64::min);
            panic!(
                "{robot} {format}: the commanded position {row:?} mm is not in the program with the frame {:?} mm entered from its text (nearest {:.4} µm per axis, tolerance {:.4} µm)",
                view.frame_mm,
                nearest * 1e3,
                view.tolerance_mm * 1e3
            );
        };
        worst = worst.max(deviation(&world[k], row));
        next = k + 1;
    }
    assert!(
        world.len() - table.len() <= 6,
        "{robot} {format}: {} positions in the program for {} rows",
        world.len(),
        table.len()
    );
    worst
}

/// Every built-in robot, every format: the frame taken from the program's text rebuilds the
/// commanded path within 0.1 µm.
#[test]
fn the_frame_an_operator_enters_from_each_program_rebuilds_the_commanded_path() {
    let dir = scratch("operator-frames");
    let readers: [(&str, ProgramReader); 7] = [
        ("inform", inform),
        ("gcode", gcode),
        ("krl", krl),
        ("rapid", rapid),
        ("urscript", urscript),
        ("val3", val3),
        ("fanuc", fanuc),
    ];
    let formats = readers.map(|(f, _)| f).join(",");
    for (robot, _) in deflex_model::BUILTIN_ROBOTS {
        let out = dir.join(robot);
        succeeds(&[
            "compensate",
            "--robot",
            robot,
            "--path",
            concat!(
                env!("CARGO_MANIFEST_DIR"),
                "/../../docs/parts/helix-pocket-g55.ngc"
            ),
            "--format",
            &formats,
            "--out",
            s(&out),
        ]);
        let table = commanded_mm(&out);
        assert!(table.len() > 100, "{robot}: {} rows", table.len());
        for (format, reader) in readers {
            let view = reader(&out.join("programs"));
            let worst = check(format, robot, &view, &table);
            assert!(worst <= view.tolerance_mm, "{robot} {format}: {worst} mm");
        }
    }
    std::fs::remove_dir_all(&dir).unwrap();
}

/// The header of a G-code program names its work offset exactly, and with
/// `gcode.set_work_offset` the program sets it itself (`G10 L2 P2` for the path's `G55`), with
/// the same numbers, and still reads back.
#[test]
fn a_gcode_program_can_set_its_own_work_offset() {
    let dir = scratch("operator-g10");
    let template = dir.join("program.toml");
    std::fs::write(&template, "[gcode]\nset_work_offset = true\n").unwrap();
    let out = dir.join("out");
    succeeds(&[
        "compensate",
        "--robot",
        "kr210-r2700",
        "--path",
        concat!(
            env!("CARGO_MANIFEST_DIR"),
            "/../../docs/parts/helix-pocket-g55.ngc"
        ),
        "--format",
        "gcode",
        "--program-config",
        s(&template),
        "--out",
        s(&out),
    ]);
    let text = read(&out.join("programs"), "deflex_path.gcode");
    let g10 = line_with(&text, "G10 L2");
    assert!(g10.starts_with("G10 L2 P2 X"), "{g10}");
    let summary: serde_json::Value = serde_json::from_str(&read(&out, "summary.json")).unwrap();
    let origin: Vec<f64> = summary["part_origin_m"]
        .as_array()
        .unwrap()
        .iter()
        .map(|v| v.as_f64().unwrap() * 1e3)
        .collect();
    let set = xyz_words(g10, "");
    for i in 0..3 {
        assert!(
            (set[i] - origin[i]).abs() <= 0.00005 + 1e-9,
            "{g10} vs {origin:?}"
        );
    }
    // Before the first motion, and the safe start names the same offset.
    let g10_at = text.find("G10 L2").unwrap();
    assert!(g10_at < text.find("G0 X").unwrap());
    assert!(text.contains("G17 G40 G49 G80 G90 G21 G55"));
    std::fs::remove_dir_all(&dir).unwrap();
}

/// One tool per cell: for every built-in robot, the tool `deflex compensate` compensates and
/// writes (its summary and the KRL `TOOL_DATA` line an operator copies) is the twin cell's,
/// which `deflex model show` prints as the tool the commands use; a robot file with a tool of
/// its own keeps it in its cell and in the compensation.
#[test]
fn the_model_the_cell_and_the_programs_name_one_tool() {
    let dir = scratch("operator-tool");
    for (robot, _) in deflex_model::BUILTIN_ROBOTS {
        let shown = crate::support::json(&["model", "show", "--robot", robot]);
        let cell_tool: Vec<f64> = shown["cell"]["tool_xyz_m"]
            .as_array()
            .unwrap_or_else(|| panic!("{robot}: no cell tool in {shown}"))
            .iter()
            .map(|v| v.as_f64().unwrap())
            .collect();
        let text = succeeds(&["model", "show", "--robot", robot]);
        assert!(
            text.contains("deflex compensate, sim and cell use"),
            "{robot}: {text}"
        );
        let out = dir.join(robot);
        succeeds(&[
            "compensate",
            "--robot",
            robot,
            "--length-mm",
            "5",
            "--format",
            "krl",
            "--out",
            s(&out),
        ]);
        let summary: serde_json::Value = serde_json::from_str(&read(&out, "summary.json")).unwrap();
        let tool: Vec<f64> = summary["tool_xyz_m"]
            .as_array()
            .unwrap()
            .iter()
            .map(|v| v.as_f64().unwrap())
            .collect();
        assert_eq!(tool, cell_tool, "{robot}");
        assert!(
            cell_tool[2] >= 0.1,
            "{robot}: a forming tool, {cell_tool:?}"
        );
        let src = read(&out.join("programs"), "deflex_path.src");
        let line = line_with(&src, "TOOL_DATA[1] must hold");
        let z = numbers_after(line, "Z ")[0];
        assert!(
            (z - cell_tool[2] * 1e3).abs() < 0.00005 + 1e-9,
            "{robot}: {line}"
        );
        assert!(read(&out, "summary.txt").contains("tool (flange to TCP) at"));
    }
    // A robot file with its own 260 mm tool: its cell and the compensation keep it.
    let file = dir.join("ur10e_260.toml");
    succeeds(&["sim", "robot", "--robot", "ur10e", "--out", s(&file)]);
    let text = std::fs::read_to_string(&file).unwrap();
    assert!(text.contains("xyz = [0.0, 0.0, 0.15]"), "{text}");
    std::fs::write(
        &file,
        text.replace("xyz = [0.0, 0.0, 0.15]", "xyz = [0.0, 0.0, 0.26]"),
    )
    .unwrap();
    let shown = crate::support::json(&["model", "show", "--robot", s(&file)]);
    assert_eq!(
        shown["cell"]["tool_xyz_m"][2].as_f64(),
        Some(0.26),
        "{shown}"
    );
    let out = dir.join("file");
    succeeds(&[
        "compensate",
        "--robot",
        s(&file),
        "--length-mm",
        "5",
        "--format",
        "krl",
        "--out",
        s(&out),
    ]);
    let summary: serde_json::Value = serde_json::from_str(&read(&out, "summary.json")).unwrap();
    assert_eq!(summary["tool_xyz_m"][2].as_f64(), Some(0.26));
    assert!(
        summary["tool"]
            .as_str()
            .unwrap()
            .contains("the robot model's tool")
    );
    std::fs::remove_dir_all(&dir).unwrap();
}
