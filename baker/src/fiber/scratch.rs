//! Pools of zeroed arrays for the tracer's per-batch tallies (`f32`) and per-slice sums
//! (`f64`) ([`super::slices`]).
//!
//! Batch tallies and slice sums are reused: a batch's `[bin][channel]` array is as large as a
//! sweep's table (1,800 bins × 60 channels at 6°, 432 kB in `f32`), and a fresh allocation
//! per batch costs two page faults per page (read-then-write of zero pages) and a TLB
//! shootdown each, more than zeroing a used array. Recycled arrays come back zeroed, so
//! results do not depend on which one a batch gets.

use std::sync::Mutex;

/// Arrays of fewer values than this are left to the allocator.
const MIN_LEN: usize = 1 << 13;
/// At most this many bytes are kept per element type (128 MiB). Arrays are kept only after
/// use, so within one table size a pool never holds more than was in use at once; after a
/// change of size (another entry) it holds at most this much beside the new arrays.
const MAX_KEPT_BYTES: usize = 1 << 27;

static KEPT_F64: Mutex<Vec<Vec<f64>>> = Mutex::new(Vec::new());
static KEPT_F32: Mutex<Vec<Vec<f32>>> = Mutex::new(Vec::new());

/// An element type with a pool of its own.
pub(crate) trait Pooled: Copy + Default + 'static {
    fn kept() -> &'static Mutex<Vec<Vec<Self>>>;
}

impl Pooled for f64 {
    fn kept() -> &'static Mutex<Vec<Vec<Self>>> {
        &KEPT_F64
    }
}

impl Pooled for f32 {
    fn kept() -> &'static Mutex<Vec<Vec<Self>>> {
        &KEPT_F32
    }
}

/// A zeroed array of `len` values, reused when one large enough is kept.
pub(crate) fn zeroed<T: Pooled>(len: usize) -> Vec<T> {
    if len >= MIN_LEN {
        let mut kept = T::kept().lock().unwrap_or_else(|e| e.into_inner());
        if let Some(i) = kept.iter().position(|v| v.capacity() >= len) {
            let mut v = kept.swap_remove(i);
            drop(kept);
            v.clear();
            v.resize(len, T::default());
            return v;
        }
    }
    // Written, not `vec![0.0; len]`: calloc's untouched pages are the shared zero page
    // until written, so a batch's first `+=` into each page (and, after recycling, the
    // zeroing of a page the batch only read) took a copy-on-write fault with a TLB
    // shootdown to the other threads. Written zeros give each page its own frame at once.
    let mut v = Vec::with_capacity(len);
    v.resize(len, T::default());
    v
}

/// Keeps `v` for a later [`zeroed`] (or frees it when enough are kept).
pub(crate) fn recycle<T: Pooled>(v: Vec<T>) {
    if v.capacity() >= MIN_LEN {
        let mut kept = T::kept().lock().unwrap_or_else(|e| e.into_inner());
        let held: usize = kept.iter().map(Vec::capacity).sum();
        if (held + v.capacity()) * std::mem::size_of::<T>() <= MAX_KEPT_BYTES {
            kept.push(v);
        }
    }
}

#[cfg(test)]
mod tests {
    /// A recycled array comes back zeroed, at the length asked for, whatever it held, in
    /// either pool.
    #[test]
    fn recycled_arrays_come_back_zeroed() {
        let n = super::MIN_LEN + 5;
        for len in [n, n - 3, n + 100] {
            let mut v = super::zeroed::<f64>(len);
            assert_eq!(v.len(), len);
            assert!(v.iter().all(|&x| x == 0.0));
            v.iter_mut().for_each(|x| *x = 7.0);
            super::recycle(v);
            let mut w = super::zeroed::<f32>(len);
            assert!(w.len() == len && w.iter().all(|&x| x == 0.0));
            w.iter_mut().for_each(|x| *x = 5.0);
            super::recycle(w);
        }
        let v = super::zeroed::<f64>(n);
        assert!(v.len() == n && v.iter().all(|&x| x == 0.0));
        let w = super::zeroed::<f32>(n);
        assert!(w.len() == n && w.iter().all(|&x| x == 0.0));
    }
}
