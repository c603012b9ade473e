//! How a front end names its options in the messages of a workflow: a check that depends on the
//! data (two set-ups and none chosen, orientations asked for and none measured) is made once, in
//! the workflow, and tells the user what to give in the words of the front end they called it
//! from — the command line's flags (`--setup`, `--target probe2`) or Python's keywords
//! (`setup=`, `target="probe2"`).

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
    /// `--sigma-rad` or `sigma_rad`.
    pub fn name(self, keyword: &str) -> String {
        match self {
            OptionNames::Cli => format!("--{}", keyword.replace('_', "-")),
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

    /// What a message about the option `keyword` starts with where the front end names the
    /// option first: nothing on the command line (its messages name the file first), `setup: `
    /// in Python (every keyword error names its keyword first).
    pub fn subject(self, keyword: &str) -> String {
        match self {
            OptionNames::Cli => String::new(),
            OptionNames::Python => format!("{keyword}: "),
        }
    }
}
