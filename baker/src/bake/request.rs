//! What a bake is asked to do: a plain request that the command line, `baker merge` or a test
//! builds, with no command-line types in it.

use std::path::PathBuf;

use crate::pipeline::{interrupt, Cache, CacheMode, Events, Runner, Shard};
use crate::spec::budget;

/// A bake of one or more specs into an output root.
#[derive(Debug, Clone, Default)]
pub struct Request {
    /// Spec files, baked in this order.
    pub specs: Vec<PathBuf>,
    /// Output root; each spec bakes into `out/<spec stem>/`.
    pub out: PathBuf,
    /// Only these entries (all when empty).
    pub entries: Vec<String>,
    /// Photon packets per simulation or direction, overriding the spec's.
    pub photons: Option<u64>,
    /// Worker threads (all cores when `None`); results do not depend on it.
    pub threads: Option<usize>,
    /// Skin: layer optics only, no Monte Carlo profiles.
    pub optics_only: bool,
    /// Skin: one simulation per entry instead of one per scattering group.
    pub no_reuse: bool,
    /// Skin: PNG plots of every entry's coefficients.
    pub plots: bool,
    /// Only the work units of this shard, into the cache and `shard.json`.
    pub shard: Option<Shard>,
    /// Recompute every unit even if it is cached.
    pub force: bool,
    /// A subset bake replaces the finished bake instead of going to `subset/`.
    pub replace: bool,
    /// Unit cache directory (`out/.cache` when `None`).
    pub cache: Option<PathBuf>,
    /// `baker merge`: every unit must come from the cache.
    pub require_cached: bool,
}

impl Request {
    /// Whether entry `name` is baked.
    pub fn selects(&self, name: &str) -> bool {
        self.entries.is_empty() || self.entries.iter().any(|e| e == name)
    }

    /// Worker threads this bake runs on.
    pub fn thread_count(&self) -> usize {
        self.threads
            .unwrap_or_else(rayon::current_num_threads)
            .max(1)
    }

    /// What the request changes in a spec's cost ([`budget::check`]).
    pub fn overrides(&self) -> budget::Overrides {
        budget::Overrides {
            photons: self.photons,
            threads: self.thread_count(),
            no_reuse: self.no_reuse,
            optics_only: self.optics_only,
        }
    }

    /// The unit cache directory.
    pub fn cache_dir(&self) -> PathBuf {
        self.cache
            .clone()
            .unwrap_or_else(|| self.out.join(".cache"))
    }

    /// The runner of this bake's units, reporting to `events`; SIGINT/SIGTERM stop its
    /// units at their next batch.
    pub fn runner(&self, events: Events) -> Runner {
        let mode = if self.force {
            CacheMode::Force
        } else {
            CacheMode::Use
        };
        let mut r = Runner::new(Cache::new(self.cache_dir(), mode), events, self.shard);
        r.require_cached = self.require_cached;
        r.cancel = interrupt::cancel();
        r
    }
}
