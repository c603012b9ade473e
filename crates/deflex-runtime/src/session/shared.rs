//! What the three threads share: the typed messages ([`crate::messages`]) in sequence cells, the
//! flags of the session's life cycle and the links' counters.

use super::summary::RunSummary;
use crate::messages::{CorrectionCommand, JointSample, WrenchAccumulation};
use deflex_telemetry::SeqCell;
use std::net::SocketAddr;
use std::sync::atomic::{AtomicBool, AtomicU64, Ordering};
use std::sync::{Mutex, PoisonError};

const NO_LATE: u64 = u64::MAX;

pub(super) struct Shared {
    /// The robot's latest telegram (robot-link thread → control thread).
    pub(super) joints: SeqCell<JointSample>,
    /// The sensor's readings so far (sensor thread → control thread).
    pub(super) wrench: SeqCell<WrenchAccumulation>,
    /// The answer of the latest control cycle (control thread → robot-link thread).
    pub(super) command: SeqCell<CorrectionCommand>,
    pub(super) stop: AtomicBool,
    pub(super) done: AtomicBool,
    pub(super) control_failed: AtomicBool,
    pub(super) link_failed: AtomicBool,
    pub(super) telegrams: AtomicU64,
    /// Answers sent later than one robot cycle after their telegram.
    pub(super) late_answers: AtomicU64,
    pub(super) last_telegram_s: AtomicU64,
    pub(super) robot_timeouts: AtomicU64,
    pub(super) robot_bad_packets: AtomicU64,
    pub(super) robot_errors: AtomicU64,
    pub(super) robot_foreign: AtomicU64,
    pub(super) robot_dropped: AtomicU64,
    pub(super) robot_starved: AtomicBool,
    pub(super) last_foreign: Mutex<Option<SocketAddr>>,
    pub(super) first_late: AtomicU64,
    pub(super) last_late: AtomicU64,
    pub(super) samples: AtomicU64,
    pub(super) sample_gaps: AtomicU64,
    pub(super) sensor_faults: AtomicU64,
    pub(super) sensor_errors: AtomicU64,
    pub(super) sensor_foreign: AtomicU64,
}

impl Shared {
    pub(super) fn new() -> Self {
        Shared {
            joints: SeqCell::new(),
            wrench: SeqCell::new(),
            command: SeqCell::new(),
            stop: AtomicBool::new(false),
            done: AtomicBool::new(false),
            control_failed: AtomicBool::new(false),
            link_failed: AtomicBool::new(false),
            telegrams: AtomicU64::new(0),
            late_answers: AtomicU64::new(0),
            last_telegram_s: AtomicU64::new(f64::NEG_INFINITY.to_bits()),
            robot_timeouts: AtomicU64::new(0),
            robot_bad_packets: AtomicU64::new(0),
            robot_errors: AtomicU64::new(0),
            robot_foreign: AtomicU64::new(0),
            robot_dropped: AtomicU64::new(0),
            robot_starved: AtomicBool::new(false),
            last_foreign: Mutex::new(None),
            first_late: AtomicU64::new(NO_LATE),
            last_late: AtomicU64::new(NO_LATE),
            samples: AtomicU64::new(0),
            sample_gaps: AtomicU64::new(0),
            sensor_faults: AtomicU64::new(0),
            sensor_errors: AtomicU64::new(0),
            sensor_foreign: AtomicU64::new(0),
        }
    }

    /// Records the robot's own count of late answers from a telegram.
    pub(super) fn note_robot_late(&self, late: u64) {
        let _ =
            self.first_late
                .compare_exchange(NO_LATE, late, Ordering::Relaxed, Ordering::Relaxed);
        self.last_late.store(late, Ordering::Relaxed);
    }

    /// Answers the robot counted as late over the session (last minus first report).
    pub(super) fn robot_late(&self) -> Option<u64> {
        let (first, last) = (
            self.first_late.load(Ordering::Relaxed),
            self.last_late.load(Ordering::Relaxed),
        );
        (first != NO_LATE && last != NO_LATE).then(|| last.saturating_sub(first))
    }

    /// Copies the link counters into the summary.
    pub(super) fn fill_counters(&self, summary: &mut RunSummary) {
        summary.telegrams = self.telegrams.load(Ordering::Relaxed);
        summary.robot_joints = self.joints.read().0.joint_count as usize;
        summary.robot_timeouts = self.robot_timeouts.load(Ordering::Relaxed);
        summary.robot_bad_packets = self.robot_bad_packets.load(Ordering::Relaxed);
        summary.robot_errors = self.robot_errors.load(Ordering::Relaxed);
        summary.robot_foreign = self.robot_foreign.load(Ordering::Relaxed);
        summary.robot_dropped = self.robot_dropped.load(Ordering::Relaxed);
        summary.robot_starved = self.robot_starved.load(Ordering::Relaxed);
        // A poisoned lock still holds the last address (a plain value): it is read, not dropped.
        summary.last_foreign = *self
            .last_foreign
            .lock()
            .unwrap_or_else(PoisonError::into_inner);
        summary.robot_late = self.robot_late();
        summary.samples = self.samples.load(Ordering::Relaxed);
        summary.sample_gaps = self.sample_gaps.load(Ordering::Relaxed);
        summary.sensor_faults = self.sensor_faults.load(Ordering::Relaxed);
        summary.sensor_errors = self.sensor_errors.load(Ordering::Relaxed);
        summary.sensor_foreign = self.sensor_foreign.load(Ordering::Relaxed);
    }
}
