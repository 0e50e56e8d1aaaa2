//! `baker merge`: the shards' units into one cache, then the tables one bake would write.

use std::path::{Path, PathBuf};

use anyhow::Context;

use super::shard::ShardManifest;
use crate::bake::request::Request;
use crate::error::UsageError;
use crate::output::atomic;
use crate::pipeline::Events;

/// `baker merge`: copies the shards' units into OUT's cache and assembles the tables as one
/// `baker bake` would (every unit must be present: nothing is traced).
pub fn merge(
    shards: &[PathBuf],
    out: &Path,
    threads: Option<usize>,
    events: Events,
) -> anyhow::Result<()> {
    let mut first: Option<ShardManifest> = None;
    let cache_dir = out.join(".cache");
    let mut seen = std::collections::BTreeSet::new();
    let mut count = None;
    for d in shards {
        let p = d.join("shard.json");
        let text = crate::files::read_text(&p, crate::files::MAX_SPEC_BYTES, "a shard manifest")
            .map_err(|e| {
                UsageError(format!(
                    "{}: not a shard directory (no readable shard.json: {e:#})",
                    d.display()
                ))
            })?;
        let s: ShardManifest = serde_json::from_str(&text)
            .map_err(|e| UsageError(format!("{}: invalid shard manifest: {e}", p.display())))?;
        let (i, n): (usize, usize) = s
            .shard
            .split_once('/')
            .and_then(|(i, n)| Some((i.parse().ok()?, n.parse().ok()?)))
            .ok_or_else(|| anyhow::anyhow!("{}: bad shard field {:?}", p.display(), s.shard))?;
        if *count.get_or_insert(n) != n || !seen.insert(i) {
            return Err(UsageError(format!(
                "{}: shard {i}/{n} repeats or disagrees with the other shards",
                d.display()
            ))
            .into());
        }
        if let Some(f) = &first {
            if f.specs != s.specs
                || f.photons != s.photons
                || f.entries != s.entries
                || f.no_reuse != s.no_reuse
                || f.optics_only != s.optics_only
            {
                return Err(UsageError(format!(
                    "{}: baked from other specs or flags than {}",
                    d.display(),
                    shards[0].display()
                ))
                .into());
            }
        }
        // Copy the units (they are immutable, content-addressed files).
        let src = crate::pipeline::Cache::new(d.join(".cache"), crate::pipeline::CacheMode::Use);
        for (key, path) in src.list() {
            let dst = crate::pipeline::cache::unit_path(&cache_dir, &key);
            if !dst.exists() {
                let bytes =
                    std::fs::read(&path).with_context(|| format!("reading {}", path.display()))?;
                atomic::write(&dst, &bytes)
                    .with_context(|| format!("writing {}", dst.display()))?;
            }
        }
        if first.is_none() {
            first = Some(s);
        }
    }
    let f = first.expect("at least one shard");
    let n = count.unwrap_or(0);
    if seen.len() != n {
        let missing: Vec<usize> = (1..=n).filter(|i| !seen.contains(i)).collect();
        return Err(UsageError(format!("shards {missing:?} of {n} are missing")).into());
    }
    for (spec, sha) in &f.specs {
        let now = crate::output::manifest::spec_sha256(&spec.to_string_lossy());
        if &now != sha {
            return Err(UsageError(format!(
                "{}: the spec changed since the shards were baked",
                spec.display()
            ))
            .into());
        }
    }
    let specs = f
        .specs
        .iter()
        .zip(&f.given)
        .map(|((abs, _), given)| match std::fs::canonicalize(given) {
            Ok(g) if &g == abs => given.clone(),
            _ => abs.clone(),
        })
        .collect();
    let req = Request {
        specs,
        out: out.to_path_buf(),
        entries: f.entries,
        photons: f.photons,
        threads,
        optics_only: f.optics_only,
        no_reuse: f.no_reuse,
        plots: f.plots,
        replace: f.replace,
        shard: None,
        force: false,
        cache: Some(cache_dir),
        require_cached: true,
    };
    super::run(&req, events)
}
