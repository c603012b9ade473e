//! A `Pod` value as a run of 64-bit words held in relaxed atomics: the storage of [`crate::SeqCell`]
//! and [`crate::Broadcast`]. Copies go through bytes, so any `Pod` type (any alignment, any size)
//! fits; the last word is zero-padded when the size is not a multiple of 8.

use bytemuck::Pod;
use std::sync::atomic::{AtomicU64, Ordering};

/// Words needed for a `T`.
pub(crate) const fn words_for<T>() -> usize {
    std::mem::size_of::<T>().div_ceil(8)
}

/// Stores `value` into `words` (exactly `words_for::<T>()` long), relaxed.
#[inline]
pub(crate) fn store<T: Pod>(words: &[AtomicU64], value: &T) {
    let bytes = bytemuck::bytes_of(value);
    for (word, chunk) in words.iter().zip(bytes.chunks(8)) {
        let mut b = [0u8; 8];
        b[..chunk.len()].copy_from_slice(chunk);
        word.store(u64::from_ne_bytes(b), Ordering::Relaxed);
    }
}

/// Loads a `T` from `words`, relaxed (the caller validates with its sequence number).
#[inline]
pub(crate) fn load<T: Pod>(words: &[AtomicU64]) -> T {
    let mut value = T::zeroed();
    let bytes = bytemuck::bytes_of_mut(&mut value);
    for (word, chunk) in words.iter().zip(bytes.chunks_mut(8)) {
        let b = word.load(Ordering::Relaxed).to_ne_bytes();
        let n = chunk.len();
        chunk.copy_from_slice(&b[..n]);
    }
    value
}
