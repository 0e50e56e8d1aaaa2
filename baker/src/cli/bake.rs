//! `baker bake`: every product of every entry of the given specs, written atomically.
//!
//! Per spec, into `OUT/<spec stem>/`: `optics.json` and `optics/<entry>.csv` (layer optics),
//! `profiles.h5` and `profiles.bkt` (spectral and RGB diffusion profiles, Gaussian fits, layer
//! optics, surface and input parameters; layout in formats/FORMAT.md), `profiles_rgb.exr`,
//! `preview/` PNGs and `manifest.json` (entries, files, SHA-256).

use std::io::IsTerminal;
use std::path::{Path, PathBuf};
use std::time::Instant;

use anyhow::Context;
use clap::Args;
use rayon::prelude::*;

use super::UsageError;
use crate::files::Shown;
use crate::output::paths::{OutRoot, Staged};
use crate::output::{self, atomic, manifest, preview, tables};
use crate::pipeline::{interrupt, Cache, CacheMode, Events, Key, ProgressMode, Runner, Shard};
use crate::profile::{self, RgbProfile, SimOptions, SpectralProfile};
use crate::spec::{budget, names, SkinSpec, Spec};
use crate::spectral::ColourMap;
use crate::transport::RadialBins;

#[derive(Debug, Args)]
pub struct BakeArgs {
    /// Spec files (YAML).
    #[arg(required = true)]
    pub specs: Vec<PathBuf>,
    /// Output root; each spec bakes into OUT/<spec name>/.
    #[arg(long, default_value = "out")]
    pub out: PathBuf,
    /// Bake only this entry (repeatable), e.g. for a preview.
    #[arg(long = "entry", value_name = "NAME")]
    pub entries: Vec<String>,
    /// Photon packets per wavelength and simulation, overriding the spec's `profiles.photons`
    /// (fewer for a quick preview).
    #[arg(long)]
    pub photons: Option<u64>,
    /// Worker threads (default: all cores). Results do not depend on it.
    #[arg(long)]
    pub threads: Option<usize>,
    /// No progress bar and no summary (errors still go to stderr).
    #[arg(long, short)]
    pub quiet: bool,
    /// Skip the Monte Carlo profiles: layer optics only.
    #[arg(long)]
    pub optics_only: bool,
    /// One simulation per entry instead of one per group of entries sharing scattering (to
    /// measure what absorption reuse saves; results differ only by Monte Carlo noise).
    #[arg(long)]
    pub no_reuse: bool,
    /// Also write PNG plots of every entry's coefficients.
    #[arg(long)]
    pub plots: bool,
    /// Progress: `auto` (a bar on a terminal, a line every ~5 % otherwise), `bar`, `json`
    /// (one JSON event per line on stderr, for pipeline tools), `none`.
    #[arg(long, value_enum, default_value = "auto")]
    pub progress: ProgressMode,
    /// Bake only the work units of shard I of N (1 ≤ I ≤ N) into OUT (their cache and
    /// `shard.json`); `baker merge` assembles the tables from all shards.
    #[arg(long, value_name = "I/N")]
    pub shard: Option<Shard>,
    /// Recompute every work unit even if it is cached (and overwrite the cache).
    #[arg(long)]
    pub force: bool,
    /// Write a subset bake (some --entry, fewer --photons, --optics-only) to OUT/<spec>/
    /// itself, replacing the finished bake there. Without it a subset goes to
    /// OUT/<spec>/subset/, and a finished bake of the same spec with more entries or photons
    /// is never replaced.
    #[arg(long)]
    pub replace: bool,
    /// Unit cache directory (default: OUT/.cache).
    #[arg(long, value_name = "DIR")]
    pub cache: Option<PathBuf>,
    /// `baker merge`: every unit must come from the cache (set by merge, not a flag).
    #[arg(skip)]
    pub require_cached: bool,
}

impl BakeArgs {
    /// Whether people get messages, bars and progress lines on stderr.
    pub fn human(&self) -> bool {
        !self.quiet && matches!(self.progress, ProgressMode::Auto | ProgressMode::Bar)
    }

    fn runner(&self) -> Runner {
        let mode = if self.force {
            CacheMode::Force
        } else {
            CacheMode::Use
        };
        let cache = Cache::new(
            self.cache
                .clone()
                .unwrap_or_else(|| self.out.join(".cache")),
            mode,
        );
        let progress = if self.quiet {
            ProgressMode::None
        } else {
            self.progress
        };
        let mut r = Runner::new(cache, Events::new(progress), self.shard);
        r.require_cached = self.require_cached;
        // SIGINT/SIGTERM stop the units at their next batch.
        r.cancel = interrupt::cancel();
        r
    }
}

pub fn run(a: BakeArgs) -> anyhow::Result<()> {
    if a.photons == Some(0) {
        return Err(UsageError("--photons must be at least 1".into()).into());
    }
    let threads = a.threads.unwrap_or_else(rayon::current_num_threads).max(1);
    let overrides = budget::Overrides {
        photons: a.photons,
        threads,
        no_reuse: a.no_reuse,
        optics_only: a.optics_only,
    };
    // Validate every spec (entries, sizes, names, cost) before writing anything.
    let specs = a
        .specs
        .iter()
        .map(|p| load_checked(p, &overrides).map(|(s, _)| s))
        .collect::<anyhow::Result<Vec<_>>>()?;
    if !a.entries.is_empty() {
        // With several specs an entry may live in any of them; each name must exist somewhere.
        let names: Vec<&str> = specs
            .iter()
            .flat_map(|s| s.entries().into_iter().map(|(n, _)| n))
            .collect();
        for name in &a.entries {
            if !names.contains(&name.as_str()) {
                return Err(UsageError(format!(
                    "{}: no entry named {name:?}; entries: {}",
                    a.specs
                        .iter()
                        .map(|p| p.display().to_string())
                        .collect::<Vec<_>>()
                        .join(", "),
                    names.join(", ")
                ))
                .into());
            }
        }
    }
    let root = OutRoot::open(&a.out).map_err(|e| UsageError(e.to_string()))?;
    let pool = rayon::ThreadPoolBuilder::new()
        .num_threads(threads)
        .build()?;
    interrupt::install();
    interrupt::set_silent(!a.human());
    let runner = a.runner();
    let t0 = Instant::now();
    let mut stems = Vec::new();
    let result = (|| -> anyhow::Result<()> {
        for (path, spec) in a.specs.iter().zip(&specs) {
            let stem = spec_stem(path)?;
            stems.push(stem.clone());
            let has = a.entries.is_empty()
                || spec
                    .entries()
                    .iter()
                    .any(|(n, _)| a.entries.iter().any(|e| e == n));
            if !has {
                continue;
            }
            let first_unit = runner.used.lock().unwrap().len();
            let dest = if a.shard.is_some() {
                None
            } else {
                Some(destination(&a, &root, path, &stem, spec)?)
            };
            // Unchanged spec, flags and executable, outputs intact: nothing to do.
            let stamp = super::pipeline::stamp(&a, path, spec_sha(spec));
            if let Some(d) = &dest {
                if !a.force && super::pipeline::up_to_date(d.staged.target(), &stamp) {
                    runner
                        .events
                        .emit(serde_json::json!({"event": "up_to_date", "spec": path}));
                    say(
                        &a,
                        format!(
                            "{}: up to date ({})",
                            path.display(),
                            Shown(d.staged.target())
                        ),
                    );
                    continue;
                }
            }
            match spec {
                Spec::Skin(s) => {
                    pool.install(|| bake_spec(&a, path, s, &runner, dest.as_ref(), &stamp))?
                }
                Spec::Fiber(s) => pool.install(|| {
                    super::bake_fiber::bake_fiber_spec(&a, path, s, &runner, dest.as_ref(), &stamp)
                })?,
            }
            if let Some(d) = dest {
                let keys: Vec<Key> = runner.used.lock().unwrap()[first_unit..]
                    .iter()
                    .map(|(_, k)| *k)
                    .collect();
                let rel = d.rel.clone();
                d.commit()?;
                // The finished output's units are live for `baker cache gc`.
                super::pipeline::write_roots(&runner, &root, &rel, &keys)?;
            }
        }
        Ok(())
    })();
    super::pipeline::finish(&a, &runner, &stems, t0, result)
}

/// Loads a spec of either kind and checks what baking it with `o` costs; every problem is a
/// [`UsageError`] naming file:line.
pub fn load_checked(path: &Path, o: &budget::Overrides) -> anyhow::Result<(Spec, budget::Cost)> {
    let usage = |e: crate::spec::SpecErrors| UsageError(e.to_string().trim_end().to_string());
    let spec = crate::spec::load_any(path).map_err(usage)?;
    let cost = budget::check(&spec, o).map_err(usage)?;
    Ok((spec, cost))
}

/// The output folder name of a spec: its file stem, which must be a plain folder name.
pub fn spec_stem(path: &Path) -> anyhow::Result<String> {
    let stem = path
        .file_stem()
        .map(|s| s.to_string_lossy().to_string())
        .unwrap_or_default();
    names::check_stem(&stem).map_err(|m| {
        UsageError(format!(
            "{}: the spec's file name gives the output folder name {stem:?}, which {m}; rename \
             the spec file",
            Shown(path)
        ))
    })?;
    Ok(stem)
}

/// Where a bake of one spec goes. Nothing finished is replaced by less:
///
/// - a bake of part of a spec (some `--entry`s, fewer `--photons` than the spec asks for,
///   `--optics-only`) goes to `OUT/<stem>/subset/` when `OUT/<stem>/` holds a finished bake;
/// - a whole bake goes to `OUT/<stem>/subset/` when `OUT/<stem>/` holds a bake of the same spec
///   with more photons (`--photons` above the spec's);
/// - anything else (a first bake, a whole bake of a changed spec) to `OUT/<stem>/`;
/// - `--replace` always to `OUT/<stem>/`.
pub struct Destination {
    /// Relative to the output root, `/`-separated.
    pub rel: String,
    pub staged: Staged,
    /// What the folder held before (its manifest's top-level names), kept or replaced.
    pub previous: std::collections::BTreeSet<String>,
}

/// The subset folder's name inside a spec's output folder.
pub const SUBSET_DIR: &str = "subset";

fn destination(
    a: &BakeArgs,
    root: &OutRoot,
    path: &Path,
    stem: &str,
    spec: &Spec,
) -> anyhow::Result<Destination> {
    let full_dir = root.join(stem)?;
    let selected = spec
        .entries()
        .iter()
        .filter(|(n, _)| a.entries.is_empty() || a.entries.iter().any(|e| e == n))
        .count();
    let spec_photons = match spec {
        Spec::Skin(s) => s.profiles.photons,
        Spec::Fiber(s) => s.bake.photons,
    };
    let photons = a.photons.unwrap_or(spec_photons);
    let partial = selected < spec.entries().len() || photons < spec_photons || a.optics_only;
    let finished = manifest_summary(&full_dir);
    // The same spec and flags as the finished bake: this is that bake again (up to date, or
    // to repair).
    let same = std::fs::read_to_string(full_dir.join(crate::output::STAMP_FILE))
        .is_ok_and(|s| s.trim() == super::pipeline::stamp(a, path, spec_sha(spec)));
    let bigger = !same
        && finished.as_ref().is_some_and(|m| {
            partial || (m.spec_sha256 == spec_sha(spec) && m.photons.is_some_and(|p| p > photons))
        });
    let subset = !a.replace && bigger;
    let rel = if subset {
        format!("{stem}/{SUBSET_DIR}")
    } else {
        stem.to_string()
    };
    if subset && a.human() {
        let why = if partial {
            "part of the spec"
        } else {
            "fewer photons than the finished bake of the same spec"
        };
        eprintln!(
            "{}: this bake is {why}, and {} holds a finished bake; writing to {} instead \
             (--replace writes over the finished bake)",
            spec.file(),
            Shown(&full_dir),
            Shown(&root.join(&rel)?),
        );
    }
    let staged = Staged::begin(root, &rel)?;
    let previous = manifest_summary(staged.target())
        .map(|m| m.top_level)
        .unwrap_or_default();
    Ok(Destination {
        rel,
        staged,
        previous,
    })
}

fn spec_sha(spec: &Spec) -> &str {
    match spec {
        Spec::Skin(s) => &s.sha256,
        Spec::Fiber(s) => &s.sha256,
    }
}

/// What a finished bake's manifest says about it.
pub struct ManifestSummary {
    pub spec_sha256: String,
    pub photons: Option<u64>,
    /// First components of the paths of its files.
    pub top_level: std::collections::BTreeSet<String>,
    /// Keys of the work units it was assembled from.
    pub units: Vec<String>,
}

/// Reads `dir/manifest.json` (skin or fiber), if there is a readable one.
pub fn manifest_summary(dir: &Path) -> Option<ManifestSummary> {
    let text = crate::files::read_text(
        &dir.join("manifest.json"),
        crate::files::MAX_SPEC_BYTES,
        "a manifest",
    )
    .ok()?;
    let m: serde_json::Value = serde_json::from_str(&text).ok()?;
    let top_level = m["files"]
        .as_array()?
        .iter()
        .filter_map(|f| f["path"].as_str()?.split('/').next().map(str::to_string))
        .collect();
    let photons = m["settings"]["photons"].as_u64();
    Some(ManifestSummary {
        spec_sha256: m["spec_sha256"].as_str().unwrap_or_default().to_string(),
        photons,
        top_level,
        units: m["units"]
            .as_array()
            .map(|u| {
                u.iter()
                    .filter_map(|k| k.as_str().map(str::to_string))
                    .collect()
            })
            .unwrap_or_default(),
    })
}

/// Top-level names a bake of either kind writes into a spec's folder.
const BAKE_FILES: [&str; 10] = [
    "manifest.json",
    "timing.json",
    crate::output::STAMP_FILE,
    "optics.json",
    "optics",
    "profiles.h5",
    "profiles.bkt",
    "profiles_rgb.exr",
    "preview",
    "plots",
];

impl Destination {
    /// Puts the finished bake in place; what the folder held that no bake wrote (a subset
    /// folder, a user's notes) is kept.
    pub fn commit(self) -> anyhow::Result<()> {
        let previous = self.previous;
        let target = self.staged.target().to_path_buf();
        self.staged
            .commit(|name| !BAKE_FILES.contains(&name) && !previous.contains(name))
            .with_context(|| format!("putting the bake in place at {}", Shown(&target)))
    }
}

/// The layer optics of the entries of `spec` that `pick` selects (evaluated by the resolver).
pub fn skin_optics(
    spec: &SkinSpec,
    pick: impl Fn(&crate::spec::ResolvedEntry) -> bool,
) -> anyhow::Result<Vec<formats::OpticsEntry>> {
    Ok(spec
        .entries
        .iter()
        .zip(&spec.optics)
        .filter(|(e, _)| pick(e))
        .map(|(_, o)| o.clone())
        .collect())
}

fn say(a: &BakeArgs, msg: impl AsRef<str>) {
    if a.human() {
        eprintln!("{}", msg.as_ref());
    }
}

/// Bakes a skin spec into `out` (`None` for a shard: units only), recording `stamp`.
fn bake_spec(
    a: &BakeArgs,
    path: &Path,
    spec: &SkinSpec,
    runner: &Runner,
    out: Option<&Destination>,
    stamp: &str,
) -> anyhow::Result<()> {
    let t0 = Instant::now();
    let stem = spec_stem(path)?;
    // Paths inside the folder being written, and the finished folder's name for messages.
    let at = |rel: &str| -> anyhow::Result<PathBuf> {
        Ok(out.expect("a shard writes no files").staged.path(rel)?)
    };
    let shown = out.map_or_else(PathBuf::new, |d| d.staged.target().to_path_buf());
    let first_unit = runner.used.lock().unwrap().len();
    runner
        .events
        .emit(serde_json::json!({"event": "bake_started", "spec": path,
        "kind": "skin", "entries": spec.entries.iter()
            .filter(|e| a.entries.is_empty() || a.entries.contains(&e.name)).count()}));
    let entries = skin_optics(spec, |e| {
        a.entries.is_empty() || a.entries.contains(&e.name)
    })?;
    let lam = spec.wavelengths.lambda_nm();
    // A shard only computes work units; `baker merge` writes every product.
    let sharded = out.is_none();
    for e in entries.iter().filter(|_| !sharded) {
        let p = at(&format!("optics/{}.csv", e.name))?;
        atomic::write(&p, output::csv::entry_csv(lam, e).as_bytes())
            .with_context(|| format!("writing {}", p.display()))?;
    }
    if a.plots && !sharded {
        super::optics::write_plots(&at("plots")?, lam, &entries)?;
    }
    let doc = crate::skin::document::document(&spec.file, lam, entries.clone());
    if !sharded {
        let p = at("optics.json")?;
        atomic::write(&p, serde_json::to_string_pretty(&doc)?.as_bytes())
            .with_context(|| format!("writing {}", p.display()))?;
    }
    if a.optics_only {
        say(
            a,
            format!(
                "baked {} (optics only): {} entries × {} wavelengths → {} ({:.2} s)",
                path.display(),
                entries.len(),
                lam.len(),
                shown.display(),
                t0.elapsed().as_secs_f64()
            ),
        );
        write_skin_manifest_optics_only(spec, &entries, out, stamp)?;
        return Ok(());
    }

    // Diffusion profiles.
    let settings = &spec.profiles;
    let photons = a.photons.unwrap_or(settings.photons);
    let bins = RadialBins::fine_then_log(settings.dr_min_mm, settings.growth, settings.r_max_mm);
    let plan = profile::plan(&entries, lam.len(), !a.no_reuse);
    let n_sims = plan.groups.len() * lam.len();
    say(
        a,
        format!(
            "{}: {} entries in {} simulation groups × {} wavelengths = {n_sims} simulations of {photons} photons",
            path.display(),
            entries.len(),
            plan.groups.len(),
            lam.len()
        ),
    );
    let terminal = std::io::stderr().is_terminal();
    let bar = (a.human() && terminal).then(|| super::progress::bar(n_sims as u64 * photons, ""));
    let sim = SimOptions {
        photons,
        seed: settings.seed,
        threads: a.threads,
        max_boost: settings.max_photon_boost,
        bar: bar.clone(),
    };
    let t_sim = Instant::now();
    let prefix = format!("{stem}/skin");
    let spectral = profile::simulate_units(
        &entries,
        lam,
        &bins,
        &plan,
        &sim,
        runner,
        &prefix,
        |done, total, _| {
            if let Some(b) = &bar {
                b.set_message(format!("simulation {done}/{total}"));
            } else if a.human() {
                // Pipelines (stderr not a terminal) get a line every ~5 % instead of a bar.
                let step = (total / 20).max(1);
                if done % step == 0 || done == total {
                    let el = t_sim.elapsed().as_secs_f64();
                    let eta = el / done as f64 * (total - done) as f64;
                    eprintln!("  simulation {done}/{total}, {el:.0} s elapsed, eta {eta:.0} s");
                }
            }
        },
    )?;
    if let Some(b) = &bar {
        b.finish_and_clear();
    }
    let Some(spectral) = spectral.filter(|_| !sharded) else {
        // A shard: its units are cached; `baker merge` assembles.
        return Ok(());
    };
    let sim_seconds = t_sim.elapsed().as_secs_f64();
    let colour = ColourMap::new(lam);
    let t_fit = Instant::now();
    // The fits are units too (minutes for a large database): keyed by the spectral profile.
    let rgb: Vec<RgbProfile> = spectral
        .par_iter()
        .zip(&entries)
        .map(|(p, e)| {
            let key = crate::pipeline::KeyBuilder::new("skin-fit")
                .part("profile", p)
                .part("gaussians", &settings.gaussians)
                .finish();
            let id = format!("{stem}/fit/{}", e.name);
            runner
                .unit(&id, key, None, 0, || {
                    Ok(profile::rgb_profile(
                        p,
                        &colour,
                        settings.gaussians,
                        runner.cancel,
                    )?)
                })
                .map_err(anyhow::Error::from)
                .map(|r| r.expect("fit units are never sharded"))
        })
        .collect::<anyhow::Result<_>>()?;
    let fit_seconds = t_fit.elapsed().as_secs_f64();

    let mut warnings = Vec::new();
    for (e, r) in entries.iter().zip(&rgb) {
        for (c, r99) in r.r99_mm.iter().enumerate() {
            if !r99.is_finite() {
                warnings.push(format!(
                    "entry {}: channel {} holds less than 99 % of its energy within r_max_mm = {} mm; \
                     raise profiles.radial.r_max_mm",
                    e.name,
                    ["R", "G", "B"][c],
                    bins.r_max_mm()
                ));
            }
        }
    }
    for w in &warnings {
        eprintln!("warning: {w}");
    }

    // Tables.
    let mut t =
        tables::Tables {
            attrs: vec![
            ("format".into(), tables::FORMAT.into()),
            ("format_version".into(), u64::from(tables::FORMAT_VERSION).into()),
            ("spec_file".into(), spec.file.clone().into()),
            ("spec_sha256".into(), spec.sha256.clone().into()),
            ("baker_version".into(), env!("CARGO_PKG_VERSION").into()),
            ("photons".into(), photons.into()),
            ("seed".into(), settings.seed.into()),
            ("gaussians".into(), (settings.gaussians as u64).into()),
            ("max_photon_boost".into(), settings.max_photon_boost.into()),
            ("absorption_reuse".into(), (!a.no_reuse).to_string().into()),
            (
                "entries".into(),
                serde_json::to_string(&entries.iter().map(|e| &e.name).collect::<Vec<_>>())?
                    .into(),
            ),
            (
                "source".into(),
                "Rd(r, lambda): white Monte Carlo with absorption reuse, pencil beam at normal \
                 incidence entering at a random point of the junction's period, MCML-class \
                 multi-layer transport with the Eq. 1 junction (thesis 3.5)"
                    .into(),
            ),
        ],
            groups: vec![tables::colour_group(&colour)],
        };
    if let Some(c) = manifest::created_utc() {
        t.attrs.push(("created_utc".into(), c.into()));
    }
    for ((e, p), r) in entries.iter().zip(&spectral).zip(&rgb) {
        t.groups
            .push(tables::entry_group(e, entry_attrs(e, p), p, r));
    }
    runner.cancel.check()?;
    output::hdf5::write(&at("profiles.h5")?, &t)?;
    output::bkt::write(&at("profiles.bkt")?, &t)?;
    let names: Vec<String> = entries.iter().map(|e| e.name.clone()).collect();
    let rows: Vec<&[[f64; 3]]> = rgb.iter().map(|r| r.rd_rgb_per_mm2.as_slice()).collect();
    output::exr::write(&at("profiles_rgb.exr")?, &names, bins.edges_mm(), &rows)?;

    // Previews.
    let sheet: Vec<preview::SheetEntry> = entries
        .iter()
        .zip(&rgb)
        .map(|(e, r)| sheet_entry(e, r))
        .collect();
    runner.cancel.check()?;
    let sheets = preview::contact_sheets(&at("preview")?, &sheet)?;
    entries.par_iter().zip(&rgb).try_for_each(|(e, r)| {
        preview::profile_plot(
            &at(&format!("preview/profiles/{}.png", e.name))?,
            &e.name,
            bins.edges_mm(),
            r,
        )
    })?;

    // Manifest.
    let dir = out.expect("a shard has returned").staged.dir();
    let mut files = vec![
        manifest::file_entry(dir, "profiles.h5", "HDF5 tables (formats/FORMAT.md)")?,
        manifest::file_entry(
            dir,
            "profiles.bkt",
            "native zstd tables (formats/FORMAT.md)",
        )?,
        manifest::file_entry(dir, "profiles_rgb.exr", "RGB profiles, one row per entry")?,
        manifest::file_entry(dir, "optics.json", "layer optics of every entry")?,
    ];
    for s in &sheets {
        let rel = format!("preview/{}", s.file_name().unwrap().to_string_lossy());
        files.push(manifest::file_entry(
            dir,
            &rel,
            "contact sheet of skin swatches",
        )?);
    }
    let mut manifest_entries = Vec::new();
    for ((e, p), r) in entries.iter().zip(&spectral).zip(&rgb) {
        let csv = format!("optics/{}.csv", e.name);
        let plot = format!("preview/profiles/{}.png", e.name);
        files.push(manifest::file_entry(dir, &csv, "layer optics table")?);
        files.push(manifest::file_entry(
            dir,
            &plot,
            "RGB profile and fit plot",
        )?);
        manifest_entries.push(serde_json::json!({
            "name": e.name,
            "params": e.inputs,
            "model": e.model,
            "simulation_group": p.group,
            "albedo_rgb": r.albedo_rgb,
            "r99_mm": r.r99_mm.map(|v| if v.is_finite() { Some(v) } else { None }),
            "fit_error_rgb": r.fit.error_rgb,
            "hdf5_group": format!("/{}", e.name),
            "files": [csv, plot],
        }));
    }
    let m = serde_json::json!({
        "format": "baker-manifest",
        "version": 1,
        "spec_file": spec.file,
        "spec_sha256": spec.sha256,
        "baker_version": env!("CARGO_PKG_VERSION"),
        "settings": {
            "photons": photons,
            "seed": settings.seed,
            "gaussians": settings.gaussians,
            "max_photon_boost": settings.max_photon_boost,
            "radial": {
                "dr_min_mm": settings.dr_min_mm,
                "growth": settings.growth,
                "r_max_mm": settings.r_max_mm,
                "bins": bins.len(),
            },
            "absorption_reuse": !a.no_reuse,
            "wavelengths_nm": lam,
        },
        "entries": manifest_entries,
        "files": files,
        "warnings": warnings,
        "units": unit_keys(runner, first_unit),
    });
    runner.cancel.check()?;
    atomic::write(
        &at("manifest.json")?,
        serde_json::to_string_pretty(&m)?.as_bytes(),
    )?;
    super::pipeline::write_stamp(dir, stamp)?;
    if a.human() {
        summary(
            path,
            &shown,
            &entries,
            &spectral,
            &rgb,
            &plan,
            sim_seconds,
            fit_seconds,
            t0,
        );
    }
    Ok(())
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

/// The manifest and stamp of an `--optics-only` bake: the layer optics it wrote.
fn write_skin_manifest_optics_only(
    spec: &SkinSpec,
    entries: &[formats::OpticsEntry],
    out: Option<&Destination>,
    stamp: &str,
) -> anyhow::Result<()> {
    let Some(d) = out else { return Ok(()) };
    let dir = d.staged.dir();
    let mut files = vec![manifest::file_entry(
        dir,
        "optics.json",
        "layer optics of every entry",
    )?];
    for e in entries {
        files.push(manifest::file_entry(
            dir,
            &format!("optics/{}.csv", e.name),
            "layer optics table",
        )?);
    }
    let m = serde_json::json!({
        "format": "baker-manifest",
        "version": 1,
        "kind": "skin",
        "spec_file": spec.file,
        "spec_sha256": spec.sha256,
        "baker_version": env!("CARGO_PKG_VERSION"),
        "settings": {"optics_only": true, "wavelengths_nm": spec.wavelengths.lambda_nm()},
        "entries": entries.iter().map(|e| serde_json::json!({"name": e.name, "params": e.inputs, "model": e.model})).collect::<Vec<_>>(),
        "files": files,
        "units": [],
    });
    atomic::write(
        &d.staged.path("manifest.json")?,
        serde_json::to_string_pretty(&m)?.as_bytes(),
    )?;
    super::pipeline::write_stamp(dir, stamp)
}

fn entry_attrs(e: &formats::OpticsEntry, p: &SpectralProfile) -> Vec<(String, tables::Attr)> {
    let v = &e.inputs;
    let mut attrs: Vec<(String, tables::Attr)> = vec![("params_json".into(), v.to_string().into())];
    for key in ["age_years", "gender", "location", "xi", "model"] {
        match v.get(key) {
            Some(serde_json::Value::String(s)) => attrs.push((key.into(), s.clone().into())),
            Some(x) => {
                if let Some(f) = x.as_f64() {
                    attrs.push((key.into(), f.into()));
                }
            }
            None => {}
        }
    }
    if let Some(t) = v
        .get("melanin")
        .and_then(|m| m.get("skin_type"))
        .and_then(|t| t.as_str())
    {
        attrs.push(("skin_type".into(), t.into()));
    }
    if let Some(f) = e
        .intermediate
        .get("melanosome_fraction")
        .and_then(|f| f.as_f64())
    {
        attrs.push(("melanosome_fraction".into(), f.into()));
    }
    attrs.push(("simulation_group".into(), (p.group as u64).into()));
    attrs
}

fn sheet_entry<'a>(e: &'a formats::OpticsEntry, r: &RgbProfile) -> preview::SheetEntry<'a> {
    let v = &e.inputs;
    let s = |k: &str| {
        v.get(k)
            .map(|x| {
                x.as_str()
                    .map(str::to_string)
                    .unwrap_or_else(|| x.to_string())
            })
            .unwrap_or_default()
    };
    let row = match v.get("melanin") {
        Some(m) if m.get("skin_type").is_some() => {
            format!("type {}", m["skin_type"].as_str().unwrap_or("?"))
        }
        Some(m) => format!(
            "melanin {}",
            m.get("melanosome_fraction")
                .map(|x| x.to_string())
                .unwrap_or_default()
        ),
        None => e.name.clone(),
    };
    let age = v.get("age_years").and_then(|x| x.as_f64()).unwrap_or(0.0);
    let mut sheet = format!("{} {}, xi {}", s("gender"), s("location"), s("xi"));
    if e.model != "five_layer" {
        sheet.push_str(&format!(", {}", e.model));
    }
    preview::SheetEntry {
        sheet,
        row,
        column: (age, format!("age {age}")),
        albedo_rgb: r.albedo_rgb,
        name: &e.name,
    }
}

#[allow(clippy::too_many_arguments)]
fn summary(
    path: &Path,
    dir: &Path,
    entries: &[formats::OpticsEntry],
    spectral: &[SpectralProfile],
    rgb: &[RgbProfile],
    plan: &profile::Plan,
    sim_seconds: f64,
    fit_seconds: f64,
    t0: Instant,
) {
    let n_sims = plan.groups.len() * spectral.first().map_or(0, |p| p.lambda_nm.len());
    let total_photons: f64 = plan
        .groups
        .iter()
        .map(|g| spectral[g[0]].photons.iter().sum::<u64>() as f64)
        .sum();
    eprintln!(
        "baked {}: {} entries, {n_sims} simulations, {:.3e} photons in {sim_seconds:.1} s ({:.0} photons/s), fits {fit_seconds:.1} s → {} ({:.1} s)",
        path.display(),
        entries.len(),
        total_photons,
        total_photons / sim_seconds.max(1e-9),
        dir.display(),
        t0.elapsed().as_secs_f64()
    );
    for c in 0..3 {
        let (k, worst) = rgb
            .iter()
            .enumerate()
            .map(|(k, r)| (k, r.fit.error_rgb[c]))
            .fold((0, 0.0), |a, b| if b.1 > a.1 { b } else { a });
        // Largest relative standard error of the channel's profile out to 2 mm, inside the
        // channel's 99 % radius (beyond it a channel may cross zero: deep-red light is out of
        // the sRGB gamut, so G and B tails are tiny and can be negative).
        let (ks, se) = rgb
            .iter()
            .enumerate()
            .map(|(k, r)| (k, max_relative_se(&spectral[k].r_edges_mm, r, c, 2.0)))
            .fold((0, 0.0), |a, b| if b.1 > a.1 { b } else { a });
        eprintln!(
            "  {}: worst fit error {:.2} % ({}), worst relative SE for r ≤ min(2 mm, r99) {:.2} % ({})",
            ["R", "G", "B"][c],
            100.0 * worst,
            entries[k].name,
            100.0 * se,
            entries[ks].name
        );
    }
}

/// Largest SE/|value| of channel `c` over bins whose centre lies within `r_max_mm` and the
/// channel's 99 % radius.
pub fn max_relative_se(edges_mm: &[f64], r: &RgbProfile, c: usize, r_max_mm: f64) -> f64 {
    let limit = r_max_mm.min(if r.r99_mm[c].is_finite() {
        r.r99_mm[c]
    } else {
        f64::INFINITY
    });
    (0..r.rd_rgb_per_mm2.len())
        .filter(|&i| 0.5 * (edges_mm[i] + edges_mm[i + 1]) <= limit)
        .map(|i| r.rd_rgb_per_mm2_se[i][c] / r.rd_rgb_per_mm2[i][c].abs())
        .fold(0.0f64, f64::max)
}

/// `baker plan`: the work units of one spec (as `baker bake` with the same flags would run
/// them), with whether each is in `cache`.
pub fn plan_units(
    spec: &Spec,
    stem: &str,
    entries: &[String],
    photons: Option<u64>,
    no_reuse: bool,
    cache: &Cache,
) -> anyhow::Result<Vec<crate::pipeline::UnitInfo>> {
    let pick = |name: &str| entries.is_empty() || entries.iter().any(|e| e == name);
    let mut out = Vec::new();
    let spec = match spec {
        Spec::Fiber(spec) => {
            let mut st = spec.bake.clone();
            if let Some(p) = photons {
                st.photons = p;
            }
            let mut index = 0;
            for e in spec.fibers.iter().filter(|e| pick(&e.name)) {
                out.extend(super::bake_fiber::plan_entry(
                    stem, e, &st, cache, &mut index,
                )?);
            }
            return Ok(out);
        }
        Spec::Skin(s) => s,
    };
    let optics = skin_optics(spec, |e| pick(&e.name))?;
    let lam = spec.wavelengths.lambda_nm();
    let s = &spec.profiles;
    let bins = RadialBins::fine_then_log(s.dr_min_mm, s.growth, s.r_max_mm);
    let plan = profile::plan(&optics, lam.len(), !no_reuse);
    let sim = SimOptions {
        photons: photons.unwrap_or(s.photons),
        seed: s.seed,
        threads: None,
        max_boost: s.max_photon_boost,
        bar: None,
    };
    let units = profile::skin_units(&optics, lam, &bins, &plan, &sim);
    let prefix = format!("{stem}/skin");
    let nl = lam.len();
    for g in 0..plan.groups.len() {
        for (i, l) in lam.iter().enumerate() {
            if let Some(k) = units.pilot.get(g).and_then(|p| p.get(i)) {
                out.push(crate::pipeline::UnitInfo {
                    id: profile::simulate::unit_id(&prefix, "pilot/", g, *l),
                    key: k.hex(),
                    index: None,
                    photons: units.pilot_photons,
                    cached: cache.path(k).exists(),
                });
            }
        }
        for (i, l) in lam.iter().enumerate() {
            let k = &units.run[g][i];
            out.push(crate::pipeline::UnitInfo {
                id: profile::simulate::unit_id(&prefix, "", g, *l),
                key: k.hex(),
                index: Some(g * nl + i),
                photons: sim.photons,
                cached: cache.path(k).exists(),
            });
        }
    }
    Ok(out)
}
