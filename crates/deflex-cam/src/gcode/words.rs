//! One line of G-code into words: comments (`( … )` and `;` to the end of the line) removed, a
//! block-delete `/` recognised, every word a letter and a number (`G01`, `X-.5`, `F1200.`,
//! `G90.1`), spaces allowed between and inside words as Fanuc controls allow them.

use crate::gcode::error::{GcodeError, GcodeErrorKind};

/// One word of a line.
#[derive(Clone, Debug, PartialEq)]
pub struct Word {
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

    /// An error of kind `kind` at this word of 1-based line `line` (its column and text).
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
pub struct Line {
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

/// Split `raw` (1-based line `line`) into words; an error names the line, the column and the
/// word (an unclosed or stray comment parenthesis, a malformed number, a character that is no
/// word).
pub fn split(raw: &str, line: usize) -> Result<Line, GcodeError> {
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
