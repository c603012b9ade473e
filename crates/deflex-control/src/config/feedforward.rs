//! From `[feedforward]` of a `CELL.toml` to the controller's [`FeedForward`]: the table read
//! (bounded in size), checked against the model and the settings.

use super::{CellFile, ConfigError};
use crate::feedforward::{
    FeedForward, FeedForwardConfig, FeedForwardMode, FeedForwardTable, PathIndex,
};
use deflex_model::Robot;
use std::io::Read;
use std::path::PathBuf;

/// Largest feed-forward table read (bytes): a million rows of `deflex compensate` output.
pub const MAX_TABLE_BYTES: u64 = 512 << 20;

impl CellFile {
    /// The feed-forward table's path resolved against the file's directory.
    pub fn feedforward_table_path(&self) -> Option<PathBuf> {
        self.feedforward
            .as_ref()
            .map(|f| self.base_dir.join(&f.table))
    }

    /// The settings of `[feedforward]` (validated at load).
    pub fn feedforward_config(&self) -> Option<FeedForwardConfig> {
        self.feedforward.as_ref().map(|f| FeedForwardConfig {
            mode: if f.mode == "precompensated" {
                FeedForwardMode::Precompensated
            } else {
                FeedForwardMode::FeedForward
            },
            index: if f.index == "time" {
                PathIndex::Time
            } else {
                PathIndex::ArcLength
            },
            lead_s: f.lead_s,
            max_offset_m: f.max_offset_m,
            window_m: f.window_m,
            time_offset_s: f.time_offset_s,
        })
    }

    /// The feed-forward of `[feedforward]` for the model `robot` (the table is in its world
    /// frame), or `None` without the section. Errors name the file and the field, or the table
    /// and its line.
    pub fn feedforward(&self, robot: &Robot) -> Result<Option<FeedForward>, ConfigError> {
        let (Some(path), Some(config)) = (self.feedforward_table_path(), self.feedforward_config())
        else {
            return Ok(None);
        };
        let name = path.display().to_string();
        let invalid = |message: String| ConfigError::Invalid {
            path: self.origin.clone(),
            field: "feedforward.table".into(),
            message,
        };
        let file = std::fs::File::open(&path).map_err(|e| invalid(format!("{name}: {e}")))?;
        let mut text = String::new();
        file.take(MAX_TABLE_BYTES + 1)
            .read_to_string(&mut text)
            .map_err(|e| invalid(format!("{name}: {e}")))?;
        if text.len() as u64 > MAX_TABLE_BYTES {
            return Err(invalid(format!(
                "{name}: larger than {MAX_TABLE_BYTES} bytes"
            )));
        }
        let rows =
            deflex_compensate::table::read_csv(&text, &name).map_err(|e| invalid(e.to_string()))?;
        let table =
            FeedForwardTable::from_rows(&rows, robot, &name).map_err(|e| invalid(e.to_string()))?;
        FeedForward::new(table, config)
            .map(Some)
            .map_err(|e| invalid(e.to_string()))
    }
}
