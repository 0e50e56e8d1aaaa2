//! Stopping long work early: a flag that Monte Carlo loops, fits and bakes check at their batch
//! boundaries (photon batches are already the unit of determinism, so stopping between two of
//! them loses nothing but the unit being run, which is not cached and is recomputed — with the
//! same seeds, the same bytes — on resume).
//!
//! The signal handler sets the process's flag ([`crate::pipeline::interrupt`]); library code
//! only sees a [`Cancel`] passed to it, so a test can cancel one run without touching others.

use std::sync::atomic::{AtomicBool, Ordering};

/// A cancellation flag to check, or none.
#[derive(Debug, Clone, Copy, Default)]
pub struct Cancel(Option<&'static AtomicBool>);

/// Work stopped because its [`Cancel`] was set (exit code 130 at the command line).
#[derive(Debug, Clone, Copy, PartialEq, Eq, thiserror::Error)]
#[error("interrupted")]
pub struct Cancelled;

impl PartialEq for Cancel {
    /// The same flag (or both none).
    fn eq(&self, o: &Cancel) -> bool {
        match (self.0, o.0) {
            (None, None) => true,
            (Some(a), Some(b)) => std::ptr::eq(a, b),
            _ => false,
        }
    }
}

impl Cancel {
    /// Never set: work runs to the end.
    pub const NEVER: Cancel = Cancel(None);

    /// Follows `flag`.
    pub fn new(flag: &'static AtomicBool) -> Cancel {
        Cancel(Some(flag))
    }

    /// A fresh flag of its own, and the token that follows it (for tests and callers that
    /// cancel one piece of work).
    pub fn fresh() -> (&'static AtomicBool, Cancel) {
        let flag: &'static AtomicBool = Box::leak(Box::new(AtomicBool::new(false)));
        (flag, Cancel::new(flag))
    }

    pub fn is_set(&self) -> bool {
        self.0.is_some_and(|f| f.load(Ordering::Relaxed))
    }

    /// `Err(Cancelled)` once the flag is set.
    pub fn check(&self) -> Result<(), Cancelled> {
        if self.is_set() {
            Err(Cancelled)
        } else {
            Ok(())
        }
    }
}
