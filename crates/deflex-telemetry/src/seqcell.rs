//! The latest value of a `Pod` message, handed from one writer thread to any number of readers
//! without locks or allocation (a sequence lock over atomic words).
//!
//! Protocol: the writer makes the sequence odd, stores the words, makes it even again (release);
//! a reader loads an even sequence (acquire), the words, and the sequence again, and retries when
//! it changed. The version counts completed writes (0: never written).

use crate::words::{load, store, words_for};
use bytemuck::Pod;
use std::marker::PhantomData;
use std::sync::atomic::{AtomicU64, Ordering, fence};

/// The latest `T` written by one thread, read by others. Exactly one thread may call
/// [`SeqCell::write`]; reads are lock-free (they retry only while a write is in progress).
#[derive(Debug)]
pub struct SeqCell<T: Pod> {
    seq: AtomicU64,
    words: Box<[AtomicU64]>,
    _t: PhantomData<T>,
}

impl<T: Pod> Default for SeqCell<T> {
    fn default() -> Self {
        Self::new()
    }
}

impl<T: Pod> SeqCell<T> {
    /// A cell holding `T::zeroed()`, version 0 (never written). Allocates once, here.
    pub fn new() -> Self {
        SeqCell {
            seq: AtomicU64::new(0),
            words: (0..words_for::<T>()).map(|_| AtomicU64::new(0)).collect(),
            _t: PhantomData,
        }
    }

    /// Publishes `value` (single writer). Wait-free, allocation-free.
    #[inline]
    pub fn write(&self, value: &T) {
        let s = self.seq.load(Ordering::Relaxed);
        self.seq.store(s.wrapping_add(1), Ordering::Relaxed);
        fence(Ordering::Release);
        store(&self.words, value);
        self.seq.store(s.wrapping_add(2), Ordering::Release);
    }

    /// A consistent snapshot and the number of writes that produced it (0: never written).
    #[inline]
    pub fn read(&self) -> (T, u64) {
        loop {
            let s1 = self.seq.load(Ordering::Acquire);
            if s1 & 1 == 1 {
                std::hint::spin_loop();
                continue;
            }
            let value = load::<T>(&self.words);
            fence(Ordering::Acquire);
            if self.seq.load(Ordering::Relaxed) == s1 {
                return (value, s1 / 2);
            }
        }
    }

    /// The latest value, or `None` before the first write.
    #[inline]
    pub fn latest(&self) -> Option<T> {
        let (value, version) = self.read();
        (version > 0).then_some(value)
    }

    /// Number of completed writes.
    #[inline]
    pub fn version(&self) -> u64 {
        self.seq.load(Ordering::Acquire) / 2
    }
}
