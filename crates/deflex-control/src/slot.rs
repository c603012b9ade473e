//! A single-writer, many-reader sequence lock over `N` f64 values stored as atomics: the
//! robot-link thread reads the latest correction ξ (eq. 7) without locks or allocation while the
//! control thread writes it, and vice versa for the joint values and the wrench.

use std::sync::atomic::{AtomicU64, Ordering, fence};

/// Seqlock slot of `N` f64 values. Exactly one thread may call [`SeqSlot::write`].
#[derive(Debug)]
pub struct SeqSlot<const N: usize> {
    seq: AtomicU64,
    values: [AtomicU64; N],
}

impl<const N: usize> Default for SeqSlot<N> {
    fn default() -> Self {
        Self::new()
    }
}

impl<const N: usize> SeqSlot<N> {
    /// All zeros, version 0 (never written).
    pub fn new() -> Self {
        SeqSlot {
            seq: AtomicU64::new(0),
            values: std::array::from_fn(|_| AtomicU64::new(0)),
        }
    }

    /// Publishes `values` (single writer). Wait-free.
    #[inline]
    pub fn write(&self, values: &[f64; N]) {
        let s = self.seq.load(Ordering::Relaxed);
        self.seq.store(s.wrapping_add(1), Ordering::Relaxed);
        fence(Ordering::Release);
        for (slot, v) in self.values.iter().zip(values) {
            slot.store(v.to_bits(), Ordering::Relaxed);
        }
        self.seq.store(s.wrapping_add(2), Ordering::Release);
    }

    /// Reads a consistent snapshot and its version (number of writes × 2; 0 = never written).
    /// Lock-free: retries only while a write is in progress.
    #[inline]
    pub fn read(&self) -> ([f64; N], u64) {
        loop {
            let s1 = self.seq.load(Ordering::Acquire);
            if s1 & 1 == 1 {
                std::hint::spin_loop();
                continue;
            }
            let mut out = [0.0; N];
            for (o, slot) in out.iter_mut().zip(&self.values) {
                *o = f64::from_bits(slot.load(Ordering::Relaxed));
            }
            fence(Ordering::Acquire);
            if self.seq.load(Ordering::Relaxed) == s1 {
                return (out, s1);
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::sync::Arc;

    #[test]
    fn readers_never_see_torn_writes() {
        let slot = Arc::new(SeqSlot::<8>::new());
        let writer = {
            let slot = slot.clone();
            std::thread::spawn(move || {
                for k in 1..200_000u64 {
                    slot.write(&[k as f64; 8]);
                }
            })
        };
        let mut last = 0u64;
        while !writer.is_finished() {
            let (v, version) = slot.read();
            assert!(v.iter().all(|x| *x == v[0]), "torn read {v:?}");
            assert!(version >= last);
            last = version;
        }
        writer.join().unwrap();
    }
}
