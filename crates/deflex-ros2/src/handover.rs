//! The bounded hand-over between the DDS reader thread and the runtime's sensor thread: a queue
//! of at most `capacity` items, allocated once; a push onto a full queue drops the oldest item
//! and counts it (the newest reading is the one worth keeping); a pop waits up to a timeout.
//! Neither side can make the other wait for more than the copy of one item under the lock, and
//! nothing allocates after [`Handover::new`].

use std::collections::VecDeque;
use std::sync::{Condvar, Mutex, MutexGuard};
use std::time::{Duration, Instant};

/// The queue.
#[derive(Debug)]
pub struct Handover<T> {
    inner: Mutex<Inner<T>>,
    ready: Condvar,
    capacity: usize,
}

#[derive(Debug)]
struct Inner<T> {
    items: VecDeque<T>,
    dropped: u64,
    closed: bool,
}

impl<T> Handover<T> {
    /// A queue of `capacity` items (at least 1).
    pub fn new(capacity: usize) -> Handover<T> {
        let capacity = capacity.max(1);
        Handover {
            inner: Mutex::new(Inner {
                items: VecDeque::with_capacity(capacity),
                dropped: 0,
                closed: false,
            }),
            ready: Condvar::new(),
            capacity,
        }
    }

    fn lock(&self) -> MutexGuard<'_, Inner<T>> {
        // A panic while holding the lock cannot leave the queue inconsistent (every change is
        // one VecDeque call): keep using it.
        self.inner.lock().unwrap_or_else(|p| p.into_inner())
    }

    /// Adds `item`; when full, drops the oldest first. Returns whether one was dropped.
    pub fn push(&self, item: T) -> bool {
        let mut inner = self.lock();
        let dropped = inner.items.len() >= self.capacity;
        if dropped {
            inner.items.pop_front();
            inner.dropped += 1;
        }
        inner.items.push_back(item);
        drop(inner);
        self.ready.notify_one();
        dropped
    }

    /// The oldest item, waiting up to `timeout` for one; `None` on timeout or once closed and
    /// empty.
    pub fn pop(&self, timeout: Duration) -> Option<T> {
        let deadline = Instant::now() + timeout;
        let mut inner = self.lock();
        loop {
            if let Some(item) = inner.items.pop_front() {
                return Some(item);
            }
            let now = Instant::now();
            if inner.closed || now >= deadline {
                return None;
            }
            inner = self
                .ready
                .wait_timeout(inner, deadline - now)
                .unwrap_or_else(|p| p.into_inner())
                .0;
        }
    }

    /// Items dropped because the queue was full.
    pub fn dropped(&self) -> u64 {
        self.lock().dropped
    }

    /// Items waiting.
    pub fn len(&self) -> usize {
        self.lock().items.len()
    }

    /// True when nothing waits.
    pub fn is_empty(&self) -> bool {
        self.len() == 0
    }

    /// The most items held.
    pub fn capacity(&self) -> usize {
        self.capacity
    }

    /// No more items will come: a waiting [`Handover::pop`] returns at once.
    pub fn close(&self) {
        self.lock().closed = true;
        self.ready.notify_all();
    }
}
