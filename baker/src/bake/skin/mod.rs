//! The bake of a skin spec (thesis ch. 3): layer optics, Monte Carlo diffusion profiles, their
//! RGB and sum-of-Gaussians fits, tables, previews and the manifest.
//!
//! Into `OUT/<spec stem>/`: `optics.json` and `optics/<entry>.csv` (layer optics),
//! `profiles.h5` and `profiles.bkt` (spectral and RGB diffusion profiles, Gaussian fits, layer
//! optics, surface and input parameters; layout in formats/FORMAT.md), `profiles_rgb.exr`,
//! `preview/` PNGs, `manifest.json` (entries, files, SHA-256) and `timing.json`.

mod preview;
mod summary;
pub mod tables;

use std::time::Instant;

use anyhow::Context;
use rayon::prelude::*;

use super::manifest::{self, Kind, Manifest, Timing};
use crate::bake::job::Job;
use crate::output::{self, atomic, manifest::file_entry};
use crate::pipeline::PhaseSpec;
use crate::profile::{self, RgbProfile, SimOptions, SpectralProfile};
use crate::spec::{ResolvedEntry, SkinSpec};
use crate::spectral::ColourMap;
use crate::transport::RadialBins;

pub use summary::max_relative_se;

/// The layer optics of the entries of `spec` that `pick` selects (evaluated by the resolver).
pub fn optics_of(
    spec: &SkinSpec,
    pick: impl Fn(&ResolvedEntry) -> bool,
) -> Vec<formats::OpticsEntry> {
    spec.entries
        .iter()
        .zip(&spec.optics)
        .filter(|(e, _)| pick(e))
        .map(|(_, o)| o.clone())
        .collect()
}

/// What the profile phase produced.
struct Profiles {
    bins: RadialBins,
    colour: ColourMap,
    plan: profile::GroupPlan,
    spectral: Vec<SpectralProfile>,
    rgb: Vec<RgbProfile>,
    sim_seconds: f64,
    fit_seconds: f64,
}

/// Bakes a skin spec into the job's destination (`None` for a shard: units only).
pub fn bake(job: &Job, spec: &SkinSpec) -> anyhow::Result<()> {
    let t0 = Instant::now();
    let a = job.req;
    job.runner.events.emit(
        serde_json::json!({"event": "bake_started", "spec": job.path,
        "kind": "skin", "entries": spec.entries.iter().filter(|e| a.selects(&e.name)).count()}),
    );
    let entries = optics_of(spec, |e| a.selects(&e.name));
    let lam = spec.wavelengths.lambda_nm();
    if job.out.is_some() {
        write_optics(job, &spec.file, lam, &entries)?;
    }
    let optics_seconds = t0.elapsed().as_secs_f64();
    if a.optics_only {
        job.runner.events.say(format!(
            "baked {} (optics only): {} entries × {} wavelengths → {} ({:.2} s)",
            job.path.display(),
            entries.len(),
            lam.len(),
            job.shown().display(),
            t0.elapsed().as_secs_f64()
        ));
        return write_manifest_optics_only(job, spec, &entries, (t0, optics_seconds));
    }
    // A shard only computes work units; `baker merge` writes every product.
    let Some(p) = profiles(job, spec, &entries)? else {
        return Ok(());
    };
    let warnings = r99_warnings(&entries, &p.rgb, &p.bins);
    for w in &warnings {
        job.runner.events.warn(w);
    }
    let clock = Clock {
        t0,
        optics_seconds,
        writing: Instant::now(),
    };
    write_tables(job, spec, &entries, &p)?;
    let previews = preview::write(job, &entries, &p.rgb, &p.bins)?;
    write_manifest(job, spec, &entries, &p, (previews, warnings), clock)?;
    if job.runner.events.human() {
        summary::print(
            job,
            &entries,
            &p.spectral,
            &p.rgb,
            &p.plan,
            t0,
            (p.sim_seconds, p.fit_seconds),
        );
    }
    Ok(())
}

/// `optics/<entry>.csv`, the plots with `--plots`, and `optics.json`.
fn write_optics(
    job: &Job,
    spec_file: &str,
    lam: &[f64],
    entries: &[formats::OpticsEntry],
) -> anyhow::Result<()> {
    for e in entries {
        let p = job.at(&format!("optics/{}.csv", e.name))?;
        atomic::write(&p, output::csv::entry_csv(lam, e).as_bytes())
            .with_context(|| format!("writing {}", p.display()))?;
    }
    if job.req.plots {
        let dir = job.at("plots")?;
        for p in output::plot::optics_plots(&dir, lam, entries)? {
            job.runner.events.say(format!("wrote {}", p.display()));
        }
    }
    let doc = crate::skin::document::document(spec_file, lam, entries.to_vec());
    let p = job.at("optics.json")?;
    atomic::write(&p, serde_json::to_string_pretty(&doc)?.as_bytes())
        .with_context(|| format!("writing {}", p.display()))
}

/// Simulates (or takes from the cache) every profile unit and fits each entry's RGB
/// profile; `None` for a shard.
fn profiles(
    job: &Job,
    spec: &SkinSpec,
    entries: &[formats::OpticsEntry],
) -> anyhow::Result<Option<Profiles>> {
    let (a, runner) = (job.req, job.runner);
    let lam = spec.wavelengths.lambda_nm();
    let settings = &spec.profiles;
    let photons = a.photons.unwrap_or(settings.photons);
    let bins = RadialBins::fine_then_log(settings.dr_min_mm, settings.growth, settings.r_max_mm);
    let plan = profile::plan(entries, lam.len(), !a.no_reuse);
    let n_sims = plan.groups.len() * lam.len();
    let packets = if settings.noise_target > 0.0 {
        format!(
            "packets per wavelength for ≤ {} % noise against {photons} everywhere",
            settings.noise_target * 100.0
        )
    } else {
        format!("{photons} photons")
    };
    runner.events.say(format!(
        "{}: {} entries in {} simulation groups × {} wavelengths = {n_sims} simulations of {packets}",
        job.path.display(),
        entries.len(),
        plan.groups.len(),
        lam.len()
    ));
    let phase = runner.begin_phase(PhaseSpec {
        name: "simulation".into(),
        label: "simulation".into(),
        units: n_sims as u64,
        photons_per_unit: photons,
        photons_per_item: Some(1),
        item: "photons".into(),
    });
    let sim = SimOptions {
        photons,
        seed: settings.seed,
        threads: a.threads,
        max_boost: settings.max_photon_boost,
        noise: profile::NoiseTarget::new(settings.noise_target, photons),
        progress: Some(phase as std::sync::Arc<dyn crate::progress::Progress>),
    };
    let t_sim = Instant::now();
    let prefix = format!("{}/skin", job.stem);
    let spectral = profile::simulate_units(
        &profile::SkinSimulation {
            entries,
            lambda_nm: lam,
            bins: &bins,
            plan: &plan,
            o: &sim,
        },
        runner,
        &prefix,
        |_, _, _| {},
    );
    runner.end_phase();
    let spectral = spectral?;
    let Some(spectral) = spectral.filter(|_| job.out.is_some()) else {
        // A shard: its units are cached; `baker merge` assembles.
        return Ok(None);
    };
    let sim_seconds = t_sim.elapsed().as_secs_f64();
    let t_fit = Instant::now();
    let colour = ColourMap::new(lam);
    let rgb = fits(job, spec, entries, &spectral, &colour)?;
    Ok(Some(Profiles {
        bins,
        colour,
        plan,
        spectral,
        rgb,
        sim_seconds,
        fit_seconds: t_fit.elapsed().as_secs_f64(),
    }))
}

/// The RGB profiles and their Gaussian fits. The fits are units too (minutes for a large
/// database): keyed by the spectral profile.
fn fits(
    job: &Job,
    spec: &SkinSpec,
    entries: &[formats::OpticsEntry],
    spectral: &[SpectralProfile],
    colour: &ColourMap,
) -> anyhow::Result<Vec<RgbProfile>> {
    let runner = job.runner;
    let gaussians = spec.profiles.gaussians;
    runner.begin_phase(PhaseSpec {
        name: "fitting".into(),
        label: "fitting".into(),
        units: entries.len() as u64,
        photons_per_unit: 0,
        photons_per_item: None,
        item: "profiles".into(),
    });
    let r = spectral
        .par_iter()
        .zip(entries)
        .map(|(p, e)| {
            let key = fit_key(p, gaussians);
            let id = fit_id(job.stem, &e.name);
            runner
                .unit(&id, key, None, 0, || {
                    Ok(profile::rgb_profile(p, colour, gaussians, runner.cancel)?)
                })
                .map_err(anyhow::Error::from)
                .map(|r| r.expect("fit units are never sharded"))
        })
        .collect();
    runner.end_phase();
    r
}

/// The key of the Gaussian fit of spectral profile `p` with `gaussians` Gaussians.
pub fn fit_key(p: &SpectralProfile, gaussians: usize) -> crate::pipeline::Key {
    crate::pipeline::KeyBuilder::new("skin-fit", crate::data::checksum())
        .part("profile", p)
        .part("gaussians", &gaussians)
        .finish()
}

/// The id of entry `name`'s fit unit: `<spec>/fit/<entry>`.
pub fn fit_id(stem: &str, name: &str) -> String {
    format!("{stem}/fit/{name}")
}

/// A warning per entry and channel whose profile holds less than 99 % of its energy within
/// the radial grid.
fn r99_warnings(
    entries: &[formats::OpticsEntry],
    rgb: &[RgbProfile],
    bins: &RadialBins,
) -> Vec<String> {
    let mut warnings = Vec::new();
    for (e, r) in entries.iter().zip(rgb) {
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
    warnings
}

/// `profiles.h5`, `profiles.bkt` and `profiles_rgb.exr`.
fn write_tables(
    job: &Job,
    spec: &SkinSpec,
    entries: &[formats::OpticsEntry],
    p: &Profiles,
) -> anyhow::Result<()> {
    let t = tables::tables(spec, job.req, entries, &p.spectral, &p.rgb, &p.colour)?;
    job.runner.cancel.check()?;
    output::hdf5::write(&job.at("profiles.h5")?, &t)?;
    output::bkt::write(&job.at("profiles.bkt")?, &t)?;
    let names: Vec<String> = entries.iter().map(|e| e.name.clone()).collect();
    let rows: Vec<&[[f64; 3]]> = p.rgb.iter().map(|r| r.rd_rgb_per_mm2.as_slice()).collect();
    output::exr::write(
        &job.at("profiles_rgb.exr")?,
        &names,
        p.bins.edges_mm(),
        &rows,
    )
}

/// When a profile bake started, how long its optics took and when it started writing its
/// tables.
struct Clock {
    t0: Instant,
    optics_seconds: f64,
    writing: Instant,
}

/// Total photon packets of the profiles of `p` (one count per simulation group), cached or
/// traced.
fn total_photons(p: &Profiles) -> u64 {
    p.plan
        .groups
        .iter()
        .map(|g| p.spectral[g[0]].photons.iter().sum::<u64>())
        .sum()
}

/// The manifest of a profile bake (its previews and warnings), and its timing.
fn write_manifest(
    job: &Job,
    spec: &SkinSpec,
    entries: &[formats::OpticsEntry],
    p: &Profiles,
    (previews, warnings): (Vec<String>, Vec<String>),
    clock: Clock,
) -> anyhow::Result<()> {
    let dir = job.out.expect("a shard has returned").staged.dir();
    let mut files = vec![
        file_entry(dir, "profiles.h5", "HDF5 tables (formats/FORMAT.md)")?,
        file_entry(
            dir,
            "profiles.bkt",
            "native zstd tables (formats/FORMAT.md)",
        )?,
        file_entry(dir, "profiles_rgb.exr", "RGB profiles, one row per entry")?,
        file_entry(dir, "optics.json", "layer optics of every entry")?,
    ];
    for rel in &previews {
        files.push(file_entry(dir, rel, "contact sheet of skin swatches")?);
    }
    let mut manifest_entries = Vec::new();
    for ((e, sp), r) in entries.iter().zip(&p.spectral).zip(&p.rgb) {
        let csv = format!("optics/{}.csv", e.name);
        let plot = format!("preview/profiles/{}.png", e.name);
        files.push(file_entry(dir, &csv, "layer optics table")?);
        files.push(file_entry(dir, &plot, "RGB profile and fit plot")?);
        manifest_entries.push(serde_json::json!({
            "name": e.name,
            "params": e.inputs,
            "model": e.model,
            "simulation_group": sp.group,
            "albedo_rgb": r.albedo_rgb,
            "r99_mm": r.r99_mm.map(|v| if v.is_finite() { Some(v) } else { None }),
            "fit_error_rgb": r.fit.error_rgb,
            "hdf5_group": format!("/{}", e.name),
            "files": [csv, plot],
        }));
    }
    let s = &spec.profiles;
    let settings = serde_json::json!({
        "photons": job.req.photons.unwrap_or(s.photons),
        "seed": s.seed,
        "gaussians": s.gaussians,
        "max_photon_boost": s.max_photon_boost,
        "noise_target": s.noise_target,
        "radial": {
            "dr_min_mm": s.dr_min_mm,
            "growth": s.growth,
            "r_max_mm": s.r_max_mm,
            "bins": p.bins.len(),
        },
        "absorption_reuse": !job.req.no_reuse,
        "wavelengths_nm": spec.wavelengths.lambda_nm(),
    });
    let m = Manifest {
        kind: Kind::Skin,
        spec_file: spec.file.clone(),
        spec_sha256: spec.sha256.clone(),
        settings,
        entries: manifest_entries.into(),
        files,
        warnings,
    };
    let t = Timing {
        seconds: clock.t0.elapsed().as_secs_f64(),
        phases: vec![
            ("optics", clock.optics_seconds),
            ("transport", p.sim_seconds),
            ("fits", p.fit_seconds),
            ("writing", clock.writing.elapsed().as_secs_f64()),
        ],
        threads: job.req.thread_count(),
        photons: total_photons(p),
        entries: vec![],
    };
    manifest::write(job, m, t)
}

/// The manifest of an `--optics-only` bake: the layer optics it wrote.
fn write_manifest_optics_only(
    job: &Job,
    spec: &SkinSpec,
    entries: &[formats::OpticsEntry],
    (t0, optics_seconds): (Instant, f64),
) -> anyhow::Result<()> {
    let Some(d) = job.out else { return Ok(()) };
    let dir = d.staged.dir();
    let mut files = vec![file_entry(
        dir,
        "optics.json",
        "layer optics of every entry",
    )?];
    for e in entries {
        files.push(file_entry(
            dir,
            &format!("optics/{}.csv", e.name),
            "layer optics table",
        )?);
    }
    let m = Manifest {
        kind: Kind::Skin,
        spec_file: spec.file.clone(),
        spec_sha256: spec.sha256.clone(),
        settings: serde_json::json!({"optics_only": true,
            "wavelengths_nm": spec.wavelengths.lambda_nm()}),
        entries: entries
            .iter()
            .map(|e| serde_json::json!({"name": e.name, "params": e.inputs, "model": e.model}))
            .collect::<Vec<_>>()
            .into(),
        files,
        warnings: vec![],
    };
    let t = Timing {
        seconds: t0.elapsed().as_secs_f64(),
        phases: vec![("optics", optics_seconds)],
        threads: job.req.thread_count(),
        photons: 0,
        entries: vec![],
    };
    manifest::write(job, m, t)
}
