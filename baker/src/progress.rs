//! How long computations report how far they are, without knowing who listens.
//!
//! The physics (transport runs, fiber traces) calls [`Progress::advance`] with the work it has
//! finished; the command line implements the trait with an indicatif bar, and bakes report
//! phases and units through their event stream. Nothing below the CLI names a terminal type.

use std::sync::Arc;

/// A sink for finished work, in the caller's units (photon packets, directions).
pub trait Progress: Send + Sync + std::fmt::Debug {
    /// `n` more units are done.
    fn advance(&self, n: u64);
}

/// A shared progress sink; `None` reports nowhere.
pub type Reporter = Option<Arc<dyn Progress>>;

/// Reports `n` finished units to `r`, if there is one.
pub fn advance(r: &Reporter, n: u64) {
    if let Some(p) = r {
        p.advance(n);
    }
}
