//! # deflex-view
//!
//! The live view of a deflex session: a small embedded HTTP + WebSocket server (std networking,
//! `httparse`, `tungstenite`) that serves one page on loopback. The page shows, at 25 updates a
//! second over a ten-minute scrolling window: the force/torque at the TCP and the force norm,
//! the estimated deflection δŝ, the correction ξ per axis against its limits, the path error when
//! it is known (the twin), the controller's phase, status and fault by name, the loop timing
//! (cycle time, its p99 over the last 1000 cycles, late answers) and a 3-D view of the program
//! and the corrected TCP path. Its JavaScript is hand-written on top of uPlot and three.js,
//! vendored in this crate with their licences (`assets/vendor/VENDORED.md`) and compiled into
//! the binary: the page loads nothing from outside (its Content-Security-Policy says so too).
//!
//! The server is fed by a telemetry [`Subscriber`](deflex_telemetry::Subscriber): the publisher
//! (the control thread) never waits for it. A slow or absent page costs only messages dropped
//! for that page, counted and shown on it ([`ViewStats`]). Every resource is bounded: pages
//! ([`ViewOptions::max_clients`]), connections ([`ViewOptions::max_connections`]), request
//! size and time, incoming message size, queue and write buffer per page.
//!
//! A stop button is shown only when the caller passes a stop callback — it must be the same safe
//! ramp-out as SIGINT — and the page asks for confirmation before sending the request.
//!
//! ```no_run
//! use std::sync::Arc;
//! use deflex_telemetry::{broadcast, CycleSample, SessionInfo, StreamSource};
//! let (mut publisher, ring) = broadcast::<CycleSample>(4096);
//! let info = Arc::new(SessionInfo::new(StreamSource::Runtime, "tx200", vec!["j1".into()]));
//! let stop_requested = Arc::new(std::sync::atomic::AtomicBool::new(false));
//! let flag = stop_requested.clone();
//! let view = deflex_view::serve(
//!     "127.0.0.1:8765".parse().unwrap(),
//!     ring,
//!     info,
//!     Some(Box::new(move || flag.store(true, std::sync::atomic::Ordering::SeqCst))),
//! )
//! .unwrap();
//! eprintln!("live view: {}", view.url());
//! publisher.publish(&CycleSample::default()); // the control thread, once per cycle
//! view.shutdown();
//! ```

#![warn(missing_docs)]
#![forbid(unsafe_code)]

mod assets;
mod connection;
pub mod frame;
mod hub;

pub use connection::{
    MAX_INCOMING_BYTES, MAX_REQUEST_BYTES, MAX_WRITE_BUFFER_BYTES, MIN_WRITE_BUFFER_BYTES,
    REQUEST_TIMEOUT, STALL_TIMEOUT,
};

use deflex_telemetry::Flags;
use deflex_telemetry::{Broadcast, CycleSample, SessionInfo};
use std::net::{SocketAddr, TcpListener};
use std::sync::Arc;
use std::sync::atomic::{AtomicBool, AtomicU64, Ordering};
use std::thread::JoinHandle;
use std::time::Duration;

/// The caller's safe stop (the runtime's ramp-out, the same as SIGINT).
pub type StopCallback = Box<dyn Fn() + Send + Sync>;

/// Bounds of the server.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct ViewOptions {
    /// Pages connected at once (more get HTTP 503).
    pub max_clients: u64,
    /// Connections handled at once, pages included (more are closed at once).
    pub max_connections: u64,
    /// Messages queued per page (a full queue drops the newest message for that page).
    pub queue_messages: usize,
    /// Unsent bytes held per page beyond the kernel's socket buffer (at least
    /// [`MIN_WRITE_BUFFER_BYTES`]); when it is full the page's queue fills, then the pump drops
    /// messages for that page.
    pub write_buffer_bytes: usize,
}

impl Default for ViewOptions {
    fn default() -> Self {
        ViewOptions {
            max_clients: 8,
            max_connections: 32,
            queue_messages: 64,
            write_buffer_bytes: MAX_WRITE_BUFFER_BYTES,
        }
    }
}

/// Why the view could not start.
#[derive(Debug, thiserror::Error)]
pub enum ViewError {
    /// The address could not be bound (in use, not an address of this machine, no permission).
    #[error("live view: cannot listen on {addr}: {source}")]
    Bind {
        /// The address asked for.
        addr: SocketAddr,
        /// The cause.
        #[source]
        source: std::io::Error,
    },
    /// A server thread could not be started.
    #[error("live view: cannot start a thread: {0}")]
    Thread(#[source] std::io::Error),
}

/// Counters of the server (cumulative since it started).
#[derive(Debug, Default)]
pub(crate) struct Counters {
    pub(crate) samples_received: AtomicU64,
    pub(crate) samples_lost: AtomicU64,
    pub(crate) buckets: AtomicU64,
    pub(crate) frames_sent: AtomicU64,
    pub(crate) frames_dropped: AtomicU64,
    pub(crate) clients: AtomicU64,
    pub(crate) clients_refused: AtomicU64,
    pub(crate) clients_stalled: AtomicU64,
    pub(crate) connections_refused: AtomicU64,
    pub(crate) stop_requests: AtomicU64,
}

/// A snapshot of what the server did.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct ViewStats {
    /// Cycle samples the view read from the telemetry ring.
    pub samples_received: u64,
    /// Cycle samples the view lost (overwritten in the ring before it read them).
    pub samples_lost: u64,
    /// Buckets made (25 per second of session time).
    pub buckets: u64,
    /// Live messages made (each offered to every page).
    pub frames_sent: u64,
    /// Messages dropped for a page whose queue was full (its socket and write buffer full
    /// behind it).
    pub frames_dropped: u64,
    /// Pages connected now.
    pub clients: u64,
    /// Pages refused because [`ViewOptions::max_clients`] were connected.
    pub clients_refused: u64,
    /// Pages disconnected because they took nothing for [`STALL_TIMEOUT`].
    pub clients_stalled: u64,
    /// Connections closed at once because [`ViewOptions::max_connections`] were open.
    pub connections_refused: u64,
    /// Stop requests passed to the callback.
    pub stop_requests: u64,
}

/// State shared by the server's threads.
pub(crate) struct Shared {
    pub(crate) addr: SocketAddr,
    pub(crate) loopback: bool,
    pub(crate) options: ViewOptions,
    pub(crate) shutdown: AtomicBool,
    pub(crate) hello: String,
    pub(crate) csp: String,
    pub(crate) stop: Option<StopCallback>,
    pub(crate) registry: hub::Registry,
    pub(crate) ws_clients: AtomicU64,
    pub(crate) connections: AtomicU64,
    pub(crate) stats: Counters,
}

/// A running view. Dropping it (or [`ViewHandle::shutdown`]) stops the server.
pub struct ViewHandle {
    shared: Arc<Shared>,
    threads: Vec<JoinHandle<()>>,
    warning: Option<String>,
}

impl ViewHandle {
    /// The address the server listens on (with the port chosen when 0 was asked).
    pub fn local_addr(&self) -> SocketAddr {
        self.shared.addr
    }

    /// The page's address.
    pub fn url(&self) -> String {
        format!("http://{}/", self.shared.addr)
    }

    /// The warning printed when the server listens beyond loopback.
    pub fn remote_warning(&self) -> Option<&str> {
        self.warning.as_deref()
    }

    /// What the server did so far.
    pub fn stats(&self) -> ViewStats {
        let c = &self.shared.stats;
        let l = |a: &AtomicU64| a.load(Ordering::Relaxed);
        ViewStats {
            samples_received: l(&c.samples_received),
            samples_lost: l(&c.samples_lost),
            buckets: l(&c.buckets),
            frames_sent: l(&c.frames_sent),
            frames_dropped: l(&c.frames_dropped),
            clients: l(&c.clients),
            clients_refused: l(&c.clients_refused),
            clients_stalled: l(&c.clients_stalled),
            connections_refused: l(&c.connections_refused),
            stop_requests: l(&c.stop_requests),
        }
    }

    /// Stops the server: closes the pages' connections and waits for its threads (a tick of
    /// the pump and a poll of each page, or up to [`REQUEST_TIMEOUT`] for a request being read).
    pub fn shutdown(mut self) {
        self.stop_threads();
    }

    fn stop_threads(&mut self) {
        self.shared.shutdown.store(true, Ordering::Release);
        for t in self.threads.drain(..) {
            let _ = t.join();
        }
    }
}

impl Drop for ViewHandle {
    fn drop(&mut self) {
        self.stop_threads();
    }
}

/// Serves the live view of the stream `ring` on `addr` with default bounds; see
/// [`serve_with`].
pub fn serve(
    addr: SocketAddr,
    ring: Arc<Broadcast<CycleSample>>,
    info: Arc<SessionInfo>,
    stop: Option<StopCallback>,
) -> Result<ViewHandle, ViewError> {
    serve_with(addr, ring, info, stop, ViewOptions::default())
}

/// Serves the live view of the stream `ring` on `addr` (port 0: any free port; see
/// [`ViewHandle::url`]). An address other than loopback makes the page reachable from the
/// network: a warning is printed on stderr (and kept in [`ViewHandle::remote_warning`]); pass
/// one only when the user asked for it. `stop`, when given, is called (at most once a second)
/// when the operator confirms the page's stop button.
pub fn serve_with(
    addr: SocketAddr,
    ring: Arc<Broadcast<CycleSample>>,
    info: Arc<SessionInfo>,
    stop: Option<StopCallback>,
    options: ViewOptions,
) -> Result<ViewHandle, ViewError> {
    let listener = TcpListener::bind(addr).map_err(|e| ViewError::Bind { addr, source: e })?;
    let local = listener
        .local_addr()
        .map_err(|e| ViewError::Bind { addr, source: e })?;
    listener
        .set_nonblocking(true)
        .map_err(|e| ViewError::Bind { addr, source: e })?;
    let loopback = local.ip().is_loopback();
    let warning = (!loopback).then(|| {
        format!(
            "warning: the live view listens on {local}, beyond this machine: anyone who can reach \
             it sees the cell's data{}",
            if stop.is_some() {
                " and can request the stop (ramp-out) of the correction"
            } else {
                ""
            }
        )
    });
    if let Some(w) = &warning {
        eprintln!("{w}");
    }
    let shared = Arc::new(Shared {
        addr: local,
        loopback,
        hello: hello_json(&info, stop.is_some()),
        csp: format!(
            "default-src 'self'; script-src 'self' 'unsafe-inline'; style-src 'self' \
             'unsafe-inline'; img-src 'self' data: blob:; connect-src 'self' ws://{local}; \
             worker-src 'none'; object-src 'none'; base-uri 'none'; form-action 'none'"
        ),
        options,
        shutdown: AtomicBool::new(false),
        stop,
        registry: hub::Registry::default(),
        ws_clients: AtomicU64::new(0),
        connections: AtomicU64::new(0),
        stats: Counters::default(),
    });
    // What the ring still holds is shown too (a view opened after the session started).
    let subscriber = ring.subscribe_from_oldest();
    let mut threads = Vec::new();
    let pump_shared = shared.clone();
    threads.push(
        std::thread::Builder::new()
            .name("deflex-view-pump".into())
            .spawn(move || hub::run(subscriber, pump_shared))
            .map_err(ViewError::Thread)?,
    );
    let accept_shared = shared.clone();
    let accept = std::thread::Builder::new()
        .name("deflex-view-accept".into())
        .spawn(move || accept_loop(listener, accept_shared));
    match accept {
        Ok(t) => threads.push(t),
        Err(e) => {
            shared.shutdown.store(true, Ordering::Release);
            for t in threads {
                let _ = t.join();
            }
            return Err(ViewError::Thread(e));
        }
    }
    Ok(ViewHandle {
        shared,
        threads,
        warning,
    })
}

/// Accepts connections (polling, so that shutdown is seen within 25 ms), one thread each, at
/// most [`ViewOptions::max_connections`] at once.
fn accept_loop(listener: TcpListener, shared: Arc<Shared>) {
    let mut handlers: Vec<JoinHandle<()>> = Vec::new();
    while !shared.shutdown.load(Ordering::Acquire) {
        handlers.retain(|h| !h.is_finished());
        match listener.accept() {
            Ok((stream, _)) => {
                if shared.connections.load(Ordering::Acquire) >= shared.options.max_connections
                    || stream.set_nonblocking(false).is_err()
                {
                    shared
                        .stats
                        .connections_refused
                        .fetch_add(1, Ordering::Relaxed);
                    continue; // dropping the stream closes it
                }
                shared.connections.fetch_add(1, Ordering::AcqRel);
                let s = shared.clone();
                let spawned = std::thread::Builder::new()
                    .name("deflex-view-conn".into())
                    .spawn(move || {
                        connection::handle(stream, s.clone());
                        s.connections.fetch_sub(1, Ordering::AcqRel);
                    });
                match spawned {
                    Ok(h) => handlers.push(h),
                    Err(_) => {
                        shared.connections.fetch_sub(1, Ordering::AcqRel);
                    }
                }
            }
            Err(e) if e.kind() == std::io::ErrorKind::WouldBlock => {
                std::thread::sleep(Duration::from_millis(25));
            }
            Err(_) => std::thread::sleep(Duration::from_millis(25)),
        }
    }
    for h in handlers {
        let _ = h.join();
    }
}

/// The first message a page gets: the session, the wire layout, names of the codes.
fn hello_json(info: &SessionInfo, stop: bool) -> String {
    let finite = |v: f64| v.is_finite().then_some(v);
    // The controller's phases, or the simulated cell's states for the twin's own stream.
    let phases = info.source.phase_names();
    let faults: Vec<&str> = deflex_telemetry::FaultKind::ALL
        .iter()
        .map(|k| k.name())
        .collect();
    let flags: Vec<(u32, String)> = (0..32)
        .map(|b| (b, Flags(1 << b).describe()))
        .filter(|(_, n)| !n.is_empty())
        .collect();
    serde_json::json!({
        "type": "hello",
        "protocol": 1,
        "label": if info.simulated { "SIMULATED" } else { "" },
        "session": {
            "source": info.source.key(),
            "simulated": info.simulated,
            "robot": info.robot,
            "joint_names": info.joint_names,
            "protocol": info.protocol,
            "control_period_s": finite(info.control_period_s),
            "robot_cycle_s": finite(info.robot_cycle_s),
            "correction_limit": info.correction_limit.map(finite),
            "correction_rate_limit": info.correction_rate_limit.map(finite),
            "force_limit_n": finite(info.force_limit_n),
            "base_frame": info.base_frame,
            "sensor_frame": info.sensor_frame,
            "tcp_frame": info.tcp_frame,
        },
        "fields": frame::FIELDS.to_vec(),
        "bucket_s": frame::BUCKET_S,
        "window_s": frame::WINDOW_S,
        "p99_window": frame::P99_WINDOW,
        "stop": stop,
        "phases": phases,
        "faults": faults,
        "flags": flags,
    })
    .to_string()
}
