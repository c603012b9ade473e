//! What is refused, with the line, the column and the word.

use deflex_cam::gcode::{GcodeErrorKind as K, ReadOptions, read};

fn refused(text: &str) -> deflex_cam::gcode::GcodeError {
    read(text, &ReadOptions::default()).unwrap_err()
}

#[test]
fn compensation_and_unsupported_words_are_named() {
    let start = "G21 G90 G54\nG0 X0 Y0 Z5\n";
    for (line, word, column, kind) in [
        (
            "G1 G41 D1 X10 F500",
            "G41",
            4,
            K::ToolCompensation { which: "radius" },
        ),
        (
            "G43 H1 Z50",
            "G43",
            1,
            K::ToolCompensation { which: "length" },
        ),
        ("G0 H2 Z4", "H2", 4, K::ToolCompensation { which: "length" }),
        (
            "G81 Z-2 R1 F100",
            "G81",
            1,
            K::Unsupported {
                reason: "canned cycles (G81-G89): let the CAM system write them out",
            },
        ),
        (
            "G1 X1 A90 F100",
            "A90",
            7,
            K::Unsupported {
                reason: "rotary or extra axes: deflex reads 3-axis programs (X Y Z)",
            },
        ),
        (
            "G53 G0 Z0",
            "G53",
            1,
            K::Unsupported {
                reason: "G53 (machine coordinates): write the program in a work offset",
            },
        ),
        (
            "M98 P100",
            "M98",
            1,
            K::Unsupported {
                reason: "subprograms (M98/M99): let the CAM system write the program out",
            },
        ),
        ("G0 X1 X2", "X2", 7, K::Conflict { other: "X1".into() }),
        ("G0 G1 X2", "G1", 4, K::Conflict { other: "G0".into() }),
    ] {
        let e = refused(&format!("{start}{line}\n"));
        assert_eq!(
            (e.line, e.column, e.word.as_str()),
            (3, column, word),
            "{line}: {e}"
        );
        assert_eq!(e.kind, kind, "{line}");
        let message = e.to_string();
        assert!(
            message.starts_with(&format!("line 3, column {column}, `{word}`")),
            "{message}"
        );
    }
    let e = refused("G0 X0 Y0 Z0\nG1 G41 X1 F100\n");
    assert!(e.to_string().contains("compensation off (G40, G49)"), "{e}");
}

#[test]
fn geometry_and_state_errors() {
    let cases: [(&str, usize, &str); 9] = [
        ("G0 X0 Y0 Z0\nG1 X5\n", 2, "before any F"),
        ("G91 G0 X5\n", 1, "position on X is not known"),
        (
            "G0 X10 Y0\nG2 X0 Y10 I-10 J0 F100\n",
            2,
            "position on Z is not known",
        ),
        (
            "G0 X10 Y0 Z0\nG3 X0 Y10.5 I-10 J0 F100\n",
            2,
            "radii differ by 0.5000 mm",
        ),
        ("G0 X10 Y0 Z0\nG3 X0 Y10 I-10 K1 F100\n", 2, "normal"),
        (
            "G0 X0 Y0 Z0\nG2 X10 Y0 R4 F100\n",
            2,
            "smaller than half the chord",
        ),
        ("G0 X0 Y0 Z0\nG1 X1 F100000\n", 2, "outside 0.6 ..= 60000"),
        (
            "G54 G0 X0 Y0 Z0\nG55 G0 X1\n",
            2,
            "second work offset (G55) after G54",
        ),
        ("G0 X0 Y0 Z0\nG1 X20000 F100\n", 2, "beyond ±10000 mm"),
    ];
    for (text, line, needle) in cases {
        let e = refused(text);
        assert_eq!(e.line, line, "{text}: {e}");
        assert!(e.to_string().contains(needle), "{text}: {e}");
    }
    assert_eq!(refused("(only a comment)\n").kind, K::NoMove);
    assert_eq!(refused("G0 X1 (open\n").kind, K::Comment);
    // Bounds: points and options.
    let many = ReadOptions {
        max_points: 100,
        ..ReadOptions::default()
    };
    let e = read("G0 X10 Y0 Z0\nG3 X10 Y0 I-10 J0 F100\n", &many).unwrap_err();
    assert_eq!(e.kind, K::TooManyPoints { max: 100 });
    let bad = ReadOptions {
        chord_tolerance_mm: 0.0,
        ..ReadOptions::default()
    };
    assert!(matches!(
        read("G0 X1\n", &bad).unwrap_err().kind,
        K::Option { .. }
    ));
    let long = format!("G0 X1 ({})\n", "x".repeat(5000));
    assert!(matches!(refused(&long).kind, K::TooLarge { .. }));
}
