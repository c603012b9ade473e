//! The sensor thread: every force/torque sample goes into the running
//! [`WrenchAccumulation`], so the control thread averages the samples of its period.

use super::{ExitGuard, Shared};
use crate::clock::Clock;
use crate::messages::WrenchAccumulation;
use bytemuck::Zeroable;
use deflex_io::ForceSensorLink;
use std::sync::atomic::Ordering;
use std::time::{Duration, Instant};

pub(super) fn sensor_loop<C: Clock>(
    mut link: Box<dyn ForceSensorLink + Send>,
    shared: &Shared,
    clock: &C,
) {
    let _guard = ExitGuard {
        shared,
        control: false,
        release: None,
    };
    let mut accumulation = WrenchAccumulation::zeroed();
    let mut started = link.start().is_ok();
    let mut last_start = Instant::now();
    while !shared.done.load(Ordering::Acquire) {
        match link.receive(Duration::from_millis(10)) {
            Ok(Some(sample)) => {
                accumulation.add(&sample.wrench, sample.status, clock.now());
                shared.wrench.write(&accumulation);
                shared.samples.fetch_add(1, Ordering::Relaxed);
                shared
                    .sample_gaps
                    .fetch_add(u64::from(sample.gap), Ordering::Relaxed);
                if sample.is_fault() {
                    shared.sensor_faults.fetch_add(1, Ordering::Relaxed);
                }
            }
            Ok(None) => {
                // Silent sensor: ask again every second (the control thread decides whether
                // this is a fault).
                if !started || last_start.elapsed() > Duration::from_secs(1) {
                    started = link.start().is_ok();
                    last_start = Instant::now();
                }
            }
            Err(e) if e.is_foreign() => {
                shared.sensor_foreign.fetch_add(1, Ordering::Relaxed);
            }
            Err(_) => {
                shared.sensor_errors.fetch_add(1, Ordering::Relaxed);
            }
        }
    }
    let _ = link.stop();
}
