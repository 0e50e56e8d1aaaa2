//! The bake of one fiber entry: its units through the cache, then its tables, previews and
//! report.

use std::path::{Path, PathBuf};
use std::time::Instant;

use anyhow::Context;
use rayon::prelude::*;
use serde::Serialize;

use super::gamut::{ClipStats, GamutClip};
use super::setup::{entry_setup, unit_id_key, EntrySetup};
use super::tables::{file_attrs, Layout, TableOut};
use crate::bake::destination::Destination;
use crate::bake::job::Job;
use crate::fiber::slices::{self as bake, incident_of_bin, unit_len, BakeSettings, NoiseTarget};
use crate::fiber::sweep::ChannelKind;
use crate::math::rng::coordinate_seed;
use crate::output::{atomic, hdf5 as h5out};
use crate::pipeline::Computed;
use crate::progress::Progress;
use crate::spec::fiber::{FiberEntry, FiberSpec};
use formats::bcsdf::{self, KIND};

/// One unit's slices: per stored direction, its sections' slices.
type UnitSlices = Vec<Vec<bake::SliceResult>>;

/// What one entry's bake measured (written to the manifest).
#[derive(Debug, Serialize)]
pub struct EntryReport {
    pub name: String,
    pub fiber_type: &'static str,
    pub sections: u64,
    pub symmetry: String,
    pub stored_directions: usize,
    pub full_directions: usize,
    /// Photons asked for per stored direction and section (`bake.photons_per_direction`,
    /// whole batches); what each direction used is in `photons`.
    pub photons_per_direction: u64,
    pub split: u32,
    pub exit_draws: u32,
    /// Expected-value exit scoring and the sampler (`bake.expected_exits`, `bake.sampling`).
    pub expected_exits: crate::fiber::slices::ExpectedExits,
    pub sampling: crate::fiber::slices::Sampling,
    /// Incoming directions sharing their photons (`share_theta`; 1: each traced alone).
    pub share_theta: u32,
    /// Adaptive allocation's target (`null`: a fixed count per direction) and cap.
    pub target_rel_se: Option<NoiseTarget>,
    pub max_photons_per_direction: u64,
    pub variants: Vec<String>,
    pub channels: Vec<String>,
    /// Wall-clock figures: in `timing.json`, not the (reproducible) manifest.
    #[serde(skip)]
    pub seconds: f64,
    #[serde(skip)]
    pub photons_per_s: f64,
    /// Photons launched per stored direction (all its sections; units taken from the cache
    /// included); each direction's own count and noise are in the HDF5 file (`photons`,
    /// `median_rel_se`, `thesis_rel_se`).
    pub photons: PhotonsUsed,
    /// Per-bin relative standard error of the sampling density (section 0).
    pub noise: NoiseReport,
    /// Per variant: the smallest and largest albedo Λ per channel over the stored directions
    /// of every table, as stored (after the RGB gamut mapping).
    pub albedo: Vec<AlbedoRange>,
    /// What the RGB gamut mapping did over the entry's tables (`bake/fiber/gamut.rs`); `None` for
    /// spectral tables, which are never mapped.
    pub rgb_gamut_clip: Option<ClipStats>,
    pub bcsdf_bytes: u64,
    pub hdf5_bytes: u64,
}

/// Photons launched per stored direction (summed over its sections).
#[derive(Debug, Clone, Default, PartialEq, Serialize)]
pub struct PhotonsUsed {
    pub min: u64,
    /// The lower median (element ⌊(n − 1)/2⌋ in increasing order).
    pub median: u64,
    pub max: u64,
    /// Over every stored direction.
    pub total: u64,
}

impl PhotonsUsed {
    fn of(per_direction: &[u64]) -> PhotonsUsed {
        let mut v = per_direction.to_vec();
        v.sort_unstable();
        PhotonsUsed {
            min: v.first().copied().unwrap_or(0),
            median: v.get(v.len().saturating_sub(1) / 2).copied().unwrap_or(0),
            max: v.last().copied().unwrap_or(0),
            total: v.iter().sum(),
        }
    }
}

/// The noise metric of an entry: per stored direction, section 0's relative standard error
/// of the sampling density over the bins whose density is ≥ 1 % of the slice's maximum
/// ([`crate::fiber::slices::Noise`]), averaged over the stored directions.
#[derive(Debug, Clone, Default, PartialEq, Serialize)]
pub struct NoiseReport {
    /// Mean over stored directions of each slice's median per-bin relative error.
    pub median_rel_se: f64,
    /// Mean over stored directions of each slice's 90th percentile.
    pub p90_rel_se: f64,
    /// Mean number of bins per slice the two statistics are taken over.
    pub bins: f64,
    /// Mean over stored directions of the thesis's noise for each slice (section 0): what
    /// plain sampling with 16 M photons would give ([`crate::fiber::slices::NoiseTarget`]).
    pub thesis_rel_se: f64,
    /// Stored directions whose section 0 reached the spec's `target_rel_se` (all of them
    /// without a target).
    pub directions_at_target: usize,
}

/// The albedo range of one variant, per channel.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct AlbedoRange {
    pub variant: String,
    pub min: Vec<f64>,
    pub max: Vec<f64>,
}

/// An entry's report and its files (path relative to the spec's output, description).
pub type EntryOutputs = (EntryReport, Vec<(String, String)>);

/// One entry of a fiber spec being baked.
pub struct EntryBake<'a> {
    pub job: &'a Job<'a>,
    pub spec: &'a FiberSpec,
    pub e: &'a FiberEntry,
    pub st: &'a BakeSettings,
    /// `<spec>/<entry>`, the prefix of its unit ids.
    pub prefix: String,
    pub setup: EntrySetup,
    /// Index of the entry's first unit among the spec's units (sharding uses it).
    pub first_unit: usize,
}

/// What the direction loop accumulates for the report.
struct Tallies {
    /// Σ over stored directions of section 0's median and p90 relative error and bins.
    noise: (f64, f64, f64),
    /// Σ over directions of section 0's thesis noise, and the directions at their target.
    thesis_noise: f64,
    at_target: usize,
    /// Photons per stored direction, in the order the units are written (only their
    /// distribution is reported).
    photons: Vec<u64>,
    /// Per variant × channel: the smallest and largest stored albedo over every table.
    albedo: Vec<(f64, f64)>,
    /// The RGB gamut mapping per table, and over the entry (a direction counts once).
    clip: Vec<ClipStats>,
    clip_entry: ClipStats,
}

impl Tallies {
    fn new(channels: usize, tables: usize) -> Tallies {
        Tallies {
            noise: (0.0, 0.0, 0.0),
            thesis_noise: 0.0,
            at_target: 0,
            photons: Vec::new(),
            albedo: vec![(f64::INFINITY, f64::NEG_INFINITY); channels],
            clip: vec![ClipStats::default(); tables],
            clip_entry: ClipStats::default(),
        }
    }
}

impl EntryBake<'_> {
    fn n_units(&self) -> usize {
        self.setup.units(self.st.share_theta).len()
    }

    /// The results of unit `u` (its stored directions, every section), from the cache or
    /// traced (and then still to be cached: [`Computed::Fresh`]); `None` if another shard
    /// owns it.
    fn unit_results(
        &self,
        u: usize,
        chunk: &[usize],
        bar: Option<&dyn Progress>,
    ) -> anyhow::Result<Option<Computed<UnitSlices>>> {
        let (s, st, runner) = (&self.setup, self.st, self.job.runner);
        let (id, key) = unit_id_key(&self.prefix, chunk, &s.stored, &s.key_base);
        let photons = (chunk.len() * s.fibers.len()) as u64 * st.photons;
        let r = runner.unit_deferred(&id, key, Some(self.first_unit + u), photons, || {
            // The unit's groups of directions sharing their photons (each direction alone
            // without `share_theta`), traced in parallel, each section in turn.
            let groups = s.groups(chunk.iter().copied(), st.share_theta as usize);
            let traced = groups
                .par_iter()
                .map(|g| {
                    let bins: Vec<usize> = g.iter().map(|&i| s.stored[i]).collect();
                    let incs: Vec<_> = bins
                        .iter()
                        .map(|&b| incident_of_bin(&s.grid, b / s.grid.n_phi, b % s.grid.n_phi))
                        .collect();
                    (0..s.fibers.len())
                        .map(|k| {
                            let seeds: Vec<u64> = bins
                                .iter()
                                .map(|&b| {
                                    coordinate_seed(st.seed, &[s.seed_base, k as u64, b as u64])
                                })
                                .collect();
                            let r = bake::trace_group(
                                &s.fibers[k],
                                &incs,
                                &s.grid,
                                &s.channels,
                                st,
                                &seeds,
                                &runner.cancel,
                            );
                            if let Some(bar) = bar {
                                bar.advance(g.len() as u64);
                            }
                            r
                        })
                        .collect::<Result<Vec<_>, _>>()
                })
                .collect::<Result<Vec<_>, _>>()?;
            // Back to the unit's order: per direction, its sections' slices.
            let mut by_dir: std::collections::BTreeMap<usize, Vec<bake::SliceResult>> =
                Default::default();
            for (g, per_section) in groups.iter().zip(traced) {
                for section in per_section {
                    for (&i, r) in g.iter().zip(section) {
                        by_dir.entry(i).or_default().push(r);
                    }
                }
            }
            Ok(chunk
                .iter()
                .map(|i| by_dir.remove(i).unwrap_or_default())
                .collect())
        })?;
        Ok(r)
    }

    /// A shard traces its units into the cache; `baker merge` writes the tables.
    fn units_only(&self) -> anyhow::Result<()> {
        let phase = self.begin_phase();
        let units = self.setup.units(self.st.share_theta);
        let r = (|| {
            for (u, chunk) in units.iter().enumerate() {
                if let Some(unit) = self.unit_results(u, chunk, Some(&*phase))? {
                    unit.stored()?;
                }
            }
            Ok(())
        })();
        self.job.runner.end_phase();
        r
    }

    /// The entry's `tracing` phase: its units, photons and directions.
    fn begin_phase(&self) -> std::sync::Arc<crate::pipeline::Phase> {
        let (s, st) = (&self.setup, self.st);
        let per_unit = unit_len(s.stored.len()).min(s.stored.len()) * s.fibers.len();
        self.job.runner.begin_phase(crate::pipeline::PhaseSpec {
            name: "tracing".into(),
            label: self.e.name.clone(),
            units: self.n_units() as u64,
            photons_per_unit: per_unit as u64 * st.photons,
            photons_per_item: Some(st.photons),
            item: "directions".into(),
        })
    }
}

/// Bakes entry `e` into `out` (`None` for a shard); its units are numbered from
/// `*unit_index`.
pub fn bake_entry(
    job: &Job,
    spec: &FiberSpec,
    e: &FiberEntry,
    st: &BakeSettings,
    unit_index: &mut usize,
) -> anyhow::Result<Option<EntryOutputs>> {
    let t0 = Instant::now();
    let eb = EntryBake {
        job,
        spec,
        e,
        st,
        prefix: format!("{}/{}", job.stem, e.name),
        setup: entry_setup(e, st)?,
        first_unit: *unit_index,
    };
    *unit_index += eb.n_units();
    announce(&eb);
    let Some(d) = job.out else {
        eb.units_only()?;
        return Ok(None);
    };
    let geo = Geometry::of(&eb);
    let h5_path = d.staged.path(&format!("{0}/{0}.h5", e.name))?;
    let mut tallies = Tallies::new(eb.setup.channels.len(), geo.table_names.len());
    let mut tables = Vec::new();
    atomic::write_with(&h5_path, |tmp| -> anyhow::Result<()> {
        tables = write_tables(&eb, &geo, tmp, &mut tallies)?;
        Ok(())
    })
    .with_context(|| format!("writing {}", h5_path.display()))?;
    let seconds = t0.elapsed().as_secs_f64();
    let (files, bcsdf_bytes) = write_outputs(&eb, d, &h5_path, tables)?;
    let report = report(
        &eb,
        &tallies,
        seconds,
        bcsdf_bytes,
        std::fs::metadata(&h5_path)?.len(),
    );
    job.runner.events.say(format!(
        "  {}: {:.1} s, {:.2} M photons/s, noise median {:.2} % / p90 {:.2} %, .bcsdf {:.2} MB, .h5 {:.2} MB",
        e.name,
        seconds,
        report.photons_per_s / 1e6,
        100.0 * report.noise.median_rel_se,
        100.0 * report.noise.p90_rel_se,
        report.bcsdf_bytes as f64 / 1e6,
        report.hdf5_bytes as f64 / 1e6
    ));
    Ok(Some((report, files)))
}

fn announce(eb: &EntryBake) {
    let s = &eb.setup;
    eb.job.runner.events.say(format!(
        "{}: {} section(s), symmetry {}, {} of {} incoming directions × {} photons{} (split {}, exit draws {}, expected exits {:?}, sampling {:?}{}), {} variant(s) × {} channel(s)",
        eb.e.name,
        s.fibers.len(),
        s.sym.describe(),
        s.stored.len(),
        s.grid.bins(),
        eb.st.photons_per_direction(),
        match eb.st.target {
            None => String::new(),
            Some(NoiseTarget::Thesis) => format!(
                " and more to the thesis's noise (at most {})",
                eb.st.max_photons
            ),
            Some(NoiseTarget::RelSe(x)) => format!(
                " and more to {:.2} % relative error (at most {})",
                100.0 * x,
                eb.st.max_photons
            ),
        },
        eb.st.split,
        eb.st.exit_draws,
        eb.st.expected_exits,
        eb.st.sampling,
        match eb.st.share_theta {
            1 => String::new(),
            k => format!(", photons shared by {k} θ rows"),
        },
        s.variants.len(),
        s.channels.per_variant()
    ));
}

/// The directions and projected widths the tables are laid out on.
struct Geometry {
    wi_deg: Vec<[f64; 2]>,
    phi_centres: Vec<f64>,
    /// Per section, then their average: projected width per φ bin, µm.
    areas: Vec<Vec<f64>>,
    table_names: Vec<String>,
}

impl Geometry {
    fn of(eb: &EntryBake) -> Geometry {
        let grid = &eb.setup.grid;
        let wi_deg = eb.setup.wi_deg();
        let phi_centres = eb.setup.phi_centres_deg();
        let ns = eb.setup.fibers.len();
        let mut areas: Vec<Vec<f64>> = eb
            .setup
            .fibers
            .iter()
            .map(|f| eb.setup.area_um(f))
            .collect();
        if ns > 1 {
            let avg = (0..grid.n_phi)
                .map(|j| areas.iter().map(|a| a[j]).sum::<f64>() / ns as f64)
                .collect();
            areas.push(avg);
        }
        let table_names = (0..ns)
            .map(|s| format!("section-{s:02}"))
            .chain((ns > 1).then(|| "average".to_string()))
            .collect();
        Geometry {
            wi_deg,
            phi_centres,
            areas,
            table_names,
        }
    }
}

/// Writes every table of the entry into the HDF5 file at `tmp` while the units run; returns
/// each table's name and `.bcsdf` bytes.
fn write_tables(
    eb: &EntryBake,
    geo: &Geometry,
    tmp: &Path,
    tallies: &mut Tallies,
) -> anyhow::Result<Vec<(String, Vec<u8>)>> {
    let (e, s, st) = (eb.e, &eb.setup, eb.st);
    let file = h5out::create_file(tmp)?;
    let symmetry = s.sym.describe();
    file_attrs(
        &file,
        &[
            ("format", KIND),
            ("entry", &e.name),
            ("fiber_type", e.fiber_type.name),
            ("spec", &eb.spec.file),
            ("symmetry", &symmetry),
        ],
    )?;
    let layout = Layout {
        grid: &s.grid,
        st,
        wi_deg: &geo.wi_deg,
        map: &s.map,
        variants: &s.channels.variants,
        channels: &s.channels.channel_names,
        phi_centres: &geo.phi_centres,
        quantise_to_se: eb.spec.storage.quantise_to_se,
        zstd_level: eb.spec.storage.zstd_level,
    };
    let mut outs = Vec::new();
    for (t, name) in geo.table_names.iter().enumerate() {
        let meta = table_metadata(eb, name, t);
        outs.push(TableOut::create(
            &file,
            name,
            &layout,
            geo.areas[t].clone(),
            meta,
        )?);
    }
    trace_into(eb, &mut outs, tallies)?;
    let rgb = st.channels == ChannelKind::Rgb;
    let tables = outs
        .into_iter()
        .zip(&tallies.clip)
        .map(|(o, c)| o.finish(&layout, rgb.then_some(c)))
        .collect::<anyhow::Result<Vec<_>>>()?;
    file.close()?;
    Ok(tables)
}

/// The directory metadata of table `t` (`name`) of the entry.
fn table_metadata(eb: &EntryBake, name: &str, t: usize) -> serde_json::Value {
    let (e, st) = (eb.e, eb.st);
    let ns = eb.setup.fibers.len();
    serde_json::json!({
        "entry": e.name, "table": name, "fiber_type": e.fiber_type.name,
        "spec": eb.spec.file, "diameter_um": e.diameter_um, "eta": e.eta,
        "beta_deg": e.beta_deg, "cuticle": e.cuticle, "source": e.source,
        "section_variant": (t < ns).then_some(t),
        "symmetry": eb.setup.sym, "photons_per_direction": st.photons_per_direction(),
        "split": st.split, "exit_draws": st.exit_draws,
        "expected_exits": st.expected_exits, "sampling": st.sampling,
        "share_theta": st.share_theta,
        "target_rel_se": st.target, "max_photons_per_direction": st.max_photons,
        "seed": st.seed, "lambda_nm": st.lambda_nm,
        "channels": st.channels, "quantise_to_se": eb.spec.storage.quantise_to_se,
        "zstd_level": eb.spec.storage.zstd_level,
        "spec_sha256": eb.spec.sha256, "baker_version": env!("CARGO_PKG_VERSION"),
        "created_utc": crate::output::manifest::created_utc(),
    })
}

/// Runs the entry's units in order and pushes every stored direction into the tables (the
/// sections, then their average weighted by the power each intercepts).
fn trace_into(eb: &EntryBake, outs: &mut [TableOut], tallies: &mut Tallies) -> anyhow::Result<()> {
    let runner = eb.job.runner;
    let phase = eb.begin_phase();
    let r = trace_units(eb, &phase, outs, tallies);
    runner.end_phase();
    r
}

/// [`trace_into`]'s loop over the units, reporting to `phase`. Caching a traced unit and
/// encoding and writing its tables run on a thread of its own while the next unit traces (a
/// wide sweep's results take a while to compress, and the writers are serial): at most two
/// units' results are held (the budget counts three, [`crate::spec::budget`]), and the
/// tables are written in unit order. A unit is cached before its tables are written, so a
/// stop while writing loses no traced unit.
fn trace_units(
    eb: &EntryBake,
    phase: &crate::pipeline::Phase,
    outs: &mut [TableOut],
    tallies: &mut Tallies,
) -> anyhow::Result<()> {
    let units = eb.setup.units(eb.st.share_theta);
    std::thread::scope(|scope| -> anyhow::Result<()> {
        let (tx, rx) = std::sync::mpsc::sync_channel::<(&[usize], Computed<UnitSlices>)>(0);
        let writer = scope.spawn(move || -> anyhow::Result<()> {
            let clip = (eb.st.channels == ChannelKind::Rgb).then(|| {
                GamutClip::new(
                    &eb.st.lambda_nm,
                    eb.e.variants.iter().map(Option::is_none).collect(),
                )
            });
            for (chunk, unit) in rx {
                let results = unit.stored()?;
                write_unit(eb, chunk, results, clip.as_ref(), outs, tallies)?;
            }
            Ok(())
        });
        for (u, chunk) in units.iter().enumerate() {
            let results = eb
                .unit_results(u, chunk, Some(phase))?
                .ok_or_else(|| anyhow::anyhow!("unit {} of {} is not available", u, eb.e.name))?;
            if tx.send((chunk.as_slice(), results)).is_err() {
                // The writer stopped with an error: it tells which below.
                break;
            }
        }
        drop(tx);
        writer
            .join()
            .unwrap_or_else(|p| std::panic::resume_unwind(p))
    })
}

/// Pushes the stored directions `chunk` of one unit (`results`: per direction, its sections'
/// slices) into the tables, after the RGB gamut mapping, and adds them to the tallies.
fn write_unit(
    eb: &EntryBake,
    chunk: &[usize],
    results: Vec<Vec<bake::SliceResult>>,
    clip: Option<&GamutClip>,
    outs: &mut [TableOut],
    tallies: &mut Tallies,
) -> anyhow::Result<()> {
    let (s, runner) = (&eb.setup, eb.job.runner);
    let bins = s.grid.bins();
    for (&i, res) in chunk.iter().zip(results) {
        // Encoding and writing a direction of a wide sweep takes a while: a signal
        // stops here too (the HDF5 file being written is dropped).
        runner.cancel.check()?;
        let photons = res.iter().map(|r| r.launched).sum::<u64>();
        tallies.photons.push(photons);
        tallies.noise.0 += res[0].noise.median_rel_se;
        tallies.noise.1 += res[0].noise.p90_rel_se;
        tallies.noise.2 += res[0].noise.bins as f64;
        tallies.thesis_noise += res[0].noise.thesis_rel_se;
        tallies.at_target += usize::from(eb.st.target.is_none_or(|t| t.met_by(&res[0].noise)));
        let mut all = with_average(eb, s.stored[i], res);
        let mut factors = Vec::new();
        for (t, (o, r)) in outs.iter_mut().zip(&mut all).enumerate() {
            if let Some(clip) = clip {
                let f = clip.apply(r, bins).with_context(|| {
                    format!(
                        "{}, table {}, stored incoming direction {i} (bin {})",
                        eb.e.name, o.name, s.stored[i]
                    )
                })?;
                tallies.clip[t].add(&f);
                factors.extend(f);
            }
            // Tables past the sections' are their average.
            let traced = t < s.fibers.len();
            let launched = if traced { r.launched } else { photons };
            o.push(i, r, &s.grid, launched, traced)?;
            // As stored (f32).
            for (range, &a) in tallies.albedo.iter_mut().zip(&r.albedo) {
                let a = f64::from(a as f32);
                *range = (range.0.min(a), range.1.max(a));
            }
        }
        tallies.clip_entry.add(&factors);
    }
    Ok(())
}

/// The sections' slices of stored bin `b`, and with several sections their average weighted
/// by the power each intercepts, ∝ W(φi).
fn with_average(eb: &EntryBake, b: usize, res: Vec<bake::SliceResult>) -> Vec<bake::SliceResult> {
    let (s, st) = (&eb.setup, eb.st);
    let mut all = res;
    if s.fibers.len() > 1 {
        // φi of the bin's centre, summed as the tables were first baked (j·res + res/2, not
        // the grid's (j + ½)·res, which can differ in the last bit): the weights, and so the
        // average's bytes, stay those of every earlier bake.
        let phi_i =
            (-180.0 + (b % s.grid.n_phi) as f64 * st.res_deg + 0.5 * st.res_deg).to_radians();
        let w: Vec<f64> = s
            .fibers
            .iter()
            .map(|f| f.projected_width_um(phi_i))
            .collect();
        let wt: f64 = w.iter().sum();
        let mut avg = all[0].clone();
        for (k, x) in avg.fraction.iter_mut().enumerate() {
            *x = all
                .iter()
                .zip(&w)
                .map(|(r, w)| w * r.fraction[k])
                .sum::<f64>()
                / wt;
        }
        // Variant 0's per-bin and per-Δφ errors, for rounding the average to its own noise
        // (the sections are independent traces).
        let combined = |se: fn(&bake::SliceResult) -> &Vec<f64>, n: usize| -> Vec<f64> {
            (0..n)
                .map(|b| {
                    (all.iter().zip(&w))
                        .map(|(r, w)| (w / wt * se(r).get(b).copied().unwrap_or(0.0)).powi(2))
                        .sum::<f64>()
                        .sqrt()
                })
                .collect()
        };
        avg.density_se = combined(|r| &r.density_se, avg.density_se.len());
        avg.dphi_se = combined(|r| &r.dphi_se, avg.dphi_se.len());
        for c in 0..avg.albedo.len() {
            // The sections' albedos averaged as their fractions are (Σ_b of the average's
            // fractions, which carry the batches' f32 tally rounding, can round an undyed
            // white furnace's one above one).
            avg.albedo[c] = all
                .iter()
                .zip(&w)
                .map(|(r, w)| w * r.albedo[c])
                .sum::<f64>()
                / wt;
            avg.albedo_se[c] = all
                .iter()
                .zip(&w)
                .map(|(r, w)| (w / wt * r.albedo_se[c]).powi(2))
                .sum::<f64>()
                .sqrt();
        }
        all.push(avg);
    }
    all
}

/// The `.bcsdf` files and previews of the entry; returns the files (relative path,
/// description) and the tables' total bytes.
fn write_outputs(
    eb: &EntryBake,
    d: &Destination,
    h5_path: &Path,
    tables: Vec<(String, Vec<u8>)>,
) -> anyhow::Result<(Vec<(String, String)>, u64)> {
    let e = eb.e;
    let dir = d.staged.dir();
    let rel = |p: &Path| -> String {
        p.strip_prefix(dir)
            .unwrap_or(p)
            .to_string_lossy()
            .replace('\\', "/")
    };
    let mut files = Vec::new();
    let mut bcsdf_bytes = 0u64;
    let mut first_table: Option<PathBuf> = None;
    for (name, bytes) in tables {
        let p = d
            .staged
            .path(&format!("{}/{name}.{}", e.name, bcsdf::EXTENSION))?;
        atomic::write(&p, &bytes).with_context(|| format!("writing {}", p.display()))?;
        bcsdf_bytes += bytes.len() as u64;
        files.push((rel(&p), format!("BCSDF table {name} of {}", e.name)));
        if first_table.is_none() || name == "average" {
            first_table = Some(p);
        }
    }
    files.push((rel(h5_path), format!("HDF5 tables of {}", e.name)));
    eb.job.runner.cancel.check()?;
    let previews = super::preview::write_previews(
        &d.staged,
        &e.name,
        first_table.as_deref().unwrap(),
        &eb.st.lambda_nm,
    )?;
    for p in previews {
        files.push((rel(&p), format!("preview slices of {}", e.name)));
    }
    Ok((files, bcsdf_bytes))
}

fn report(
    eb: &EntryBake,
    t: &Tallies,
    seconds: f64,
    bcsdf_bytes: u64,
    hdf5_bytes: u64,
) -> EntryReport {
    let (e, s, st) = (eb.e, &eb.setup, eb.st);
    let n = t.photons.len().max(1) as f64;
    let nc = s.channels.per_variant();
    let albedo = s
        .channels
        .variants
        .iter()
        .zip(t.albedo.chunks(nc))
        .map(|(v, r)| AlbedoRange {
            variant: v.clone(),
            min: r.iter().map(|x| x.0).collect(),
            max: r.iter().map(|x| x.1).collect(),
        })
        .collect();
    let photons = PhotonsUsed::of(&t.photons);
    EntryReport {
        name: e.name.clone(),
        fiber_type: e.fiber_type.name,
        sections: e.sections,
        symmetry: s.sym.describe(),
        stored_directions: s.stored.len(),
        full_directions: s.grid.bins(),
        photons_per_direction: st.photons_per_direction(),
        split: st.split,
        exit_draws: st.exit_draws,
        expected_exits: st.expected_exits,
        sampling: st.sampling,
        share_theta: st.share_theta,
        target_rel_se: st.target,
        max_photons_per_direction: st.max_photons,
        variants: s.channels.variants.clone(),
        channels: s.channels.channel_names.clone(),
        seconds,
        photons_per_s: photons.total as f64 / seconds,
        photons,
        noise: NoiseReport {
            median_rel_se: t.noise.0 / n,
            p90_rel_se: t.noise.1 / n,
            bins: t.noise.2 / n,
            thesis_rel_se: t.thesis_noise / n,
            directions_at_target: t.at_target,
        },
        albedo,
        rgb_gamut_clip: (st.channels == ChannelKind::Rgb).then(|| t.clip_entry.clone()),
        bcsdf_bytes,
        hdf5_bytes,
    }
}
