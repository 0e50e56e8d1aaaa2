//! What a profile bake tells people when it is done.

use std::time::Instant;

use crate::bake::job::Job;
use crate::profile::{self, RgbProfile, SpectralProfile};
use crate::spec::skin::profiles::NOISE_R_MAX_MM;

/// The summary of a profile bake for people: photons, speed, and per channel the worst fit
/// error and the worst relative standard error. `seconds` are (simulation, fits).
pub(super) fn print(
    job: &Job,
    entries: &[formats::OpticsEntry],
    spectral: &[SpectralProfile],
    rgb: &[RgbProfile],
    plan: &profile::GroupPlan,
    t0: Instant,
    (sim_seconds, fit_seconds): (f64, f64),
) {
    let (path, dir) = (job.path, job.shown());
    let events = &job.runner.events;
    let n_sims = plan.groups.len() * spectral.first().map_or(0, |p| p.lambda_nm.len());
    let total_photons: f64 = plan
        .groups
        .iter()
        .map(|g| spectral[g[0]].photons.iter().sum::<u64>() as f64)
        .sum();
    events.say(format!(
        "baked {}: {} entries, {n_sims} simulations, {:.3e} photons in {sim_seconds:.1} s ({:.0} photons/s), fits {fit_seconds:.1} s → {} ({:.1} s)",
        path.display(),
        entries.len(),
        total_photons,
        total_photons / sim_seconds.max(1e-9),
        dir.display(),
        t0.elapsed().as_secs_f64()
    ));
    for c in 0..3 {
        let (k, worst) = rgb
            .iter()
            .enumerate()
            .map(|(k, r)| (k, r.fit.error_rgb[c]))
            .fold((0, 0.0), |a, b| if b.1 > a.1 { b } else { a });
        // Largest relative standard error of the channel's profile out to 2 mm, inside the
        // channel's 99 % radius (beyond it a channel may cross zero: deep-red light is out of
        // the sRGB gamut, so G and B tails are tiny and can be negative).
        let per_entry: Vec<f64> = rgb
            .iter()
            .enumerate()
            .map(|(k, r)| max_relative_se(&spectral[k].r_edges_mm, r, c, NOISE_R_MAX_MM))
            .collect();
        let (ks, se) = per_entry
            .iter()
            .copied()
            .enumerate()
            .fold((0, 0.0), |a, b| if b.1 > a.1 { b } else { a });
        let within = per_entry.iter().filter(|&&x| x <= 0.01).count();
        events.say(format!(
            "  {}: worst fit error {:.2} % ({}), worst relative SE for r ≤ min(2 mm, r99) {:.2} % ({}), ≤ 1 % for {within} of {} entries",
            ["R", "G", "B"][c],
            100.0 * worst,
            entries[k].name,
            100.0 * se,
            entries[ks].name,
            per_entry.len()
        ));
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
