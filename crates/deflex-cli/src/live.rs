//! What `deflex run`, `deflex cell --sim` and `deflex sim isf` share to watch a session: the
//! `--view [ADDR]` flag and its server (`deflex-view`). The MCAP recording's file name beside
//! the CSV log is the application's (`deflex_app::cell::run_session::mcap_beside`).

use crate::error::UsageError;
use deflex_runtime::telemetry::{Broadcast, CycleSample, SessionInfo};
use deflex_view::{StopCallback, ViewError, ViewHandle, ViewStats};
use std::net::SocketAddr;
use std::sync::Arc;

/// Default address of `deflex run --view`.
pub const RUN_VIEW: &str = "127.0.0.1:8765";
/// Default address of `deflex cell --sim --view` (another port: both run on one machine).
pub const CELL_VIEW: &str = "127.0.0.1:8766";
/// Default address of `deflex sim isf --view`.
pub const SIM_VIEW: &str = "127.0.0.1:8767";

/// `--view` value: `HOST:PORT` (an IP address or `localhost`) or a bare `PORT` on 127.0.0.1.
pub fn view_address(text: &str) -> Result<SocketAddr, UsageError> {
    let text = text.trim();
    let expected = || {
        UsageError::invalid(
            "--view",
            "an address such as 127.0.0.1:8765 (or a port)",
            format!("\"{text}\""),
        )
    };
    if let Ok(port) = text.parse::<u16>() {
        return Ok(SocketAddr::from(([127, 0, 0, 1], port)));
    }
    if let Some(port) = text.strip_prefix("localhost:") {
        let port = port.parse::<u16>().map_err(|_| expected())?;
        return Ok(SocketAddr::from(([127, 0, 0, 1], port)));
    }
    text.parse::<SocketAddr>().map_err(|_| expected())
}

/// Starts the live view of `ring` on `addr` and prints its address on stderr (and, beyond
/// loopback, the server's warning). `stop` is the session's safe stop, when it has one.
pub fn start_view(
    addr: SocketAddr,
    ring: Arc<Broadcast<CycleSample>>,
    info: Arc<SessionInfo>,
    stop: Option<StopCallback>,
    quiet: bool,
) -> Result<ViewHandle, ViewError> {
    let simulated = info.simulated;
    let view = deflex_view::serve(addr, ring, info, stop)?;
    if !quiet {
        eprintln!(
            "live view{}: open {}",
            if simulated { " (SIMULATED)" } else { "" },
            view.url()
        );
    }
    Ok(view)
}

/// One line about what the view did.
pub fn view_line(stats: &ViewStats) -> String {
    format!(
        "{} samples shown, {} lost for the view, {} messages dropped for slow pages, {} page(s) \
         refused",
        stats.samples_received, stats.samples_lost, stats.frames_dropped, stats.clients_refused
    )
}
