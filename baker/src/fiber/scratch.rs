//! A pool of zeroed `f64` arrays for the tracer's per-batch tallies and per-slice sums
//! ([`super::slices`]).
//!
//! Batch tallies and slice sums are reused: a batch's `[bin][channel]` array is as large as a
//! sweep's table (1,800 bins × 60 channels at 6°, 864 kB), and a fresh allocation per batch
//! costs two page faults per page (read-then-write of zero pages) and a TLB shootdown each,
//! more than zeroing a used array. Recycled arrays come back zeroed, so results do not depend
//! on which one a batch gets.

use std::sync::Mutex;

/// Arrays smaller than this are left to the allocator.
const MIN_LEN: usize = 1 << 13;
/// At most this many values are kept (128 MiB). Arrays are kept only after use, so
/// within one table size the pool never holds more than was in use at once; after a
/// change of size (another entry) it holds at most this much beside the new arrays.
const MAX_KEPT_VALUES: usize = 1 << 24;

static KEPT: Mutex<Vec<Vec<f64>>> = Mutex::new(Vec::new());

/// A zeroed array of `len` values, reused when one large enough is kept.
pub(crate) fn zeroed(len: usize) -> Vec<f64> {
    if len >= MIN_LEN {
        let mut kept = KEPT.lock().unwrap_or_else(|e| e.into_inner());
        if let Some(i) = kept.iter().position(|v| v.capacity() >= len) {
            let mut v = kept.swap_remove(i);
            drop(kept);
            v.clear();
            v.resize(len, 0.0);
            return v;
        }
    }
    // Written, not `vec![0.0; len]`: calloc's untouched pages are the shared zero page
    // until written, so a batch's first `+=` into each page (and, after recycling, the
    // zeroing of a page the batch only read) took a copy-on-write fault with a TLB
    // shootdown to the other threads. Written zeros give each page its own frame at once.
    let mut v = Vec::with_capacity(len);
    v.resize(len, 0.0);
    v
}

/// Keeps `v` for a later [`zeroed`] (or frees it when enough are kept).
pub(crate) fn recycle(v: Vec<f64>) {
    if v.capacity() >= MIN_LEN {
        let mut kept = KEPT.lock().unwrap_or_else(|e| e.into_inner());
        let held: usize = kept.iter().map(Vec::capacity).sum();
        if held + v.capacity() <= MAX_KEPT_VALUES {
            kept.push(v);
        }
    }
}

#[cfg(test)]
mod tests {
    /// A recycled array comes back zeroed, at the length asked for, whatever it held.
    #[test]
    fn recycled_arrays_come_back_zeroed() {
        let n = super::MIN_LEN + 5;
        for len in [n, n - 3, n + 100] {
            let mut v = super::zeroed(len);
            assert_eq!(v.len(), len);
            assert!(v.iter().all(|&x| x == 0.0));
            v.iter_mut().for_each(|x| *x = 7.0);
            super::recycle(v);
        }
        let v = super::zeroed(n);
        assert!(v.len() == n && v.iter().all(|&x| x == 0.0));
    }
}
