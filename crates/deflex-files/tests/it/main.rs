//! The tests of `deflex-files`, through its public API: one test binary (modules below), so the
//! library is compiled once (`[lib] test = false`). A module per part: outputs written whole or
//! not at all, bounded inputs, escaped messages, the shared file errors, CSV text in memory.

use std::path::PathBuf;
use std::sync::atomic::{AtomicU64, Ordering};

mod csv_text;
mod errors;
mod input;
mod output;
mod shown;

/// A fresh folder under the system's temporary folder.
pub fn scratch(name: &str) -> PathBuf {
    static N: AtomicU64 = AtomicU64::new(0);
    let dir = std::env::temp_dir().join(format!(
        "deflex-files-{name}-{}-{}",
        std::process::id(),
        N.fetch_add(1, Ordering::Relaxed)
    ));
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(&dir).unwrap();
    dir
}
