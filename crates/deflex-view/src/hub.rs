//! The pump: one thread reads the telemetry [`Subscriber`], decimates it into buckets, keeps the
//! ten-minute history and hands every message to each connected page's bounded queue with
//! `try_send`. A full queue drops the message for that page and counts it; nothing here can
//! make the publisher wait (it never looks at its subscribers).

use crate::Shared;
use crate::frame::{
    self, BUCKET_S, Bucket, Decimator, HISTORY_BUCKETS, KIND_HISTORY, KIND_LIVE,
    MAX_BUCKETS_PER_MESSAGE,
};
use deflex_telemetry::{CycleSample, Subscriber};
use std::collections::VecDeque;
use std::sync::atomic::{AtomicU64, Ordering};
use std::sync::mpsc::{SyncSender, TrySendError};
use std::sync::{Arc, Mutex};
use std::time::{Duration, Instant};

/// Encoded messages in one queue slot: a live message, or a new page's whole history (so that
/// a short queue never drops the history).
pub(crate) type Encoded = Arc<Vec<Arc<[u8]>>>;

/// A page's end of the pump: its queue and its dropped count.
pub(crate) struct ClientSlot {
    pub(crate) tx: SyncSender<Encoded>,
    pub(crate) dropped: Arc<AtomicU64>,
}

/// Pages waiting for their history (handed over by the connection threads).
#[derive(Default)]
pub(crate) struct Registry {
    pub(crate) waiting: Mutex<Vec<ClientSlot>>,
}

fn offer(slot: &ClientSlot, message: &Encoded, shared: &Shared) -> bool {
    match slot.tx.try_send(message.clone()) {
        Ok(()) => true,
        Err(TrySendError::Full(_)) => {
            slot.dropped.fetch_add(1, Ordering::Relaxed);
            shared.stats.frames_dropped.fetch_add(1, Ordering::Relaxed);
            true
        }
        Err(TrySendError::Disconnected(_)) => false,
    }
}

/// Runs the pump until shutdown.
pub(crate) fn run(mut subscriber: Subscriber<CycleSample>, shared: Arc<Shared>) {
    let tick = Duration::from_secs_f64(BUCKET_S);
    let mut decimator = Decimator::default();
    let mut history: VecDeque<Bucket> = VecDeque::with_capacity(HISTORY_BUCKETS);
    let mut clients: Vec<ClientSlot> = Vec::new();
    let mut fresh: Vec<Bucket> = Vec::with_capacity(MAX_BUCKETS_PER_MESSAGE);
    let mut next = Instant::now();
    // The subscriber's lost count as of the previous tick: buckets closed while draining carry
    // it, the tick's last bucket carries the current one.
    let mut lost_before = 0;
    while !shared.shutdown.load(Ordering::Acquire) {
        fresh.clear();
        subscriber.drain(|s| {
            if let Some(b) = decimator.push(s, lost_before) {
                fresh.push(b);
            }
        });
        let lost = subscriber.lost();
        lost_before = lost;
        if let Some(mut b) = decimator.flush() {
            b[41] = lost as f64;
            fresh.push(b);
        }
        shared
            .stats
            .samples_received
            .store(subscriber.received(), Ordering::Relaxed);
        shared.stats.samples_lost.store(lost, Ordering::Relaxed);
        for b in &fresh {
            if history.len() == HISTORY_BUCKETS {
                history.pop_front();
            }
            history.push_back(*b);
        }
        shared
            .stats
            .buckets
            .fetch_add(fresh.len() as u64, Ordering::Relaxed);

        // New pages: their history first, then the live stream like everyone else.
        let waiting: Vec<ClientSlot> = std::mem::take(
            &mut *shared
                .registry
                .waiting
                .lock()
                .unwrap_or_else(|p| p.into_inner()),
        );
        for slot in waiting {
            // Everything before this tick's buckets, which the page gets as live ones below.
            let all: Vec<Bucket> = history
                .iter()
                .take(history.len() - fresh.len().min(history.len()))
                .copied()
                .collect();
            let pieces: Vec<Arc<[u8]>> = all
                .chunks(MAX_BUCKETS_PER_MESSAGE)
                .map(|chunk| frame::encode(KIND_HISTORY, chunk, 0).into())
                .collect();
            if pieces.is_empty() || offer(&slot, &Arc::new(pieces), &shared) {
                clients.push(slot);
            }
        }

        for chunk in fresh.chunks(MAX_BUCKETS_PER_MESSAGE) {
            let message: Encoded = Arc::new(vec![frame::encode(KIND_LIVE, chunk, 0).into()]);
            clients.retain(|slot| offer(slot, &message, &shared));
            shared.stats.frames_sent.fetch_add(1, Ordering::Relaxed);
        }
        shared
            .stats
            .clients
            .store(clients.len() as u64, Ordering::Relaxed);

        next += tick;
        let now = Instant::now();
        if next > now {
            std::thread::sleep(next - now);
        } else {
            // Fell behind (a busy machine): start the next tick now, do not try to catch up.
            next = now;
        }
    }
}
