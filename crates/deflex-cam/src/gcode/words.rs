//! One line of G-code into words: comments (`( … )` and `;` to the end of the line) removed, a
//! block-delete `/` recognised, every word a letter and a number (`G01`, `X-.5`, `F1200.`,
//! `G90.1`), spaces allowed between and inside words as Fanuc controls allow them.

use crate::gcode::error::{GcodeError, GcodeErrorKind};

/// One word of a line.
#[derive(Clone, Debug, PartialEq)]
pub(crate) struct Word {
    /// Upper-case letter.
    pub letter: char,
    /// The number.
    pub value: f64,
    /// As written (letter and number, without spaces), for messages.
    pub text: String,
    /// 1-based column of the letter.
    pub column: usize,
}

impl Word {
    /// The code of a G or M word times ten (`G90.1` → 901, `G1` → 10), when it is a plain
    /// non-negative code with at most one decimal.
    pub fn code10(&self) -> Option<u32> {
        let scaled = self.value * 10.0;
        (self.value >= 0.0 && self.value < 10_000.0 && (scaled - scaled.round()).abs() < 1e-9)
            .then_some(scaled.round() as u32)
    }

    pub fn error(&self, line: usize, kind: GcodeErrorKind) -> GcodeError {
        GcodeError {
            line,
            column: self.column,
            word: self.text.clone(),
            kind,
        }
    }
}

/// A line split into words.
#[derive(Clone, Debug, Default, PartialEq)]
pub(crate) struct Line {
    /// The words, in order.
    pub words: Vec<Word>,
    /// The line starts with a block-delete `/`.
    pub block_delete: bool,
    /// The line is a `%` tape marker.
    pub percent: bool,
}

fn excerpt(text: &str) -> String {
    text.chars().take(24).collect()
}

/// Split `raw` (1-based line `line`) into words.
pub(crate) fn split(raw: &str, line: usize) -> Result<Line, GcodeError> {
    let chars: Vec<char> = raw.chars().collect();
    let err = |column: usize, word: String, kind| GcodeError {
        line,
        column,
        word,
        kind,
    };
    // Comments out: keep (column, char) of the code.
    let mut code: Vec<(usize, char)> = Vec::with_capacity(chars.len());
    let mut depth = 0usize;
    let mut open_column = 0;
    for (i, &c) in chars.iter().enumerate() {
        match c {
            ';' if depth == 0 => break,
            '(' => {
                if depth == 0 {
                    open_column = i + 1;
                }
                depth += 1;
            }
            ')' => {
                if depth == 0 {
                    return Err(err(i + 1, ")".into(), GcodeErrorKind::Comment));
                }
                depth -= 1;
            }
            _ if depth == 0 => code.push((i + 1, c)),
            _ => {}
        }
    }
    if depth != 0 {
        return Err(err(
            open_column,
            chars[open_column.saturating_sub(1)..]
                .iter()
                .take(24)
                .collect(),
            GcodeErrorKind::Comment,
        ));
    }
    let code: Vec<(usize, char)> = code
        .into_iter()
        .filter(|(_, c)| !c.is_whitespace())
        .collect();
    let mut out = Line::default();
    let mut i = 0;
    if let Some((_, '%')) = code.first() {
        out.percent = true;
        return Ok(out);
    }
    if let Some((_, '/')) = code.first() {
        out.block_delete = true;
        i = 1;
    }
    while i < code.len() {
        let (column, c) = code[i];
        let letter = c.to_ascii_uppercase();
        if !letter.is_ascii_alphabetic() {
            let rest: String = code[i..].iter().map(|(_, c)| *c).collect();
            return Err(err(column, excerpt(&rest), GcodeErrorKind::Syntax));
        }
        i += 1;
        let start = i;
        while i < code.len() && (code[i].1.is_ascii_digit() || matches!(code[i].1, '.' | '-' | '+'))
        {
            i += 1;
        }
        let number: String = code[start..i].iter().map(|(_, c)| *c).collect();
        let text = format!("{letter}{number}");
        // Rust's float syntax is a superset of G-code's (`1.`, `.5`, `-.5`, `+2` parse); `inf`
        // and `nan` cannot reach here (letters end the number).
        let value = number
            .parse::<f64>()
            .ok()
            .filter(|v| v.is_finite())
            .ok_or_else(|| err(column, excerpt(&text), GcodeErrorKind::BadNumber))?;
        out.words.push(Word {
            letter,
            value,
            text,
            column,
        });
    }
    Ok(out)
}

#[cfg(test)]
mod tests {
    use super::*;

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
}
