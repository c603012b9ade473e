//! The live page in headless Chromium, as an operator would see it: the charts receive data
//! and move, the page runs at ≥ 20 updates a second, logs no error, requests nothing beyond
//! the server, and its stop button goes through the confirmation to the caller's callback.
//! The data is the SIMULATED synthetic stream at 100 Hz.
//!
//! Ignored by default (it needs `/usr/bin/chromium`); `.ci/run` runs it with
//! `cargo test -p deflex-view -- --ignored`. With `DEFLEX_VIEW_SCREENSHOT=PATH` it also saves
//! the page's screenshot there (the README's `docs/live-view.png`).

use crate::cdp::Browser;
use crate::support::Publisher;
use serde_json::{Value, json};
use std::sync::Arc;
use std::sync::atomic::{AtomicU64, Ordering};
use std::time::{Duration, Instant};

/// Fewest page updates a second that count as a live stream (the page's own count over its last
/// two seconds, best window): half the ≥ 20 a second the page keeps on an idle machine.
const MIN_LIVE_UPDATE_HZ: f64 = 10.0;

fn number(v: &Value) -> f64 {
    v.as_f64().unwrap_or(f64::NAN)
}

#[test]
#[ignore = "needs /usr/bin/chromium; run by .ci/run with --ignored"]
fn the_live_page_shows_moving_data_without_errors_or_outside_requests() {
    // 20 s already published: the page starts with a history, then goes live.
    let publisher = Publisher::start(100.0, 2000);
    let stops = Arc::new(AtomicU64::new(0));
    let counter = stops.clone();
    let view = deflex_view::serve(
        "127.0.0.1:0".parse().unwrap(),
        publisher.ring.clone(),
        publisher.info.clone(),
        Some(Box::new(move || {
            counter.fetch_add(1, Ordering::SeqCst);
        })),
    )
    .unwrap();
    let url = view.url();
    let mut browser = Browser::launch();
    browser.page("Page.navigate", json!({"url": url}));

    // Connected, with data in every chart.
    let deadline = Instant::now() + Duration::from_secs(60);
    loop {
        let ready = browser.eval(
            "!!(window.deflexView && window.deflexView.connected && window.deflexView.buckets > 100)",
        );
        if ready == Value::Bool(true) {
            break;
        }
        assert!(Instant::now() < deadline, "the page got no data in 60 s");
        browser.idle(Duration::from_millis(200));
    }
    let state = "(() => { const v = window.deflexView; const f = v.hello.fields; \
                 const at = (n) => v.last[f.indexOf(n)]; \
                 return {t: at('t_s'), fz: at('fz_n'), xi: at('xi_z_m'), buckets: v.buckets, \
                 lengths: v.chartLengths(), hz: v.updateHz, draws: v.draws, webgl: v.webgl, \
                 label: v.hello.label}; })()";
    let first = browser.eval(state);
    assert_eq!(first["label"], "SIMULATED");
    for chart in [
        "force",
        "torque",
        "deflection",
        "correction",
        "error",
        "timing",
    ] {
        assert!(
            number(&first["lengths"][chart]) > 100.0,
            "{chart}: {}",
            first["lengths"]
        );
    }

    // The values move, and the page keeps ≥ 20 updates a second (its own count of redraws
    // over the last 2 s; the best 2-second window of 20 s, the machine being shared).
    let mut best_hz: f64 = 0.0;
    let mut later = first.clone();
    let until = Instant::now() + Duration::from_secs(20);
    while Instant::now() < until {
        browser.idle(Duration::from_millis(500));
        later = browser.eval(state);
        best_hz = best_hz.max(number(&later["hz"]));
        if best_hz >= 20.0 && number(&later["t"]) > number(&first["t"]) + 3.0 {
            break;
        }
    }
    eprintln!(
        "page: {} buckets, {} redraws, best update rate {best_hz:.1}/s, WebGL {}",
        later["buckets"], later["draws"], later["webgl"]
    );
    assert!(
        number(&later["t"]) > number(&first["t"]) + 1.0,
        "{first} {later}"
    );
    assert_ne!(number(&later["fz"]), number(&first["fz"]));
    assert_ne!(number(&later["xi"]), number(&first["xi"]));
    assert!(
        number(&later["buckets"]) > number(&first["buckets"]),
        "{first} {later}"
    );
    // The page streams live (a stalled or polling page draws a few frames a second at most);
    // its design rate (25 a second, ≥ 20 on an idle machine) is measured and printed above,
    // not asserted: a loaded machine starves the browser of the CPU it draws with.
    assert!(best_hz >= MIN_LIVE_UPDATE_HZ, "update rate {best_hz:.1}/s");

    if let Ok(path) = std::env::var("DEFLEX_VIEW_SCREENSHOT") {
        let shot = browser.page("Page.captureScreenshot", json!({"format": "png"}));
        let png = data_encoding::BASE64
            .decode(shot["data"].as_str().unwrap().as_bytes())
            .unwrap();
        std::fs::write(&path, png).unwrap();
        eprintln!("screenshot: {path}");
    }

    // The stop button: a confirmation, then the caller's callback.
    assert_eq!(
        browser.eval("!document.getElementById('stop').hidden"),
        Value::Bool(true)
    );
    let click = browser.page_nowait(
        "Runtime.evaluate",
        json!({"expression": "document.getElementById('stop').click()"}),
    );
    let dialog = browser
        .wait_event("Page.javascriptDialogOpening", Duration::from_secs(10))
        .expect("a confirmation dialog");
    assert_eq!(dialog["type"], "confirm");
    assert!(
        dialog["message"]
            .as_str()
            .unwrap()
            .contains("Stop the correction"),
        "{dialog}"
    );
    assert_eq!(stops.load(Ordering::SeqCst), 0, "stopped before confirming");
    browser.page("Page.handleJavaScriptDialog", json!({"accept": true}));
    assert!(browser.result(click, Duration::from_secs(10)).is_some());
    let mut stopped = false;
    for _ in 0..50 {
        browser.idle(Duration::from_millis(100));
        if stops.load(Ordering::SeqCst) == 1 {
            stopped = true;
            break;
        }
    }
    assert!(stopped, "the stop callback was not called");

    // No console error, no exception, nothing requested beyond this server.
    browser.idle(Duration::from_millis(300));
    let origin = format!("127.0.0.1:{}", view.local_addr().port());
    let mut requests = 0;
    for (method, params) in &browser.events {
        match method.as_str() {
            "Runtime.exceptionThrown" => panic!("exception in the page: {params}"),
            "Runtime.consoleAPICalled" if params["type"] == "error" => {
                panic!("console error: {params}")
            }
            "Log.entryAdded" if params["entry"]["level"] == "error" => {
                panic!("console error: {params}")
            }
            "Network.requestWillBeSent" | "Network.webSocketCreated" => {
                let url = params["request"]["url"]
                    .as_str()
                    .or(params["url"].as_str())
                    .unwrap_or("");
                let local = url.starts_with(&format!("http://{origin}/"))
                    || url.starts_with(&format!("ws://{origin}/"))
                    || url.starts_with("data:")
                    || url.starts_with("blob:")
                    || url == "about:blank";
                assert!(local, "request beyond the server: {url}");
                requests += 1;
            }
            _ => {}
        }
    }
    // The page, its script and style, the two libraries (three in two files + controls), the
    // WebSocket.
    assert!(requests >= 8, "{requests} requests seen");
    let stats = view.stats();
    assert_eq!(stats.stop_requests, 1);
    assert!(stats.clients >= 1);
    drop(browser);
    view.shutdown();
    drop(publisher);
}
