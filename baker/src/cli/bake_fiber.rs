//! `baker bake` for fiber specs: every entry's 4D BCSDF tables (thesis §5.3.2, §5.5).
//!
//! Into `OUT/<spec stem>/`:
//! - `<entry>/section-NN.bcsdf`, one per seeded cross-section, and `<entry>/average.bcsdf`
//!   (projected-area weighted average, Fig. 64) when there are several: the streaming tables
//!   (layout in formats/FORMAT.md and `formats::bcsdf`);
//! - `<entry>/<entry>.h5`: the same numbers, one group per table, chunked per incoming
//!   direction, shuffle + deflate, axes as dimension scales, plus the sampling CDFs;
//! - `preview/<entry>.png` (false-colour log slices, θi ∈ {0°, −45°, −80°} × fiber rotations
//!   φi ∈ {0°, 30°, 60°, 90°}) and `preview/<entry>.exr` (linear RGB f in sr⁻¹, same grid);
//! - `manifest.json`: settings, symmetry, timing, noise, sizes and SHA-256 of every file.

use std::io::IsTerminal;
use std::path::{Path, PathBuf};
use std::time::Instant;

use anyhow::Context;
use hdf5_metno as h5;
use ndarray::{s, ArrayView3, ArrayView4, ArrayView5};
use rayon::prelude::*;
use serde::Serialize;

use super::bake::{BakeArgs, Destination};
use crate::fiber::bake::{
    self, incident_of_bin, name_hash, task_seed, unit_len, BakeSettings, Noise,
};
use crate::fiber::sweep::{Channels, Variant};
use crate::fiber::symmetry::Symmetry;
use crate::fiber::{AngularGrid, Fiber};
use crate::files::Shown;
use crate::output::paths::Staged;
use crate::output::{atomic, exr, hdf5 as h5out, manifest, slice};
use crate::pipeline::{KeyBuilder, Runner};
use crate::spec::fiber::{FiberEntry, FiberSpec};
use crate::spectral::ColourMap;
use formats::bcsdf::{self, Bcsdf, Directory, Writer, KIND};

/// What one entry's bake measured (written to the manifest).
#[derive(Debug, Serialize)]
pub struct EntryReport {
    pub name: String,
    pub fiber_type: &'static str,
    pub sections: u64,
    pub symmetry: String,
    pub stored_directions: usize,
    pub full_directions: usize,
    pub photons_per_direction: u64,
    pub split: u32,
    pub variants: Vec<String>,
    pub channels: Vec<String>,
    /// Wall-clock figures: in `timing.json`, not the (reproducible) manifest.
    #[serde(skip)]
    pub seconds: f64,
    #[serde(skip)]
    pub photons_per_s: f64,
    /// Mean over stored directions of each slice's median / 90th-percentile per-bin relative
    /// standard error (section 0).
    pub noise: Noise,
    /// Largest |Λ − 1|/SE over directions for undyed variants (0 when none is undyed).
    pub albedo_min: f64,
    pub albedo_max: f64,
    pub bcsdf_bytes: u64,
    pub hdf5_bytes: u64,
}

/// Bakes every selected entry of a fiber spec into `out` (`None` for a shard: units only),
/// recording `stamp`.
pub fn bake_fiber_spec(
    a: &BakeArgs,
    path: &Path,
    spec: &FiberSpec,
    runner: &Runner,
    out: Option<&Destination>,
    stamp: &str,
) -> anyhow::Result<()> {
    let t0 = Instant::now();
    let stem = super::bake::spec_stem(path)?;
    let first_unit = runner.used.lock().unwrap().len();
    runner
        .events
        .emit(serde_json::json!({"event": "bake_started", "spec": path,
        "kind": "fiber", "entries": spec.fibers.iter()
            .filter(|e| a.entries.is_empty() || a.entries.contains(&e.name)).count()}));
    let mut settings = spec.bake.clone();
    if let Some(p) = a.photons {
        settings.photons = p;
    }
    let mut reports = Vec::new();
    let mut files = Vec::new();
    let mut timing = Vec::new();
    // Work units are numbered across the spec's entries (sharding uses the number).
    let mut unit_index = 0usize;
    for e in spec
        .fibers
        .iter()
        .filter(|e| a.entries.is_empty() || a.entries.contains(&e.name))
    {
        let ctx = UnitCtx {
            runner,
            prefix: format!("{stem}/{}", e.name),
        };
        if let Some((r, f)) = bake_entry(a, out, spec, e, &settings, &ctx, &mut unit_index)? {
            timing.push(serde_json::json!({"entry": r.name, "seconds": r.seconds,
                "photons_per_s": r.photons_per_s}));
            reports.push(r);
            files.extend(f);
        }
    }
    let Some(d) = out else {
        return Ok(());
    };
    let dir = d.staged.dir();
    let mut mfiles = Vec::new();
    for (rel, desc) in &files {
        mfiles.push(manifest::file_entry(dir, rel, desc)?);
    }
    let doc = serde_json::json!({
        "kind": "baker-fiber-bake",
        "spec": spec.file,
        "spec_sha256": spec.sha256,
        "settings": settings,
        "entries": reports,
        "files": mfiles,
        "units": super::bake::unit_keys(runner, first_unit),
    });
    runner.cancel.check()?;
    let p = d.staged.path("manifest.json")?;
    atomic::write(&p, serde_json::to_string_pretty(&doc)?.as_bytes())
        .with_context(|| format!("writing {}", p.display()))?;
    // Wall-clock figures change from run to run (and a cached unit costs nothing): they live
    // apart from the manifest, which is byte-identical for the same spec and flags.
    let p = d.staged.path("timing.json")?;
    let doc = serde_json::json!({"seconds": t0.elapsed().as_secs_f64(), "entries": timing,
        "note": "this run's wall-clock time; units taken from the cache cost nothing"});
    atomic::write(&p, serde_json::to_string_pretty(&doc)?.as_bytes())
        .with_context(|| format!("writing {}", p.display()))?;
    super::pipeline::write_stamp(dir, stamp)?;
    if a.human() {
        eprintln!(
            "baked {}: {} fibers → {} ({:.1} s)",
            path.display(),
            reports.len(),
            Shown(d.staged.target()),
            t0.elapsed().as_secs_f64()
        );
    }
    Ok(())
}

/// The variants of an entry as μa spectra.
pub fn variants_of(e: &FiberEntry, lambda_nm: &[f64]) -> Vec<Variant> {
    e.variants
        .iter()
        .map(|v| Variant {
            name: FiberEntry::variant_name(v.as_ref()),
            mua_per_um: lambda_nm
                .iter()
                .map(|&l| e.variant_mua_per_um(v.as_ref(), l))
                .collect(),
        })
        .collect()
}

/// Typical longest path worth tabulating: 16 bounding diameters.
pub fn typical_path_um(f: &Fiber) -> f64 {
    let s = f.cuticle_slope().map_or(1.0, |c| c.1);
    32.0 * f.section.bound_radius_um() * s
}

/// One table being written: streaming file and HDF5 group.
struct TableOut {
    name: String,
    writer: Writer,
    f: h5::Dataset,
    cdf_theta: h5::Dataset,
    cdf_phi: h5::Dataset,
    albedo: Vec<f32>,
    albedo_se: Vec<f32>,
    group: h5::Group,
}

/// What an entry's units are made of: the grid, the sections, the stored directions, the
/// channels, and the digest of everything a unit's result depends on besides its directions
/// (pipeline::KeyBuilder).
pub struct EntrySetup {
    pub grid: AngularGrid,
    pub fibers: Vec<Fiber>,
    pub sym: Symmetry,
    pub stored: Vec<usize>,
    pub map: Vec<u32>,
    pub variants: Vec<Variant>,
    pub channels: Channels,
    pub seed_base: u64,
    pub key_base: [u8; 32],
}

/// The setup of entry `e` from what the resolver built (its sections and symmetries).
pub fn entry_setup(e: &FiberEntry, st: &BakeSettings) -> anyhow::Result<EntrySetup> {
    let grid = AngularGrid::new(st.res_deg).map_err(anyhow::Error::msg)?;
    let fibers: Vec<Fiber> = e
        .population
        .iter()
        .map(|s| e.fiber_with(s.clone()))
        .collect();
    let sym = e.symmetries;
    let (stored, map) = sym.wi_map(grid.n_theta, grid.n_phi, st.res_deg);
    let variants = variants_of(e, &st.lambda_nm);
    let channels = Channels::new(
        &variants,
        &st.lambda_nm,
        st.channels,
        typical_path_um(&fibers[0]),
    );
    let seed_base = name_hash(&e.name);
    let key_base =
        crate::pipeline::digest_of(&(&fibers, &channels, st, seed_base, grid.n_theta, grid.n_phi));
    Ok(EntrySetup {
        grid,
        fibers,
        sym,
        stored,
        map,
        variants,
        channels,
        seed_base,
        key_base,
    })
}

/// `baker plan`: the entry's units, numbered from `*unit_index`.
pub fn plan_entry(
    stem: &str,
    e: &FiberEntry,
    st: &BakeSettings,
    cache: &crate::pipeline::Cache,
    unit_index: &mut usize,
) -> anyhow::Result<Vec<crate::pipeline::UnitInfo>> {
    let setup = entry_setup(e, st)?;
    let n_wi = setup.stored.len();
    let all: Vec<usize> = (0..n_wi).collect();
    let mut out = Vec::new();
    for chunk in all.chunks(unit_len(n_wi)) {
        let prefix = format!("{stem}/{}", e.name);
        let (id, key) = unit_id_key(&prefix, chunk, &setup.stored, &setup.key_base);
        out.push(crate::pipeline::UnitInfo {
            id,
            key: key.hex(),
            index: Some(*unit_index),
            photons: (chunk.len() * setup.fibers.len()) as u64 * st.photons,
            cached: cache.path(&key).exists(),
        });
        *unit_index += 1;
    }
    Ok(out)
}

/// An entry's report and its files (path relative to the spec's output, description).
type EntryOutputs = (EntryReport, Vec<(String, String)>);

/// What an entry bake needs to run its work units.
struct UnitCtx<'a> {
    runner: &'a Runner,
    prefix: String,
}

/// Id (`<spec>/<entry>/wi<first>-<last>`) and key of the unit of stored directions `chunk`.
fn unit_id_key(
    prefix: &str,
    chunk: &[usize],
    stored: &[usize],
    key_base: &[u8; 32],
) -> (String, crate::pipeline::Key) {
    let bins: Vec<usize> = chunk.iter().map(|&i| stored[i]).collect();
    let key = KeyBuilder::new("fiber-slices")
        .digest("entry", key_base)
        .part("bins", &bins)
        .finish();
    let id = format!("{prefix}/wi{}-{}", chunk[0], chunk[chunk.len() - 1]);
    (id, key)
}

/// The results of one unit (stored directions `chunk`, every section), from the cache or
/// traced; `None` if another shard owns it.
#[allow(clippy::too_many_arguments)]
fn unit_results(
    ctx: &UnitCtx,
    index: usize,
    chunk: &[usize],
    stored: &[usize],
    key_base: &[u8; 32],
    fibers: &[Fiber],
    grid: &AngularGrid,
    channels: &Channels,
    st: &BakeSettings,
    seed_base: u64,
    bar: Option<&indicatif::ProgressBar>,
) -> anyhow::Result<Option<Vec<Vec<bake::SliceResult>>>> {
    let (id, key) = unit_id_key(&ctx.prefix, chunk, stored, key_base);
    let photons = (chunk.len() * fibers.len()) as u64 * st.photons;
    let r = ctx.runner.unit(&id, key, Some(index), photons, || {
        Ok(chunk
            .par_iter()
            .map(|&i| {
                let b = stored[i];
                let inc = incident_of_bin(grid, b / grid.n_phi, b % grid.n_phi);
                (0..fibers.len())
                    .map(|s| {
                        let seed = task_seed(st.seed, &[seed_base, s as u64, b as u64]);
                        let r = bake::trace_slice(
                            &fibers[s],
                            inc,
                            grid,
                            channels,
                            st,
                            seed,
                            &ctx.runner.cancel,
                        );
                        if let Some(bar) = bar {
                            bar.inc(1);
                        }
                        r
                    })
                    .collect::<Result<Vec<_>, _>>()
            })
            .collect::<Result<Vec<_>, _>>()?)
    })?;
    Ok(r)
}

#[allow(clippy::too_many_arguments)]
fn bake_entry(
    a: &BakeArgs,
    out: Option<&Destination>,
    spec: &FiberSpec,
    e: &FiberEntry,
    st: &BakeSettings,
    ctx: &UnitCtx,
    unit_index: &mut usize,
) -> anyhow::Result<Option<EntryOutputs>> {
    let t0 = Instant::now();
    let spec_sha = spec.sha256.clone();
    let EntrySetup {
        grid,
        fibers,
        sym,
        stored,
        map,
        variants,
        channels,
        seed_base,
        key_base,
    } = entry_setup(e, st)?;
    let (nv, nc) = (variants.len(), channels.per_variant());
    let ns = fibers.len();
    let n_tables = if ns > 1 { ns + 1 } else { ns };
    let table_names: Vec<String> = (0..ns)
        .map(|s| format!("section-{s:02}"))
        .chain((ns > 1).then(|| "average".to_string()))
        .collect();
    if a.human() {
        eprintln!(
            "{}: {} section(s), symmetry {}, {} of {} incoming directions × {} photons (split {}), {} variant(s) × {} channel(s)",
            e.name,
            ns,
            sym.describe(),
            stored.len(),
            grid.bins(),
            st.photons.div_ceil(st.batch).max(2) * st.batch,
            st.split,
            nv,
            nc
        );
    }
    let wi_deg: Vec<[f64; 2]> = stored
        .iter()
        .map(|&b| {
            let (it, jp) = (b / grid.n_phi, b % grid.n_phi);
            [
                -90.0 + (it as f64 + 0.5) * st.res_deg,
                -180.0 + (jp as f64 + 0.5) * st.res_deg,
            ]
        })
        .collect();
    let phi_centres: Vec<f64> = (0..grid.n_phi)
        .map(|j| -180.0 + (j as f64 + 0.5) * st.res_deg)
        .collect();
    let area_of = |f: &Fiber| -> Vec<f64> {
        phi_centres
            .iter()
            .map(|p| f.projected_width_um(p.to_radians()))
            .collect()
    };
    let areas: Vec<Vec<f64>> = fibers.iter().map(area_of).collect();
    let area_avg: Vec<f64> = (0..grid.n_phi)
        .map(|j| areas.iter().map(|a| a[j]).sum::<f64>() / ns as f64)
        .collect();
    let mut noise_acc = (0.0, 0.0, 0usize);
    let mut photons_total = 0u64;
    let mut albedo_range = (f64::INFINITY, f64::NEG_INFINITY);
    let bins = grid.bins();
    let n_wi = stored.len();
    let ulen = unit_len(n_wi);
    let first_unit = *unit_index;
    *unit_index += n_wi.div_ceil(ulen);
    let all: Vec<usize> = (0..n_wi).collect();
    let Some(d) = out else {
        // A shard traces its units into the cache; `baker merge` writes the tables.
        for (u, chunk) in all.chunks(ulen).enumerate() {
            unit_results(
                ctx,
                first_unit + u,
                chunk,
                &stored,
                &key_base,
                &fibers,
                &grid,
                &channels,
                st,
                seed_base,
                None,
            )?;
        }
        return Ok(None);
    };
    let dir = d.staged.dir();
    let h5_path = d.staged.path(&format!("{0}/{0}.h5", e.name))?;

    let mut tables: Vec<Option<(String, Vec<u8>)>> = vec![None; n_tables];
    let bcsdf_bytes = std::cell::Cell::new(0u64);
    atomic::write_with(&h5_path, |tmp| -> anyhow::Result<()> {
        let file = h5::File::with_options()
            .with_fcpl(|p| p.obj_track_times(false))
            .create(tmp)?;
        h5out::text_attr(&file, "format", KIND)?;
        h5out::text_attr(&file, "entry", &e.name)?;
        h5out::text_attr(&file, "fiber_type", e.fiber_type.name)?;
        h5out::text_attr(&file, "spec", &spec.file)?;
        h5out::text_attr(&file, "symmetry", &sym.describe())?;
        h5out::text_attr(
            &file,
            "description",
            "Tabulated fiber BCSDFs (Aliaga et al. 2017 / thesis ch. 5). f = albedo * f_normalised, \
             sr^-1; fiber axis +z, theta = asin(w.z), phi = atan2(w.y, w.x), dphi = phi_o - phi_i. \
             Layout: formats/FORMAT.md, section 'Fiber BCSDF tables'.",
        )?;
        let mut outs = Vec::new();
        for (t, name) in table_names.iter().enumerate() {
            let area = if t < ns { &areas[t] } else { &area_avg };
            let dir_t = Directory {
                kind: KIND.into(),
                res_deg: st.res_deg,
                n_theta: grid.n_theta,
                n_phi: grid.n_phi,
                wi_deg: wi_deg.clone(),
                wi_map: map.clone(),
                variants: channels.variants.clone(),
                channels: channels.channel_names.clone(),
                dtype: st.precision,
                keep_bits: st.keep_bits,
                scale: vec![],
                albedo: vec![],
                albedo_se: vec![],
                area_um: area.clone(),
                chunks: vec![],
                metadata: serde_json::json!({
                    "entry": e.name, "table": name, "fiber_type": e.fiber_type.name,
                    "spec": spec.file, "diameter_um": e.diameter_um, "eta": e.eta,
                    "beta_deg": e.beta_deg, "cuticle": e.cuticle, "source": e.source,
                    "section_variant": (t < ns).then_some(t),
                    "symmetry": sym, "photons_per_direction": st.photons.div_ceil(st.batch).max(2) * st.batch,
                    "split": st.split, "seed": st.seed, "lambda_nm": st.lambda_nm,
                    "channels": st.channels,
                    "spec_sha256": spec_sha, "baker_version": env!("CARGO_PKG_VERSION"),
                    "created_utc": crate::output::manifest::created_utc(),
                }),
            };
            let g = file
                .create_group_builder()
                .obj_track_times(false)
                .create(name.as_str())?;
            let shape5 = [n_wi, nv, nc, grid.n_theta, grid.n_phi];
            let f = g
                .new_dataset::<f32>()
                .obj_track_times(false)
                .shape(shape5)
                .chunk([1, nv, nc, grid.n_theta, grid.n_phi])
                .shuffle()
                .deflate(4)
                .create("f_normalised")?;
            h5out::text_attr(&f, "units", "sr^-1")?;
            h5out::text_attr(&f, "description", "BCSDF normalised to one per incoming direction (sum of f * solid angle = 1); decoded values of the .bcsdf file")?;
            let cdf_theta = g
                .new_dataset::<f32>()
                .obj_track_times(false)
                .shape([n_wi, nv, grid.n_theta])
                .chunk([1, nv, grid.n_theta])
                .shuffle()
                .deflate(4)
                .create("cdf_theta")?;
            h5out::text_attr(&cdf_theta, "description", "sampling CDF over theta_o rows (density = mean of channels)")?;
            let cdf_phi = g
                .new_dataset::<f32>()
                .obj_track_times(false)
                .shape([n_wi, nv, grid.n_theta, grid.n_phi])
                .chunk([1, nv, grid.n_theta, grid.n_phi])
                .shuffle()
                .deflate(4)
                .create("cdf_phi")?;
            h5out::text_attr(&cdf_phi, "description", "sampling CDF over dphi within each theta_o row")?;
            outs.push(TableOut {
                name: name.clone(),
                writer: Writer::new(dir_t, st.zstd_level),
                f,
                cdf_theta,
                cdf_phi,
                albedo: Vec::new(),
                albedo_se: Vec::new(),
                group: g,
            });
        }

        let terminal = std::io::stderr().is_terminal();
        let bar = (a.human() && terminal)
            .then(|| super::progress::bar((n_wi * ns) as u64, &e.name));
        let mut done = 0usize;
        let t_trace = Instant::now();
        for (u, chunk) in all.chunks(ulen).enumerate() {
            let results = unit_results(
                ctx, first_unit + u, chunk, &stored, &key_base, &fibers, &grid, &channels, st,
                seed_base, bar.as_ref(),
            )?
            .ok_or_else(|| anyhow::anyhow!("unit {} of {} is not available", u, e.name))?;
            if let Some(bar) = &bar {
                bar.set_position(((done + chunk.len()) * ns) as u64);
            }
            for (&i, res) in chunk.iter().zip(results) {
                let b = stored[i];
                let phi_i = (-180.0 + (b % grid.n_phi) as f64 * st.res_deg + 0.5 * st.res_deg)
                    .to_radians();
                photons_total += res.iter().map(|r| r.launched).sum::<u64>();
                noise_acc.0 += res[0].noise.median_rel_se;
                noise_acc.1 += res[0].noise.p90_rel_se;
                noise_acc.2 += 1;
                let mut all = res;
                if ns > 1 {
                    // Average of the sections weighted by the power each intercepts, ∝ W(φi).
                    let w: Vec<f64> = fibers.iter().map(|f| f.projected_width_um(phi_i)).collect();
                    let wt: f64 = w.iter().sum();
                    let mut avg = all[0].clone();
                    for (k, x) in avg.fraction.iter_mut().enumerate() {
                        *x = all.iter().zip(&w).map(|(r, w)| w * r.fraction[k]).sum::<f64>() / wt;
                    }
                    for c in 0..avg.albedo.len() {
                        avg.albedo[c] = avg.fraction[c * bins..(c + 1) * bins].iter().sum();
                        avg.albedo_se[c] = all
                            .iter()
                            .zip(&w)
                            .map(|(r, w)| (w / wt * r.albedo_se[c]).powi(2))
                            .sum::<f64>()
                            .sqrt();
                    }
                    all.push(avg);
                }
                for (o, r) in outs.iter_mut().zip(&all) {
                    let decoded = o.writer.push(&r.normalised(&grid))?;
                    o.albedo.extend(r.albedo.iter().map(|&x| x as f32));
                    o.albedo_se.extend(r.albedo_se.iter().map(|&x| x as f32));
                    for (v, &al) in r.albedo.iter().enumerate() {
                        if e.variants[v / nc].is_none() {
                            albedo_range.0 = albedo_range.0.min(al);
                            albedo_range.1 = albedo_range.1.max(al);
                        }
                    }
                    let view = ArrayView5::from_shape((1, nv, nc, grid.n_theta, grid.n_phi), &decoded)?;
                    o.f.write_slice(view, s![i..i + 1, .., .., .., ..])?;
                    let (ct, cp, _) = bcsdf::sampling_cdfs(&o.writer.dir, &decoded);
                    let ct: Vec<f32> = ct.iter().flatten().map(|&x| x as f32).collect();
                    let cp: Vec<f32> = cp.iter().flatten().map(|&x| x as f32).collect();
                    o.cdf_theta.write_slice(
                        ArrayView3::from_shape((1, nv, grid.n_theta), &ct)?,
                        s![i..i + 1, .., ..],
                    )?;
                    o.cdf_phi.write_slice(
                        ArrayView4::from_shape((1, nv, grid.n_theta, grid.n_phi), &cp)?,
                        s![i..i + 1, .., .., ..],
                    )?;
                }
            }
            done += chunk.len();
            if bar.is_none() && a.human() {
                let step = (n_wi / 10).max(1);
                if done % step < chunk.len() || done == n_wi {
                    let el = t_trace.elapsed().as_secs_f64();
                    eprintln!(
                        "  {}: {done}/{n_wi} directions, {el:.0} s elapsed, eta {:.0} s",
                        e.name,
                        el / done as f64 * (n_wi - done) as f64
                    );
                }
            }
        }
        if let Some(b) = &bar {
            b.finish_and_clear();
        }
        // Axes, albedo, area, map; then the streaming files.
        for (t, mut o) in outs.into_iter().enumerate() {
            let g = &o.group;
            let albedo = g
                .new_dataset::<f32>()
                .obj_track_times(false)
                .shape([n_wi, nv, nc])
                .create("albedo")?;
            albedo.write_raw(&o.albedo)?;
            h5out::text_attr(&albedo, "description", "directional albedo Lambda(w_i): fraction of the intercepted power that leaves")?;
            let albedo_se = g
                .new_dataset::<f32>()
                .obj_track_times(false)
                .shape([n_wi, nv, nc])
                .create("albedo_se")?;
            albedo_se.write_raw(&o.albedo_se)?;
            let area = g.new_dataset::<f64>().obj_track_times(false).shape([grid.n_phi]).create("area_um")?;
            area.write_raw(&o.writer.dir.area_um)?;
            h5out::text_attr(&area, "units", "um")?;
            h5out::text_attr(&area, "description", "projected width per unit length seen from azimuth phi (A(w) of Eq. 17 before sin(w, w_f))")?;
            let wmap = g.new_dataset::<u32>().obj_track_times(false).shape([grid.n_theta, grid.n_phi]).create("wi_map")?;
            wmap.write_raw(&map)?;
            h5out::text_attr(&wmap, "description", "full (theta_i, phi_i) grid -> stored index | 2^31 (theta_o flips sign) | 2^30 (dphi flips sign)")?;
            let th_i = g.new_dataset::<f64>().obj_track_times(false).shape([n_wi]).create("theta_i_deg")?;
            th_i.write_raw(&wi_deg.iter().map(|w| w[0]).collect::<Vec<_>>())?;
            let ph_i = g.new_dataset::<f64>().obj_track_times(false).shape([n_wi]).create("phi_i_deg")?;
            ph_i.write_raw(&wi_deg.iter().map(|w| w[1]).collect::<Vec<_>>())?;
            let th_o = g.new_dataset::<f64>().obj_track_times(false).shape([grid.n_theta]).create("theta_o_deg")?;
            th_o.write_raw(&(0..grid.n_theta).map(|i| -90.0 + (i as f64 + 0.5) * st.res_deg).collect::<Vec<_>>())?;
            let dphi = g.new_dataset::<f64>().obj_track_times(false).shape([grid.n_phi]).create("dphi_deg")?;
            dphi.write_raw(&phi_centres)?;
            let phi = g.new_dataset::<f64>().obj_track_times(false).shape([grid.n_phi]).create("phi_deg")?;
            phi.write_raw(&phi_centres)?;
            let var = g.new_dataset::<h5::types::VarLenUnicode>().obj_track_times(false).shape([nv]).create("variant")?;
            let vnames: Vec<h5::types::VarLenUnicode> = channels.variants.iter().map(|s| s.parse().unwrap()).collect();
            var.write_raw(&vnames)?;
            let ch = g.new_dataset::<h5::types::VarLenUnicode>().obj_track_times(false).shape([nc]).create("channel")?;
            let cnames: Vec<h5::types::VarLenUnicode> = channels.channel_names.iter().map(|s| s.parse().unwrap()).collect();
            ch.write_raw(&cnames)?;
            for (d, u) in [(&th_i, "degree"), (&ph_i, "degree"), (&th_o, "degree"), (&dphi, "degree"), (&phi, "degree"), (&albedo, "1"), (&albedo_se, "1"), (&o.cdf_theta, "1"), (&o.cdf_phi, "1"), (&wmap, "1")] {
                h5out::text_attr(d, "units", u)?;
            }
            h5out::attach_scale(&th_i, "theta_i_deg", &[(&o.f, 0), (&albedo, 0), (&albedo_se, 0), (&o.cdf_theta, 0), (&o.cdf_phi, 0)])?;
            h5out::attach_scale(&ph_i, "phi_i_deg", &[(&o.f, 0), (&albedo, 0), (&albedo_se, 0), (&o.cdf_theta, 0), (&o.cdf_phi, 0)])?;
            h5out::attach_scale(&var, "variant", &[(&o.f, 1), (&albedo, 1), (&albedo_se, 1), (&o.cdf_theta, 1), (&o.cdf_phi, 1)])?;
            h5out::attach_scale(&ch, "channel", &[(&o.f, 2), (&albedo, 2), (&albedo_se, 2)])?;
            h5out::attach_scale(&th_o, "theta_o_deg", &[(&o.f, 3), (&o.cdf_theta, 2), (&o.cdf_phi, 2), (&wmap, 0)])?;
            h5out::attach_scale(&dphi, "dphi_deg", &[(&o.f, 4), (&o.cdf_phi, 3)])?;
            h5out::attach_scale(&phi, "phi_deg", &[(&area, 0), (&wmap, 1)])?;
            o.writer.dir.albedo = std::mem::take(&mut o.albedo);
            o.writer.dir.albedo_se = std::mem::take(&mut o.albedo_se);
            let name = o.name.clone();
            let bytes = o.writer.finish()?;
            bcsdf_bytes.set(bcsdf_bytes.get() + bytes.len() as u64);
            tables[t] = Some((name, bytes));
        }
        file.close()?;
        Ok(())
    })
    .with_context(|| format!("writing {}", h5_path.display()))?;
    let seconds = t0.elapsed().as_secs_f64();

    let mut files = Vec::new();
    let rel = |p: &Path| -> String {
        p.strip_prefix(dir)
            .unwrap_or(p)
            .to_string_lossy()
            .replace('\\', "/")
    };
    let mut first_table: Option<PathBuf> = None;
    for (name, bytes) in tables.into_iter().flatten() {
        let p = d
            .staged
            .path(&format!("{}/{name}.{}", e.name, bcsdf::EXTENSION))?;
        atomic::write(&p, &bytes).with_context(|| format!("writing {}", p.display()))?;
        files.push((rel(&p), format!("BCSDF table {name} of {}", e.name)));
        if first_table.is_none() || name == "average" {
            first_table = Some(p);
        }
    }
    files.push((rel(&h5_path), format!("HDF5 tables of {}", e.name)));
    ctx.runner.cancel.check()?;
    let previews = write_previews(
        &d.staged,
        &e.name,
        first_table.as_deref().unwrap(),
        &st.lambda_nm,
    )?;
    for p in previews {
        files.push((rel(&p), format!("preview slices of {}", e.name)));
    }
    let hdf5_bytes = std::fs::metadata(&h5_path)?.len();
    let n = noise_acc.2.max(1) as f64;
    let report = EntryReport {
        name: e.name.clone(),
        fiber_type: e.fiber_type.name,
        sections: e.sections,
        symmetry: sym.describe(),
        stored_directions: n_wi,
        full_directions: grid.bins(),
        photons_per_direction: st.photons.div_ceil(st.batch).max(2) * st.batch,
        split: st.split,
        variants: channels.variants.clone(),
        channels: channels.channel_names.clone(),
        seconds,
        photons_per_s: photons_total as f64 / seconds,
        noise: Noise {
            median_rel_se: noise_acc.0 / n,
            p90_rel_se: noise_acc.1 / n,
            bins: 0,
        },
        albedo_min: if albedo_range.0.is_finite() {
            albedo_range.0
        } else {
            0.0
        },
        albedo_max: if albedo_range.1.is_finite() {
            albedo_range.1
        } else {
            0.0
        },
        bcsdf_bytes: bcsdf_bytes.get(),
        hdf5_bytes,
    };
    if a.human() {
        eprintln!(
            "  {}: {:.1} s, {:.2} M photons/s, noise median {:.2} % / p90 {:.2} %, .bcsdf {:.2} MB, .h5 {:.2} MB",
            e.name,
            seconds,
            report.photons_per_s / 1e6,
            100.0 * report.noise.median_rel_se,
            100.0 * report.noise.p90_rel_se,
            report.bcsdf_bytes as f64 / 1e6,
            hdf5_bytes as f64 / 1e6
        );
    }
    Ok(Some((report, files)))
}

/// θi of the preview rows and φi (fiber rotations) of its columns, degrees.
const PREVIEW_THETA: [f64; 3] = [-0.001, -45.0, -80.0];
const PREVIEW_PHI: [f64; 4] = [0.0, 30.0, 60.0, 90.0];

/// Preview grid from a written table (read back through the renderer's reader): PNG of the
/// mean-channel f on a log scale, EXR of linear RGB f (variant 0).
fn write_previews(
    out: &Staged,
    entry: &str,
    table: &Path,
    lambda_nm: &[f64],
) -> anyhow::Result<Vec<PathBuf>> {
    let t = Bcsdf::open(table)?;
    let (nt, np) = (t.dir.n_theta, t.dir.n_phi);
    let res = t.dir.res_deg;
    let spectral = t.dir.channels.len() != 3;
    let cmap = spectral.then(|| ColourMap::new(lambda_nm));
    let mut panels = Vec::new();
    let mut rgb_panels = Vec::new();
    for &th in &PREVIEW_THETA {
        for &ph in &PREVIEW_PHI {
            let wi = bcsdf::direction(th.to_radians(), ph.to_radians());
            let mut mono = vec![0.0; nt * np];
            let mut rgb = vec![[0f32; 3]; nt * np];
            for it in 0..nt {
                for j in 0..np {
                    let to = (-90.0 + (it as f64 + 0.5) * res).to_radians();
                    let dp = (-180.0 + (j as f64 + 0.5) * res).to_radians();
                    let wo = bcsdf::direction(to, ph.to_radians() + dp);
                    let f = t.eval(wi, wo, 0)?;
                    mono[it * np + j] = f.iter().map(|&x| x as f64).sum::<f64>() / f.len() as f64;
                    rgb[it * np + j] = match &cmap {
                        Some(cm) => {
                            let r = cm.rgb(&f.iter().map(|&x| x as f64).collect::<Vec<_>>());
                            [r[0] as f32, r[1] as f32, r[2] as f32]
                        }
                        None => [f[0], f[1], f[2]],
                    };
                }
            }
            panels.push(mono);
            rgb_panels.push(rgb);
        }
    }
    let png = out.path(&format!("preview/{entry}.png"))?;
    let px = (4.0 * 2.0 / res).round().max(1.0) as u32;
    slice::write_panels_png(&png, nt, np, &panels, PREVIEW_PHI.len(), px)?;
    // EXR: same grid, one pixel per bin, θo increasing downwards reversed like the PNG.
    let cols = PREVIEW_PHI.len();
    let (w, h) = (cols * np, PREVIEW_THETA.len() * nt);
    let mut chans = [vec![0f32; w * h], vec![0f32; w * h], vec![0f32; w * h]];
    for (k, p) in rgb_panels.iter().enumerate() {
        let (r, c) = (k / cols, k % cols);
        for it in 0..nt {
            for j in 0..np {
                let (x, y) = (c * np + j, r * nt + (nt - 1 - it));
                for ch in 0..3 {
                    chans[ch][y * w + x] = p[it * np + j][ch];
                }
            }
        }
    }
    let exr_path = out.path(&format!("preview/{entry}.exr"))?;
    exr::write_rgb(
        &exr_path,
        w,
        h,
        chans,
        "baker fiber BCSDF preview: rows theta_i = 0, -45, -80 deg; columns phi_i = 0, 30, 60, 90 deg; \
         in each panel theta_o increases upwards, dphi from -180 (left) to 180 deg; linear sRGB f in sr^-1",
    )?;
    Ok(vec![png, exr_path])
}
