//! The bake as a build tool: deterministic work units, a content-addressed cache of their raw
//! results, machine-readable progress, interruption, and sharding.
//!
//! - A **work unit** is one piece of transport whose result depends only on its inputs: a
//!   skin simulation group × wavelength (and its pilot run), or a run of consecutive stored
//!   incoming directions of one fiber entry (all its cross-sections).
//! - Its **key** is the SHA-256 of everything that determines the result ([`KeyBuilder`]):
//!   the resolved physical inputs, photon counts, seeds, batch sizes, [`ENGINE_VERSION`], the
//!   digest of the source code that computes that kind of unit ([`code_digest`]) and the
//!   checksums of the data tables compiled into the binary.
//! - The [`cache`] keeps each unit's raw result (Σw, Σw², photon counts — not only
//!   normalised values) under its key. A bake whose units are all cached runs no transport
//!   and assembles byte-identical tables.
//! - [`events`] reports progress as a bar, as lines, or as JSON events; [`interrupt`] turns
//!   SIGINT/SIGTERM into a clean stop after the running units.
//! - A [`Shard`] `I/N` owns every unit whose index in the spec's unit list is ≡ I − 1 (mod N).

pub mod cache;
pub mod events;
pub mod interrupt;
pub mod phase;
pub mod source_digest;

mod unit_code {
    include!(concat!(env!("OUT_DIR"), "/unit_code.rs"));
}

use std::fmt;

use sha2::{Digest, Sha256};

pub use cache::{Cache, CacheMode};
pub use events::{Bar, Events, Observer};
pub use phase::{Phase, PhaseSpec};

/// The version of the cache's key and result layout. Code changes need no bump: every key
/// holds the digest of the code behind its kind of unit ([`code_digest`]).
/// 2: the junction search (envelope bounds, bracketed Newton) moves crossings by < 1e-10 mm,
/// and disk rejection takes one 64-bit draw per try (profile/DECISIONS.md row 13).
/// 3: keys hold the code digest; fiber units keep per-bin standard errors.
pub const ENGINE_VERSION: u32 = 3;

/// The digest of the source files that compute units of `kind` (and of `Cargo.lock`),
/// computed by the build script from the code itself ([`source_digest`]). Kinds without a
/// row (tests) get the digest of every kind's code together.
pub fn code_digest(kind: &str) -> [u8; 32] {
    match unit_code::UNIT_CODE.iter().find(|(k, ..)| *k == kind) {
        Some((_, d, _)) => *d,
        None => {
            let mut h = Sha256::new();
            for (_, d, _) in unit_code::UNIT_CODE {
                h.update(d);
            }
            h.finalize().into()
        }
    }
}

/// The source files behind units of `kind` (`crate/…` for baker, `formats/…`), as the build
/// script found them.
pub fn code_files(kind: &str) -> &'static [&'static str] {
    unit_code::UNIT_CODE
        .iter()
        .find(|(k, ..)| *k == kind)
        .map_or(&[], |(_, _, f)| f)
}

/// A unit's content address.
#[derive(Clone, Copy, PartialEq, Eq, Hash, PartialOrd, Ord)]
pub struct Key(pub [u8; 32]);

impl Key {
    pub fn hex(&self) -> String {
        self.0.iter().map(|b| format!("{b:02x}")).collect()
    }

    pub fn from_hex(s: &str) -> Option<Key> {
        if s.len() != 64 {
            return None;
        }
        let mut k = [0u8; 32];
        for (i, b) in k.iter_mut().enumerate() {
            *b = u8::from_str_radix(s.get(2 * i..2 * i + 2)?, 16).ok()?;
        }
        Some(Key(k))
    }
}

impl fmt::Debug for Key {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(f, "{}", &self.hex()[..16])
    }
}

/// Builds a [`Key`] from labelled parts. Values are rendered with `Debug`, which prints
/// floating-point numbers in their shortest round-trip form, so two inputs give the same key
/// only if they are bit-identical.
pub struct KeyBuilder(Sha256);

impl KeyBuilder {
    /// A key of `kind` (e.g. `skin-run`), with the engine version and `data`, the checksum of
    /// the data tables the result depends on ([`crate::data::checksum`] in a bake).
    pub fn new(kind: &str, data: &[u8; 32]) -> KeyBuilder {
        Self::with_code(kind, &code_digest(kind), data)
    }

    /// [`KeyBuilder::new`] with the code digest given: what a key would be under other code.
    pub fn with_code(kind: &str, code: &[u8; 32], data: &[u8; 32]) -> KeyBuilder {
        let mut h = Sha256::new();
        h.update(b"baker-unit\0");
        h.update(ENGINE_VERSION.to_le_bytes());
        h.update(env!("CARGO_PKG_VERSION").as_bytes());
        h.update([0]);
        h.update(code);
        h.update(data);
        h.update(kind.as_bytes());
        h.update([0]);
        KeyBuilder(h)
    }

    /// Adds one labelled part.
    pub fn part(mut self, label: &str, value: &impl fmt::Debug) -> KeyBuilder {
        self.0.update(label.as_bytes());
        self.0.update([0]);
        self.0.update(format!("{value:?}").as_bytes());
        self.0.update([0]);
        self
    }

    /// Adds a digest computed elsewhere (e.g. of a large geometry, computed once).
    pub fn digest(mut self, label: &str, d: &[u8; 32]) -> KeyBuilder {
        self.0.update(label.as_bytes());
        self.0.update([0]);
        self.0.update(d);
        self
    }

    pub fn finish(self) -> Key {
        Key(self.0.finalize().into())
    }
}

/// SHA-256 of the `Debug` rendering of a value (a part digested once, used by many keys).
pub fn digest_of(value: &impl fmt::Debug) -> [u8; 32] {
    Sha256::digest(format!("{value:?}").as_bytes()).into()
}

/// `--shard I/N`: this process bakes units whose index ≡ I − 1 (mod N).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Shard {
    /// 1-based, as Slurm's `$SLURM_ARRAY_TASK_ID` with `--array=1-N`.
    pub index: usize,
    pub count: usize,
}

impl Shard {
    pub fn owns(&self, unit_index: usize) -> bool {
        unit_index % self.count == self.index - 1
    }
}

impl std::str::FromStr for Shard {
    type Err = String;
    fn from_str(s: &str) -> Result<Shard, String> {
        let bad = || format!("--shard {s:?}: expected I/N with 1 ≤ I ≤ N, e.g. 2/4");
        let (i, n) = s.split_once('/').ok_or_else(bad)?;
        let (index, count): (usize, usize) = (
            i.trim().parse().map_err(|_| bad())?,
            n.trim().parse().map_err(|_| bad())?,
        );
        if count == 0 || index == 0 || index > count {
            return Err(bad());
        }
        Ok(Shard { index, count })
    }
}

/// A unit of a plan: what `baker plan` lists and what the runner executes.
#[derive(Debug, Clone, serde::Serialize)]
pub struct UnitInfo {
    /// Stable, readable id, e.g. `fitzpatrick/skin/group3/450nm`.
    pub id: String,
    pub key: String,
    /// Index in the spec's unit list (sharding uses it); pilots are not sharded (`None`).
    pub index: Option<usize>,
    /// Estimated cost: photon packets (skin: before the boost of cheap wavelengths; fibers:
    /// packets × cross-sections × directions; 0 for fits).
    pub photons: u64,
    pub cached: bool,
    /// `pilot`, `transport` (a skin simulation), `fit` (a skin entry's Gaussian fit) or
    /// `fiber` (stored directions of a fiber entry).
    pub kind: &'static str,
    /// Estimated wall-clock seconds on the bake's threads (0 when cached), from `baker
    /// plan`'s calibration; absent with `--no-estimate`.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub estimate_s: Option<f64>,
}

/// Why a unit's result is not available.
#[derive(Debug)]
pub enum UnitError {
    /// SIGINT/SIGTERM: stopped before this unit.
    Interrupted,
    /// `baker merge`: a unit is in no shard.
    Missing(String),
    Failed(anyhow::Error),
}

/// Everything a bake needs to run units: the cache, progress, interruption, the shard.
pub struct Runner {
    pub cache: Cache,
    pub events: Events,
    pub shard: Option<Shard>,
    /// `baker merge`: every unit must come from the cache.
    pub require_cached: bool,
    /// Units computed and taken from the cache in this process.
    pub computed: std::sync::atomic::AtomicUsize,
    pub hits: std::sync::atomic::AtomicUsize,
    /// Keys used (for `baker cache gc` roots and shard manifests).
    pub used: std::sync::Mutex<Vec<(String, Key)>>,
    /// Stops units at their next batch (SIGINT/SIGTERM in a bake).
    pub cancel: crate::cancel::Cancel,
    /// The running phase, whose counts the unit events carry.
    pub phase: std::sync::Mutex<Option<std::sync::Arc<Phase>>>,
}

impl Runner {
    pub fn new(cache: Cache, events: Events, shard: Option<Shard>) -> Runner {
        Runner {
            cache,
            events,
            shard,
            require_cached: false,
            computed: Default::default(),
            hits: Default::default(),
            used: Default::default(),
            cancel: crate::cancel::Cancel::NEVER,
            phase: Default::default(),
        }
    }

    /// Starts a phase (its units are counted in the events and the bar); returns it as the
    /// physics' progress sink.
    pub fn begin_phase(&self, spec: PhaseSpec) -> std::sync::Arc<Phase> {
        let p = Phase::start(spec, &self.events);
        *self.phase.lock().unwrap() = Some(p.clone());
        p
    }

    /// Ends the running phase (its bar is cleared, `phase_finished` emitted).
    pub fn end_phase(&self) {
        if let Some(p) = self.phase.lock().unwrap().take() {
            p.finish();
        }
    }

    fn current_phase(&self) -> Option<std::sync::Arc<Phase>> {
        self.phase.lock().unwrap().clone()
    }

    /// Whether this process computes the unit at `index` (always, without a shard; pilots
    /// have no index and are computed by every shard that needs them).
    pub fn owns(&self, index: Option<usize>) -> bool {
        match (self.shard, index) {
            (Some(s), Some(i)) => s.owns(i),
            _ => true,
        }
    }

    /// Records that the outputs depend on unit `key` although this run did not need to load
    /// it (a pilot run whose main runs were all cached), so that the manifest and the cache
    /// roots list the same units however many runs the bake took.
    pub fn depends_on(&self, id: &str, key: Key) {
        self.used.lock().unwrap().push((id.to_string(), key));
    }

    /// The result of a unit: from the cache, or computed (and cached) if this process owns
    /// it; `Ok(None)` if another shard owns it. Units without an index (pilot runs, fits) are
    /// computed by whichever process needs them, `baker merge` included. The unit counts in
    /// the running phase.
    pub fn unit<T>(
        &self,
        id: &str,
        key: Key,
        index: Option<usize>,
        photons: u64,
        compute: impl FnOnce() -> anyhow::Result<T>,
    ) -> Result<Option<T>, UnitError>
    where
        T: serde::Serialize + serde::de::DeserializeOwned,
    {
        self.unit_deferred(id, key, index, photons, compute)?
            .map(Computed::stored)
            .transpose()
            .map_err(UnitError::Failed)
    }

    /// [`Runner::unit`], leaving a freshly computed result's cache write to the caller
    /// ([`Computed::Fresh`]'s [`ToStore`]): a pipeline that hands each unit on to a thread of
    /// its own writes it there, and the units that follow start at once.
    pub fn unit_deferred<T>(
        &self,
        id: &str,
        key: Key,
        index: Option<usize>,
        photons: u64,
        compute: impl FnOnce() -> anyhow::Result<T>,
    ) -> Result<Option<Computed<T>>, UnitError>
    where
        T: serde::Serialize + serde::de::DeserializeOwned,
    {
        self.unit_in(self.current_phase(), id, key, index, photons, compute)
    }

    /// [`Runner::unit`] for a unit outside the phase's counts (a pilot run).
    pub fn side_unit<T>(
        &self,
        id: &str,
        key: Key,
        photons: u64,
        compute: impl FnOnce() -> anyhow::Result<T>,
    ) -> Result<Option<T>, UnitError>
    where
        T: serde::Serialize + serde::de::DeserializeOwned,
    {
        self.unit_in(None, id, key, None, photons, compute)?
            .map(Computed::stored)
            .transpose()
            .map_err(UnitError::Failed)
    }

    fn unit_in<T>(
        &self,
        phase: Option<std::sync::Arc<Phase>>,
        id: &str,
        key: Key,
        index: Option<usize>,
        photons: u64,
        compute: impl FnOnce() -> anyhow::Result<T>,
    ) -> Result<Option<Computed<T>>, UnitError>
    where
        T: serde::Serialize + serde::de::DeserializeOwned,
    {
        use std::sync::atomic::Ordering::Relaxed;
        if let Some(v) = self.cache.load::<T>(&key) {
            self.hits.fetch_add(1, Relaxed);
            self.used.lock().unwrap().push((id.to_string(), key));
            let place = phase.as_ref().map(|p| p.unit_done(photons, true));
            self.events.cache_hit(id, &key, place);
            return Ok(Some(Computed::Cached(v)));
        }
        if self.require_cached && index.is_some() {
            return Err(UnitError::Missing(id.to_string()));
        }
        if !self.owns(index) {
            return Ok(None);
        }
        if self.cancel.is_set() {
            return Err(UnitError::Interrupted);
        }
        let place = phase.as_ref().map(|p| p.unit_started(photons));
        self.events.unit_started(id, &key, place);
        let t0 = std::time::Instant::now();
        let v = compute().map_err(|e| {
            if e.is::<crate::cancel::Cancelled>() {
                UnitError::Interrupted
            } else {
                UnitError::Failed(e)
            }
        })?;
        self.computed.fetch_add(1, Relaxed);
        self.used.lock().unwrap().push((id.to_string(), key));
        let place = phase.as_ref().map(|p| p.unit_done(photons, false));
        self.events
            .unit_finished(id, &key, t0.elapsed().as_secs_f64(), photons, place);
        let store = ToStore {
            cache: self.cache.clone(),
            id: id.to_string(),
            key,
        };
        Ok(Some(Computed::Fresh(v, store)))
    }
}

/// A unit's result: read from the cache, or computed here and still to be written there.
pub enum Computed<T> {
    Cached(T),
    Fresh(T, ToStore),
}

impl<T: serde::Serialize> Computed<T> {
    /// The result, written to the cache first if it was computed here.
    pub fn stored(self) -> anyhow::Result<T> {
        match self {
            Computed::Cached(v) => Ok(v),
            Computed::Fresh(v, store) => {
                store.write(&v)?;
                Ok(v)
            }
        }
    }
}

/// Where a freshly computed unit goes in the cache ([`Runner::unit_deferred`]).
#[must_use = "a computed unit is only cached once written"]
pub struct ToStore {
    cache: Cache,
    id: String,
    key: Key,
}

impl ToStore {
    /// Writes `v`, the unit's result, to the cache (atomically).
    pub fn write<T: serde::Serialize>(self, v: &T) -> anyhow::Result<()> {
        self.cache
            .store(&self.key, v)
            .map_err(|e| e.context(format!("caching unit {}", self.id)))
    }
}

impl From<UnitError> for anyhow::Error {
    fn from(e: UnitError) -> anyhow::Error {
        match e {
            UnitError::Interrupted => anyhow::Error::new(interrupt::Interrupted),
            UnitError::Missing(id) => anyhow::anyhow!(
                "unit {id} is in none of the shards (were all shards baked with the same spec \
                 and flags?)"
            ),
            UnitError::Failed(e) => e,
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Issue 22: a unit's key follows the code that computes it. Keys under other code
    /// differ; the key a bake uses is the one under the digest compiled in for its kind.
    #[test]
    fn keys_change_with_the_code() {
        let data = [7u8; 32];
        let key = |code: &[u8; 32]| {
            KeyBuilder::with_code("skin-run", code, &data)
                .part("x", &1.5)
                .finish()
        };
        let here = code_digest("skin-run");
        let mut other = here;
        other[0] ^= 1;
        assert_ne!(key(&here), key(&other));
        assert_eq!(
            KeyBuilder::new("skin-run", &data).part("x", &1.5).finish(),
            key(&here)
        );
        assert_ne!(code_digest("skin-run"), code_digest("fiber-slices"));
        assert!(!code_files("fiber-slices").is_empty());
    }
}
