//! Grouping entries by shared scattering, and running one white simulation per group and
//! wavelength.

// Index loops mirror the formulas (rows, columns, bins); iterator chains would hide them.
#![allow(clippy::needless_range_loop)]

use std::collections::HashMap;
use std::time::Instant;

use anyhow::Context as _;

use formats::OpticsEntry;

use super::allocate::{allocate, NoiseTarget};
use crate::math::rng::{digest_words, group_wavelength_seed};
use crate::pipeline::{Cache, CacheMode, Events, Key, KeyBuilder, Runner};
use crate::spec::skin::profiles::{BOOST_PILOT_MAX, NOISE_PILOT_MAX};
use crate::transport::white::{SetTally, WhiteSets};
use crate::transport::{self, run_white_sets, McOptions, RadialBins, Stack};

/// Spectral profile of one entry: per wavelength, Rd(r) per unit area on the radial bins and
/// the whole-plane totals, each with its standard error.
#[derive(Debug, Clone, PartialEq)]
pub struct SpectralProfile {
    pub lambda_nm: Vec<f64>,
    pub r_edges_mm: Vec<f64>,
    /// `[nλ][nr]`, mm⁻².
    pub rd_per_mm2: Vec<Vec<f64>>,
    pub rd_per_mm2_se: Vec<Vec<f64>>,
    /// Diffuse reflectance of scattered light over the whole plane, `[nλ]`.
    pub rd_total: Vec<f64>,
    pub rd_total_se: Vec<f64>,
    /// Light sent back by inner interfaces without scattering (a delta at r ≈ 0), `[nλ]`.
    pub rd_unscattered: Vec<f64>,
    pub tt: Vec<f64>,
    pub tt_se: Vec<f64>,
    /// Specular reflectance of the air–stratum corneum interface, `[nλ]`.
    pub rsp: Vec<f64>,
    /// Photons traced per wavelength.
    pub photons: Vec<u64>,
    /// Index of the simulation group the entry belongs to.
    pub group: usize,
}

/// Which entries share a simulation.
#[derive(Debug, Clone, PartialEq)]
pub struct GroupPlan {
    /// Entry indices per group, in entry order; groups in order of their first entry.
    pub groups: Vec<Vec<usize>>,
    /// Per group, a 64-bit digest of its scattering stacks (seeds derive from it).
    pub digests: Vec<u64>,
}

#[derive(Debug, Clone)]
pub struct SimOptions {
    pub photons: u64,
    pub seed: u64,
    pub threads: Option<usize>,
    /// Wavelengths whose packets are cheap (few scattering events, e.g. strongly absorbed
    /// blue) get up to this many times `photons`, so that every wavelength of a group costs
    /// about the same as its most expensive one. 1 turns it off. Only without `noise`.
    pub max_boost: u64,
    /// Photons per wavelength chosen by [`allocate`] from pilot runs to meet a noise target at
    /// the least work; `None`: `photons` at every wavelength (times the boost).
    pub noise: Option<NoiseTarget>,
    /// Where finished photon packets are reported.
    pub progress: crate::progress::Reporter,
}

/// Everything of entry `e`'s stacks except absorption, as bits: equal keys ⇔ the same
/// scattering simulation at every wavelength.
fn scattering_key(e: &OpticsEntry, n_lambda: usize) -> Vec<u64> {
    let mut k = Vec::new();
    for i in 0..n_lambda {
        let s = transport::stack::from_skin(e, i);
        k.push(s.n_above.to_bits());
        k.push(s.n_below.to_bits());
        for l in &s.layers {
            k.extend([
                l.d_mm.to_bits(),
                l.eta.to_bits(),
                l.mus_per_mm.to_bits(),
                l.g.to_bits(),
            ]);
        }
        match &s.junction {
            Some(j) => k.extend([
                j.upper_layer as u64,
                j.amplitude_mm.to_bits(),
                j.omega_x_per_mm.to_bits(),
                j.omega_y_per_mm.to_bits(),
                j.phi_x_rad.to_bits(),
                j.phi_y_rad.to_bits(),
            ]),
            None => k.push(u64::MAX),
        }
    }
    k
}

/// Groups `entries` by shared scattering (or one group each without `reuse`).
pub fn plan(entries: &[OpticsEntry], n_lambda: usize, reuse: bool) -> GroupPlan {
    let mut index: HashMap<Vec<u64>, usize> = HashMap::new();
    let mut groups: Vec<Vec<usize>> = Vec::new();
    let mut digests = Vec::new();
    for (i, e) in entries.iter().enumerate() {
        let key = scattering_key(e, n_lambda);
        let d = digest_words(&key);
        let g = if reuse {
            *index.entry(key).or_insert_with(|| {
                groups.push(Vec::new());
                digests.push(d);
                groups.len() - 1
            })
        } else {
            groups.push(Vec::new());
            // Without sharing, an entry's own absorption is part of what it simulates.
            digests.push(digest_words(&[d, digest_words(&absorption_bits(e))]));
            groups.len() - 1
        };
        groups[g].push(i);
    }
    GroupPlan { groups, digests }
}

fn absorption_bits(e: &OpticsEntry) -> Vec<u64> {
    e.layers
        .iter()
        .flat_map(|l| l.mua_per_mm.iter().map(|m| m.to_bits()))
        .collect()
}

/// Runs every group of `plan` at every wavelength; `on_task(done, total, seconds)` after each.
/// No cache (see [`simulate_units`] for the bake's cached, shardable version).
pub fn simulate(
    entries: &[OpticsEntry],
    lambda_nm: &[f64],
    bins: &RadialBins,
    plan: &GroupPlan,
    o: &SimOptions,
    on_task: impl FnMut(usize, usize, f64),
) -> anyhow::Result<Vec<SpectralProfile>> {
    let runner = Runner::new(Cache::new("", CacheMode::Off), Events::silent(), None);
    let sim = SkinSimulation {
        entries,
        lambda_nm,
        bins,
        plan,
        o,
    };
    let out = simulate_units(&sim, &runner, "", on_task)?;
    Ok(out.expect("without a shard every unit is computed"))
}

/// The work units of a skin bake: per group and wavelength a pilot run (photon counts, only
/// with a noise target or `max_boost > 1`; not sharded) and the main run (sharded by its index
/// g·nλ + i).
pub struct SkinUnits {
    pub pilot: Vec<Vec<Key>>,
    pub run: Vec<Vec<Key>>,
    /// Packets of each pilot run.
    pub pilot_photons: u64,
}

pub fn stack_and_sets(
    entries: &[OpticsEntry],
    plan: &GroupPlan,
    g: usize,
    i: usize,
) -> (Stack, Vec<Vec<f64>>) {
    let members = &plan.groups[g];
    let stack: Stack = transport::stack::from_skin(&entries[members[0]], i);
    let sets: Vec<Vec<f64>> = members
        .iter()
        .map(|&m| entries[m].layers.iter().map(|l| l.mua_per_mm[i]).collect())
        .collect();
    (stack, sets)
}

/// The units' keys: everything that determines each result (pipeline::KeyBuilder).
pub fn skin_units(
    entries: &[OpticsEntry],
    lambda_nm: &[f64],
    bins: &RadialBins,
    plan: &GroupPlan,
    o: &SimOptions,
) -> SkinUnits {
    let nl = lambda_nm.len();
    let pilot_photons = pilot_photons(o);
    // A noise target's pilots score every bin; a boost's pilots only count events.
    let pilot_bins = if o.noise.is_some() {
        bins.edges_mm().to_vec()
    } else {
        vec![0.0, 1.0]
    };
    let batch = McOptions::new(1, 0).batch_size;
    let mut pilot = Vec::new();
    let mut run = Vec::new();
    for g in 0..plan.groups.len() {
        let mut pk = Vec::new();
        let mut rk = Vec::new();
        let inputs: Vec<(Stack, Vec<Vec<f64>>)> = (0..nl)
            .map(|i| stack_and_sets(entries, plan, g, i))
            .collect();
        if o.noise.is_some() || o.max_boost > 1 {
            for (i, (stack, sets)) in inputs.iter().enumerate() {
                pk.push(
                    KeyBuilder::new("skin-pilot", crate::data::checksum())
                        .part("stack", stack)
                        .part("sets", sets)
                        .part("photons", &pilot_photons)
                        .part("r_edges_mm", &pilot_bins)
                        .part(
                            "seed",
                            &group_wavelength_seed(o.seed ^ PILOT_TAG, plan.digests[g], i),
                        )
                        .part("batch", &batch)
                        .part("random_entry", &true)
                        .finish(),
                );
            }
        }
        let pilots = crate::pipeline::digest_of(&pk);
        for (i, (stack, sets)) in inputs.iter().enumerate() {
            rk.push(
                KeyBuilder::new("skin-run", crate::data::checksum())
                    .part("stack", stack)
                    .part("sets", sets)
                    .part("r_edges_mm", &bins.edges_mm())
                    .part("photons", &o.photons)
                    .part("max_boost", &o.max_boost)
                    .part("noise", &o.noise)
                    .part("lambda_nm", &lambda_nm)
                    .digest("pilots", &pilots)
                    .part("seed", &group_wavelength_seed(o.seed, plan.digests[g], i))
                    .part("batch", &batch)
                    .part("random_entry", &true)
                    .finish(),
            );
        }
        pilot.push(pk);
        run.push(rk);
    }
    SkinUnits {
        pilot,
        run,
        pilot_photons,
    }
}

/// Unit id: `<prefix>/group<g>/<λ>nm` (pilots: `<prefix>/pilot/group<g>/<λ>nm`).
pub fn unit_id(prefix: &str, kind: &str, g: usize, lambda_nm: f64) -> String {
    format!("{prefix}/{kind}group{g}/{lambda_nm}nm")
}

/// What a skin simulation runs: the entries' optics at every wavelength of `lambda_nm`, the
/// radial bins Rd(r) is scored on, the plan of shared simulations and the options.
#[derive(Clone, Copy)]
pub struct SkinSimulation<'a> {
    pub entries: &'a [OpticsEntry],
    pub lambda_nm: &'a [f64],
    pub bins: &'a RadialBins,
    pub plan: &'a GroupPlan,
    pub o: &'a SimOptions,
}

/// [`simulate`] through a [`Runner`]: cached units are read, owned units computed and cached,
/// units of other shards skipped. `Ok(None)` when some units belong to other shards.
pub fn simulate_units(
    sim: &SkinSimulation<'_>,
    runner: &Runner,
    prefix: &str,
    mut on_task: impl FnMut(usize, usize, f64),
) -> anyhow::Result<Option<Vec<SpectralProfile>>> {
    let SkinSimulation {
        entries,
        lambda_nm,
        bins,
        plan,
        o,
    } = *sim;
    let nl = lambda_nm.len();
    let areas = bins.areas_mm2();
    let units = skin_units(entries, lambda_nm, bins, plan, o);
    let mut out: Vec<SpectralProfile> = entries
        .iter()
        .map(|_| empty_profile(lambda_nm, bins))
        .collect();
    let total = plan.groups.len() * nl;
    let mut done = 0;
    let mut complete = true;
    for (g, members) in plan.groups.iter().enumerate() {
        // Photon counts of the group: only needed if this process runs one of its units.
        let mut photons: Option<Vec<u64>> = None;
        for i in 0..nl {
            let t0 = Instant::now();
            let index = g * nl + i;
            let key = units.run[g][i];
            let id = unit_id(prefix, "", g, lambda_nm[i]);
            let needs_compute = runner.cache.load::<WhiteSets>(&key).is_none()
                && runner.owns(Some(index))
                && !runner.require_cached;
            if needs_compute && photons.is_none() {
                photons = Some(photon_counts(sim, &units, runner, prefix, g)?);
            }
            let n_main = photons.as_ref().map_or(o.photons, |p| p[i]);
            let run = runner.unit(&id, key, Some(index), n_main, || {
                let (stack, sets) = stack_and_sets(entries, plan, g, i);
                let mut mo =
                    McOptions::new(n_main, group_wavelength_seed(o.seed, plan.digests[g], i));
                mo.threads = o.threads;
                mo.progress = o.progress.clone();
                mo.cancel = runner.cancel;
                // The profile a renderer applies everywhere: averaged over where the beam
                // meets the junction's papillae (profile/DECISIONS.md, row 1).
                mo.random_entry = true;
                run_white_sets(&stack, &sets, bins, &mo).with_context(|| {
                    format!("entry {} at {} nm", entries[members[0]].name, lambda_nm[i])
                })
            })?;
            done += 1;
            let Some(run) = run else {
                complete = false;
                continue;
            };
            for (&m, t) in members.iter().zip(&run.sets) {
                store_run(&mut out[m], g, i, &run, t, &areas);
            }
            on_task(done, total, t0.elapsed().as_secs_f64());
        }
        if photons.is_none() {
            // The group's pilots were not needed this time; the results still depend on them.
            for (i, &key) in units.pilot[g].iter().enumerate() {
                runner.depends_on(&unit_id(prefix, "pilot/", g, lambda_nm[i]), key);
            }
        }
    }
    Ok(complete.then_some(out))
}

/// A profile on `bins` at every wavelength of `lambda_nm`, all zero.
pub fn empty_profile(lambda_nm: &[f64], bins: &RadialBins) -> SpectralProfile {
    let (nl, nr) = (lambda_nm.len(), bins.len());
    SpectralProfile {
        lambda_nm: lambda_nm.to_vec(),
        r_edges_mm: bins.edges_mm().to_vec(),
        rd_per_mm2: vec![vec![0.0; nr]; nl],
        rd_per_mm2_se: vec![vec![0.0; nr]; nl],
        rd_total: vec![0.0; nl],
        rd_total_se: vec![0.0; nl],
        rd_unscattered: vec![0.0; nl],
        tt: vec![0.0; nl],
        tt_se: vec![0.0; nl],
        rsp: vec![0.0; nl],
        photons: vec![0; nl],
        group: 0,
    }
}

/// Stores absorption set `t` of group `g`'s run at wavelength index `i` in profile `p`: the
/// means over the run's photons, Rd(r) per unit area of each annulus (of area `areas`, mm²).
pub fn store_run(
    p: &mut SpectralProfile,
    g: usize,
    i: usize,
    run: &WhiteSets,
    t: &SetTally,
    areas: &[f64],
) {
    let n = run.photons;
    p.group = g;
    p.photons[i] = n;
    p.rsp[i] = run.rsp;
    p.rd_total[i] = t.rd.mean(n);
    p.rd_total_se[i] = t.rd.se(n);
    p.rd_unscattered[i] = t.rd_unscattered.mean(n);
    p.tt[i] = t.tt.mean(n);
    p.tt_se[i] = t.tt.se(n);
    for k in 0..areas.len() {
        p.rd_per_mm2[i][k] = t.rd_r[k].mean(n) / areas[k];
        p.rd_per_mm2_se[i][k] = t.rd_r[k].se(n) / areas[k];
    }
}

/// Packets of each pilot run: 2.5 % of `photons` (at most 100,000) for a noise target, whose
/// pilots estimate per-bin variances; 1 % (at most 20,000) for a boost, which counts events.
pub fn pilot_photons(o: &SimOptions) -> u64 {
    if o.noise.is_some() {
        (o.photons / 40)
            .clamp(2_000, NOISE_PILOT_MAX)
            .min(o.photons)
    } else {
        (o.photons / 100)
            .clamp(2_000, BOOST_PILOT_MAX)
            .min(o.photons)
    }
}

/// Photons of group `g` per wavelength:
/// - with a noise target, [`allocate`]'s counts from the group's pilot runs;
/// - with a boost, `o.photons` times an integer boost ⌊e_max/e_λ⌋ capped at `o.max_boost`,
///   e_λ the scattering events per packet of the pilot and e_max the group's largest. Cheap
///   wavelengths — strongly absorbed blue light, where dark skin's profiles are noisiest — get
///   more packets for about the cost of the group's most expensive wavelength;
/// - else `o.photons`.
///
/// Deterministic: the pilots are seeded like the main runs.
fn photon_counts(
    sim: &SkinSimulation<'_>,
    units: &SkinUnits,
    runner: &Runner,
    prefix: &str,
    g: usize,
) -> anyhow::Result<Vec<u64>> {
    let SkinSimulation {
        entries,
        lambda_nm,
        bins,
        plan,
        o,
    } = *sim;
    let nl = lambda_nm.len();
    if o.noise.is_none() && o.max_boost <= 1 {
        return Ok(vec![o.photons; nl]);
    }
    let pilot = units.pilot_photons;
    let pilot_bins = match o.noise {
        Some(_) => bins.clone(),
        None => RadialBins::uniform(1.0, 1),
    };
    let mut runs = Vec::with_capacity(nl);
    for i in 0..nl {
        let id = unit_id(prefix, "pilot/", g, lambda_nm[i]);
        let run = runner
            .side_unit(&id, units.pilot[g][i], pilot, || {
                let (stack, sets) = stack_and_sets(entries, plan, g, i);
                let mut mo = McOptions::new(
                    pilot,
                    group_wavelength_seed(o.seed ^ PILOT_TAG, plan.digests[g], i),
                );
                mo.threads = o.threads;
                mo.random_entry = true;
                mo.cancel = runner.cancel;
                run_white_sets(&stack, &sets, &pilot_bins, &mo).with_context(|| {
                    format!(
                        "entry {} at {} nm",
                        entries[plan.groups[g][0]].name, lambda_nm[i]
                    )
                })
            })?
            .expect("pilot units are never sharded");
        runs.push(run);
    }
    if let Some(target) = &o.noise {
        let colour = crate::spectral::ColourMap::new(lambda_nm);
        return Ok(allocate(&runs, bins, &colour.rgb_weights, target));
    }
    let events: Vec<f64> = runs
        .iter()
        .map(|r| (r.scattering_events as f64 / r.photons as f64).max(1.0))
        .collect();
    let e_max = events.iter().cloned().fold(1.0, f64::max);
    Ok(events
        .iter()
        .map(|e| o.photons * ((e_max / e).floor() as u64).clamp(1, o.max_boost))
        .collect())
}

/// Seeds of the pilot runs differ from those of the main runs.
const PILOT_TAG: u64 = 0x5049_4c4f_545f_5255; // "PILOT_RU"

#[cfg(test)]
mod tests {
    use super::*;
    use crate::skin::{self, BodyLocation, Gender, MelaninInput, SkinParams, SkinType};
    use crate::spectral::WavelengthGrid;

    fn entry(t: SkinType, age: f64) -> OpticsEntry {
        let p = SkinParams::new(
            age,
            Gender::Female,
            BodyLocation::Face,
            MelaninInput::SkinType(t),
            0.5,
        );
        let grid = WavelengthGrid::uniform(450.0, 650.0, 100.0);
        skin::document::entry("e", &p, &skin::evaluate(&p, &grid).unwrap())
    }

    /// Entries that differ only in absorption share one simulation with reuse; without it each
    /// is its own group, and their groups' digests (part of the cache keys) differ, so two
    /// such entries can never read each other's cached runs.
    #[test]
    fn groups_share_scattering_and_digests_tell_absorption_apart_without_reuse() {
        let es = [
            entry(SkinType::I, 30.0),
            entry(SkinType::VI, 30.0),
            entry(SkinType::I, 80.0),
        ];
        let shared = plan(&es, 3, true);
        assert_eq!(shared.groups, vec![vec![0, 1], vec![2]]);
        let own = plan(&es, 3, false);
        assert_eq!(own.groups, vec![vec![0], vec![1], vec![2]]);
        assert_ne!(own.digests[0], own.digests[1]);
        assert_ne!(own.digests[0], shared.digests[0]);
        assert_eq!(shared.digests.len(), 2);
    }

    /// Unit ids name the spec, the kind, the group and the wavelength (they appear in
    /// `baker plan`, the progress events and the cache's roots).
    #[test]
    fn unit_ids_name_group_and_wavelength() {
        assert_eq!(unit_id("db", "pilot/", 3, 550.0), "db/pilot/group3/550nm");
        assert_eq!(unit_id("db", "", 0, 412.5), "db/group0/412.5nm");
    }
}
