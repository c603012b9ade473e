//! The server over loopback sockets: what a page receives, and every bound and check.

use crate::support::{Publisher, counting_stop, wait_until};
use deflex_telemetry::synthetic::SyntheticCell;
use deflex_view::{ViewOptions, frame};
use std::io::{Read, Write};
use std::net::TcpStream;
use std::sync::Arc;
use std::sync::atomic::Ordering;
use std::time::Duration;
use tungstenite::stream::MaybeTlsStream;
use tungstenite::{Message, WebSocket};

type Page = WebSocket<MaybeTlsStream<TcpStream>>;

fn open_page(view: &deflex_view::ViewHandle) -> Page {
    let (ws, _) = tungstenite::connect(format!("ws://{}/ws", view.local_addr())).unwrap();
    if let MaybeTlsStream::Plain(s) = ws.get_ref() {
        s.set_read_timeout(Some(Duration::from_secs(20))).unwrap();
    }
    ws
}

fn hello(page: &mut Page) -> serde_json::Value {
    match page.read().unwrap() {
        Message::Text(t) => serde_json::from_str(t.as_str()).unwrap(),
        other => panic!("expected the hello, got {other:?}"),
    }
}

/// (kind, buckets) of the next binary message.
fn next_buckets(page: &mut Page) -> (u32, Vec<Vec<f64>>) {
    loop {
        if let Message::Binary(b) = page.read().unwrap() {
            let word = |i: usize| u32::from_le_bytes(b[4 * i..4 * i + 4].try_into().unwrap());
            let (kind, count, nf) = (word(0), word(1) as usize, word(2) as usize);
            assert_eq!(b.len(), 16 + count * nf * 8);
            let values: Vec<f64> = b[16..]
                .chunks_exact(8)
                .map(|c| f64::from_le_bytes(c.try_into().unwrap()))
                .collect();
            return (kind, values.chunks(nf).map(<[f64]>::to_vec).collect());
        }
    }
}

fn field(name: &str) -> usize {
    frame::FIELDS.iter().position(|f| *f == name).unwrap()
}

/// Sends raw bytes and returns the response's status line.
fn raw_status(view: &deflex_view::ViewHandle, request: &[u8]) -> String {
    let mut s = TcpStream::connect(view.local_addr()).unwrap();
    s.set_read_timeout(Some(Duration::from_secs(20))).unwrap();
    s.write_all(request).unwrap();
    let mut response = Vec::new();
    let _ = s.read_to_end(&mut response);
    let text = String::from_utf8_lossy(&response).to_string();
    text.lines().next().unwrap_or("").to_string()
}

#[test]
fn a_page_gets_the_history_then_live_buckets_of_the_stream() {
    let publisher = Publisher::start(100.0, 500);
    let view = publisher.serve("127.0.0.1:0", None);
    // Let the pump read the prefill so that it is history when the page connects.
    assert!(wait_until(Duration::from_secs(20), || view.stats().buckets > 100));
    let mut page = open_page(&view);
    let h = hello(&mut page);
    assert_eq!(h["label"], "SIMULATED");
    assert_eq!(h["stop"], false);
    let (kind, history) = next_buckets(&mut page);
    assert_eq!(kind, frame::KIND_HISTORY);
    assert!(history.len() >= 100, "{}", history.len());
    let mut live = Vec::new();
    while live.len() < 30 {
        let (kind, buckets) = next_buckets(&mut page);
        if kind == frame::KIND_LIVE {
            live.extend(buckets);
        }
    }
    let all: Vec<&Vec<f64>> = history.iter().chain(&live).collect();
    for pair in all.windows(2) {
        assert!(pair[1][field("t_s")] > pair[0][field("t_s")]);
    }
    for b in &all {
        // |F| from its components, computed here.
        let f =
            (b[field("fx_n")].powi(2) + b[field("fy_n")].powi(2) + b[field("fz_n")].powi(2)).sqrt();
        assert!((b[field("f_norm_n")] - f).abs() < 1e-9 * f.max(1.0));
        assert!(b[field("f_norm_max_n")] >= b[field("f_norm_n")] - 1e-9);
        // The program point is the corrected TCP minus ξ.
        assert!((b[field("prog_z_m")] - (b[field("tcp_z_m")] - b[field("xi_z_m")])).abs() < 1e-12);
        assert!(b[field("samples")] >= 1.0);
    }
    // 100 Hz in 0.04 s buckets: 4 samples, at most a few more when a tick is late.
    let live_samples: f64 = live.iter().map(|b| b[field("samples")]).sum();
    assert!(live_samples / live.len() as f64 <= 6.0);
    assert_eq!(view.stats().samples_lost, 0);
    view.shutdown();
}

#[test]
fn a_page_that_reads_nothing_costs_only_its_own_dropped_messages() {
    // 10 minutes of history (5 MB) against a 1 MiB write buffer and an 8-message queue (0.3 s
    // of live updates: how long the queue is changes only when the drops begin).
    let publisher = Publisher::start(100.0, 60_000);
    let options = ViewOptions {
        queue_messages: 8,
        write_buffer_bytes: deflex_view::MIN_WRITE_BUFFER_BYTES,
        ..ViewOptions::default()
    };
    let view = publisher.serve_with("127.0.0.1:0", None, options);
    assert!(wait_until(Duration::from_secs(30), || view.stats().buckets > 10_000));
    // The stalled page: handshake, then never read.
    let mut stalled = TcpStream::connect(view.local_addr()).unwrap();
    write!(
        stalled,
        "GET /ws HTTP/1.1\r\nHost: {}\r\nUpgrade: websocket\r\nConnection: Upgrade\r\n\
         Sec-WebSocket-Key: dGhlIHNhbXBsZSBub25jZQ==\r\nSec-WebSocket-Version: 13\r\n\r\n",
        view.local_addr()
    )
    .unwrap();
    assert!(
        wait_until(Duration::from_secs(60), || view.stats().frames_dropped > 0),
        "{:?}",
        view.stats()
    );
    // A reading page beside it gets everything live, and is told it lost nothing.
    let mut page = open_page(&view);
    hello(&mut page);
    let published_before = publisher.published.load(Ordering::Relaxed);
    let mut live = 0;
    let mut dropped_for_page = 0;
    while live < 25 {
        if let Message::Binary(b) = page.read().unwrap() {
            dropped_for_page = u32::from_le_bytes(b[12..16].try_into().unwrap());
            if u32::from_le_bytes(b[0..4].try_into().unwrap()) == frame::KIND_LIVE {
                live += 1;
            }
        }
    }
    assert_eq!(dropped_for_page, 0);
    // The publisher went on at its rate: the view never made it wait.
    assert!(publisher.published.load(Ordering::Relaxed) > published_before);
    let stats = view.stats();
    eprintln!(
        "stalled page beside a reading one: {} samples published, {} read by the view, {} lost; \
         {} messages dropped (all for the stalled page), 0 for the reading page",
        publisher.published.load(Ordering::Relaxed),
        stats.samples_received,
        stats.samples_lost,
        stats.frames_dropped
    );
    assert_eq!(stats.samples_lost, 0, "{stats:?}");
    assert!(stats.frames_dropped > 0);
    drop(stalled);
    view.shutdown();
}

#[test]
fn pages_beyond_the_limit_are_refused() {
    let publisher = Publisher::start(100.0, 0);
    let options = ViewOptions {
        max_clients: 2,
        ..ViewOptions::default()
    };
    let view = publisher.serve_with("127.0.0.1:0", None, options);
    let mut a = open_page(&view);
    let mut b = open_page(&view);
    hello(&mut a);
    hello(&mut b);
    match tungstenite::connect(format!("ws://{}/ws", view.local_addr())) {
        Err(tungstenite::Error::Http(response)) => assert_eq!(response.status(), 503),
        other => panic!("third page: {:?}", other.map(|_| ())),
    }
    assert_eq!(view.stats().clients_refused, 1);
    // One leaves; another may come.
    a.close(None).unwrap();
    drop(a);
    assert!(wait_until(Duration::from_secs(20), || {
        tungstenite::connect(format!("ws://{}/ws", view.local_addr())).is_ok()
    }));
    view.shutdown();
}

#[test]
fn requests_are_bounded_and_checked() {
    let publisher = Publisher::start(100.0, 0);
    let view = publisher.serve("127.0.0.1:0", None);
    let host = view.local_addr().to_string();
    let get = |path: &str, extra: &str| {
        format!("GET {path} HTTP/1.1\r\nHost: {host}\r\n{extra}\r\n").into_bytes()
    };
    assert_eq!(raw_status(&view, &get("/", "")), "HTTP/1.1 200 OK");
    assert_eq!(
        raw_status(&view, &get("/vendor/three/LICENSE", "")),
        "HTTP/1.1 200 OK"
    );
    assert!(raw_status(&view, &get("/etc/passwd", "")).starts_with("HTTP/1.1 404"));
    assert!(raw_status(&view, &get("/../Cargo.toml", "")).starts_with("HTTP/1.1 404"));
    let post = format!("POST / HTTP/1.1\r\nHost: {host}\r\nContent-Length: 0\r\n\r\n");
    assert!(raw_status(&view, post.as_bytes()).starts_with("HTTP/1.1 405"));
    // A name that is not loopback (DNS rebinding) and a page of another site.
    let rebinding = b"GET / HTTP/1.1\r\nHost: attacker.example:80\r\n\r\n";
    assert!(raw_status(&view, rebinding).starts_with("HTTP/1.1 421"));
    let cross = get(
        "/ws",
        "Upgrade: websocket\r\nConnection: Upgrade\r\nSec-WebSocket-Key: dGhlIHNhbXBsZSBub25jZQ==\r\n\
         Sec-WebSocket-Version: 13\r\nOrigin: http://attacker.example\r\n",
    );
    assert!(raw_status(&view, &cross).starts_with("HTTP/1.1 403"));
    // An oversized head is refused before it is read whole.
    let huge = get("/", &format!("X-Filler: {}\r\n", "a".repeat(20_000)));
    assert!(raw_status(&view, &huge).starts_with("HTTP/1.1 431"));
    assert!(raw_status(&view, b"\x00\x01garbage\r\n\r\n").starts_with("HTTP/1.1 400"));
    // The page's policy allows nothing from elsewhere.
    let mut s = TcpStream::connect(view.local_addr()).unwrap();
    s.write_all(&get("/", "")).unwrap();
    let mut response = String::new();
    s.read_to_string(&mut response).unwrap();
    assert!(response.contains("Content-Security-Policy: default-src 'self'"));
    assert!(response.contains("<title>deflex live view</title>"));
    view.shutdown();
}

#[test]
fn stop_reaches_the_callback_only_when_one_was_given() {
    let publisher = Publisher::start(100.0, 0);
    let (calls, stop) = counting_stop();
    let view = publisher.serve("127.0.0.1:0", stop);
    let mut page = open_page(&view);
    assert_eq!(hello(&mut page)["stop"], true);
    page.send(Message::text(r#"{"cmd":"stop"}"#)).unwrap();
    loop {
        if let Message::Text(t) = page.read().unwrap() {
            assert_eq!(t.as_str(), r#"{"type":"stop_ack"}"#);
            break;
        }
    }
    assert_eq!(calls.load(Ordering::SeqCst), 1);
    // An oversized message closes the page's connection, never the server.
    let _ = page.send(Message::text(
        "x".repeat(deflex_view::MAX_INCOMING_BYTES * 2),
    ));
    view.shutdown();

    let view = publisher.serve("127.0.0.1:0", None);
    let mut page = open_page(&view);
    assert_eq!(hello(&mut page)["stop"], false);
    page.send(Message::text(r#"{"cmd":"stop"}"#)).unwrap();
    loop {
        if let Message::Text(t) = page.read().unwrap() {
            assert!(t.as_str().contains("no stop"), "{t}");
            break;
        }
    }
    assert_eq!(view.stats().stop_requests, 0);
    view.shutdown();
}

#[test]
fn an_address_beyond_loopback_is_served_with_a_warning() {
    let publisher = Publisher::start(100.0, 0);
    let view = publisher.serve("0.0.0.0:0", None);
    let warning = view.remote_warning().expect("a warning");
    assert!(warning.contains("beyond this machine"), "{warning}");
    view.shutdown();
    let view = publisher.serve("127.0.0.1:0", None);
    assert!(view.remote_warning().is_none());
    let taken = view.local_addr();
    let e = deflex_view::serve(taken, publisher.ring.clone(), publisher.info.clone(), None)
        .err()
        .expect("the port is taken");
    assert!(e.to_string().contains(&taken.to_string()), "{e}");
    view.shutdown();
}

/// The hello as a page receives it from a server serving `info`, with or without a stop
/// callback.
fn hello_of(info: deflex_telemetry::SessionInfo, stop: bool) -> serde_json::Value {
    let (_publisher, ring) = deflex_telemetry::broadcast::<deflex_telemetry::CycleSample>(16);
    let stop = stop.then(|| Box::new(|| {}) as deflex_view::StopCallback);
    let view =
        deflex_view::serve("127.0.0.1:0".parse().unwrap(), ring, Arc::new(info), stop).unwrap();
    let mut page = open_page(&view);
    let h = hello(&mut page);
    drop(page);
    view.shutdown();
    h
}

/// The first message a page gets: the session, the wire layout and the names of the codes.
#[test]
fn the_hello_names_the_layout_and_says_simulated() {
    let info = SyntheticCell::new(0.01, 1, true).session_info();
    let hello = hello_of(info, false);
    assert_eq!(hello["label"], "SIMULATED");
    assert_eq!(hello["stop"], false);
    assert_eq!(hello["fields"].as_array().unwrap().len(), frame::NFIELDS);
    assert_eq!(hello["phases"][2], "running");
    assert_eq!(hello["faults"][0], "force_over_limit");
    assert_eq!(hello["session"]["correction_limit"][0], 0.01);
    let info = deflex_telemetry::SessionInfo::new(
        deflex_telemetry::StreamSource::Runtime,
        "tx200",
        vec!["j1".into()],
    );
    let hello = hello_of(info, true);
    assert_eq!(hello["label"], "");
    assert_eq!(hello["stop"], true);
    // Unbounded limits are null, not an invalid JSON number.
    assert!(hello["session"]["force_limit_n"].is_null());
    // The twin's own stream: its source, SIMULATED, and the cell's states as phase names.
    let mut info = SyntheticCell::new(0.02, 1, true).session_info();
    info.source = deflex_telemetry::StreamSource::TwinCell;
    let hello = hello_of(info, false);
    assert_eq!(hello["session"]["source"], "twin-cell");
    assert_eq!(hello["label"], "SIMULATED");
    assert_eq!(hello["phases"][2], "forming");
}
