//! Injectable time for the control loop: the same loop runs against hardware in wall time
//! ([`WallClock`]) and against the digital twin in simulated time ([`SimClock`], as fast as the
//! CPU allows). Times are seconds since the clock's origin. The control period of eq. 17's
//! discretisation (100 Hz in the paper, Section 4.2) is paced with [`Clock::sleep_until`].

use std::sync::Arc;
use std::sync::atomic::{AtomicBool, AtomicU64, Ordering};
use std::time::{Duration, Instant};

/// A monotonic clock the control loop can be paced by.
pub trait Clock: Send + Sync {
    /// Seconds since the clock's origin.
    fn now(&self) -> f64;
    /// Returns once `now() >= t_s`.
    fn sleep_until(&self, t_s: f64);
    /// The paced loop ends: it will not sleep on this clock again (lets a driven simulated
    /// clock run on).
    fn release(&self) {}
}

/// Wall time from [`Instant`]; sleeps with the OS and spins the last `spin` of each wait.
#[derive(Clone, Copy, Debug)]
pub struct WallClock {
    origin: Instant,
    spin: Duration,
}

impl WallClock {
    /// A clock starting now, without spinning (friendliest to shared CPUs).
    pub fn new() -> Self {
        WallClock {
            origin: Instant::now(),
            spin: Duration::ZERO,
        }
    }
    /// Spin (busy-wait) the last `spin` of each sleep for sub-scheduler-tick accuracy.
    pub fn with_spin(spin: Duration) -> Self {
        WallClock {
            origin: Instant::now(),
            spin,
        }
    }
    /// The origin instant.
    pub fn origin(&self) -> Instant {
        self.origin
    }
}

impl Default for WallClock {
    fn default() -> Self {
        Self::new()
    }
}

impl Clock for WallClock {
    fn now(&self) -> f64 {
        self.origin.elapsed().as_secs_f64()
    }
    fn sleep_until(&self, t_s: f64) {
        if !t_s.is_finite() {
            return;
        }
        let target = self.origin + Duration::from_secs_f64(t_s.max(0.0));
        let now = Instant::now();
        if target > now + self.spin {
            std::thread::sleep(target - now - self.spin);
        }
        while Instant::now() < target {
            std::hint::spin_loop();
        }
    }
}

/// Simulated time shared between clones.
///
/// * **Free-running** (default): `sleep_until` jumps the time forward at once, so a loop paced
///   by it runs as fast as the CPU allows.
/// * **Driven** ([`SimClock::driven`]): a simulator (the digital twin) owns the time and moves
///   it with [`SimClock::advance_to`]; the paced loop's `sleep_until(t)` waits until the time
///   reaches t, and the simulator never moves the time past a wake-up before that loop's cycle
///   is done (a lockstep handshake), so data produced up to t is seen by the cycle at t. The
///   simulator calls [`SimClock::finish`] when it stops; the paced loop then runs free.
#[derive(Clone, Debug)]
pub struct SimClock {
    inner: Arc<SimInner>,
}

#[derive(Debug)]
struct SimInner {
    now: AtomicU64,
    wake: AtomicU64,
    driven: AtomicBool,
}

impl Default for SimClock {
    fn default() -> Self {
        Self::new()
    }
}

impl SimClock {
    fn with_mode(driven: bool) -> Self {
        SimClock {
            inner: Arc::new(SimInner {
                now: AtomicU64::new(0f64.to_bits()),
                wake: AtomicU64::new(f64::INFINITY.to_bits()),
                driven: AtomicBool::new(driven),
            }),
        }
    }

    /// A free-running clock at t = 0.
    pub fn new() -> Self {
        Self::with_mode(false)
    }

    /// A clock at t = 0 whose time only [`SimClock::advance_to`] moves.
    pub fn driven() -> Self {
        Self::with_mode(true)
    }

    fn set_now(&self, t_s: f64) {
        let _ = self
            .inner
            .now
            .fetch_update(Ordering::AcqRel, Ordering::Acquire, |b| {
                (t_s > f64::from_bits(b)).then_some(t_s.to_bits())
            });
    }

    /// Moves the time to `t_s` (never backwards). Driven clock: first lets the paced loop run
    /// every cycle due at or before `t_s`, each at its own time.
    pub fn advance_to(&self, t_s: f64) {
        if self.inner.driven.load(Ordering::Acquire) {
            loop {
                let wake_bits = self.inner.wake.load(Ordering::Acquire);
                let wake = f64::from_bits(wake_bits);
                if wake.is_nan() || wake > t_s || !self.inner.driven.load(Ordering::Acquire) {
                    break;
                }
                self.set_now(wake);
                while self.inner.wake.load(Ordering::Acquire) == wake_bits
                    && self.inner.driven.load(Ordering::Acquire)
                {
                    std::thread::yield_now();
                }
            }
        }
        self.set_now(t_s);
    }

    /// Waits (wall time, at most `timeout`) until the paced loop has registered its first
    /// wake-up; returns whether it did. A simulator calls it once its first data is out, so the
    /// lockstep starts at the loop's first cycle.
    pub fn wait_for_follower(&self, timeout: Duration) -> bool {
        let start = Instant::now();
        while f64::from_bits(self.inner.wake.load(Ordering::Acquire)).is_infinite() {
            if start.elapsed() > timeout {
                return false;
            }
            std::thread::sleep(Duration::from_micros(100));
        }
        true
    }

    /// The simulator is done: from now on the clock runs free (`sleep_until` jumps).
    pub fn finish(&self) {
        self.inner.driven.store(false, Ordering::Release);
    }
}

impl Clock for SimClock {
    fn now(&self) -> f64 {
        f64::from_bits(self.inner.now.load(Ordering::Acquire))
    }
    fn sleep_until(&self, t_s: f64) {
        if self.inner.driven.load(Ordering::Acquire) {
            self.inner.wake.store(t_s.to_bits(), Ordering::Release);
            while self.now() < t_s && self.inner.driven.load(Ordering::Acquire) {
                std::thread::yield_now();
            }
        }
        self.set_now(t_s);
    }
    fn release(&self) {
        self.inner
            .wake
            .store(f64::INFINITY.to_bits(), Ordering::Release);
    }
}
