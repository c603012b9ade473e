//! A lossy single-producer, many-consumer ring of `Pod` samples: the telemetry stream.
//!
//! Sample `i` (counting from 0) lives in slot `i mod N` under a sequence number: the publisher
//! marks the slot `2i + 1` (writing), stores the words, marks it `2i + 2` (release), then raises
//! the head to `i + 1` (release). A subscriber at position `p < head` reads slot `p mod N`: the
//! sample is its own only when the slot's sequence is `2p + 2` before and after the words are
//! read; a larger number means the publisher has lapped it (the sample was overwritten), which is
//! counted as lost. A subscriber more than `N` behind the head jumps to the oldest sample still
//! held and counts what it skipped. The publisher never looks at subscribers: it cannot be
//! slowed, blocked or made to allocate by them, and a subscriber can join or leave at any time.

use crate::words::{load, store, words_for};
use bytemuck::Pod;
use std::marker::PhantomData;
use std::sync::Arc;
use std::sync::atomic::{AtomicBool, AtomicU64, Ordering, fence};

/// The shared ring. Create with [`broadcast`]; subscribe with [`Broadcast::subscribe`].
#[derive(Debug)]
pub struct Broadcast<T: Pod> {
    capacity: u64,
    words_per_sample: usize,
    seqs: Box<[AtomicU64]>,
    words: Box<[AtomicU64]>,
    head: AtomicU64,
    closed: AtomicBool,
    _t: PhantomData<T>,
}

/// The one writing end, held by the control thread (not `Clone`).
#[derive(Debug)]
pub struct Publisher<T: Pod> {
    ring: Arc<Broadcast<T>>,
    next: u64,
}

/// A reading end: its own position and its own count of samples it lost.
#[derive(Debug)]
pub struct Subscriber<T: Pod> {
    ring: Arc<Broadcast<T>>,
    next: u64,
    lost: u64,
    received: u64,
}

/// A ring holding the last `capacity` samples (at least 2), its publisher and the shared ring to
/// subscribe to. Allocates once, here: `capacity × size_of::<T>()` bytes.
pub fn broadcast<T: Pod>(capacity: usize) -> (Publisher<T>, Arc<Broadcast<T>>) {
    let capacity = capacity.max(2);
    let words_per_sample = words_for::<T>();
    let ring = Arc::new(Broadcast {
        capacity: capacity as u64,
        words_per_sample,
        seqs: (0..capacity).map(|_| AtomicU64::new(0)).collect(),
        words: (0..capacity * words_per_sample)
            .map(|_| AtomicU64::new(0))
            .collect(),
        head: AtomicU64::new(0),
        closed: AtomicBool::new(false),
        _t: PhantomData,
    });
    (
        Publisher {
            ring: ring.clone(),
            next: 0,
        },
        ring,
    )
}

impl<T: Pod> Broadcast<T> {
    /// A subscriber that receives every sample published from now on.
    pub fn subscribe(self: &Arc<Self>) -> Subscriber<T> {
        Subscriber {
            ring: self.clone(),
            next: self.head.load(Ordering::Acquire),
            lost: 0,
            received: 0,
        }
    }

    /// A subscriber that starts with the oldest sample still held (up to `capacity` back).
    pub fn subscribe_from_oldest(self: &Arc<Self>) -> Subscriber<T> {
        let head = self.head.load(Ordering::Acquire);
        Subscriber {
            ring: self.clone(),
            next: head.saturating_sub(self.capacity),
            lost: 0,
            received: 0,
        }
    }

    /// Samples published so far.
    pub fn published(&self) -> u64 {
        self.head.load(Ordering::Acquire)
    }

    /// The latest sample published, or `None` before the first. Lock-free: retries while the
    /// publisher overwrites the slot it reads (a live status line, a dashboard).
    pub fn latest(&self) -> Option<T> {
        loop {
            let head = self.head.load(Ordering::Acquire);
            let p = head.checked_sub(1)?;
            let slot = (p % self.capacity) as usize;
            let expected = 2 * p + 2;
            if self.seqs[slot].load(Ordering::Acquire) != expected {
                std::hint::spin_loop();
                continue;
            }
            let value = load::<T>(self.slot_words(slot));
            fence(Ordering::Acquire);
            if self.seqs[slot].load(Ordering::Relaxed) == expected {
                return Some(value);
            }
        }
    }

    /// How many samples the ring holds.
    pub fn capacity(&self) -> usize {
        self.capacity as usize
    }

    /// True once the publisher was dropped or [`Publisher::close`]d: no sample will follow the
    /// ones already published.
    pub fn is_closed(&self) -> bool {
        self.closed.load(Ordering::Acquire)
    }

    fn slot_words(&self, slot: usize) -> &[AtomicU64] {
        &self.words[slot * self.words_per_sample..(slot + 1) * self.words_per_sample]
    }
}

impl<T: Pod> Publisher<T> {
    /// Publishes one sample. Wait-free and allocation-free; overwrites the oldest sample when
    /// the ring is full.
    #[inline]
    pub fn publish(&mut self, sample: &T) {
        let ring = &*self.ring;
        let i = self.next;
        let slot = (i % ring.capacity) as usize;
        ring.seqs[slot].store(2 * i + 1, Ordering::Relaxed);
        fence(Ordering::Release);
        store(ring.slot_words(slot), sample);
        ring.seqs[slot].store(2 * i + 2, Ordering::Release);
        self.next = i + 1;
        ring.head.store(self.next, Ordering::Release);
    }

    /// Samples published so far.
    pub fn published(&self) -> u64 {
        self.next
    }

    /// The shared ring (to subscribe more sinks).
    pub fn ring(&self) -> &Arc<Broadcast<T>> {
        &self.ring
    }

    /// Marks the stream ended (also done on drop).
    pub fn close(&self) {
        self.ring.closed.store(true, Ordering::Release);
    }
}

impl<T: Pod> Drop for Publisher<T> {
    fn drop(&mut self) {
        self.close();
    }
}

impl<T: Pod> Subscriber<T> {
    /// The next sample not yet read, or `None` when the subscriber has caught up. Samples the
    /// publisher overwrote before they were read are skipped and counted in [`Self::lost`].
    pub fn try_next(&mut self) -> Option<T> {
        let ring = &*self.ring;
        loop {
            let head = ring.head.load(Ordering::Acquire);
            if self.next >= head {
                return None;
            }
            if head - self.next > ring.capacity {
                let skip = head - ring.capacity - self.next;
                self.lost += skip;
                self.next += skip;
            }
            let p = self.next;
            let slot = (p % ring.capacity) as usize;
            let expected = 2 * p + 2;
            let s1 = ring.seqs[slot].load(Ordering::Acquire);
            if s1 != expected {
                // Lapped by the publisher (being or already overwritten).
                self.lost += 1;
                self.next += 1;
                continue;
            }
            let value = load::<T>(ring.slot_words(slot));
            fence(Ordering::Acquire);
            if ring.seqs[slot].load(Ordering::Relaxed) != expected {
                self.lost += 1;
                self.next += 1;
                continue;
            }
            self.next += 1;
            self.received += 1;
            return Some(value);
        }
    }

    /// Calls `f` on every sample available now; returns how many it read.
    pub fn drain(&mut self, mut f: impl FnMut(&T)) -> usize {
        let mut n = 0;
        while let Some(sample) = self.try_next() {
            f(&sample);
            n += 1;
        }
        n
    }

    /// Samples this subscriber lost (overwritten before it read them).
    pub fn lost(&self) -> u64 {
        self.lost
    }

    /// Samples this subscriber received.
    pub fn received(&self) -> u64 {
        self.received
    }

    /// True when the publisher has ended and every sample it published was read or lost.
    pub fn is_finished(&self) -> bool {
        self.ring.is_closed() && self.next >= self.ring.head.load(Ordering::Acquire)
    }

    /// The shared ring.
    pub fn ring(&self) -> &Arc<Broadcast<T>> {
        &self.ring
    }
}
