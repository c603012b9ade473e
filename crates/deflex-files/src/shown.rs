//! User text in messages with its control characters escaped: a label or a path holding an
//! escape sequence or a carriage return must not rewrite the operator's terminal.

use std::borrow::Cow;
use std::fmt::Write as _;
use std::path::Path;

/// `text` with every control character escaped (`\n`, `\r`, `\t`, `\u{1b}`, …); borrowed when
/// there is none.
pub fn shown(text: &str) -> Cow<'_, str> {
    escape(text, false)
}

/// A message for the terminal: like [`shown`] but line breaks are kept (messages of several
/// lines are written so on purpose; a line break inside a label is refused where the label is
/// read).
pub fn shown_text(text: &str) -> Cow<'_, str> {
    escape(text, true)
}

/// A path for a message, its control characters escaped.
pub fn shown_path(path: &Path) -> String {
    shown(&path.display().to_string()).into_owned()
}

fn escape(text: &str, keep_newlines: bool) -> Cow<'_, str> {
    let bad = |c: char| c.is_control() && !(keep_newlines && c == '\n');
    if !text.chars().any(bad) {
        return Cow::Borrowed(text);
    }
    let mut out = String::with_capacity(text.len() + 8);
    for c in text.chars() {
        if !bad(c) {
            out.push(c);
            continue;
        }
        match c {
            '\n' => out.push_str("\\n"),
            '\r' => out.push_str("\\r"),
            '\t' => out.push_str("\\t"),
            _ => {
                let _ = write!(out, "\\u{{{:x}}}", c as u32);
            }
        }
    }
    Cow::Owned(out)
}
