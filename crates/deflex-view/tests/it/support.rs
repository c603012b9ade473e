//! A SIMULATED publisher thread: the synthetic stream (`deflex_telemetry::synthetic`) published
//! in real time, as a control thread would.

use deflex_telemetry::synthetic::SyntheticCell;
use deflex_telemetry::{Broadcast, CycleSample, SessionInfo, broadcast};
use std::sync::Arc;
use std::sync::atomic::{AtomicBool, AtomicU64, Ordering};
use std::thread::JoinHandle;
use std::time::{Duration, Instant};

pub struct Publisher {
    pub ring: Arc<Broadcast<CycleSample>>,
    pub info: Arc<SessionInfo>,
    pub published: Arc<AtomicU64>,
    stop: Arc<AtomicBool>,
    handle: Option<JoinHandle<()>>,
}

impl Publisher {
    /// Publishes at `rate_hz` until dropped (and `prefill` samples at once first).
    pub fn start(rate_hz: f64, prefill: usize) -> Publisher {
        let period = 1.0 / rate_hz;
        let mut cell = SyntheticCell::new(period, 11, true);
        let info = Arc::new(cell.session_info());
        let (mut publisher, ring) = broadcast::<CycleSample>(65_536);
        for _ in 0..prefill {
            publisher.publish(&cell.next_sample());
        }
        let stop = Arc::new(AtomicBool::new(false));
        let published = Arc::new(AtomicU64::new(prefill as u64));
        let (s, p) = (stop.clone(), published.clone());
        let handle = std::thread::spawn(move || {
            let start = Instant::now();
            let mut n = 0u64;
            while !s.load(Ordering::Acquire) {
                publisher.publish(&cell.next_sample());
                p.fetch_add(1, Ordering::Relaxed);
                n += 1;
                let due = start + Duration::from_secs_f64(n as f64 * period);
                if let Some(wait) = due.checked_duration_since(Instant::now()) {
                    std::thread::sleep(wait);
                }
            }
        });
        Publisher {
            ring,
            info,
            published,
            stop,
            handle: Some(handle),
        }
    }
}

impl Publisher {
    /// The live view of this stream on `addr` with `options`, and `stop` for its stop button.
    pub fn serve_with(
        &self,
        addr: &str,
        stop: Option<deflex_view::StopCallback>,
        options: deflex_view::ViewOptions,
    ) -> deflex_view::ViewHandle {
        deflex_view::serve_with(
            addr.parse().unwrap(),
            self.ring.clone(),
            self.info.clone(),
            stop,
            options,
        )
        .unwrap()
    }

    /// The live view of this stream on `addr` with the default options.
    pub fn serve(
        &self,
        addr: &str,
        stop: Option<deflex_view::StopCallback>,
    ) -> deflex_view::ViewHandle {
        self.serve_with(addr, stop, deflex_view::ViewOptions::default())
    }
}

/// A stop callback that counts its calls, and the count.
pub fn counting_stop() -> (Arc<AtomicU64>, Option<deflex_view::StopCallback>) {
    let calls = Arc::new(AtomicU64::new(0));
    let counter = calls.clone();
    let stop: deflex_view::StopCallback = Box::new(move || {
        counter.fetch_add(1, Ordering::SeqCst);
    });
    (calls, Some(stop))
}

impl Drop for Publisher {
    fn drop(&mut self) {
        self.stop.store(true, Ordering::Release);
        if let Some(h) = self.handle.take() {
            let _ = h.join();
        }
    }
}

/// Polls `f` every 20 ms until it is true or `limit` passes.
pub fn wait_until(limit: Duration, mut f: impl FnMut() -> bool) -> bool {
    let deadline = Instant::now() + limit;
    loop {
        if f() {
            return true;
        }
        if Instant::now() >= deadline {
            return false;
        }
        std::thread::sleep(Duration::from_millis(20));
    }
}
