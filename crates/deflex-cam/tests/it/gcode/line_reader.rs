//! The line reader ([`LineReader`]) hands out, line by line, the moves [`read`] keeps, with the
//! same errors; the options widen the coordinate and feed bounds only as far as deflex's own
//! programs need.

use deflex_cam::gcode::{
    GcodeErrorKind as K, LineMove, LineReader, MAX_COORDINATE_BOUND_MM, MAX_FEED_BOUND_MM_MIN,
    ReadOptions, read,
};

const CORPUS: [&str; 4] = [
    include_str!("../../../../../docs/parts/cone-contour-arcs.nc"),
    include_str!("../../../../../docs/parts/helix-pocket-g55.ngc"),
    include_str!("../../data/inch-incremental.nc"),
    include_str!("../../../../../docs/parts/pyramid-pocket.gcode"),
];

fn line_moves(
    text: &str,
    options: &ReadOptions,
) -> Result<Vec<LineMove>, deflex_cam::gcode::GcodeError> {
    let mut reader = LineReader::new(options)?;
    let mut moves = Vec::new();
    for line in text.lines() {
        moves.extend(reader.read_line(line)?);
    }
    Ok(moves)
}

#[test]
fn the_line_reader_hands_out_the_moves_read_keeps() {
    for text in CORPUS {
        let program = read(text, &ReadOptions::default()).unwrap();
        let moves = line_moves(text, &ReadOptions::default()).unwrap();
        assert_eq!(moves.len(), program.moves.len());
        for (by_line, kept) in moves.iter().zip(&program.moves) {
            assert_eq!(by_line.line, kept.line);
            assert_eq!(by_line.kind, kept.kind);
            assert_eq!(by_line.feed_mm_s, kept.feed_mm_s);
            // Known axes are the kept ones; read fills the start's unknown axes in at the end.
            for axis in 0..3 {
                if let Some(v) = by_line.end_mm[axis] {
                    assert_eq!(v, kept.end_mm[axis]);
                }
                if let Some(v) = by_line.start_mm[axis] {
                    assert_eq!(v, kept.start_mm[axis]);
                }
            }
        }
        // Past the first move, every axis is known.
        assert!(
            moves[1..]
                .iter()
                .all(|m| m.end_mm.iter().all(Option::is_some))
        );
    }
    // The same error, at the same line and word.
    let bad = "G0 X0 Y0 Z0\nG1 X1 F100\nG41 X2\n";
    let kept = read(bad, &ReadOptions::default()).unwrap_err();
    let by_line = line_moves(bad, &ReadOptions::default()).unwrap_err();
    assert_eq!(by_line, kept);
    // Lines after the program's end are ignored.
    let mut reader = LineReader::new(&ReadOptions::default()).unwrap();
    for line in ["G0 X0 Y0 Z0", "G1 X1 F100 M30"] {
        assert!(reader.read_line(line).unwrap().is_some());
    }
    assert!(reader.ended());
    assert_eq!(reader.read_line("G41 X2").unwrap(), None);
}

#[test]
fn coordinate_and_feed_bounds_widen_to_deflex_programs_only() {
    let far = "G0 X0 Y0 Z0\nG1 X20000 F100000\n";
    let e = read(far, &ReadOptions::default()).unwrap_err();
    assert!(e.to_string().contains("outside 0.6 ..= 60000"), "{e}");
    let wide = ReadOptions {
        max_coordinate_mm: MAX_COORDINATE_BOUND_MM,
        max_feed_mm_min: MAX_FEED_BOUND_MM_MIN,
        ..ReadOptions::default()
    };
    let program = read(far, &wide).unwrap();
    assert_eq!(program.points[1].p_mm, [20000.0, 0.0, 0.0]);
    let e = read("G0 X0 Y0 Z0\nG1 X100001 F100\n", &wide).unwrap_err();
    assert!(e.to_string().contains("beyond ±100000 mm"), "{e}");
    let e = read("G0 X0 Y0 Z0\nG1 X1 F120001\n", &wide).unwrap_err();
    assert!(e.to_string().contains("outside 0.6 ..= 120000"), "{e}");
    let e = read(
        "G0 X0 Y0 Z0\nG2 X0 Y0 I20000 J0 F100\n",
        &ReadOptions::default(),
    )
    .unwrap_err();
    assert!(e.to_string().contains("beyond ±10000 mm"), "{e}");
    for options in [
        ReadOptions {
            max_coordinate_mm: MAX_COORDINATE_BOUND_MM * 1.01,
            ..ReadOptions::default()
        },
        ReadOptions {
            max_feed_mm_min: f64::NAN,
            ..ReadOptions::default()
        },
    ] {
        assert!(matches!(
            read(far, &options).unwrap_err().kind,
            K::Option { .. }
        ));
        assert!(LineReader::new(&options).is_err());
    }
}
