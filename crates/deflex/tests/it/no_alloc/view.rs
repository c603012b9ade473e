//! What a page costs the control loop, measured **in one session**: `deflex run`'s threads
//! (deflex-runtime's `spawn`, the links of a CELL.toml from deflex-app) against
//! `deflex cell --sim`'s twin served on loopback (deflex-sim's `twin::cell_server::serve_cell`,
//! SIMULATED), the live view on the session's telemetry,
//! and a page (a WebSocket client reading every message) that comes and goes: closed, open,
//! closed, open. The clock that paces the control thread counts that thread's allocations at
//! every cycle (the counting allocator counts per thread) and files them under the page's state;
//! the cycle times come from the session's own telemetry, split at the cycles where the page
//! opened and closed.
//!
//! The allocations must be zero with the page open as with it closed. The cycle-time p99 of
//! both is printed (`--nocapture`), not judged: the machine is shared.

use super::cycle_counter::CycleCounter;
use deflex_app::cell::config::CellFile;
use deflex_control::Controller;
use deflex_runtime::telemetry::{StreamSource, Telemetry, session_info};
use deflex_runtime::{Clock, RuntimeOptions, WallClock, spawn};
use deflex_sim::twin::cell_server::{ServeOptions, serve_cell};
use deflex_sim::{CellConfig, ToolPath};
use std::net::TcpStream;
use std::sync::Arc;
use std::sync::atomic::{AtomicBool, Ordering};
use std::time::{Duration, Instant};
use tungstenite::Message;
use tungstenite::stream::MaybeTlsStream;

/// Wall time that files, at every `sleep_until` (the control thread's, once per cycle), the
/// allocations its caller made since the previous call under the page's state then (class 0:
/// page closed, 1: open; the first two calls include the thread's start and are left out).
#[derive(Clone)]
struct CountingClock {
    inner: WallClock,
    page_open: Arc<AtomicBool>,
    counter: Arc<CycleCounter<2>>,
}

impl Clock for CountingClock {
    fn now(&self) -> f64 {
        self.inner.now()
    }
    fn sleep_until(&self, t_s: f64) {
        self.counter
            .cycle(self.page_open.load(Ordering::Relaxed) as usize);
        self.inner.sleep_until(t_s)
    }
}

/// The documented `CELL.toml` as a test session runs it (deflex-app's test fixture, compiled here
/// rather than copied).
#[path = "../../../../deflex-app/tests/it/example_cell.rs"]
mod example_cell;

/// A page: reads every message while `open`, closes its socket while not; counts messages.
fn page(addr: std::net::SocketAddr, open: Arc<AtomicBool>, done: Arc<AtomicBool>) -> u64 {
    let mut messages = 0;
    while !done.load(Ordering::Acquire) {
        if !open.load(Ordering::Acquire) {
            std::thread::sleep(Duration::from_millis(20));
            continue;
        }
        let (mut ws, _) = tungstenite::connect(format!("ws://{addr}/ws")).unwrap();
        if let MaybeTlsStream::Plain(s) = ws.get_ref() {
            s.set_read_timeout(Some(Duration::from_millis(100)))
                .unwrap();
        }
        while open.load(Ordering::Acquire) && !done.load(Ordering::Acquire) {
            match ws.read() {
                Ok(Message::Binary(_)) => messages += 1,
                Ok(_) => {}
                Err(tungstenite::Error::Io(e))
                    if matches!(
                        e.kind(),
                        std::io::ErrorKind::WouldBlock | std::io::ErrorKind::TimedOut
                    ) => {}
                Err(_) => break,
            }
        }
        let _ = ws.close(None);
        let _ = ws.flush();
        drop::<tungstenite::WebSocket<MaybeTlsStream<TcpStream>>>(ws);
    }
    messages
}

fn p99(mut v: Vec<f64>) -> f64 {
    v.sort_by(f64::total_cmp);
    let n = v.len();
    v.get(((0.99 * n as f64).ceil() as usize).clamp(1, n.max(1)) - 1)
        .copied()
        .unwrap_or(f64::NAN)
}

#[test]
fn an_open_page_costs_the_control_loop_no_allocation() {
    let dir = std::env::temp_dir().join(format!("deflex-view-cost-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(&dir).unwrap();
    let file = CellFile::load(&example_cell::example_cell_file(&dir)).unwrap();

    // The twin, served as `deflex cell --sim` serves it: the first 300 mm of the cone (≈ 30 s).
    let stop_cell = Arc::new(AtomicBool::new(false));
    let cell = {
        let options = ServeOptions {
            twin: CellConfig::default(),
            path: ToolPath::paper_cone().truncated(300.0),
            seed: 1,
            speed: 1.0,
            wait_s: 60.0,
            dwell_s: 0.5,
            pose_jump: None,
        };
        // The ends of the cell from the file, as `deflex cell --sim` takes them.
        let sides = file.cell_sides(&options.twin).unwrap();
        let stop = stop_cell.clone();
        std::thread::spawn(move || serve_cell(&sides, &options, &stop, &mut |_| {}))
    };

    // `deflex run`'s threads from the same file, paced by the counting clock.
    let robot = deflex_app::load::load_robot(&file.model_spec()).unwrap();
    let controller = Controller::new(robot, file.controller_config()).unwrap();
    let joints = controller.robot().joint_count();
    let info = session_info(
        &controller,
        StreamSource::Runtime,
        file.robot.kind.key(),
        file.robot.cycle_s,
    );
    let telemetry = Telemetry::new(info, 1 << 14);
    let mut cycles = telemetry.subscribe();
    let page_open = Arc::new(AtomicBool::new(false));
    let clock = CountingClock {
        inner: WallClock::new(),
        page_open: page_open.clone(),
        counter: Arc::new(CycleCounter::new(2)),
    };
    let ring = telemetry.ring().clone();
    let view_info = telemetry.info().clone();
    let options = RuntimeOptions {
        robot_cycle_s: file.robot.cycle_s,
        realtime: false,
        lock_memory: false,
        startup_timeout_s: 60.0,
        idle_exit_s: Some(1.0),
    };
    let runtime = spawn(
        controller,
        file.open_robot_link(joints).unwrap(),
        file.open_sensor_link().unwrap(),
        clock.clone(),
        telemetry,
        options,
    )
    .unwrap();
    let view = deflex_view::serve(
        "127.0.0.1:0".parse().unwrap(),
        ring.clone(),
        view_info,
        None,
    )
    .unwrap();
    let done = Arc::new(AtomicBool::new(false));
    let reader = {
        let (addr, open, done) = (view.local_addr(), page_open.clone(), done.clone());
        std::thread::spawn(move || page(addr, open, done))
    };

    // Wait for the correction to run, then alternate: closed, open, closed, open, noting the
    // cycle where each phase began. A phase lasts control cycles, not seconds (longer in wall
    // time on a slow machine): 310 closed, 400 open, so that each state has more than 500 timed
    // cycles after the margin below, and the page reads ≈ 25 updates/s for 8 s.
    let start = Instant::now();
    while ring
        .latest()
        .is_none_or(|s| s.phase() != deflex_telemetry::Phase::Running)
    {
        assert!(
            start.elapsed() < Duration::from_secs(60),
            "the session did not start"
        );
        std::thread::sleep(Duration::from_millis(20));
    }
    let mut phases = Vec::new();
    let mut clients_while_closed = 0;
    for open in [false, true, false, true] {
        page_open.store(open, Ordering::Release);
        let first = ring.published();
        let length = if open { 400 } else { 310 };
        let phase = Instant::now();
        while ring.published() < first + length {
            assert!(
                phase.elapsed() < Duration::from_secs(60),
                "{} cycles in 60 s",
                ring.published() - first
            );
            std::thread::sleep(Duration::from_millis(10));
        }
        if !open {
            clients_while_closed += view.stats().clients;
        }
        phases.push((open, first, ring.published()));
    }
    done.store(true, Ordering::Release);
    page_open.store(false, Ordering::Release);
    let messages = reader.join().unwrap();
    // Stopped while the twin still plays: the correction ramps out as the robot hears it and
    // the link sends its last answer (a robot stopped first would leave the link waiting to
    // send it); then the twin stops.
    runtime.request_stop();
    let stopping = Instant::now();
    while !runtime.is_finished() && stopping.elapsed() < Duration::from_secs(10) {
        std::thread::sleep(Duration::from_millis(10));
    }
    let summary = runtime.join();
    stop_cell.store(true, Ordering::Release);
    let served = cell.join().unwrap();
    let stats = view.stats();
    view.shutdown();

    // Cycle times per phase (0.5 s after each switch left out: the page connecting or leaving,
    // which takes a handshake on loopback, or one 100 ms read timeout).
    let mut samples = Vec::new();
    cycles.drain(|s| samples.push((s.cycle, s.cycle_time_s)));
    assert_eq!(cycles.lost(), 0);
    let margin = 50; // cycles at 100 Hz
    let mut times = [Vec::new(), Vec::new()];
    for (open, first, last) in &phases {
        for (cycle, t) in &samples {
            if *cycle > first + margin && *cycle <= *last {
                times[*open as usize].push(t * 1e6);
            }
        }
    }
    let allocations = [0, 1].map(|i| clock.counter.allocations(i));
    let measured = [0, 1].map(|i| clock.counter.cycles(i));
    let (n_closed, n_open) = (times[0].len(), times[1].len());
    eprintln!(
        "control thread, one session (SIMULATED cell on loopback): page closed {} allocations \
         in {} cycles, p99 {:.1} µs over {n_closed} cycles; page open {} allocations in {} \
         cycles, p99 {:.1} µs over {n_open} cycles; the page read {messages} messages; view: \
         {} samples, {} lost, {} messages dropped; session p99 {:.1} µs, cell: {:?}",
        allocations[0],
        measured[0],
        p99(times[0].clone()),
        allocations[1],
        measured[1],
        p99(times[1].clone()),
        stats.samples_received,
        stats.samples_lost,
        stats.frames_dropped,
        summary.control.p99_us,
        served
            .as_ref()
            .map(|o| o.cycles)
            .map_err(ToString::to_string),
    );
    assert_eq!(summary.error, None);
    assert!(served.is_ok());
    assert!(n_closed > 500 && n_open > 500, "{n_closed} {n_open}");
    assert!(messages > 100, "the page read {messages} messages");
    assert_eq!(clients_while_closed, 0, "a page stayed while closed");
    assert_eq!(allocations, [0, 0], "allocations in {measured:?} cycles");
    let _ = std::fs::remove_dir_all(&dir);
}
