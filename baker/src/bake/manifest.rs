//! One manifest writer and one `timing.json` for both kinds of bake.
//!
//! `manifest.json` is reproducible: the same spec and flags give the same bytes. Its keys
//! (sorted): `baker_version`, `entries`, `files` (path, bytes, SHA-256, description),
//! `format` (`baker-manifest`), `kind` (`baker-skin-bake` or `baker-fiber-bake`), `settings`,
//! `spec_file`, `spec_sha256`, `units` (the unit keys it was assembled from), `version` (1),
//! `warnings`; a fiber manifest also keeps its first key for the spec, `spec`. Wall-clock
//! figures change from run to run (and a cached unit costs nothing), so they live apart, in
//! `timing.json`.

use anyhow::Context;

use crate::bake::job::Job;
use crate::output::atomic;
use crate::output::manifest::ManifestFile;

/// Which bake wrote a manifest.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Kind {
    Skin,
    Fiber,
}

impl Kind {
    /// The manifest's `kind` value.
    pub fn name(self) -> &'static str {
        match self {
            Kind::Skin => "baker-skin-bake",
            Kind::Fiber => "baker-fiber-bake",
        }
    }
}

/// What a bake of either kind records about itself.
pub struct Manifest {
    pub kind: Kind,
    pub spec_file: String,
    pub spec_sha256: String,
    pub settings: serde_json::Value,
    pub entries: serde_json::Value,
    pub files: Vec<ManifestFile>,
    pub warnings: Vec<String>,
}

/// This run's wall-clock figures: `timing.json`, `{"seconds", "threads", "photons",
/// "<phase>_seconds"…, "entries", "note"}` (formats/FORMAT.md).
pub struct Timing {
    pub seconds: f64,
    /// Per phase, seconds: skin `optics`, `transport`, `fits`, `writing` (`optics` only for
    /// `--optics-only`); fiber bakes time each entry instead.
    pub phases: Vec<(&'static str, f64)>,
    /// Worker threads of the bake.
    pub threads: usize,
    /// Photon packets of the baked tables (cached units included; 0 for optics only).
    pub photons: u64,
    /// Per entry, as the kind measures it.
    pub entries: Vec<serde_json::Value>,
}

/// Writes `manifest.json`, `timing.json` and the stamp into the job's staged folder (nothing
/// for a shard). The manifest is written last but for the stamp, which marks the bake done.
pub fn write(job: &Job, m: Manifest, t: Timing) -> anyhow::Result<()> {
    let Some(d) = job.out else { return Ok(()) };
    let mut doc = serde_json::json!({
        "format": "baker-manifest",
        "version": 1,
        "kind": m.kind.name(),
        "spec_file": m.spec_file,
        "spec_sha256": m.spec_sha256,
        "baker_version": env!("CARGO_PKG_VERSION"),
        "settings": m.settings,
        "entries": m.entries,
        "files": m.files,
        "warnings": m.warnings,
        "units": job.unit_keys(),
    });
    if m.kind == Kind::Fiber {
        doc["spec"] = doc["spec_file"].clone();
    }
    let mut timing = serde_json::json!({
        "seconds": t.seconds,
        "threads": t.threads,
        "photons": t.photons,
        "entries": t.entries,
        "note": "this run's wall-clock time; units taken from the cache cost nothing",
    });
    for (phase, s) in &t.phases {
        timing[format!("{phase}_seconds")] = (*s).into();
    }
    job.runner.cancel.check()?;
    for (name, doc) in [("timing.json", &timing), ("manifest.json", &doc)] {
        let p = d.staged.path(name)?;
        atomic::write(&p, serde_json::to_string_pretty(doc)?.as_bytes())
            .with_context(|| format!("writing {}", p.display()))?;
    }
    super::stamp::write_stamp(d.staged.dir(), job.stamp)
}
