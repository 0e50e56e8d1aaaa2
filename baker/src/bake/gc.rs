//! `baker cache gc`: which cached units something still needs, and deleting the rest.

use std::path::Path;

use anyhow::Context;

use super::shard::ShardManifest;
use crate::pipeline::Key;

/// What `baker cache gc` did (or would do, with `dry_run`).
#[derive(Debug, Clone, Copy)]
pub struct Collected {
    /// Units deleted (or to delete).
    pub units: usize,
    pub bytes: u64,
    /// Units still in use.
    pub live: usize,
}

/// Deletes the units of the cache at `cache_dir` that nothing under `out` needs.
pub fn collect(cache_dir: &Path, out: &Path, dry_run: bool) -> anyhow::Result<Collected> {
    if !cache_dir.is_dir() {
        return Err(crate::error::UsageError(format!(
            "{}: no unit cache there (a bake into {} makes one; --cache DIR names another)",
            cache_dir.display(),
            out.display()
        ))
        .into());
    }
    let c = crate::pipeline::Cache::new(cache_dir, crate::pipeline::CacheMode::Use);
    let live = live_units(cache_dir, out)?;
    let (mut units, mut bytes) = (0usize, 0u64);
    for (k, p) in c.list() {
        if !live.contains(&k) {
            bytes += std::fs::metadata(&p).map(|m| m.len()).unwrap_or(0);
            units += 1;
            if !dry_run {
                std::fs::remove_file(&p).with_context(|| format!("deleting {}", p.display()))?;
            }
        }
    }
    Ok(Collected {
        units,
        bytes,
        live: live.len(),
    })
}

/// Every unit something still needs: the keys of every roots file in the cache, of every
/// manifest under `out` (each spec's folder and its subset folder) and of every shard
/// manifest there.
pub fn live_units(cache_dir: &Path, out: &Path) -> anyhow::Result<std::collections::BTreeSet<Key>> {
    let mut live = std::collections::BTreeSet::new();
    let read = |p: &Path| {
        crate::files::read_text(p, crate::files::MAX_SPEC_BYTES, "a cache roots file")
            .map_err(anyhow::Error::from)
    };
    if let Ok(rd) = std::fs::read_dir(cache_dir.join("roots")) {
        for f in rd.flatten() {
            let keys: Vec<String> = serde_json::from_str(&read(&f.path())?)
                .with_context(|| format!("{}: invalid roots file", f.path().display()))?;
            live.extend(keys.iter().filter_map(|k| Key::from_hex(k)));
        }
    }
    if let Ok(rd) = std::fs::read_dir(out) {
        for d in rd.flatten().filter(|d| d.path().is_dir()) {
            for dir in [d.path(), d.path().join(super::destination::SUBSET_DIR)] {
                if let Some(m) = super::destination::manifest_summary(&dir) {
                    live.extend(m.units.iter().filter_map(|k| Key::from_hex(k)));
                }
            }
        }
    }
    if let Ok(text) = read(&out.join("shard.json")) {
        if let Ok(m) = serde_json::from_str::<ShardManifest>(&text) {
            live.extend(m.units.iter().filter_map(|(_, k)| Key::from_hex(k)));
        }
    }
    Ok(live)
}
