//! Progress for people and for machines.
//!
//! `--progress json` writes one JSON object per line to stderr, each with an `event` field:
//!
//! | event | fields |
//! |---|---|
//! | `bake_started` | `spec`, `kind` (`skin` or `fiber`), `entries` |
//! | `phase_started` | `phase` (`simulation`, `fitting`, `tracing`), `label` (a fiber entry's name), `units`, `photons_total` (expected) |
//! | `unit_started` | `unit` (id), `key`, and the phase's counts (below) |
//! | `unit_finished` | `unit`, `key`, `seconds`, `photons`, and the phase's counts |
//! | `cache_hit` | `unit`, `key`, and the phase's counts |
//! | `phase_finished` | `phase`, `label`, `units` (done), `photons` (done), `seconds` |
//! | `up_to_date` | `spec` (nothing to do: same spec, flags and executable, outputs intact) |
//! | `output` | `path` (a final file, written atomically) |
//! | `summary` | `spec`, `units_computed`, `cache_hits`, `seconds`, `shard` |
//! | `interrupted` | `units_computed`, `resume` (the command to run again) |
//! | `error` | `message`, `exit_code` |
//!
//! A skin bake runs the phases `simulation` (one unit per simulation group and wavelength)
//! and `fitting` (one Gaussian fit per entry, no photons); a fiber bake one `tracing` phase
//! per entry (`label`: the entry). Unit events of a phase carry its counts: `phase`,
//! `index` (1-based: the how-manieth unit of the phase to start, for `unit_started`, or to be
//! done — computed or from the cache — for `unit_finished` and `cache_hit`; so each rises by
//! one per event and the last done index is `total`), `total` (units of the phase, cached
//! ones included), `photons_done` (photons of the phase's units done so far) and
//! `photons_total` (of all its units: the real count of each unit started or cached, the
//! expected count of the rest — a skin run's boost of cheap wavelengths raises it). Pilot
//! runs (`…/pilot/…`) choose photon counts before their simulation: their events have no
//! phase counts.
//!
//! Who listens is an [`Observer`]: the command line implements it (`cli/observer.rs`) with an
//! indicatif bar on a terminal, a line every ~5 % otherwise, JSON lines for `--progress json`,
//! or nothing but errors and warnings for `--quiet`. The library never names a terminal type.

use std::sync::Arc;

/// A unit's place in its phase, for the JSON events.
#[derive(Debug, Clone)]
pub struct Place {
    pub phase: String,
    pub index: u64,
    pub total: u64,
    pub photons_done: u64,
    pub photons_total: u64,
}

/// A listener for a bake's progress and messages.
pub trait Observer: Send + Sync {
    /// A machine-readable event (an object with an `event` field, as tabulated above).
    fn event(&self, v: &serde_json::Value);
    /// Whether people read the messages: [`Observer::say`] and progress lines are for them.
    fn human(&self) -> bool;
    /// A message for people (progress lines, summaries); shown only when [`Observer::human`].
    fn say(&self, msg: &str);
    /// A message that matters even in pipelines (how to resume): shown unless quiet.
    fn notice(&self, msg: &str);
    /// A warning about the results: always shown.
    fn warn(&self, msg: &str);
    /// A progress bar over `total` items (`unit`: `photons`, `directions`, `profiles`, for
    /// its rate) labelled `label`, where one can be drawn (a terminal); `None` otherwise, and
    /// the caller prints periodic lines through `say`.
    fn bar(&self, total: u64, label: &str, unit: &str) -> Option<Arc<dyn Bar>>;
}

/// A progress bar the library advances (photons, directions) and labels.
pub trait Bar: crate::progress::Progress {
    fn set_position(&self, pos: u64);
    /// The items the bar counts to (the work left changed: cached units, a boost).
    fn set_length(&self, total: u64);
    fn set_message(&self, msg: &str);
    /// Clears the bar when its work is done.
    fn finish(&self);
}

/// An observer that listens to nothing (tests, library callers without output).
#[derive(Debug, Clone, Copy)]
pub struct Silent;

impl Observer for Silent {
    fn event(&self, _: &serde_json::Value) {}
    fn human(&self) -> bool {
        false
    }
    fn say(&self, _: &str) {}
    fn notice(&self, _: &str) {}
    fn warn(&self, _: &str) {}
    fn bar(&self, _: u64, _: &str, _: &str) -> Option<Arc<dyn Bar>> {
        None
    }
}

/// A shared [`Observer`] with the bake's event vocabulary.
#[derive(Clone)]
pub struct Events(Arc<dyn Observer>);

impl std::fmt::Debug for Events {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str("Events")
    }
}

impl Events {
    pub fn new(o: Arc<dyn Observer>) -> Events {
        Events(o)
    }

    /// Events nobody hears.
    pub fn silent() -> Events {
        Events(Arc::new(Silent))
    }

    /// Whether people get messages, bars and progress lines.
    pub fn human(&self) -> bool {
        self.0.human()
    }

    /// A message for people.
    pub fn say(&self, msg: impl AsRef<str>) {
        if self.0.human() {
            self.0.say(msg.as_ref());
        }
    }

    /// A message shown unless quiet.
    pub fn notice(&self, msg: impl AsRef<str>) {
        self.0.notice(msg.as_ref());
    }

    /// A warning, always shown.
    pub fn warn(&self, msg: impl AsRef<str>) {
        self.0.warn(msg.as_ref());
    }

    /// A bar for people on a terminal.
    pub fn bar(&self, total: u64, label: &str, unit: &str) -> Option<Arc<dyn Bar>> {
        if self.0.human() {
            self.0.bar(total, label, unit)
        } else {
            None
        }
    }

    /// Writes one event.
    pub fn emit(&self, v: serde_json::Value) {
        self.0.event(&v);
    }

    pub fn cache_hit(&self, id: &str, key: &super::Key, place: Option<Place>) {
        self.emit(with_place(
            serde_json::json!({"event": "cache_hit", "unit": id, "key": key.hex()}),
            place,
        ));
    }

    pub fn unit_started(&self, id: &str, key: &super::Key, place: Option<Place>) {
        self.emit(with_place(
            serde_json::json!({"event": "unit_started", "unit": id, "key": key.hex()}),
            place,
        ));
    }

    pub fn unit_finished(
        &self,
        id: &str,
        key: &super::Key,
        seconds: f64,
        photons: u64,
        place: Option<Place>,
    ) {
        self.emit(with_place(
            serde_json::json!({"event": "unit_finished", "unit": id, "key": key.hex(),
            "seconds": seconds, "photons": photons}),
            place,
        ));
    }

    pub fn output(&self, path: &std::path::Path) {
        self.emit(serde_json::json!({"event": "output", "path": path.display().to_string()}));
    }
}

/// `v` with a unit's place in its phase (see the module docs).
fn with_place(mut v: serde_json::Value, place: Option<Place>) -> serde_json::Value {
    if let (Some(p), Some(o)) = (place, v.as_object_mut()) {
        o.insert("phase".into(), p.phase.into());
        o.insert("index".into(), p.index.into());
        o.insert("total".into(), p.total.into());
        o.insert("photons_done".into(), p.photons_done.into());
        o.insert("photons_total".into(), p.photons_total.into());
    }
    v
}

/// `bar` as a progress sink for the physics.
pub fn reporter(bar: &Option<Arc<dyn Bar>>) -> crate::progress::Reporter {
    bar.clone().map(|b| b as Arc<dyn crate::progress::Progress>)
}
