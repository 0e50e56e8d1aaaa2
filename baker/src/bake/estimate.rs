//! `baker plan`'s time estimate: a short calibration run of the spec's own units (a few
//! photons of sampled simulation groups and wavelengths, or of a fiber entry's directions,
//! with the real transport, and a shortened Gaussian fit of a profile from those photons),
//! scaled by each unit's photons and the bake's threads.

use std::time::Instant;

use crate::fit::GaussianFitOptions;
use crate::profile::{self, GroupPlan, SimOptions, SpectralProfile};
use crate::spectral::ColourMap;
use crate::transport::{run_white_sets, McOptions, RadialBins};

/// Simulation groups and wavelengths the calibration traces (spread over the spec's).
const MAX_GROUPS: usize = 4;
const MAX_WAVELENGTHS: usize = 8;
/// Each sampled unit is traced until it took this long (photons ×4 per try).
const MIN_SECONDS: f64 = 0.02;
const MIN_PHOTONS: u64 = 256;
/// The fit is timed with a tenth of its simplex evaluations, then scaled by `FIT_SCALE`, not
/// 10: a whole fit stops restarting once it stops improving, a shortened one rarely does.
/// Measured on tests/specs/profiles_small.yaml (20,000 photons, 2 threads): ×10 predicted
/// 41 s of fits against 17.7 s.
const FIT_SHORTEN: usize = 10;
const FIT_SCALE: f64 = 4.0;

/// What one simulation unit costs: seconds per photon on one thread, scattering events per
/// photon (the boost's measure).
#[derive(Debug, Clone, Copy)]
pub struct UnitCost {
    pub seconds_per_photon: f64,
    pub events_per_photon: f64,
}

/// A skin spec's calibration: the cost of every group × wavelength (sampled ones measured,
/// the others those of the nearest sampled group and wavelength) and of one fit.
#[derive(Debug, Clone)]
pub struct SkinCalibration {
    pub cost: Vec<Vec<UnitCost>>,
    /// Seconds of one entry's Gaussian fit on one thread.
    pub fit_seconds: f64,
    /// Wall-clock seconds the calibration took.
    pub seconds: f64,
}

/// `n` indices spread over `0..len`, first and last included.
fn spread(len: usize, n: usize) -> Vec<usize> {
    if len <= n {
        return (0..len).collect();
    }
    let mut v: Vec<usize> = (0..n).map(|k| k * (len - 1) / (n - 1)).collect();
    v.dedup();
    v
}

fn nearest(samples: &[usize], i: usize) -> usize {
    let mut best = 0;
    for (k, &s) in samples.iter().enumerate() {
        if s.abs_diff(i) < samples[best].abs_diff(i) {
            best = k;
        }
    }
    best
}

/// What a skin calibration traces.
pub struct SkinInputs<'a> {
    pub entries: &'a [formats::OpticsEntry],
    pub lambda_nm: &'a [f64],
    pub bins: &'a RadialBins,
    pub plan: &'a GroupPlan,
    pub sim: &'a SimOptions,
    pub gaussians: usize,
}

/// Traces sampled units of a skin spec and times a fit.
pub fn calibrate_skin(x: &SkinInputs<'_>) -> anyhow::Result<SkinCalibration> {
    let t0 = Instant::now();
    let (nl, ng) = (x.lambda_nm.len(), x.plan.groups.len());
    let gs = spread(ng, MAX_GROUPS);
    let ls = spread(nl, MAX_WAVELENGTHS);
    let mut measured = Vec::new();
    // The first sampled group's runs make a profile for the fit's timing.
    let mut profile = profile::simulate::empty_profile(x.lambda_nm, x.bins);
    let areas = x.bins.areas_mm2();
    for &g in &gs {
        let mut row = Vec::new();
        for &i in &ls {
            let (stack, sets) = profile::simulate::stack_and_sets(x.entries, x.plan, g, i);
            let mut n = MIN_PHOTONS;
            let run = loop {
                let mut mo = McOptions::new(n, x.sim.seed ^ 0xca1b ^ (g * nl + i) as u64);
                mo.threads = Some(1);
                mo.batch_size = n;
                mo.random_entry = true;
                let t = Instant::now();
                let run = run_white_sets(&stack, &sets, x.bins, &mo)?;
                let s = t.elapsed().as_secs_f64();
                if s >= MIN_SECONDS || n >= 1 << 20 {
                    break (run, s);
                }
                n *= 4;
            };
            let (run, s) = run;
            if g == gs[0] {
                for k in (0..nl).filter(|&k| ls[nearest(&ls, k)] == i) {
                    profile::simulate::store_run(&mut profile, g, k, &run, &run.sets[0], &areas);
                }
            }
            row.push(UnitCost {
                seconds_per_photon: s / run.photons.max(1) as f64,
                events_per_photon: (run.scattering_events as f64 / run.photons.max(1) as f64)
                    .max(1.0),
            });
        }
        measured.push(row);
    }
    let cost = (0..ng)
        .map(|g| {
            let row = &measured[nearest(&gs, g)];
            (0..nl).map(|i| row[nearest(&ls, i)]).collect()
        })
        .collect();
    let fit_seconds = time_fit(&profile, x.lambda_nm, x.gaussians)?;
    Ok(SkinCalibration {
        cost,
        fit_seconds,
        seconds: t0.elapsed().as_secs_f64(),
    })
}

/// Seconds of a whole fit of `p`, from a fit with a tenth of the evaluations.
fn time_fit(p: &SpectralProfile, lambda_nm: &[f64], gaussians: usize) -> anyhow::Result<f64> {
    let colour = ColourMap::new(lambda_nm);
    let full = GaussianFitOptions::default();
    let o = GaussianFitOptions {
        count: gaussians,
        max_evaluations: full.max_evaluations / FIT_SHORTEN,
        ..full
    };
    let t = Instant::now();
    profile::rgb::rgb_profile_with(p, &colour, &o)?;
    Ok(t.elapsed().as_secs_f64() * FIT_SCALE)
}

/// Seconds of `photons` photons at `cost` on `threads` threads, in batches of `batch`
/// photons (a run uses at most one thread per batch).
pub fn transport_seconds(photons: u64, cost: UnitCost, threads: usize, batch: u64) -> f64 {
    let usable = photons
        .div_ceil(batch.max(1))
        .clamp(1, threads.max(1) as u64);
    photons as f64 * cost.seconds_per_photon / usable as f64
}

/// Photons of each wavelength of group `g` after the boost of cheap wavelengths (as the
/// bake's pilots will choose them, from the calibration's scattering events); without a
/// boost (or with a noise target, whose counts the pilots allocate) `photons`.
pub fn boosted(photons: u64, costs: &[UnitCost], sim: &SimOptions) -> Vec<u64> {
    if sim.noise.is_some() || sim.max_boost <= 1 {
        return vec![photons; costs.len()];
    }
    let e_max = costs
        .iter()
        .map(|c| c.events_per_photon)
        .fold(1.0, f64::max);
    costs
        .iter()
        .map(|c| photons * ((e_max / c.events_per_photon).floor() as u64).clamp(1, sim.max_boost))
        .collect()
}
