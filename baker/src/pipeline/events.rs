//! Progress for people and for machines.
//!
//! `--progress json` writes one JSON object per line to stderr, each with an `event` field:
//!
//! | event | fields |
//! |---|---|
//! | `bake_started` | `spec`, `kind` (`skin` or `fiber`), `entries` |
//! | `unit_started` | `unit` (id), `key` |
//! | `unit_finished` | `unit`, `key`, `seconds`, `photons` |
//! | `cache_hit` | `unit`, `key` |
//! | `up_to_date` | `spec` (nothing to do: same spec, flags and executable, outputs intact) |
//! | `output` | `path` (a final file, written atomically) |
//! | `summary` | `spec`, `units_computed`, `cache_hits`, `seconds`, `shard` |
//! | `interrupted` | `units_computed`, `resume` (the command to run again) |
//! | `error` | `message`, `exit_code` |
//!
//! Who listens is an [`Observer`]: the command line implements it (`cli/observer.rs`) with an
//! indicatif bar on a terminal, a line every ~5 % otherwise, JSON lines for `--progress json`,
//! or nothing but errors and warnings for `--quiet`. The library never names a terminal type.

use std::sync::Arc;

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
    /// A progress bar over `total` units labelled `label`, where one can be drawn (a
    /// terminal); `None` otherwise, and the caller prints periodic lines through `say`.
    fn bar(&self, total: u64, label: &str) -> Option<Arc<dyn Bar>>;
}

/// A progress bar the library advances (photons, directions) and labels.
pub trait Bar: crate::progress::Progress {
    fn set_position(&self, pos: u64);
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
    fn bar(&self, _: u64, _: &str) -> Option<Arc<dyn Bar>> {
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
    pub fn bar(&self, total: u64, label: &str) -> Option<Arc<dyn Bar>> {
        if self.0.human() {
            self.0.bar(total, label)
        } else {
            None
        }
    }

    /// Writes one event.
    pub fn emit(&self, v: serde_json::Value) {
        self.0.event(&v);
    }

    pub fn cache_hit(&self, id: &str, key: &super::Key) {
        self.emit(serde_json::json!({"event": "cache_hit", "unit": id, "key": key.hex()}));
    }

    pub fn unit_started(&self, id: &str, key: &super::Key) {
        self.emit(serde_json::json!({"event": "unit_started", "unit": id, "key": key.hex()}));
    }

    pub fn unit_finished(&self, id: &str, key: &super::Key, seconds: f64, photons: u64) {
        self.emit(
            serde_json::json!({"event": "unit_finished", "unit": id, "key": key.hex(),
            "seconds": seconds, "photons": photons}),
        );
    }

    pub fn output(&self, path: &std::path::Path) {
        self.emit(serde_json::json!({"event": "output", "path": path.display().to_string()}));
    }
}

/// `bar` as a progress sink for the physics.
pub fn reporter(bar: &Option<Arc<dyn Bar>>) -> crate::progress::Reporter {
    bar.clone().map(|b| b as Arc<dyn crate::progress::Progress>)
}
