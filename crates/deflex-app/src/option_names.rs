//! How a front end names its options in the messages of a workflow: a check that depends on the
//! data (two set-ups and none chosen, orientations asked for and none measured, a seed that
//! tilts the tool) is made once, in the workflow, and tells the user what to give in the words of
//! the front end they called it from — the command line's flags (`--setup`, `--target probe2`,
//! `--seed-deg`) or Python's keywords (`setup=`, `target="probe2"`, `seed_q`).
//!
//! An option is named by its Python keyword (`sigma_rad`, `seed_q`); the command line's flag is
//! the keyword with dashes (`--sigma-rad`), except where the flag carries another unit or word
//! than the keyword ([`CLI_FLAGS`]: `seed_q` is `--seed-deg`). Every workflow that names an
//! option in a message takes an [`OptionNames`] and names it through it.

/// The command-line flags not spelt as their Python keyword with dashes: `(keyword, flag)`. The
/// flag carries the unit the command line takes (mm, degrees) where the keyword carries SI, or
/// another word.
pub const CLI_FLAGS: [(&str, &str); 7] = [
    ("part_xyz_m", "--part-xyz-mm"),
    ("seed_q", "--seed-deg"),
    ("length_m", "--length-mm"),
    ("max_segment_m", "--max-segment-mm"),
    ("feed_m_s", "--feed-mm-s"),
    ("fk_tolerance_m", "--fk-tolerance-mm"),
    ("settings", "--program-config"),
];

/// The front end a workflow was called from, for the option names in its messages.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum OptionNames {
    /// The command-line tool: `--sigma-rad`, `--target probe2`.
    Cli,
    /// The Python package: `sigma_rad`, `target="probe2"`.
    Python,
}

impl OptionNames {
    /// The option `keyword` (Python's spelling, `sigma_rad`) as this front end names it:
    /// `--sigma-rad` or `sigma_rad` (`seed_q`: `--seed-deg` or `seed_q`, see [`CLI_FLAGS`]).
    pub fn name(self, keyword: &str) -> String {
        match self {
            OptionNames::Cli => match CLI_FLAGS.iter().find(|(k, _)| *k == keyword) {
                Some((_, flag)) => (*flag).to_string(),
                None => format!("--{}", keyword.replace('_', "-")),
            },
            OptionNames::Python => keyword.to_string(),
        }
    }

    /// How to give the option `keyword`, without its value: `--setup` or `setup=`.
    pub fn give(self, keyword: &str) -> String {
        match self {
            OptionNames::Cli => self.name(keyword),
            OptionNames::Python => format!("{keyword}="),
        }
    }

    /// How to give the option `keyword` the text `value`: `--target probe2` or
    /// `target="probe2"`.
    pub fn give_text(self, keyword: &str, value: &str) -> String {
        match self {
            OptionNames::Cli => format!("{} {value}", self.name(keyword)),
            OptionNames::Python => format!("{keyword}=\"{value}\""),
        }
    }

    /// How to turn on the switch `keyword`: `--ignore-fk-check` or `ignore_fk_check=True`.
    pub fn switch(self, keyword: &str) -> String {
        match self {
            OptionNames::Cli => self.name(keyword),
            OptionNames::Python => format!("{keyword}=True"),
        }
    }

    /// What a message about the option `keyword` starts with where the front end names the
    /// option first: nothing on the command line (its messages name the file first), `setup: `
    /// in Python (every keyword error names its keyword first).
    pub fn subject(self, keyword: &str) -> String {
        match self {
            OptionNames::Cli => String::new(),
            OptionNames::Python => format!("{keyword}: "),
        }
    }

    /// The option `keyword` with its `value`, named before an error about that value where the
    /// front end does so: `--data m.csv` on the command line; nothing in Python (the call is in
    /// the traceback).
    pub fn context(self, keyword: &str, value: &str) -> Option<String> {
        match self {
            OptionNames::Cli => Some(format!("{} {value}", self.name(keyword))),
            OptionNames::Python => None,
        }
    }
}
