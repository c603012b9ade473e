//! A minimal Chrome DevTools Protocol client over `tungstenite`: launches Debian's headless
//! Chromium on a fresh profile, attaches to one page and sends commands, keeping every event;
//! and the checks every live-page test makes with it (the page moves, logs no error, requests
//! nothing beyond its servers, its stop button asks first; the screenshot for the README).
//!
//! deflex-cli's browser test compiles this file too, by `#[path]`: the live page of a
//! `deflex run` is checked as this package's is, with one client.

use serde_json::{Value, json};
use std::io::{BufRead, BufReader};
use std::net::TcpStream;
use std::path::PathBuf;
use std::process::{Child, Command, Stdio};
use std::time::{Duration, Instant};
use tungstenite::stream::MaybeTlsStream;
use tungstenite::{Message, WebSocket};

pub const CHROMIUM: &str = "/usr/bin/chromium";

/// Fewest page updates a second that count as a live stream (the page's own count over its last
/// two seconds, best window): half the ≥ 20 a second the page keeps on an idle machine.
pub const MIN_LIVE_UPDATE_HZ: f64 = 10.0;

/// The page's charts (`window.deflexView.chartLengths()` names them).
pub const CHARTS: [&str; 6] = [
    "force",
    "torque",
    "deflection",
    "correction",
    "error",
    "timing",
];

/// A JSON number of the page's state (NaN when absent).
pub fn number(v: &Value) -> f64 {
    v.as_f64().unwrap_or(f64::NAN)
}

pub struct Browser {
    child: Child,
    profile: PathBuf,
    ws: WebSocket<MaybeTlsStream<TcpStream>>,
    next_id: u64,
    session: String,
    /// Every event received so far (method, params).
    pub events: Vec<(String, Value)>,
}

impl Drop for Browser {
    fn drop(&mut self) {
        let _ = self.ws.send(Message::text(
            json!({"id": 0, "method": "Browser.close"}).to_string(),
        ));
        let deadline = Instant::now() + Duration::from_secs(5);
        while Instant::now() < deadline {
            if let Ok(Some(_)) = self.child.try_wait() {
                break;
            }
            std::thread::sleep(Duration::from_millis(50));
        }
        let _ = self.child.kill();
        let _ = self.child.wait();
        let _ = std::fs::remove_dir_all(&self.profile);
    }
}

impl Browser {
    /// Starts Chromium (headless, no network services, a new empty profile) and attaches to a
    /// new page.
    pub fn launch() -> Browser {
        let profile = std::env::temp_dir().join(format!(
            "deflex-view-chromium-{}-{}",
            std::process::id(),
            std::time::SystemTime::now()
                .duration_since(std::time::UNIX_EPOCH)
                .unwrap()
                .as_nanos()
        ));
        std::fs::create_dir_all(&profile).unwrap();
        let mut child = Command::new(CHROMIUM)
            .args([
                "--headless",
                "--no-sandbox",
                "--disable-gpu",
                "--disable-quic",
                "--no-first-run",
                "--disable-background-networking",
                "--disable-component-update",
                "--disable-sync",
                // WebGL on the CPU for the 3-D view (no GPU here).
                "--enable-unsafe-swiftshader",
                "--use-angle=swiftshader",
                "--window-size=1400,1700",
                "--remote-debugging-port=0",
            ])
            .arg(format!("--user-data-dir={}", profile.display()))
            .arg("about:blank")
            .stdin(Stdio::null())
            .stdout(Stdio::null())
            .stderr(Stdio::piped())
            .spawn()
            .unwrap_or_else(|e| panic!("{CHROMIUM}: {e} (apt-get install chromium)"));
        // "DevTools listening on ws://127.0.0.1:PORT/devtools/browser/ID" on stderr.
        let stderr = child.stderr.take().unwrap();
        let (tx, rx) = std::sync::mpsc::channel();
        std::thread::spawn(move || {
            let mut sent = false;
            for line in BufReader::new(stderr).lines().map_while(Result::ok) {
                if !sent && let Some(i) = line.find("ws://") {
                    let _ = tx.send(line[i..].trim().to_string());
                    sent = true;
                }
            }
        });
        let url = rx
            .recv_timeout(Duration::from_secs(60))
            .expect("Chromium did not print its DevTools address within 60 s");
        let (ws, _) = tungstenite::connect(url.as_str()).expect("DevTools WebSocket");
        if let MaybeTlsStream::Plain(s) = ws.get_ref() {
            s.set_read_timeout(Some(Duration::from_millis(200)))
                .unwrap();
        }
        let mut browser = Browser {
            child,
            profile,
            ws,
            next_id: 1,
            session: String::new(),
            events: Vec::new(),
        };
        let target = browser.call("Target.createTarget", json!({"url": "about:blank"}));
        let target_id = target["targetId"].as_str().unwrap().to_string();
        let attached = browser.call(
            "Target.attachToTarget",
            json!({"targetId": target_id, "flatten": true}),
        );
        browser.session = attached["sessionId"].as_str().unwrap().to_string();
        for domain in [
            "Runtime.enable",
            "Log.enable",
            "Network.enable",
            "Page.enable",
        ] {
            browser.page(domain, json!({}));
        }
        browser
    }

    fn send(&mut self, method: &str, params: Value, session: bool) -> u64 {
        let id = self.next_id;
        self.next_id += 1;
        let mut msg = json!({"id": id, "method": method, "params": params});
        if session {
            msg["sessionId"] = Value::String(self.session.clone());
        }
        self.ws.send(Message::text(msg.to_string())).unwrap();
        id
    }

    /// Reads messages for up to `wait`; returns the result of command `id` if it arrived.
    fn pump(&mut self, id: Option<u64>, wait: Duration) -> Option<Value> {
        let deadline = Instant::now() + wait;
        while Instant::now() < deadline {
            match self.ws.read() {
                Ok(Message::Text(text)) => {
                    let v: Value = serde_json::from_str(text.as_str()).unwrap();
                    if let Some(method) = v.get("method").and_then(|m| m.as_str()) {
                        self.events.push((method.to_string(), v["params"].clone()));
                    } else if id.is_some() && v.get("id").and_then(|i| i.as_u64()) == id {
                        if let Some(e) = v.get("error") {
                            panic!("DevTools error: {e}");
                        }
                        return Some(v["result"].clone());
                    }
                }
                Ok(_) => {}
                Err(tungstenite::Error::Io(e))
                    if matches!(
                        e.kind(),
                        std::io::ErrorKind::WouldBlock | std::io::ErrorKind::TimedOut
                    ) => {}
                Err(e) => panic!("DevTools connection: {e}"),
            }
        }
        None
    }

    fn call(&mut self, method: &str, params: Value) -> Value {
        let id = self.send(method, params, false);
        self.pump(Some(id), Duration::from_secs(30))
            .unwrap_or_else(|| panic!("{method}: no answer in 30 s"))
    }

    /// A command to the page's session; waits up to 30 s for its result.
    pub fn page(&mut self, method: &str, params: Value) -> Value {
        let id = self.send(method, params, true);
        self.pump(Some(id), Duration::from_secs(30))
            .unwrap_or_else(|| panic!("{method}: no answer in 30 s"))
    }

    /// Sends a page command without waiting (one that opens a dialog); returns its id.
    pub fn page_nowait(&mut self, method: &str, params: Value) -> u64 {
        self.send(method, params, true)
    }

    /// Waits up to `wait` for the result of an earlier command.
    pub fn result(&mut self, id: u64, wait: Duration) -> Option<Value> {
        self.pump(Some(id), wait)
    }

    /// Keeps collecting events for `wait`.
    pub fn idle(&mut self, wait: Duration) {
        self.pump(None, wait);
    }

    /// Evaluates `expression` in the page and returns its value (JSON).
    pub fn eval(&mut self, expression: &str) -> Value {
        let r = self.page(
            "Runtime.evaluate",
            json!({"expression": expression, "returnByValue": true}),
        );
        if let Some(e) = r.get("exceptionDetails") {
            panic!("{expression}: {e}");
        }
        r["result"]["value"].clone()
    }

    /// The first event named `method` received so far, waiting up to `wait` for it.
    pub fn wait_event(&mut self, method: &str, wait: Duration) -> Option<Value> {
        let deadline = Instant::now() + wait;
        loop {
            if let Some((_, p)) = self.events.iter().find(|(m, _)| m == method) {
                return Some(p.clone());
            }
            if Instant::now() >= deadline {
                return None;
            }
            self.pump(None, Duration::from_millis(100));
        }
    }
}

/// The checks of a live page.
impl Browser {
    /// Evaluates `state` (an expression giving the page's state, with `t` its session time and
    /// `hz` its update rate) every 0.5 s for up to `limit`, until the page has kept 20 updates a
    /// second and its time has passed `t_from + advance_s`. Returns the last state and the best
    /// update rate seen.
    pub fn watch_live(
        &mut self,
        state: &str,
        t_from: f64,
        advance_s: f64,
        limit: Duration,
    ) -> (Value, f64) {
        let mut best_hz: f64 = 0.0;
        let mut later = Value::Null;
        let until = Instant::now() + limit;
        while Instant::now() < until {
            self.idle(Duration::from_millis(500));
            later = self.eval(state);
            best_hz = best_hz.max(number(&later["hz"]));
            if best_hz >= 20.0 && number(&later["t"]) > t_from + advance_s {
                break;
            }
        }
        (later, best_hz)
    }

    /// Asserts that the events so far hold no console error or exception and no request beyond
    /// `origins` (`host:port` of the servers); returns the requests seen; forgets the events.
    pub fn check_events(&mut self, origins: &[String]) -> usize {
        let mut requests = 0;
        for (method, params) in &self.events {
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
                    let local = origins.iter().any(|o| {
                        url.starts_with(&format!("http://{o}/"))
                            || url.starts_with(&format!("ws://{o}/"))
                    }) || url.starts_with("data:")
                        || url.starts_with("blob:")
                        || url == "about:blank";
                    assert!(local, "request beyond the servers: {url}");
                    requests += 1;
                }
                _ => {}
            }
        }
        self.events.clear();
        requests
    }

    /// With `DEFLEX_VIEW_SCREENSHOT=PATH` set, saves the page's screenshot there (the README's
    /// `docs/live-view.png`).
    pub fn screenshot_if_asked(&mut self) {
        if let Ok(path) = std::env::var("DEFLEX_VIEW_SCREENSHOT") {
            let shot = self.page("Page.captureScreenshot", json!({"format": "png"}));
            let png = data_encoding::BASE64
                .decode(shot["data"].as_str().unwrap().as_bytes())
                .unwrap();
            std::fs::write(&path, png).unwrap();
            eprintln!("screenshot: {path}");
        }
    }

    /// Clicks the page's stop button; returns the click's command id and the dialog it opened
    /// (a confirmation, still open: [`Browser::accept_dialog`]).
    pub fn click_stop(&mut self) -> (u64, Value) {
        let click = self.page_nowait(
            "Runtime.evaluate",
            json!({"expression": "document.getElementById('stop').click()"}),
        );
        let dialog = self
            .wait_event("Page.javascriptDialogOpening", Duration::from_secs(10))
            .expect("a confirmation dialog");
        assert_eq!(dialog["type"], "confirm");
        (click, dialog)
    }

    /// Accepts the open dialog; waits for the command `click` that opened it to complete.
    pub fn accept_dialog(&mut self, click: u64) {
        self.page("Page.handleJavaScriptDialog", json!({"accept": true}));
        assert!(self.result(click, Duration::from_secs(10)).is_some());
    }
}
