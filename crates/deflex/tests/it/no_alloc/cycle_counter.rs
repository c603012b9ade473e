//! Allocations per control cycle of another thread (the runtime's control thread), for the
//! runtime's, the live view's and the ROS 2 bridge's no-allocation sessions.

use super::allocations;
use deflex_runtime::{Clock, WallClock};
use std::sync::Arc;
use std::sync::atomic::{AtomicU64, Ordering};

/// The allocations one thread makes between consecutive calls of [`CycleCounter::cycle`]
/// (a control thread's clock calls it once per cycle), filed under one of `N` classes (e.g.
/// "page closed" / "page open"); the first `skip` calls are left out (they include the
/// thread's start). Shared between the measured thread and the test through an `Arc`.
#[derive(Debug)]
pub struct CycleCounter<const N: usize> {
    skip: u64,
    calls: AtomicU64,
    last: AtomicU64,
    allocations: [AtomicU64; N],
    cycles: [AtomicU64; N],
}

impl<const N: usize> CycleCounter<N> {
    /// A counter that leaves out the first `skip` calls.
    pub fn new(skip: u64) -> Self {
        CycleCounter {
            skip,
            calls: AtomicU64::new(0),
            last: AtomicU64::new(0),
            allocations: [const { AtomicU64::new(0) }; N],
            cycles: [const { AtomicU64::new(0) }; N],
        }
    }

    /// Called by the measured thread once per cycle: files its allocations since the previous
    /// call under `class` (< `N`).
    pub fn cycle(&self, class: usize) {
        let count = allocations();
        if self.calls.fetch_add(1, Ordering::Relaxed) >= self.skip {
            let previous = self.last.load(Ordering::Relaxed);
            self.allocations[class].fetch_add(count - previous, Ordering::Relaxed);
            self.cycles[class].fetch_add(1, Ordering::Relaxed);
        }
        self.last.store(count, Ordering::Relaxed);
    }

    /// Allocations filed under `class`.
    pub fn allocations(&self, class: usize) -> u64 {
        self.allocations[class].load(Ordering::Relaxed)
    }

    /// Cycles measured under `class`.
    pub fn cycles(&self, class: usize) -> u64 {
        self.cycles[class].load(Ordering::Relaxed)
    }
}

/// Wall time that records, at every `sleep_until` (called by the control thread only, once per
/// cycle), the allocations its caller made since the previous call (from the third call on: the
/// first two include the thread's start).
#[derive(Clone)]
pub struct CountingClock {
    inner: WallClock,
    /// The allocations and cycles measured (one class).
    pub counter: Arc<CycleCounter<1>>,
}

impl CountingClock {
    /// Wall time from now, nothing counted yet.
    pub fn new() -> Self {
        CountingClock {
            inner: WallClock::new(),
            counter: Arc::new(CycleCounter::new(2)),
        }
    }
}

impl Clock for CountingClock {
    fn now(&self) -> f64 {
        self.inner.now()
    }
    fn sleep_until(&self, t_s: f64) {
        self.counter.cycle(0);
        self.inner.sleep_until(t_s)
    }
}
