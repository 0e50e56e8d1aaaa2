//! Photons per wavelength for a noise target: a short pilot run per wavelength measures what a
//! packet of each wavelength costs and how much it contributes to the variance of every RGB
//! profile bin; the main runs then get the packet counts that meet the target at the least
//! cost.
//!
//! The RGB value of a bin is Σ_λ w_λ·Rd_λ (linear sRGB weights `w`), and the wavelengths are
//! simulated independently, so its variance with N_λ packets at λ is Σ_λ a_λ/N_λ with
//! a_λ = w_λ²·σ²_λ (σ²_λ the per-packet variance of Rd_λ in that bin). Minimising the work
//! Σ_λ c_λ·N_λ under such constraints for every bin is a convex problem; with one constraint its
//! solution is Neyman's allocation N_λ ∝ |w_λ|·σ_λ/√c_λ (Neyman 1934[^neyman34]). Here there is
//! one constraint per bin, channel and entry of the group, so a greedy search solves it: while
//! some bin misses its target, the wavelength whose extra packets lower that bin's variance the
//! most per unit of work gets 5 % more. On the default database this comes within 1 % of the
//! optimum found by a general solver (SLSQP) on the same pilot data (validation record
//! 2026-12-02).
//!
//! Which bins, and which target: the bins of each channel whose centre lies within
//! min(`r_max_mm`, the channel's 99 % radius) — where the bake's summary measures noise
//! (DECISIONS.md row 7) — each held to a relative standard error of
//! max(`target_rel_se`, what `reference` packets at every wavelength would give). So the
//! result is never noisier than the uniform bake of `reference` packets (up to the pilot's own
//! error), and bins the uniform bake makes better than the target are relaxed to it.
//!
//! [^neyman34]: J. Neyman, "On the two different aspects of the representative method",
//! Journal of the Royal Statistical Society 97(4), 558–606 (1934).

use crate::spec::skin::profiles::{MAX_SHARE, MIN_SHARE, NOISE_R_MAX_MM};
use crate::transport::radial::radius_of_energy;
use crate::transport::white::WhiteSets;
use crate::transport::RadialBins;

/// What the allocation aims at.
#[derive(Debug, Clone, PartialEq)]
pub struct NoiseTarget {
    /// Relative standard error each bin may relax to.
    pub target_rel_se: f64,
    /// Packets per wavelength of the uniform bake the result must not be noisier than.
    pub reference: u64,
    /// Bins beyond this radius are not held to the target, mm.
    pub r_max_mm: f64,
    /// Fewest and most packets any wavelength gets.
    pub min_photons: u64,
    pub max_photons: u64,
}

impl NoiseTarget {
    /// A target of `target_rel_se` (0: none) over a reference of `reference` packets per
    /// wavelength, with the default radius and bounds.
    pub fn new(target_rel_se: f64, reference: u64) -> Option<Self> {
        (target_rel_se > 0.0).then(|| NoiseTarget {
            target_rel_se,
            reference,
            r_max_mm: NOISE_R_MAX_MM,
            min_photons: (reference / MIN_SHARE).max(1),
            max_photons: reference.saturating_mul(MAX_SHARE),
        })
    }
}

/// Work of a packet, in units of one scattering event: its events, its evaluations of the
/// junction's height field (each 0.65 of an event) and a fixed part for the launch and the
/// scoring of its exit (11 events). Fitted by least squares to the wall time of the 31 pilot
/// runs of the default database's age-30 group (100,000 packets each, one thread: 0.080 µs per
/// event, 0.052 µs per junction evaluation, 0.91 µs per packet; rms residual 4.6 %). Deterministic
/// counts, not measured time, so that the allocation and hence the results are the same on
/// every machine. The faster junction search of 2026-12-02 (second record) needs fewer
/// evaluations per crossing but costs about the same per evaluation (50 vs 55 ns on 3·10⁶ rays
/// recorded from the age-30 bake), so the constant stands.
const PACKET_OVERHEAD_EVENTS: f64 = 11.0;
const JUNCTION_EVAL_EVENTS: f64 = 0.65;

/// The target is aimed at with this margin for the pilots' own error (their per-bin variances
/// are estimates: at the pilot's 2.5 % of the packets, a bin's relative SE is off by a few %).
const TARGET_MARGIN: f64 = 0.95;

/// Growth of a wavelength's count per greedy step.
const STEP: f64 = 1.05;

/// One constraint: per wavelength its variance per packet, and the variance allowed.
struct Constraint {
    a: Vec<f64>,
    limit: f64,
}

/// Packets per wavelength of one simulation group: `pilots[λ]` is the group's pilot run at
/// wavelength λ (every member's absorption set scored on `bins`), `rgb_weights[λ]` the linear
/// sRGB weight of λ.
pub fn allocate(
    pilots: &[WhiteSets],
    bins: &RadialBins,
    rgb_weights: &[[f64; 3]],
    target: &NoiseTarget,
) -> Vec<u64> {
    let nl = pilots.len();
    let cost: Vec<f64> = pilots
        .iter()
        .map(|p| {
            (p.scattering_events as f64 + JUNCTION_EVAL_EVENTS * p.junction_evals as f64)
                / p.photons.max(1) as f64
                + PACKET_OVERHEAD_EVENTS
        })
        .collect();
    let constraints = constraints(pilots, bins, rgb_weights, target);
    let (lo, hi) = (target.min_photons as f64, target.max_photons as f64);
    let mut n = vec![lo; nl];
    // Variance of every constraint at the current counts, kept up to date.
    let mut var: Vec<f64> = constraints
        .iter()
        .map(|c| c.a.iter().zip(&n).map(|(a, n)| a / n).sum())
        .collect();
    // While some constraint is over its limit, the one furthest over it.
    while let Some((j, ratio)) = var
        .iter()
        .zip(&constraints)
        .map(|(v, c)| v / c.limit)
        .enumerate()
        .max_by(|a, b| a.1.total_cmp(&b.1))
    {
        if ratio <= 1.0 {
            break;
        }
        // The wavelength that lowers it most per unit of work: −∂var/∂N per cost.
        let best = (0..nl)
            .filter(|&l| n[l] < hi)
            .map(|l| (l, constraints[j].a[l] / (n[l] * n[l] * cost[l])))
            .filter(|&(_, g)| g > 0.0)
            .max_by(|a, b| a.1.total_cmp(&b.1));
        let Some((l, _)) = best else {
            // Nothing left to raise: the target is out of reach within `max_photons`.
            break;
        };
        let grown = (n[l] * STEP).min(hi);
        for (v, c) in var.iter_mut().zip(&constraints) {
            *v += c.a[l] * (1.0 / grown - 1.0 / n[l]);
        }
        n[l] = grown;
    }
    let allocated: Vec<u64> = n.iter().map(|&x| x.ceil() as u64).collect();
    // Never more work than the uniform bake the target refers to.
    let work =
        |counts: &[u64]| -> f64 { counts.iter().zip(&cost).map(|(&n, c)| n as f64 * c).sum() };
    let uniform = vec![target.reference; nl];
    if work(&allocated) > work(&uniform) {
        uniform
    } else {
        allocated
    }
}

/// Every bin, channel and member the target holds, from the pilots' means and per-packet
/// variances.
fn constraints(
    pilots: &[WhiteSets],
    bins: &RadialBins,
    rgb_weights: &[[f64; 3]],
    target: &NoiseTarget,
) -> Vec<Constraint> {
    let nl = pilots.len();
    let edges = bins.edges_mm();
    let areas = bins.areas_mm2();
    let nr = areas.len();
    let members = pilots.first().map_or(0, |p| p.sets.len());
    let mut out = Vec::new();
    for m in 0..members {
        // Per wavelength and bin: mean Rd per area and per-packet variance of it.
        let mut mean = vec![vec![0.0; nr]; nl];
        let mut var = vec![vec![0.0; nr]; nl];
        for (l, p) in pilots.iter().enumerate() {
            let n = p.photons.max(1) as f64;
            for k in 0..nr {
                let s = &p.sets[m].rd_r[k];
                let mu = s.sum / n;
                mean[l][k] = mu / areas[k];
                var[l][k] = (s.sum2 / n - mu * mu).max(0.0) / (areas[k] * areas[k]);
            }
        }
        for c in [0usize, 1, 2] {
            let value: Vec<f64> = (0..nr)
                .map(|k| (0..nl).map(|l| rgb_weights[l][c] * mean[l][k]).sum())
                .collect();
            let albedo: f64 = (0..nl)
                .map(|l| {
                    rgb_weights[l][c] * pilots[l].sets[m].rd.sum / pilots[l].photons.max(1) as f64
                })
                .sum();
            let r99 = radius_of_energy(edges, value.iter().copied(), 0.99 * albedo);
            let r_limit = target
                .r_max_mm
                .min(if r99.is_finite() { r99 } else { f64::INFINITY });
            for k in 0..nr {
                if 0.5 * (edges[k] + edges[k + 1]) > r_limit || value[k] == 0.0 {
                    continue;
                }
                let a: Vec<f64> = (0..nl)
                    .map(|l| rgb_weights[l][c] * rgb_weights[l][c] * var[l][k])
                    .collect();
                let uniform: f64 = a.iter().sum::<f64>() / target.reference as f64;
                let limit = uniform.max((TARGET_MARGIN * target.target_rel_se * value[k]).powi(2));
                if limit > 0.0 {
                    out.push(Constraint { a, limit });
                }
            }
        }
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::stats::Sums;
    use crate::transport::SetTally;

    /// A pilot whose one member has, in every bin, mean `mu` and per-packet standard deviation
    /// `sd` per unit area, at `events` per packet.
    fn pilot(bins: &RadialBins, mu: f64, sd: f64, events: f64) -> WhiteSets {
        let n = 10_000u64;
        let areas = bins.areas_mm2();
        let rd_r: Vec<Sums> = areas
            .iter()
            .map(|a| {
                let (m, s) = (mu * a, sd * a);
                Sums {
                    sum: m * n as f64,
                    sum2: (s * s + m * m) * n as f64,
                }
            })
            .collect();
        let total: f64 = rd_r.iter().map(|s| s.sum).sum();
        WhiteSets {
            photons: n,
            rsp: 0.0,
            sets: vec![SetTally {
                rd: Sums {
                    sum: total,
                    sum2: 0.0,
                },
                rd_unscattered: Sums::default(),
                tt: Sums::default(),
                rd_r,
            }],
            scattering_events: (events * n as f64) as u64,
            junction_evals: 0,
            threads: 1,
            seconds: 0.0,
        }
    }

    fn target(reference: u64, rel: f64) -> NoiseTarget {
        NoiseTarget {
            target_rel_se: rel,
            reference,
            r_max_mm: 2.0,
            min_photons: reference / 10,
            max_photons: reference * 4,
        }
    }

    #[test]
    fn one_channel_follows_neyman_allocation() {
        // Two wavelengths feeding R alone, equal cost: N ∝ |w|·σ.
        let bins = RadialBins::uniform(0.5, 4);
        let pilots = vec![pilot(&bins, 1.0, 4.0, 50.0), pilot(&bins, 1.0, 1.0, 50.0)];
        let w = [[0.5, 0.0, 0.0], [0.5, 0.0, 0.0]];
        // Target: the noise of 10⁶ packets each.
        let n = allocate(&pilots, &bins, &w, &target(1_000_000, 0.0));
        let ratio = n[0] as f64 / n[1] as f64;
        assert!((ratio / 4.0 - 1.0).abs() < 0.12, "{n:?}");
        // Σ a/N meets the uniform bake's variance with less work.
        let var = |n0: f64, n1: f64| 0.25 * 16.0 / n0 + 0.25 / n1;
        assert!(var(n[0] as f64, n[1] as f64) <= var(1e6, 1e6) * 1.0001);
        assert!(n[0] + n[1] < 2_000_000);
    }

    #[test]
    fn a_loose_target_relaxes_and_never_costs_more_than_uniform() {
        let bins = RadialBins::uniform(0.5, 4);
        let pilots = vec![pilot(&bins, 1.0, 2.0, 50.0), pilot(&bins, 1.0, 2.0, 10.0)];
        let w = [[0.5, 0.5, 0.5], [0.5, 0.5, 0.5]];
        // A target far looser than the reference gives: every wavelength at the floor.
        let n = allocate(&pilots, &bins, &w, &target(1_000_000, 0.5));
        assert_eq!(n, vec![100_000, 100_000]);
        // A target tighter than reachable: capped, never above the uniform bake's work.
        let n = allocate(&pilots, &bins, &w, &target(1_000, 1e-6));
        let work = |n: &[u64]| n[0] as f64 * 61.0 + n[1] as f64 * 21.0;
        assert!(work(&n) <= work(&[1_000, 1_000]), "{n:?}");
    }

    #[test]
    fn cheap_wavelengths_get_more_packets() {
        // Equal variance and weight, one five times dearer per packet: N ∝ 1/√c.
        let bins = RadialBins::uniform(0.5, 4);
        let pilots = vec![pilot(&bins, 1.0, 1.0, 235.0), pilot(&bins, 1.0, 1.0, 35.0)];
        let w = [[0.5, 0.0, 0.0], [0.5, 0.0, 0.0]];
        let n = allocate(&pilots, &bins, &w, &target(1_000_000, 0.0));
        let expected = ((235.0 + PACKET_OVERHEAD_EVENTS) / (35.0 + PACKET_OVERHEAD_EVENTS)).sqrt();
        let ratio = n[1] as f64 / n[0] as f64;
        assert!(
            (ratio / expected - 1.0).abs() < 0.12,
            "{n:?} vs √(c ratio) {expected}"
        );
    }

    /// Only bins inside each channel's 99 % energy radius (from the pilots' own Rd and Rd(r))
    /// are held to the target: here 99 % of the energy lies within 1.47 mm, so the bins
    /// centred at 0.25, 0.75 and 1.25 mm count and the five beyond do not, in each channel.
    #[test]
    fn constraints_stop_at_the_99_percent_radius() {
        let bins = RadialBins::uniform(0.5, 8);
        let energy = [0.6, 0.3, 0.095, 0.004, 0.0009, 0.00009, 0.000009, 0.000001];
        let mut p = pilot(&bins, 1.0, 1.0, 10.0);
        let n = p.photons as f64;
        for (s, e) in p.sets[0].rd_r.iter_mut().zip(energy) {
            *s = Sums {
                sum: e * n,
                sum2: 2.0 * e * e * n,
            };
        }
        p.sets[0].rd.sum = energy.iter().sum::<f64>() * n;
        let t = NoiseTarget {
            r_max_mm: 100.0,
            ..target(1_000, 0.05)
        };
        let c = constraints(&[p], &bins, &[[1.0, 1.0, 1.0]], &t);
        assert_eq!(c.len(), 3 * 3);
    }
}
