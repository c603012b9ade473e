//! One TCP connection: a bounded HTTP/1.1 request (parsed with `httparse`), answered with an
//! embedded file or upgraded to the page's WebSocket (`tungstenite`), whose loop sends the
//! pump's messages and receives the page's commands.
//!
//! Bounds: the request head is at most [`MAX_REQUEST_BYTES`] and must arrive within
//! [`REQUEST_TIMEOUT`]; a page's incoming messages are at most [`MAX_INCOMING_BYTES`]; its queue
//! holds [`crate::ViewOptions::queue_messages`] messages and its socket write buffer
//! [`crate::ViewOptions::write_buffer_bytes`]; a page that takes nothing for [`STALL_TIMEOUT`] is disconnected
//! (it reconnects by itself and gets the history again).

use crate::hub::{ClientSlot, Encoded};
use crate::{Shared, assets, frame};
use std::io::{Read, Write};
use std::net::TcpStream;
use std::sync::Arc;
use std::sync::atomic::{AtomicU64, Ordering};
use std::sync::mpsc::{RecvTimeoutError, sync_channel};
use std::time::{Duration, Instant};
use tungstenite::protocol::{Role, WebSocketConfig};
use tungstenite::{Message, WebSocket};

/// Largest request head (bytes).
pub const MAX_REQUEST_BYTES: usize = 8 * 1024;
/// Time allowed for the request head.
pub const REQUEST_TIMEOUT: Duration = Duration::from_secs(5);
/// Largest message a page may send (bytes).
pub const MAX_INCOMING_BYTES: usize = 4 * 1024;
/// Default of the unsent data held for one page (bytes).
pub const MAX_WRITE_BUFFER_BYTES: usize = 4 << 20;
/// Smallest write buffer: room for the largest message (a history piece) and a write chunk.
pub const MIN_WRITE_BUFFER_BYTES: usize = 1 << 20;
/// A page whose socket takes nothing for this long is disconnected.
pub const STALL_TIMEOUT: Duration = Duration::from_secs(10);
/// Longest wait of a page's loop (its latency to commands and shutdown).
const POLL: Duration = Duration::from_millis(10);
/// Smallest interval between two stop requests passed to the callback.
const STOP_INTERVAL: Duration = Duration::from_secs(1);

struct Request {
    method: String,
    path: String,
    host: Option<String>,
    origin: Option<String>,
    upgrade_websocket: bool,
    ws_key: Option<String>,
    ws_version: Option<String>,
    body_start: Vec<u8>,
}

enum Head {
    Complete(Request),
    Bad(u16, &'static str),
}

fn read_request(stream: &mut TcpStream) -> std::io::Result<Head> {
    let mut buf = vec![0u8; MAX_REQUEST_BYTES];
    let mut len = 0;
    let deadline = Instant::now() + REQUEST_TIMEOUT;
    loop {
        if len == buf.len() {
            return Ok(Head::Bad(431, "request header fields too large"));
        }
        let left = deadline.saturating_duration_since(Instant::now());
        if left.is_zero() {
            return Ok(Head::Bad(408, "request timeout"));
        }
        stream.set_read_timeout(Some(left))?;
        let n = match stream.read(&mut buf[len..]) {
            Ok(0) => return Err(std::io::ErrorKind::UnexpectedEof.into()),
            Ok(n) => n,
            Err(e)
                if matches!(
                    e.kind(),
                    std::io::ErrorKind::WouldBlock | std::io::ErrorKind::TimedOut
                ) =>
            {
                return Ok(Head::Bad(408, "request timeout"));
            }
            Err(e) => return Err(e),
        };
        len += n;
        let mut headers = [httparse::EMPTY_HEADER; 32];
        let mut req = httparse::Request::new(&mut headers);
        match req.parse(&buf[..len]) {
            Ok(httparse::Status::Partial) => continue,
            Err(httparse::Error::TooManyHeaders) => {
                return Ok(Head::Bad(431, "too many header fields"));
            }
            Err(_) => return Ok(Head::Bad(400, "malformed request")),
            Ok(httparse::Status::Complete(used)) => {
                let header = |name: &str| {
                    req.headers
                        .iter()
                        .find(|h| h.name.eq_ignore_ascii_case(name))
                        .and_then(|h| std::str::from_utf8(h.value).ok())
                        .map(|v| v.trim().to_string())
                };
                let has_token = |name: &str, token: &str| {
                    header(name)
                        .is_some_and(|v| v.split(',').any(|t| t.trim().eq_ignore_ascii_case(token)))
                };
                return Ok(Head::Complete(Request {
                    method: req.method.unwrap_or("").to_string(),
                    path: req.path.unwrap_or("").to_string(),
                    host: header("host"),
                    origin: header("origin"),
                    upgrade_websocket: has_token("upgrade", "websocket")
                        && has_token("connection", "upgrade"),
                    ws_key: header("sec-websocket-key"),
                    ws_version: header("sec-websocket-version"),
                    body_start: buf[used..len].to_vec(),
                }));
            }
        }
    }
}

fn respond(
    stream: &mut TcpStream,
    status: u16,
    reason: &str,
    content_type: &str,
    body: &[u8],
    shared: &Shared,
) -> std::io::Result<()> {
    let head = format!(
        "HTTP/1.1 {status} {reason}\r\nContent-Type: {content_type}\r\nContent-Length: {}\r\n\
         Cache-Control: no-cache\r\nX-Content-Type-Options: nosniff\r\n\
         Content-Security-Policy: {}\r\nConnection: close\r\n\r\n",
        body.len(),
        shared.csp,
    );
    stream.write_all(head.as_bytes())?;
    stream.write_all(body)?;
    stream.flush()
}

fn refuse(stream: &mut TcpStream, status: u16, reason: &str, shared: &Shared) {
    let _ = respond(
        stream,
        status,
        reason,
        "text/plain; charset=utf-8",
        format!("{status} {reason}\n").as_bytes(),
        shared,
    );
}

/// True when a `Host` (or an `Origin`'s host) names this server: on a loopback address only
/// loopback names are accepted (a page elsewhere cannot reach the server through a DNS name
/// that resolves to 127.0.0.1).
fn host_allowed(host: &str, shared: &Shared) -> bool {
    if !shared.loopback {
        return true;
    }
    let port = shared.addr.port();
    let name = match host.rsplit_once(':') {
        Some((name, p)) if p.parse::<u16>() == Ok(port) => name,
        Some(_) => return false,
        None => return false,
    };
    let name = name.trim_start_matches('[').trim_end_matches(']');
    name.eq_ignore_ascii_case("localhost")
        || name
            .parse::<std::net::IpAddr>()
            .is_ok_and(|ip| ip.is_loopback())
}

/// Serves one connection to its end.
pub(crate) fn handle(mut stream: TcpStream, shared: Arc<Shared>) {
    let _ = stream.set_nodelay(true);
    let _ = stream.set_write_timeout(Some(REQUEST_TIMEOUT));
    let request = match read_request(&mut stream) {
        Ok(Head::Complete(r)) => r,
        Ok(Head::Bad(status, reason)) => return refuse(&mut stream, status, reason, &shared),
        Err(_) => return,
    };
    if !request
        .host
        .as_deref()
        .is_some_and(|h| host_allowed(h, &shared))
    {
        return refuse(
            &mut stream,
            421,
            "misdirected request (unexpected Host)",
            &shared,
        );
    }
    if request.method != "GET" {
        return refuse(&mut stream, 405, "method not allowed", &shared);
    }
    if request.path == "/ws" {
        return websocket(stream, request, shared);
    }
    match assets::find(&request.path) {
        Some(asset) => {
            let _ = respond(
                &mut stream,
                200,
                "OK",
                asset.content_type,
                asset.body,
                &shared,
            );
        }
        None => refuse(&mut stream, 404, "not found", &shared),
    }
}

fn websocket(mut stream: TcpStream, request: Request, shared: Arc<Shared>) {
    let (Some(key), true) = (request.ws_key.as_deref(), request.upgrade_websocket) else {
        return refuse(&mut stream, 400, "expected a WebSocket upgrade", &shared);
    };
    if request.ws_version.as_deref() != Some("13") {
        return refuse(&mut stream, 426, "WebSocket version 13 required", &shared);
    }
    // A page of another site must not read the cell's data or press stop.
    if let Some(origin) = request.origin.as_deref() {
        let host = request.host.as_deref().unwrap_or("");
        let same = origin
            .strip_prefix("http://")
            .is_some_and(|o| o.eq_ignore_ascii_case(host));
        if !same {
            return refuse(&mut stream, 403, "cross-origin WebSocket refused", &shared);
        }
    }
    // Count this page; refuse it when the server is full.
    let count = shared.ws_clients.fetch_add(1, Ordering::AcqRel) + 1;
    let _guard = Decrement(&shared.ws_clients);
    if count > shared.options.max_clients {
        shared.stats.clients_refused.fetch_add(1, Ordering::Relaxed);
        return refuse(&mut stream, 503, "too many pages open", &shared);
    }
    let accept = tungstenite::handshake::derive_accept_key(key.as_bytes());
    let head = format!(
        "HTTP/1.1 101 Switching Protocols\r\nUpgrade: websocket\r\nConnection: Upgrade\r\n\
         Sec-WebSocket-Accept: {accept}\r\n\r\n"
    );
    if stream.write_all(head.as_bytes()).is_err() || stream.set_nonblocking(true).is_err() {
        return;
    }
    let config = WebSocketConfig::default()
        .max_message_size(Some(MAX_INCOMING_BYTES))
        .max_frame_size(Some(MAX_INCOMING_BYTES))
        .write_buffer_size(32 * 1024)
        .max_write_buffer_size(
            shared
                .options
                .write_buffer_bytes
                .max(MIN_WRITE_BUFFER_BYTES),
        );
    let ws = WebSocket::from_partially_read(stream, request.body_start, Role::Server, Some(config));
    page_loop(ws, &shared);
}

struct Decrement<'a>(&'a std::sync::atomic::AtomicU64);

impl Drop for Decrement<'_> {
    fn drop(&mut self) {
        self.0.fetch_sub(1, Ordering::AcqRel);
    }
}

fn would_block(e: &tungstenite::Error) -> bool {
    matches!(e, tungstenite::Error::Io(io) if io.kind() == std::io::ErrorKind::WouldBlock)
}

fn page_loop(mut ws: WebSocket<TcpStream>, shared: &Shared) {
    let (tx, rx) = sync_channel::<Encoded>(shared.options.queue_messages);
    let dropped = Arc::new(AtomicU64::new(0));
    // The hello first, then register for the history and the live stream.
    match ws.write(Message::text(shared.hello.clone())) {
        Ok(()) => {}
        Err(e) if would_block(&e) => {}
        Err(_) => return,
    }
    shared
        .registry
        .waiting
        .lock()
        .unwrap_or_else(|p| p.into_inner())
        .push(ClientSlot {
            tx,
            dropped: dropped.clone(),
        });
    let mut last_progress = Instant::now();
    let mut last_stop: Option<Instant> = None;
    // Messages taken from the queue and not yet in the socket's write buffer (one queue slot:
    // a live message or the history), held until it has room while the page's queue fills up
    // behind them and the pump drops for this page.
    let mut pending: std::collections::VecDeque<Message> = std::collections::VecDeque::new();
    loop {
        if shared.shutdown.load(Ordering::Acquire) {
            let _ = ws.close(None);
            let _ = ws.flush();
            return;
        }
        if pending.is_empty() {
            match rx.recv_timeout(POLL) {
                Ok(batch) => {
                    for message in batch.iter() {
                        let mut bytes = message.to_vec();
                        frame::set_dropped(&mut bytes, dropped.load(Ordering::Relaxed));
                        pending.push_back(Message::binary(bytes));
                    }
                }
                Err(RecvTimeoutError::Timeout) => {}
                Err(RecvTimeoutError::Disconnected) => return,
            }
        } else {
            std::thread::sleep(POLL);
        }
        while let Some(message) = pending.pop_front() {
            match ws.write(message) {
                Ok(()) => {}
                Err(tungstenite::Error::WriteBufferFull(back)) => {
                    pending.push_front(*back);
                    break;
                }
                Err(e) if would_block(&e) => {}
                Err(_) => return,
            }
        }
        match ws.flush() {
            Ok(()) => last_progress = Instant::now(),
            Err(e) if would_block(&e) => {
                if last_progress.elapsed() > STALL_TIMEOUT {
                    shared.stats.clients_stalled.fetch_add(1, Ordering::Relaxed);
                    return;
                }
            }
            Err(_) => return,
        }
        loop {
            match ws.read() {
                Ok(Message::Text(text)) => command(&mut ws, text.as_str(), shared, &mut last_stop),
                Ok(Message::Close(_)) => {
                    let _ = ws.flush();
                    return;
                }
                Ok(_) => {}
                Err(e) if would_block(&e) => break,
                Err(_) => return,
            }
        }
    }
}

/// A command from the page: only `{"cmd":"stop"}` exists, and only with a stop callback.
fn command(
    ws: &mut WebSocket<TcpStream>,
    text: &str,
    shared: &Shared,
    last_stop: &mut Option<Instant>,
) {
    let cmd = serde_json::from_str::<serde_json::Value>(text)
        .ok()
        .and_then(|v| v.get("cmd").and_then(|c| c.as_str()).map(str::to_string));
    let reply = match (cmd.as_deref(), &shared.stop) {
        (Some("stop"), Some(stop)) => {
            if last_stop.is_none_or(|t| t.elapsed() >= STOP_INTERVAL) {
                *last_stop = Some(Instant::now());
                shared.stats.stop_requests.fetch_add(1, Ordering::Relaxed);
                stop();
            }
            r#"{"type":"stop_ack"}"#
        }
        (Some("stop"), None) => {
            r#"{"type":"error","message":"this session has no stop through the page"}"#
        }
        _ => r#"{"type":"error","message":"unknown command"}"#,
    };
    let _ = ws.write(Message::text(reply));
}
