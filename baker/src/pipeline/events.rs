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
//! `bar` (the default on a terminal) draws a progress bar with ETA and photons/s; without a
//! terminal the default prints a line every ~5 %; `none` (or `--quiet`) prints nothing but
//! errors.

use std::io::Write as _;

#[derive(Debug, Clone, Copy, PartialEq, Eq, clap::ValueEnum)]
pub enum ProgressMode {
    /// A bar on a terminal, periodic lines otherwise.
    Auto,
    Bar,
    Json,
    None,
}

#[derive(Debug, Clone, Copy)]
pub struct Events {
    pub mode: ProgressMode,
}

impl Events {
    pub fn new(mode: ProgressMode) -> Events {
        Events { mode }
    }

    pub fn json(&self) -> bool {
        self.mode == ProgressMode::Json
    }

    /// Whether people get a bar or progress lines.
    pub fn human(&self) -> bool {
        matches!(self.mode, ProgressMode::Auto | ProgressMode::Bar)
    }

    /// Writes one event line (JSON mode only).
    pub fn emit(&self, v: serde_json::Value) {
        if self.json() {
            let mut e = std::io::stderr().lock();
            let _ = writeln!(e, "{v}");
        }
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
