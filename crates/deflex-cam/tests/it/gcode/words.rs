//! One line into words (`deflex_cam::gcode::words`): words, comments, columns, and the errors
//! naming line, column and word.

use deflex_cam::gcode::GcodeErrorKind;
use deflex_cam::gcode::words::split;

#[test]
fn words_comments_and_columns() {
    let l = split("N10 G01 X-.5 Y1. (cut) Z+2 F 1200 ; end", 3).unwrap();
    let texts: Vec<&str> = l.words.iter().map(|w| w.text.as_str()).collect();
    assert_eq!(texts, ["N10", "G01", "X-.5", "Y1.", "Z+2", "F1200"]);
    assert_eq!(l.words[2].value, -0.5);
    assert_eq!(l.words[1].column, 5);
    assert_eq!(l.words[5].column, 28);
    assert_eq!(l.words[1].code10(), Some(10));
    let l = split("g90.1 g17", 1).unwrap();
    assert_eq!(l.words[0].code10(), Some(901));
    assert!(split("%", 1).unwrap().percent);
    assert!(split("/G0 X1", 1).unwrap().block_delete);
}

#[test]
fn errors_name_line_column_and_word() {
    let e = split("G0 X1 (open", 7).unwrap_err();
    assert_eq!((e.line, e.column), (7, 7));
    assert_eq!(e.kind, GcodeErrorKind::Comment);
    let e = split("G0 X1 )", 2).unwrap_err();
    assert_eq!(e.column, 7);
    let e = split("G0 X1..2", 1).unwrap_err();
    assert_eq!((e.column, e.word.as_str()), (4, "X1..2"));
    assert_eq!(e.kind, GcodeErrorKind::BadNumber);
    let e = split("G0 #1=2", 1).unwrap_err();
    assert_eq!((e.column, e.kind), (4, GcodeErrorKind::Syntax));
}
