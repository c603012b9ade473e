//! Names (program, module, variable, file) made valid for each language.
//!
//! * **KRL**: at most 24 characters; letters, digits, `_` and `$`; not starting with a digit
//!   (KUKA *Quickguide KRL syntax, KSS 8.x*, "Names in KRL"); `$` is left to system variables.
//! * **RAPID**: at most 32 characters; a letter, then letters, digits and `_` (ABB's RAPID
//!   kernel manual; the limit could not be re-read from a public copy while writing this, so the
//!   exporters also keep their own names short).
//! * **VAL3**: a letter, then letters, digits and `_`; at most 15 characters. This is a
//!   conservative choice: the limit could not be confirmed from a public copy of the VAL3
//!   manual, and SRS rejects names it does not accept at import, so shorter is safer.
//! * **URScript**: Python-like identifiers (a letter, then letters, digits and `_`); at most 32
//!   characters (our bound).
//! * **FANUC TP**: a letter, then letters, digits and `_`, written in upper case; at most 16
//!   characters (our bound: R-30iB takes up to 36, older controllers 8 for names shown on the
//!   teach pendant; deflex keeps parts' names `NAME_P01` within 16).
//! * **Yaskawa INFORM**: a letter, then letters, digits and `_`, written in upper case; at most
//!   32 characters (DX100 and later; the NX100 took 8).
//! * **G-code files**: letters, digits, `_` and `-`; at most 64 characters.
//!
//! Anything else is replaced by `_`; a name that does not start with a letter gets a `p` in
//! front; reserved words get `_prog` appended.

use crate::program::error::ProgramError;

/// A language's naming rule.
#[derive(Clone, Copy, Debug)]
pub struct NameRule {
    /// Language, for messages.
    pub language: &'static str,
    /// Longest name.
    pub max_len: usize,
    /// Extra characters allowed besides ASCII letters, digits and `_`.
    pub extra: &'static [char],
    /// Words the name must not be (compared case-insensitively).
    pub reserved: &'static [&'static str],
}

/// KUKA KRL.
pub const KRL: NameRule = NameRule {
    language: "KRL",
    max_len: 24,
    extra: &[],
    reserved: &[
        "DEF", "END", "DEFDAT", "ENDDAT", "DECL", "LIN", "PTP", "CIRC", "IF", "FOR", "WHILE",
        "LOOP", "GLOBAL", "PUBLIC", "INT", "REAL", "BOOL", "FRAME", "POS", "E6POS",
    ],
};

/// ABB RAPID.
pub const RAPID: NameRule = NameRule {
    language: "RAPID",
    max_len: 32,
    extra: &[],
    reserved: &[
        "MODULE",
        "ENDMODULE",
        "PROC",
        "ENDPROC",
        "CONST",
        "PERS",
        "VAR",
        "main",
        "robtarget",
        "tooldata",
        "wobjdata",
        "speeddata",
        "zonedata",
        "tool0",
        "wobj0",
    ],
};

/// Stäubli VAL3.
pub const VAL3: NameRule = NameRule {
    language: "VAL3",
    max_len: 15,
    extra: &[],
    reserved: &[
        "begin", "end", "start", "stop", "movel", "movej", "world", "flange", "num", "point",
        "tool", "frame", "mdesc", "trsf",
    ],
};

/// URScript.
pub const URSCRIPT: NameRule = NameRule {
    language: "URScript",
    max_len: 32,
    extra: &[],
    reserved: &[
        "def", "end", "if", "else", "while", "for", "return", "thread", "global", "movel", "movej",
        "True", "False",
    ],
};

/// FANUC TP program names (upper case is applied by the writer).
pub const FANUC: NameRule = NameRule {
    language: "FANUC TP",
    max_len: 16,
    extra: &[],
    reserved: &[
        "CALL", "END", "JMP", "LBL", "IF", "SELECT", "WAIT", "PAYLOAD",
    ],
};

/// Yaskawa INFORM job names (upper case is applied by the writer).
pub const INFORM: NameRule = NameRule {
    language: "Yaskawa INFORM",
    max_len: 32,
    extra: &[],
    reserved: &["NOP", "END", "CALL", "JOB", "MOVJ", "MOVL", "TIMER", "RET"],
};

/// G-code file names.
pub const GCODE_FILE: NameRule = NameRule {
    language: "G-code file name",
    max_len: 64,
    extra: &['-'],
    reserved: &[],
};

fn allowed(c: char, rule: &NameRule) -> bool {
    c.is_ascii_alphanumeric() || c == '_' || rule.extra.contains(&c)
}

/// `name` made valid under `rule` (see the module documentation).
pub fn sanitize(name: &str, rule: &NameRule) -> String {
    let mut out: String = name
        .trim()
        .chars()
        .map(|c| if allowed(c, rule) { c } else { '_' })
        .collect();
    if !out.starts_with(|c: char| c.is_ascii_alphabetic()) {
        out.insert(0, 'p');
    }
    out.truncate(rule.max_len);
    if rule.reserved.iter().any(|r| r.eq_ignore_ascii_case(&out)) {
        out.truncate(rule.max_len - 5);
        out.push_str("_prog");
    }
    out
}

/// Whether `name` is already valid under `rule`.
pub fn is_valid(name: &str, rule: &NameRule) -> bool {
    !name.is_empty()
        && name.len() <= rule.max_len
        && name.starts_with(|c: char| c.is_ascii_alphabetic())
        && name.chars().all(|c| allowed(c, rule))
        && !rule.reserved.iter().any(|r| r.eq_ignore_ascii_case(name))
}

/// A user-given identifier (settings) must already be valid: it names something on the
/// controller, so it is refused rather than silently changed.
pub(crate) fn check_identifier(
    name: &str,
    rule: NameRule,
    key: &str,
    source: &str,
) -> Result<(), ProgramError> {
    if is_valid(name, &rule) {
        Ok(())
    } else {
        Err(ProgramError::Settings {
            source_name: source.to_string(),
            key: key.to_string(),
            message: format!(
                "\"{name}\" is not a valid {} name: a letter, then letters, digits or _, at most {} characters, not a reserved word",
                rule.language, rule.max_len
            ),
        })
    }
}
