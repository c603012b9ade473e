//! The corpus against its analytic geometry.

use deflex_cam::gcode::{GcodePoint, MoveKind, NoteKind, Plane, ReadOptions, WorkOffset, read};
use std::f64::consts::PI;

const CONE: &str = include_str!("../../../../../docs/parts/cone-contour-arcs.nc");
const HELIX: &str = include_str!("../../../../../docs/parts/helix-pocket-g55.ngc");
const INCH: &str = include_str!("../../data/inch-incremental.nc");
const POCKET: &str = include_str!("../../../../../docs/parts/pyramid-pocket.gcode");

/// Line numbers (1-based) of the text lines containing `needle`.
fn lines_with(text: &str, needle: &str) -> Vec<usize> {
    text.lines()
        .enumerate()
        .filter(|(_, l)| l.contains(needle))
        .map(|(i, _)| i + 1)
        .collect()
}

fn points_of(points: &[GcodePoint], line: usize) -> Vec<[f64; 3]> {
    points
        .iter()
        .filter(|p| p.line == line)
        .map(|p| p.p_mm)
        .collect()
}

fn norm(v: [f64; 3]) -> f64 {
    (v[0] * v[0] + v[1] * v[1] + v[2] * v[2]).sqrt()
}

fn sub(a: [f64; 3], b: [f64; 3]) -> [f64; 3] {
    [a[0] - b[0], a[1] - b[1], a[2] - b[2]]
}

/// Every chord of consecutive points `ps` (after `from`) stays within `tol` of the circle of
/// radius `r` about `c` in the plane of axes (i, j): the chord's midpoint is at least `r − tol`
/// from the centre; and at least one chord uses most of the tolerance (no needless points).
fn check_chords(
    from: [f64; 3],
    ps: &[[f64; 3]],
    c: [f64; 3],
    r: f64,
    (i, j): (usize, usize),
    tol: f64,
) {
    let mut previous = from;
    let mut worst: f64 = 0.0;
    for p in ps {
        let mid = [
            (previous[i] + p[i]) / 2.0 - c[i],
            (previous[j] + p[j]) / 2.0 - c[j],
        ];
        let sagitta = r - mid[0].hypot(mid[1]);
        assert!(sagitta <= tol + 1e-9, "sagitta {sagitta} > {tol}");
        worst = worst.max(sagitta);
        previous = *p;
    }
    assert!(worst > 0.5 * tol, "chords far finer than needed: {worst}");
}

#[test]
fn fanuc_cone_contours_lie_on_their_circles() {
    let options = ReadOptions::default();
    let tol = options.chord_tolerance_mm;
    let program = read(CONE, &options).unwrap();
    assert_eq!(program.number, Some(2301));
    assert_eq!(program.work_offset, Some(WorkOffset::G54));
    let words: Vec<(&str, &NoteKind)> = program
        .notes
        .iter()
        .map(|n| (n.word.as_str(), &n.kind))
        .collect();
    assert!(words.contains(&("T1", &NoteKind::ToolIgnored)), "{words:?}");
    assert!(words.contains(&("M6", &NoteKind::ToolIgnored)));
    assert!(words.contains(&("M5", &NoteKind::SpindleIgnored)));
    assert!(words.contains(&("M30", &NoteKind::ProgramEnd)));
    // The start: X25 Y0 from the first rapid, Z5 from the second (filled back, noted).
    assert_eq!(program.points[0].p_mm, [25.0, 0.0, 5.0]);
    assert!(words.contains(&(
        "Z",
        &NoteKind::StartAxisFilled {
            axis: 'Z',
            value_mm: 5.0
        }
    )));
    // Lead-in: a clockwise quarter circle about +Y in the ZX plane, centre (25, 0, 0), r 5.
    let lead = lines_with(CONE, "G18 G2 X20.")[0];
    let ps = points_of(&program.points, lead);
    assert_eq!(*ps.last().unwrap(), [20.0, 0.0, 0.0]);
    let mut angle = 0.0; // atan2(x − 25, z): 0 at the start, −π/2 at the end
    for p in &ps {
        assert!(
            (norm(sub(*p, [25.0, 0.0, 0.0])) - 5.0).abs() < 1e-9,
            "{p:?}"
        );
        assert_eq!(p[1], 0.0);
        let a = (p[0] - 25.0).atan2(p[2]);
        assert!(a < angle, "clockwise about +Y: {a} after {angle}");
        angle = a;
    }
    check_chords([25.0, 0.0, 5.0], &ps, [25.0, 0.0, 0.0], 5.0, (0, 2), tol);
    // Twelve levels: each a full counter-clockwise circle of radius 20 + z at its z.
    let circles = lines_with(CONE, "G3 X");
    assert_eq!(circles.len(), 12);
    let mut expected_length = PI / 2.0 * 5.0;
    for (k, line) in circles.iter().enumerate() {
        let z = -0.5 * (k + 1) as f64;
        let r = 20.0 + z;
        let ps = points_of(&program.points, *line);
        let expected_steps = (2.0 * PI / (2.0 * (1.0 - tol / r).acos())).ceil() as usize;
        assert_eq!(ps.len(), expected_steps, "level {k}");
        let mut turned = 0.0;
        let mut previous = [r, 0.0, z];
        for p in &ps {
            assert!(
                (p[0].hypot(p[1]) - r).abs() < 1e-9 && (p[2] - z).abs() < 1e-12,
                "{p:?}"
            );
            let step = (previous[0] * p[1] - previous[1] * p[0])
                .atan2(previous[0] * p[0] + previous[1] * p[1]);
            assert!(step > 0.0, "counter-clockwise");
            turned += step;
            previous = *p;
        }
        assert!((turned - 2.0 * PI).abs() < 1e-9, "{turned}");
        check_chords([r, 0.0, z], &ps, [0.0; 3], r, (0, 1), tol);
        expected_length += 0.5 * 2f64.sqrt() + 2.0 * PI * r;
    }
    expected_length += 11.0; // the retract from Z-6 to Z5
    assert_eq!(
        *program.points.last().map(|p| &p.p_mm).unwrap(),
        [14.0, 0.0, 5.0]
    );
    // A chord of sagitta s on radius r is shorter than its arc by about s / (3 r) of it:
    // at most 0.005 / (3 · 14) relative here.
    let length = program.length_mm();
    let shortest = expected_length * (1.0 - 1.05 * tol / (3.0 * 14.0));
    assert!(
        length < expected_length && length > shortest,
        "{length} vs {expected_length}"
    );
    // Feeds: the lead-in at F300, the contours at F600 (mm/min → mm/s), the retract rapid.
    assert_eq!(
        points_of(&program.points, lead).len(),
        program
            .points
            .iter()
            .filter(|p| p.feed_mm_s == Some(5.0))
            .count()
    );
    assert!(
        program
            .points
            .iter()
            .filter(|p| p.feed_mm_s == Some(10.0))
            .count()
            > 1000
    );
    assert_eq!(program.points.last().unwrap().feed_mm_s, None);
    // The typed moves: the lead-in is a clockwise ZX arc of −90°.
    let m = program.moves.iter().find(|m| m.line == lead).unwrap();
    match m.kind {
        MoveKind::Arc {
            center_mm,
            plane,
            counter_clockwise,
            sweep_rad,
        } => {
            assert_eq!(center_mm, [25.0, 0.0, 0.0]);
            assert_eq!(plane, Plane::Zx);
            assert!(!counter_clockwise);
            assert!((sweep_rad + PI / 2.0).abs() < 1e-12);
        }
        other => panic!("{other:?}"),
    }
}

#[test]
fn linuxcnc_helix_and_r_corners_in_g55() {
    let options = ReadOptions {
        chord_tolerance_mm: 0.002,
        ..ReadOptions::default()
    };
    let program = read(HELIX, &options).unwrap();
    assert_eq!(program.work_offset, Some(WorkOffset::G55));
    assert!(
        program
            .notes
            .iter()
            .any(|n| n.word == "T2" && n.kind == NoteKind::ToolIgnored)
    );
    assert_eq!(program.points[0].p_mm, [15.0, 0.0, 5.0]);
    // The helix: radius 15, four counter-clockwise turns, z falling 0.5 mm per turn from 0.5.
    let helix = lines_with(HELIX, "P4")[0];
    let ps = points_of(&program.points, helix);
    let mut unwrapped = 0.0;
    let mut previous = [15.0, 0.0, 0.5];
    for p in &ps {
        assert!((p[0].hypot(p[1]) - 15.0).abs() < 1e-9);
        unwrapped += (previous[0] * p[1] - previous[1] * p[0])
            .atan2(previous[0] * p[0] + previous[1] * p[1]);
        let z = 0.5 - 0.5 * unwrapped / (2.0 * PI);
        assert!((p[2] - z).abs() < 1e-9, "{} vs {z}", p[2]);
        previous = *p;
    }
    assert!((unwrapped - 8.0 * PI).abs() < 1e-9);
    assert_eq!(*ps.last().unwrap(), [15.0, 0.0, -1.5]);
    // The R corners: radius 5 about the rounded square's corner centres.
    for (needle, centre) in [
        ("X-15 Y10 R5", [-10.0, 10.0]),
        ("X-10 Y-15 R5", [-10.0, -10.0]),
        ("X15 Y-10 R5", [10.0, -10.0]),
    ] {
        let ps = points_of(&program.points, lines_with(HELIX, needle)[0]);
        assert!(ps.len() > 5, "{needle}");
        for p in &ps {
            assert!(
                ((p[0] - centre[0]).hypot(p[1] - centre[1]) - 5.0).abs() < 1e-9,
                "{needle}: {p:?}"
            );
        }
    }
    // R−6 from (15, 0) to (5, 0), clockwise, the long way: centre (10, −√11), passes y = −√11 − 6.
    let ps = points_of(&program.points, lines_with(HELIX, "R-6")[0]);
    let c = [10.0, -(11f64.sqrt())];
    let lowest = ps.iter().map(|p| p[1]).fold(f64::MAX, f64::min);
    assert!((lowest - (c[1] - 6.0)).abs() < 0.002 + 1e-9, "{lowest}");
    for p in &ps {
        assert!(((p[0] - c[0]).hypot(p[1] - c[1]) - 6.0).abs() < 1e-9);
    }
    assert!(
        program
            .notes
            .iter()
            .any(|n| n.word == "M2" && n.kind == NoteKind::ProgramEnd)
    );
}

#[test]
fn inch_incremental_program_in_millimetres() {
    let program = read(INCH, &ReadOptions::default()).unwrap();
    assert_eq!(program.number, Some(42));
    let inch = 25.4;
    let expect = |p: [f64; 3], q: [f64; 3]| {
        assert!(
            norm(sub(p, q.map(|v| v * inch))) < 1e-9,
            "{p:?} vs {q:?} in"
        );
    };
    expect(program.points[0].p_mm, [1.0, 1.0, 0.2]);
    expect(program.points[1].p_mm, [1.0, 1.0, 0.0]);
    expect(program.points[2].p_mm, [1.5, 1.0, 0.0]);
    expect(program.points[3].p_mm, [1.5, 0.75, 0.0]);
    // F20 in/min = 8.4667 mm/s.
    assert!((program.points[1].feed_mm_s.unwrap() - 20.0 * inch / 60.0).abs() < 1e-12);
    // The YZ arc (block-delete line, executed): clockwise about +X, centre Y1.25 Z0, r 0.5 in.
    let arc_line = lines_with(INCH, "G19 G2")[0];
    let ps = points_of(&program.points, arc_line);
    for p in &ps {
        assert!((p[0] - 1.5 * inch).abs() < 1e-12);
        assert!(((p[1] - 1.25 * inch).hypot(p[2]) - 0.5 * inch).abs() < 1e-9);
        assert!(p[2] >= -1e-12, "the arc rises over the top: {p:?}");
    }
    expect(*ps.last().unwrap(), [1.5, 1.25, 0.5]);
    expect(program.points.last().unwrap().p_mm, [1.5, 1.25, 1.0]);
    let kinds: Vec<&NoteKind> = program.notes.iter().map(|n| &n.kind).collect();
    for kind in [
        NoteKind::DwellIgnored,
        NoteKind::BlockDeleteExecuted,
        NoteKind::HomeIgnored,
        NoteKind::ProgramEnd,
    ] {
        assert!(kinds.contains(&&kind), "{kind:?} in {kinds:?}");
    }
    // Nothing after M30 is read (N11 G0 X99).
    assert!(program.points.iter().all(|p| p.p_mm[0] < 50.0));
}

#[test]
fn the_shipped_pocket_starts_at_its_first_move() {
    let program = read(POCKET, &ReadOptions::default()).unwrap();
    // No start at the part origin: the first point is the first commanded position.
    assert_eq!(program.points[0].p_mm, [15.0, 0.0, 2.0]);
    assert_eq!(program.work_offset, None);
    assert!(
        program
            .points
            .iter()
            .all(|p| p.p_mm.iter().all(|v| v.is_finite()))
    );
}
