//! A file's header comments: which robot it was made for.

use crate::measurements::MAX_LABEL_CHARS;
use deflex_model::Robot;

/// What a file's header comments say about the robot it was made for.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct FileHeader {
    /// `# robot: <name>`.
    pub robot: Option<String>,
    /// `# geometry: <fingerprint>` (`Robot::geometry_fingerprint`).
    pub geometry: Option<String>,
    /// Other comment lines before the column names (without the leading `#`), in order.
    pub notes: Vec<String>,
}

impl FileHeader {
    /// The header naming `robot` and its geometry fingerprint.
    pub fn for_robot(robot: &Robot) -> FileHeader {
        FileHeader {
            robot: Some(one_line(&robot.name)),
            geometry: Some(robot.geometry_fingerprint()),
            notes: Vec::new(),
        }
    }

    /// Add a free comment line (written after the robot lines).
    pub fn with_note(mut self, note: impl Into<String>) -> FileHeader {
        self.notes.push(one_line(&note.into()));
        self
    }

    /// The comment lines, each ending in a newline (empty when there is nothing to say).
    pub fn render(&self) -> String {
        let mut out = String::new();
        for note in &self.notes {
            out.push_str(&format!("# {note}\n"));
        }
        if let Some(robot) = &self.robot {
            out.push_str(&format!("# robot: {}\n", one_line(robot)));
        }
        if let Some(geometry) = &self.geometry {
            out.push_str(&format!("# geometry: {}\n", one_line(geometry)));
        }
        out
    }

    /// Read the comment lines before the first non-comment line of `text`.
    pub fn parse(text: &str) -> FileHeader {
        let mut header = FileHeader::default();
        for line in text.lines() {
            let line = line.trim();
            if line.is_empty() {
                continue;
            }
            let Some(comment) = line.strip_prefix('#') else {
                break;
            };
            let comment = comment.trim();
            let value = |key: &str| {
                comment
                    .strip_prefix(key)
                    .map(|v| v.trim().chars().take(MAX_LABEL_CHARS).collect::<String>())
            };
            if let Some(v) = value("robot:") {
                header.robot = Some(v);
            } else if let Some(v) = value("geometry:") {
                header.geometry = Some(v);
            } else if header.notes.len() < 100 {
                header
                    .notes
                    .push(comment.chars().take(MAX_LABEL_CHARS).collect());
            }
        }
        header
    }
}

/// A header value on one line (a robot name with a newline would end the comment).
fn one_line(text: &str) -> String {
    text.replace(['\n', '\r'], " ")
}
