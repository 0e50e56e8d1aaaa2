//! The end of a bake: a shard's manifest for `baker merge`, the cache roots of finished
//! outputs, the summary event and interruption.

use std::path::PathBuf;
use std::sync::atomic::Ordering::Relaxed;
use std::time::Instant;

use anyhow::Context;

use crate::bake::request::Request;
use crate::output::atomic;
use crate::output::paths::OutRoot;
use crate::pipeline::{interrupt, Key, Runner};

/// What a shard records for `baker merge`.
#[derive(Debug, serde::Serialize, serde::Deserialize)]
pub struct ShardManifest {
    pub format: String,
    pub shard: String,
    /// Absolute spec paths and their SHA-256 at bake time.
    pub specs: Vec<(PathBuf, String)>,
    /// The spec paths as given on the command line (recorded in the tables' provenance; merge
    /// uses them where they still name the same files, so its tables equal a local bake's).
    pub given: Vec<PathBuf>,
    pub photons: Option<u64>,
    pub entries: Vec<String>,
    pub no_reuse: bool,
    pub optics_only: bool,
    #[serde(default)]
    pub plots: bool,
    #[serde(default)]
    pub replace: bool,
    /// Units this shard holds (computed or found in its cache): id and key.
    pub units: Vec<(String, String)>,
}

/// Ends a bake: on success the shard manifest and its cache roots (with `--shard`) and the
/// summary event; on a signal, the `interrupted` event and how to resume. The roots of each
/// finished output were recorded when it was put in place ([`write_roots`]); a bake that was
/// up to date or failed changes none.
pub fn finish(
    a: &Request,
    runner: &Runner,
    stems: &[String],
    t0: Instant,
    result: anyhow::Result<()>,
) -> anyhow::Result<()> {
    let computed = runner.computed.load(Relaxed);
    let hits = runner.hits.load(Relaxed);
    let used: Vec<(String, Key)> = runner.used.lock().unwrap().clone();
    if let Err(e) = result {
        if e.downcast_ref::<interrupt::Interrupted>().is_some() {
            let resume = std::env::args().collect::<Vec<_>>().join(" ");
            runner
                .events
                .emit(serde_json::json!({"event": "interrupted",
                "units_computed": computed, "resume": resume}));
            runner.events.notice(format!(
                "interrupted: {computed} work units finished and cached; finished outputs are \
                 unchanged; run the same command again to resume:\n  {resume}"
            ));
            return Err(e);
        }
        let code = crate::error::exit_code(&e);
        runner.events.emit(
            serde_json::json!({"event": "error", "message": format!("{e:#}"),
            "exit_code": code}),
        );
        return Err(e);
    }
    if let Some(s) = a.shard {
        let root = crate::output::paths::OutRoot::open(&a.out)?;
        let name = format!("{}-shard{}of{}", stems.join("+"), s.index, s.count);
        let keys: Vec<Key> = used.iter().map(|(_, k)| *k).collect();
        write_roots(runner, &root, &name, &keys)?;
        let specs = a
            .specs
            .iter()
            .map(|p| {
                let abs = std::fs::canonicalize(p)
                    .with_context(|| format!("resolving {}", p.display()))?;
                Ok((
                    abs.clone(),
                    crate::output::manifest::spec_sha256(&abs.to_string_lossy()),
                ))
            })
            .collect::<anyhow::Result<Vec<_>>>()?;
        let m = ShardManifest {
            format: "baker-shard".into(),
            shard: format!("{}/{}", s.index, s.count),
            specs,
            photons: a.photons,
            entries: a.entries.clone(),
            no_reuse: a.no_reuse,
            optics_only: a.optics_only,
            plots: a.plots,
            replace: a.replace,
            given: a.specs.clone(),
            units: used.iter().map(|(id, k)| (id.clone(), k.hex())).collect(),
        };
        let p = root.join("shard.json")?;
        atomic::write(&p, serde_json::to_string_pretty(&m)?.as_bytes())
            .with_context(|| format!("writing {}", p.display()))?;
    }
    let seconds = t0.elapsed().as_secs_f64();
    runner
        .events
        .emit(serde_json::json!({"event": "summary", "specs": stems,
        "units_computed": computed, "cache_hits": hits, "seconds": seconds,
        "shard": a.shard.map(|s| format!("{}/{}", s.index, s.count))}));
    if hits > 0 || a.shard.is_some() {
        runner.events.say(format!(
            "work units: {computed} computed, {hits} from the cache ({})",
            runner.cache.dir.display()
        ));
    }
    Ok(())
}

/// Records `keys` as the units output `name` of `root` needs (`roots/<name>-<id>.json` in the
/// cache; `<id>` tells apart outputs of the same name in different output folders sharing a
/// cache). `baker cache gc` keeps every unit any roots file names.
pub fn write_roots(
    runner: &Runner,
    root: &OutRoot,
    name: &str,
    keys: &[Key],
) -> anyhow::Result<()> {
    if runner.cache.mode == crate::pipeline::CacheMode::Off {
        return Ok(());
    }
    let out_id = crate::pipeline::digest_of(&root.canonical().join(name));
    let file = format!(
        "{}-{}.json",
        name.replace('/', "+"),
        &Key(out_id).hex()[..12]
    );
    let p = runner.cache.dir.join("roots").join(file);
    let mut hex: Vec<String> = keys.iter().map(Key::hex).collect();
    hex.sort();
    hex.dedup();
    atomic::write(&p, serde_json::to_string(&hex)?.as_bytes())
        .with_context(|| format!("writing {}", p.display()))
}

/// The keys of the units this process used since `first`, sorted, each once (units run in
/// parallel, so use order is not reproducible; the manifest must be).
pub fn unit_keys(runner: &Runner, first: usize) -> Vec<String> {
    let used = runner.used.lock().unwrap();
    let mut keys: Vec<String> = used[first.min(used.len())..]
        .iter()
        .map(|(_, k)| k.hex())
        .collect();
    keys.sort();
    keys.dedup();
    keys
}
