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

use super::{load_spec, UsageError};
use crate::output::{self, atomic, manifest, preview, tables};
use crate::pipeline::{interrupt, Cache, CacheMode, Events, ProgressMode, Runner, Shard};
use crate::profile::{self, RgbProfile, SimOptions, SpectralProfile};
use crate::spec::SkinSpec;
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
        r
    }
}

pub fn run(a: BakeArgs) -> anyhow::Result<()> {
    if a.photons == Some(0) {
        return Err(UsageError("--photons must be at least 1".into()).into());
    }
    // Validate every spec (and the entry selection) before writing anything.
    let specs = a
        .specs
        .iter()
        .map(|p| {
            let text = std::fs::read_to_string(p).unwrap_or_default();
            if crate::spec::fiber::is_fiber_spec(&text) {
                crate::spec::fiber::load(p)
                    .map(Loaded::Fiber)
                    .map_err(|e| UsageError(e.to_string().trim_end().to_string()).into())
            } else {
                load_spec(p).map(Loaded::Skin)
            }
        })
        .collect::<anyhow::Result<Vec<_>>>()?;
    if !a.entries.is_empty() {
        // With several specs an entry may live in any of them; each name must exist somewhere.
        let names: Vec<(String, String)> = specs
            .iter()
            .flat_map(|s| match s {
                Loaded::Skin(s) => s
                    .entries
                    .iter()
                    .map(|e| (s.file.clone(), e.name.clone()))
                    .collect::<Vec<_>>(),
                Loaded::Fiber(s) => s
                    .fibers
                    .iter()
                    .map(|e| (s.file.clone(), e.name.clone()))
                    .collect(),
            })
            .collect();
        for name in &a.entries {
            if !names.iter().any(|(_, n)| n == name) {
                let all: Vec<&str> = names.iter().map(|(_, n)| n.as_str()).collect();
                return Err(UsageError(format!(
                    "{}: no entry named {name:?}; entries: {}",
                    a.specs
                        .iter()
                        .map(|p| p.display().to_string())
                        .collect::<Vec<_>>()
                        .join(", "),
                    all.join(", ")
                ))
                .into());
            }
        }
    }
    let pool = rayon::ThreadPoolBuilder::new()
        .num_threads(a.threads.unwrap_or(0))
        .build()?;
    interrupt::install();
    interrupt::set_silent(!a.human());
    let runner = a.runner();
    let t0 = Instant::now();
    let mut stems = Vec::new();
    let result = (|| -> anyhow::Result<()> {
        for (path, spec) in a.specs.iter().zip(&specs) {
            stems.push(spec_stem(path));
            match spec {
                Loaded::Skin(s) => {
                    let has = a.entries.is_empty()
                        || s.entries.iter().any(|e| a.entries.contains(&e.name));
                    if has {
                        pool.install(|| bake_spec(&a, path, s, &runner))?
                    }
                }
                Loaded::Fiber(s) => {
                    let has = a.entries.is_empty()
                        || s.fibers.iter().any(|e| a.entries.contains(&e.name));
                    if has {
                        pool.install(|| super::bake_fiber::bake_fiber_spec(&a, path, s, &runner))?
                    }
                }
            }
        }
        Ok(())
    })();
    super::pipeline::finish(&a, &runner, &stems, t0, result)
}

/// The output directory name of a spec: its file stem.
pub fn spec_stem(path: &Path) -> String {
    path.file_stem()
        .map(|s| s.to_string_lossy().to_string())
        .unwrap_or_else(|| "spec".into())
}

/// A spec of either kind.
enum Loaded {
    Skin(SkinSpec),
    Fiber(crate::spec::fiber::FiberSpec),
}

fn say(a: &BakeArgs, msg: impl AsRef<str>) {
    if a.human() {
        eprintln!("{}", msg.as_ref());
    }
}

fn bake_spec(a: &BakeArgs, path: &Path, spec: &SkinSpec, runner: &Runner) -> anyhow::Result<()> {
    let t0 = Instant::now();
    let stem = spec_stem(path);
    let dir = a.out.join(&stem);
    // Unchanged spec, flags and executable, outputs intact: nothing to do.
    let stamp = super::pipeline::stamp(a, path)?;
    if a.shard.is_none() && !a.force && super::pipeline::up_to_date(&dir, &stamp) {
        runner
            .events
            .emit(serde_json::json!({"event": "up_to_date", "spec": path}));
        say(
            a,
            format!("{}: up to date ({})", path.display(), dir.display()),
        );
        return Ok(());
    }
    let _ = std::fs::remove_file(dir.join(super::pipeline::STAMP_FILE));
    runner
        .events
        .emit(serde_json::json!({"event": "bake_started", "spec": path,
        "kind": "skin", "entries": spec.entries.iter()
            .filter(|e| a.entries.is_empty() || a.entries.contains(&e.name)).count()}));
    let selected: Vec<&crate::spec::ResolvedEntry> = spec
        .entries
        .iter()
        .filter(|e| a.entries.is_empty() || a.entries.contains(&e.name))
        .collect();
    let entries = selected
        .iter()
        .map(|e| {
            let o = crate::skin::evaluate(&e.params, &spec.wavelengths).map_err(|err| {
                UsageError(format!("{}:{}: entry {}: {err}", spec.file, e.line, e.name))
            })?;
            Ok(output::document::entry(e, &o))
        })
        .collect::<anyhow::Result<Vec<_>>>()?;
    let lam = spec.wavelengths.lambda_nm();
    // A shard only computes work units; `baker merge` writes every product.
    let sharded = a.shard.is_some();
    for e in entries.iter().filter(|_| !sharded) {
        let p = dir.join("optics").join(format!("{}.csv", e.name));
        atomic::write(&p, output::csv::entry_csv(lam, e).as_bytes())
            .with_context(|| format!("writing {}", p.display()))?;
    }
    if a.plots && !sharded {
        super::optics::write_plots(&dir.join("plots"), lam, &entries)?;
    }
    let doc = output::document::document(&spec.file, lam, entries.clone());
    let p = dir.join("optics.json");
    if !sharded {
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
                dir.display(),
                t0.elapsed().as_secs_f64()
            ),
        );
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
                    Ok(profile::rgb_profile(p, &colour, settings.gaussians))
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
            ("spec_sha256".into(), manifest::spec_sha256(&spec.file).into()),
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
    output::hdf5::write(&dir.join("profiles.h5"), &t)?;
    output::bkt::write(&dir.join("profiles.bkt"), &t)?;
    let names: Vec<String> = entries.iter().map(|e| e.name.clone()).collect();
    let rows: Vec<&[[f64; 3]]> = rgb.iter().map(|r| r.rd_rgb_per_mm2.as_slice()).collect();
    output::exr::write(
        &dir.join("profiles_rgb.exr"),
        &names,
        bins.edges_mm(),
        &rows,
    )?;

    // Previews.
    let sheet: Vec<preview::SheetEntry> = entries
        .iter()
        .zip(&rgb)
        .map(|(e, r)| sheet_entry(e, r))
        .collect();
    let sheets = preview::contact_sheets(&dir.join("preview"), &sheet)?;
    entries.par_iter().zip(&rgb).try_for_each(|(e, r)| {
        preview::profile_plot(
            &dir.join("preview/profiles").join(format!("{}.png", e.name)),
            &e.name,
            bins.edges_mm(),
            r,
        )
    })?;

    // Manifest.
    let mut files = vec![
        manifest::file_entry(&dir, "profiles.h5", "HDF5 tables (formats/FORMAT.md)")?,
        manifest::file_entry(
            &dir,
            "profiles.bkt",
            "native zstd tables (formats/FORMAT.md)",
        )?,
        manifest::file_entry(&dir, "profiles_rgb.exr", "RGB profiles, one row per entry")?,
        manifest::file_entry(&dir, "optics.json", "layer optics of every entry")?,
    ];
    for s in &sheets {
        let rel = format!("preview/{}", s.file_name().unwrap().to_string_lossy());
        files.push(manifest::file_entry(
            &dir,
            &rel,
            "contact sheet of skin swatches",
        )?);
    }
    let mut manifest_entries = Vec::new();
    for ((e, p), r) in entries.iter().zip(&spectral).zip(&rgb) {
        let csv = format!("optics/{}.csv", e.name);
        let plot = format!("preview/profiles/{}.png", e.name);
        files.push(manifest::file_entry(&dir, &csv, "layer optics table")?);
        files.push(manifest::file_entry(
            &dir,
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
        "spec_sha256": manifest::spec_sha256(&spec.file),
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
    });
    atomic::write(
        &dir.join("manifest.json"),
        serde_json::to_string_pretty(&m)?.as_bytes(),
    )?;

    super::pipeline::write_stamp(&dir, &stamp)?;
    if a.human() {
        summary(
            path,
            &dir,
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
    path: &Path,
    entries: &[String],
    photons: Option<u64>,
    no_reuse: bool,
    cache: &Cache,
) -> anyhow::Result<Vec<crate::pipeline::UnitInfo>> {
    let stem = spec_stem(path);
    let text = std::fs::read_to_string(path).unwrap_or_default();
    let pick = |name: &str| entries.is_empty() || entries.iter().any(|e| e == name);
    let mut out = Vec::new();
    if crate::spec::fiber::is_fiber_spec(&text) {
        let spec = crate::spec::fiber::load(path)
            .map_err(|e| UsageError(e.to_string().trim_end().to_string()))?;
        let mut st = spec.bake.clone();
        if let Some(p) = photons {
            st.photons = p;
        }
        let mut index = 0;
        for e in spec.fibers.iter().filter(|e| pick(&e.name)) {
            out.extend(super::bake_fiber::plan_entry(
                &spec, &stem, e, &st, cache, &mut index,
            )?);
        }
        return Ok(out);
    }
    let spec = load_spec(path)?;
    let optics = spec
        .entries
        .iter()
        .filter(|e| pick(&e.name))
        .map(|e| {
            let o = crate::skin::evaluate(&e.params, &spec.wavelengths).map_err(|err| {
                UsageError(format!("{}:{}: entry {}: {err}", spec.file, e.line, e.name))
            })?;
            Ok(output::document::entry(e, &o))
        })
        .collect::<anyhow::Result<Vec<_>>>()?;
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
