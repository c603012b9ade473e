//! Cycle-time statistics: a fixed histogram (1 µs bins up to 50 ms, allocated once), count,
//! maximum and deadline misses, with p50/p99/max. Recording never allocates. Used for the
//! control cycle (100 Hz, Section 4.2) and for the robot-link reply latency (KUKA RSI: within
//! the 4 ms cycle).

use std::time::Duration;

const BINS: usize = 50_000;

/// Latency / cycle-time histogram.
#[derive(Clone, Debug)]
pub struct CycleStats {
    bins: Box<[u32]>,
    overflow: u64,
    count: u64,
    sum_ns: u128,
    max_ns: u64,
    deadline_ns: u64,
    misses: u64,
}

/// Summary of a [`CycleStats`].
#[derive(Clone, Copy, Debug, PartialEq, Default)]
pub struct StatsSummary {
    /// Samples recorded.
    pub count: u64,
    /// Median (µs, bin resolution 1 µs).
    pub p50_us: f64,
    /// 99th percentile (µs).
    pub p99_us: f64,
    /// Maximum (µs, exact).
    pub max_us: f64,
    /// Mean (µs).
    pub mean_us: f64,
    /// Samples longer than the deadline.
    pub deadline_misses: u64,
}

impl CycleStats {
    /// Empty statistics with a deadline (samples longer than it count as misses).
    pub fn new(deadline: Duration) -> Self {
        CycleStats {
            bins: vec![0u32; BINS].into_boxed_slice(),
            overflow: 0,
            count: 0,
            sum_ns: 0,
            max_ns: 0,
            deadline_ns: deadline.as_nanos() as u64,
            misses: 0,
        }
    }

    /// Records one duration. Allocation-free.
    #[inline]
    pub fn record(&mut self, d: Duration) {
        let ns = d.as_nanos().min(u128::from(u64::MAX)) as u64;
        let us = (ns / 1000) as usize;
        if us < BINS {
            self.bins[us] = self.bins[us].saturating_add(1);
        } else {
            self.overflow += 1;
        }
        self.count += 1;
        self.sum_ns += u128::from(ns);
        self.max_ns = self.max_ns.max(ns);
        if ns > self.deadline_ns {
            self.misses += 1;
        }
    }

    /// Counts a miss that has no duration (e.g. a cycle skipped entirely).
    pub fn record_miss(&mut self) {
        self.misses += 1;
    }

    /// Number of samples.
    pub fn count(&self) -> u64 {
        self.count
    }

    /// Percentile `p` in [0, 100] (µs, upper edge of the bin).
    pub fn percentile_us(&self, p: f64) -> f64 {
        if self.count == 0 {
            return 0.0;
        }
        let rank = ((p / 100.0) * self.count as f64).ceil().max(1.0) as u64;
        let mut seen = 0u64;
        for (us, n) in self.bins.iter().enumerate() {
            seen += u64::from(*n);
            if seen >= rank {
                return (us as f64 + 1.0).min(self.max_ns as f64 / 1000.0);
            }
        }
        self.max_ns as f64 / 1000.0
    }

    /// The summary.
    pub fn summary(&self) -> StatsSummary {
        StatsSummary {
            count: self.count,
            p50_us: self.percentile_us(50.0),
            p99_us: self.percentile_us(99.0),
            max_us: self.max_ns as f64 / 1000.0,
            mean_us: if self.count == 0 {
                0.0
            } else {
                self.sum_ns as f64 / self.count as f64 / 1000.0
            },
            deadline_misses: self.misses,
        }
    }
}

impl std::fmt::Display for StatsSummary {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(
            f,
            "n = {}, p50 = {:.0} µs, p99 = {:.0} µs, max = {:.0} µs, misses = {}",
            self.count, self.p50_us, self.p99_us, self.max_us, self.deadline_misses
        )
    }
}
