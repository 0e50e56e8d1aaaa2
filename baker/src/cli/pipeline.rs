//! The build-tool side of `baker bake`: the end of a bake (shard manifest, cache roots,
//! summary, interruption), `baker merge`, `baker plan` and `baker cache`.

use std::path::{Path, PathBuf};
use std::sync::atomic::Ordering::Relaxed;
use std::time::Instant;

use anyhow::Context;
use clap::{Args, Subcommand};

use super::bake::BakeArgs;
use crate::output::atomic;
use crate::output::paths::OutRoot;
use crate::pipeline::{interrupt, Key, Runner};

/// Exit code of a bake stopped by SIGINT/SIGTERM (128 + SIGINT, the shell convention).
pub const EXIT_INTERRUPTED: i32 = 130;

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
    a: &BakeArgs,
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
            if !a.quiet {
                eprintln!(
                    "interrupted: {computed} work units finished and cached; finished outputs \
                     are unchanged; run the same command again to resume:\n  {resume}"
                );
            }
            return Err(e);
        }
        let code = if e.downcast_ref::<super::UsageError>().is_some() {
            2
        } else {
            1
        };
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
    if a.human() && (hits > 0 || a.shard.is_some()) {
        eprintln!(
            "work units: {computed} computed, {hits} from the cache ({})",
            runner.cache.dir.display()
        );
    }
    Ok(())
}

/// Records `keys` as the units output `name` of `root` needs (`roots/<name>-<id>.json` in the
/// cache; `<id>` tells apart outputs of the same name in different output folders sharing a
/// cache). [`cache`] `gc` keeps every unit any roots file names.
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

#[derive(Debug, Args)]
pub struct MergeArgs {
    /// Shard directories written by `baker bake … --shard I/N --out DIR`.
    #[arg(required = true)]
    pub shards: Vec<PathBuf>,
    /// Output root (as `baker bake --out`).
    #[arg(short = 'o', long = "out", default_value = "out")]
    pub out: PathBuf,
    /// Progress (as `baker bake --progress`).
    #[arg(long, value_enum, default_value = "auto")]
    pub progress: crate::pipeline::ProgressMode,
    #[arg(long, short)]
    pub quiet: bool,
    #[arg(long)]
    pub threads: Option<usize>,
}

/// `baker merge`: copies the shards' units into OUT's cache and assembles the tables as one
/// `baker bake` would (every unit must be present: nothing is traced).
pub fn merge(m: MergeArgs) -> anyhow::Result<()> {
    let mut first: Option<ShardManifest> = None;
    let cache_dir = m.out.join(".cache");
    let mut seen = std::collections::BTreeSet::new();
    let mut count = None;
    for d in &m.shards {
        let p = d.join("shard.json");
        let text = crate::files::read_text(&p, crate::files::MAX_SPEC_BYTES, "a shard manifest")
            .with_context(|| {
                format!(
                    "{}: not a shard directory (no readable shard.json)",
                    d.display()
                )
            })?;
        let s: ShardManifest = serde_json::from_str(&text)
            .with_context(|| format!("{}: invalid shard manifest", p.display()))?;
        let (i, n): (usize, usize) = s
            .shard
            .split_once('/')
            .and_then(|(i, n)| Some((i.parse().ok()?, n.parse().ok()?)))
            .ok_or_else(|| anyhow::anyhow!("{}: bad shard field {:?}", p.display(), s.shard))?;
        if *count.get_or_insert(n) != n || !seen.insert(i) {
            return Err(super::UsageError(format!(
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
                return Err(super::UsageError(format!(
                    "{}: baked from other specs or flags than {}",
                    d.display(),
                    m.shards[0].display()
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
        return Err(super::UsageError(format!("shards {missing:?} of {n} are missing")).into());
    }
    for (spec, sha) in &f.specs {
        let now = crate::output::manifest::spec_sha256(&spec.to_string_lossy());
        if &now != sha {
            return Err(super::UsageError(format!(
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
    let a = BakeArgs {
        specs,
        out: m.out.clone(),
        entries: f.entries,
        photons: f.photons,
        threads: m.threads,
        quiet: m.quiet,
        optics_only: f.optics_only,
        no_reuse: f.no_reuse,
        plots: f.plots,
        replace: f.replace,
        progress: m.progress,
        shard: None,
        force: false,
        cache: Some(cache_dir),
        require_cached: true,
    };
    super::bake::run(a)
}

#[derive(Debug, Args)]
pub struct PlanArgs {
    /// Spec files.
    #[arg(required = true)]
    pub specs: Vec<PathBuf>,
    /// Output root whose cache is consulted (as `baker bake --out`).
    #[arg(long, default_value = "out")]
    pub out: PathBuf,
    #[arg(long, value_name = "DIR")]
    pub cache: Option<PathBuf>,
    #[arg(long)]
    pub photons: Option<u64>,
    #[arg(long = "entry", value_name = "NAME")]
    pub entries: Vec<String>,
    #[arg(long)]
    pub no_reuse: bool,
    /// Worker threads the bake will run (for the memory bound; default: all cores).
    #[arg(long)]
    pub threads: Option<usize>,
    /// Print JSON instead of a table.
    #[arg(long)]
    pub json: bool,
}

/// `baker plan`: the work units of the specs, their cost and whether they are cached, and
/// what each bake will cost (photons, the memory bound) against the spec's limits.
pub fn plan(p: PlanArgs) -> anyhow::Result<()> {
    let cache = crate::pipeline::Cache::new(
        p.cache.clone().unwrap_or_else(|| p.out.join(".cache")),
        crate::pipeline::CacheMode::Use,
    );
    let o = crate::spec::budget::Overrides {
        photons: p.photons,
        threads: p.threads.unwrap_or_else(rayon::current_num_threads).max(1),
        no_reuse: p.no_reuse,
        optics_only: false,
    };
    let mut units = Vec::new();
    let mut costs = Vec::new();
    for path in &p.specs {
        let (spec, cost) = super::bake::load_checked(path, &o)?;
        let stem = super::bake::spec_stem(path)?;
        units.extend(super::bake::plan_units(
            &spec, &stem, &p.entries, p.photons, p.no_reuse, &cache,
        )?);
        costs.push((path.clone(), cost, *spec.limits()));
    }
    let cached = units.iter().filter(|u| u.cached).count();
    let photons: u64 = units.iter().filter(|u| !u.cached).map(|u| u.photons).sum();
    if p.json {
        let budgets: Vec<serde_json::Value> = costs
            .iter()
            .map(|(path, c, l)| {
                serde_json::json!({"spec": path, "photons_max": c.photons,
                    "memory_bytes_max": c.memory_bytes, "threads": o.threads, "limits": l})
            })
            .collect();
        outln!(
            "{}",
            serde_json::to_string_pretty(&serde_json::json!({
                "units": units, "total": units.len(), "cached": cached,
                "photons_to_trace": photons, "cache": cache.dir, "budget": budgets,
            }))?
        )?;
        return Ok(());
    }
    outln!(
        "{:<56} {:>7} {:>14} {}",
        "unit",
        "shard#",
        "photons",
        "cached"
    )?;
    for u in &units {
        outln!(
            "{:<56} {:>7} {:>14} {}",
            u.id,
            u.index.map_or("-".into(), |i| i.to_string()),
            u.photons,
            if u.cached { "yes" } else { "no" }
        )?;
    }
    outln!(
        "{} units, {cached} cached; {photons} photons to trace (cache {})",
        units.len(),
        cache.dir.display()
    )?;
    for (path, c, l) in &costs {
        outln!(
            "{}: at most {} on {} thread(s) (limits: {:.3e} photons, {} GiB)",
            path.display(),
            c.describe(),
            o.threads,
            l.photons,
            l.memory_gib
        )?;
    }
    Ok(())
}

#[derive(Debug, Subcommand)]
pub enum CacheCommand {
    /// Delete cached units that no recorded bake uses (the roots are the keys of the last
    /// bake of each spec and shard).
    Gc {
        #[arg(long, default_value = "out")]
        out: PathBuf,
        #[arg(long, value_name = "DIR")]
        cache: Option<PathBuf>,
        /// Only list what would be deleted.
        #[arg(long)]
        dry_run: bool,
    },
}

pub fn cache(c: CacheCommand) -> anyhow::Result<()> {
    match c {
        CacheCommand::Gc {
            out,
            cache,
            dry_run,
        } => {
            let dir = cache.unwrap_or_else(|| out.join(".cache"));
            let c = crate::pipeline::Cache::new(&dir, crate::pipeline::CacheMode::Use);
            let live = live_units(&dir, &out)?;
            let (mut n, mut bytes) = (0usize, 0u64);
            for (k, p) in c.list() {
                if !live.contains(&k) {
                    bytes += std::fs::metadata(&p).map(|m| m.len()).unwrap_or(0);
                    n += 1;
                    if !dry_run {
                        remove(&p)?;
                    }
                }
            }
            outln!(
                "{} {n} unused units ({:.1} MB) from {}; {} in use",
                if dry_run { "would delete" } else { "deleted" },
                bytes as f64 / 1e6,
                dir.display(),
                live.len()
            )?;
            Ok(())
        }
    }
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
            for dir in [d.path(), d.path().join(super::bake::SUBSET_DIR)] {
                if let Some(m) = super::bake::manifest_summary(&dir) {
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

fn remove(p: &Path) -> anyhow::Result<()> {
    std::fs::remove_file(p).with_context(|| format!("deleting {}", p.display()))
}

use crate::output::STAMP_FILE;

/// What determines a spec's outputs: the spec's bytes (`spec_sha256`), this executable's bytes
/// (code and data tables), the engine version and the flags that change outputs. Equal stamps
/// and intact files (checked against the manifest's SHA-256) make a bake a no-op.
pub fn stamp(a: &BakeArgs, spec: &Path, spec_sha256: &str) -> String {
    static EXE: std::sync::OnceLock<String> = std::sync::OnceLock::new();
    let exe = EXE.get_or_init(|| {
        std::env::current_exe()
            .ok()
            .and_then(|p| std::fs::read(p).ok())
            .map(|b| crate::pipeline::digest_of(&sha_hex(&b)))
            .map(|d| sha_hex(&d))
            .unwrap_or_default()
    });
    sha_hex(&crate::pipeline::digest_of(&(
        spec_sha256,
        spec,
        exe,
        crate::pipeline::ENGINE_VERSION,
        a.photons,
        &a.entries,
        a.no_reuse,
        a.optics_only,
        a.plots,
    )))
}

fn sha_hex(b: &[u8]) -> String {
    use sha2::Digest as _;
    sha2::Sha256::digest(b)
        .iter()
        .map(|x| format!("{x:02x}"))
        .collect()
}

/// Whether `dir` holds the outputs of `stamp`, every file of its manifest intact.
pub fn up_to_date(dir: &Path, stamp: &str) -> bool {
    // Only regular files count (a FIFO or device planted there is not an output).
    let regular = |p: &Path| std::fs::symlink_metadata(p).is_ok_and(|m| m.is_file());
    if !regular(&dir.join(STAMP_FILE)) || !regular(&dir.join("manifest.json")) {
        return false;
    }
    let Ok(s) = std::fs::read_to_string(dir.join(STAMP_FILE)) else {
        return false;
    };
    if s.trim() != stamp {
        return false;
    }
    let Ok(m) = std::fs::read_to_string(dir.join("manifest.json")) else {
        return false;
    };
    let Ok(m) = serde_json::from_str::<serde_json::Value>(&m) else {
        return false;
    };
    let Some(files) = m["files"].as_array() else {
        return false;
    };
    files.iter().all(|f| {
        let (Some(rel), Some(sha)) = (f["path"].as_str(), f["sha256"].as_str()) else {
            return false;
        };
        rel.split('/')
            .all(|c| crate::output::paths::check_component(c, false).is_ok())
            && regular(&dir.join(rel))
            && std::fs::read(dir.join(rel)).is_ok_and(|b| sha_hex(&b) == sha)
    })
}

/// Records `stamp` once every output of the spec is written.
pub fn write_stamp(dir: &Path, stamp: &str) -> anyhow::Result<()> {
    let p = dir.join(STAMP_FILE);
    atomic::write(&p, stamp.as_bytes()).with_context(|| format!("writing {}", p.display()))
}
