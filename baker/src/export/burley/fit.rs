//! The per-channel fit of (A, d) to a baked profile (see the module docs, "The fit").

use std::f64::consts::PI;

use super::profile::burley_energy;

/// Why a channel cannot be fitted.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum BurleyError {
    /// The radial grid is not 0 = e₀ < e₁ < … or does not match the table.
    #[error("radial grid: {0}")]
    Grid(String),
    /// No positive energy inside the fitted radius: nothing to fit.
    #[error("no positive energy in the {bins} bins inside r99 = {r99_mm} mm")]
    NoEnergy { bins: usize, r99_mm: f64 },
}

/// The fit of one channel.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct BurleyFit {
    /// Surface albedo A (the profile's integral over the plane).
    pub a: f64,
    /// Shape parameter d, mm.
    pub d_mm: f64,
    /// Energy-weighted relative L1 error (FORMAT.md's fit error), over the bins inside r99.
    pub error: f64,
}

/// The bins that count for a channel with 99 % radius `r99_mm`: k with `edges[k] < r99`, and
/// bin 0 always (FORMAT.md; the same rule as `fit::gaussians::fit_error`). NaN or ∞ = all.
pub fn bins_inside(edges_mm: &[f64], r99_mm: f64) -> usize {
    let nr = edges_mm.len().saturating_sub(1);
    if r99_mm.is_nan() {
        return nr;
    }
    let n = edges_mm[..nr].iter().take_while(|&&a| a < r99_mm).count();
    n.max(nr.min(1))
}

/// FORMAT.md's energy-weighted relative L1 error of the profile (A, d) against one channel of
/// a table (`table_per_mm2`, annulus averages), over the bins inside `r99_mm`.
pub fn fit_error(edges_mm: &[f64], table_per_mm2: &[f64], r99_mm: f64, a: f64, d_mm: f64) -> f64 {
    let n = bins_inside(edges_mm, r99_mm).min(table_per_mm2.len());
    let (mut num, mut den) = (0.0, 0.0);
    for k in 0..n {
        let (lo, hi) = (edges_mm[k], edges_mm[k + 1]);
        let t = table_per_mm2[k] * PI * (hi * hi - lo * lo);
        num += (a * burley_energy(d_mm, lo, hi) - t).abs();
        den += t;
    }
    num / den
}

/// The channel data a fit works on: annulus energies T_k of the counted bins.
struct Channel<'a> {
    edges_mm: &'a [f64],
    energy: Vec<f64>,
    total: f64,
}

impl Channel<'_> {
    /// For shape `d_mm`: the L1-optimal A (weighted median of T_k/E_k, weights E_k) and the
    /// error it leaves. `scratch` avoids an allocation per evaluation.
    fn best_a(&self, d_mm: f64, scratch: &mut Vec<(f64, f64)>) -> (f64, f64) {
        scratch.clear();
        let mut weight = 0.0;
        for (k, &t) in self.energy.iter().enumerate() {
            let e = burley_energy(d_mm, self.edges_mm[k], self.edges_mm[k + 1]);
            if e > 0.0 {
                scratch.push((t / e, e));
                weight += e;
            }
        }
        let a = if weight > 0.0 {
            scratch.sort_by(|x, y| x.0.total_cmp(&y.0));
            let mut cum = 0.0;
            let mut med = scratch.last().map_or(0.0, |p| p.0);
            for &(ratio, e) in scratch.iter() {
                cum += e;
                if cum >= 0.5 * weight {
                    med = ratio;
                    break;
                }
            }
            // A negative albedo is never optimal for a physical profile; keep A ≥ 0.
            med.max(0.0)
        } else {
            0.0
        };
        let mut num = 0.0;
        for (k, &t) in self.energy.iter().enumerate() {
            let e = burley_energy(d_mm, self.edges_mm[k], self.edges_mm[k + 1]);
            num += (a * e - t).abs();
        }
        (a, num / self.total)
    }
}

/// Log-spaced shapes scanned before the golden-section refinement.
const SCAN_POINTS: usize = 241;

/// Golden-section stopping width in ln d (relative precision of d).
const LN_D_TOLERANCE: f64 = 1e-10;

/// Fits A and d to one channel: `table_per_mm2[k]` is the annulus average of bin
/// \[`edges_mm[k]`, `edges_mm[k+1]`), `r99_mm` the channel's 99 % radius (NaN: use every bin).
pub fn fit_channel(
    edges_mm: &[f64],
    table_per_mm2: &[f64],
    r99_mm: f64,
) -> Result<BurleyFit, BurleyError> {
    if edges_mm.len() != table_per_mm2.len() + 1 || table_per_mm2.is_empty() {
        return Err(BurleyError::Grid(format!(
            "{} edges for {} bins",
            edges_mm.len(),
            table_per_mm2.len()
        )));
    }
    if edges_mm[0] != 0.0
        || !edges_mm.iter().all(|e| e.is_finite())
        || edges_mm.windows(2).any(|w| w[0] >= w[1])
    {
        return Err(BurleyError::Grid(
            "edges must start at 0 and increase strictly".into(),
        ));
    }
    let n = bins_inside(edges_mm, r99_mm);
    let energy: Vec<f64> = (0..n)
        .map(|k| {
            let (a, b) = (edges_mm[k], edges_mm[k + 1]);
            table_per_mm2[k] * PI * (b * b - a * a)
        })
        .collect();
    let total: f64 = energy.iter().sum();
    if total.is_nan() || total <= 0.0 {
        return Err(BurleyError::NoEnergy { bins: n, r99_mm });
    }
    let ch = Channel {
        edges_mm,
        energy,
        total,
    };
    let mut scratch = Vec::with_capacity(n);
    let mut eval = |ln_d: f64| ch.best_a(ln_d.exp(), &mut scratch).1;

    // d ≈ r99/13 for a pure Burley profile (F(13d) ≈ 0.99); scan far beyond both ends of the
    // counted grid so neither a one-bin spike nor a flat tail sits on the boundary.
    let lo = (edges_mm[1] * 1e-2).ln();
    let hi = (edges_mm[n] * 10.0).ln();
    let step = (hi - lo) / (SCAN_POINTS - 1) as f64;
    let (mut best_i, mut best_f) = (0, f64::INFINITY);
    for i in 0..SCAN_POINTS {
        let f = eval(lo + step * i as f64);
        if f < best_f {
            (best_i, best_f) = (i, f);
        }
    }
    // Golden section on the bracket around the best scan point.
    let mut a = lo + step * best_i.saturating_sub(1) as f64;
    let mut b = lo + step * (best_i + 1).min(SCAN_POINTS - 1) as f64;
    let inv_phi = (5f64.sqrt() - 1.0) / 2.0;
    let mut x1 = b - inv_phi * (b - a);
    let mut x2 = a + inv_phi * (b - a);
    let (mut f1, mut f2) = (eval(x1), eval(x2));
    while b - a > LN_D_TOLERANCE {
        if f1 <= f2 {
            (b, x2, f2) = (x2, x1, f1);
            x1 = b - inv_phi * (b - a);
            f1 = eval(x1);
        } else {
            (a, x1, f1) = (x1, x2, f2);
            x2 = a + inv_phi * (b - a);
            f2 = eval(x2);
        }
    }
    let mut ln_d = 0.5 * (a + b);
    // The scan point itself may beat the refined one (kinks of an L1 objective).
    if eval(ln_d) > best_f {
        ln_d = lo + step * best_i as f64;
    }
    let d_mm = ln_d.exp();
    let (a, error) = ch.best_a(d_mm, &mut scratch);
    Ok(BurleyFit { a, d_mm, error })
}

/// Fits each channel of an RGB table (`table_rgb_per_mm2[k][c]`) with its own 99 % radius.
pub fn fit_rgb(
    edges_mm: &[f64],
    table_rgb_per_mm2: &[[f64; 3]],
    r99_mm: [f64; 3],
) -> Result<[BurleyFit; 3], BurleyError> {
    let ch = |c: usize| -> Result<BurleyFit, BurleyError> {
        let t: Vec<f64> = table_rgb_per_mm2.iter().map(|v| v[c]).collect();
        fit_channel(edges_mm, &t, r99_mm[c])
    };
    Ok([ch(0)?, ch(1)?, ch(2)?])
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::transport::radial::radius_of_energy;
    use crate::transport::RadialBins;

    /// Annulus averages of Burley (A, d) on `edges`, as the bake writes them.
    fn burley_table(edges: &[f64], a: f64, d: f64) -> Vec<f64> {
        edges
            .windows(2)
            .map(|e| a * burley_energy(d, e[0], e[1]) / (PI * (e[1] * e[1] - e[0] * e[0])))
            .collect()
    }

    /// The bake's radial grid: 10 µm bins, growing 5 % per bin from 0.2 mm, out to 40 mm
    /// (FORMAT.md; spec `profiles.radial`).
    fn bake_grid() -> Vec<f64> {
        RadialBins::fine_then_log(0.01, 1.05, 40.0)
            .edges_mm()
            .to_vec()
    }

    fn r99(edges: &[f64], table: &[f64], albedo: f64) -> f64 {
        radius_of_energy(edges, table.iter().copied(), 0.99 * albedo)
    }

    fn assert_recovers(edges: &[f64], a: f64, d: f64, r99_mm: f64, tol: f64) {
        let t = burley_table(edges, a, d);
        let fit = fit_channel(edges, &t, r99_mm).unwrap();
        assert!(
            (fit.a / a - 1.0).abs() < tol && (fit.d_mm / d - 1.0).abs() < tol,
            "A {a} d {d}: fitted A {} d {} (error {})",
            fit.a,
            fit.d_mm,
            fit.error
        );
        assert!(fit.error < 1e-6, "error {}", fit.error);
    }

    #[test]
    fn recovers_known_a_and_d_on_the_bake_grid() {
        let edges = bake_grid();
        assert!((edges[1] - 0.01).abs() < 1e-15 && edges.last().copied().unwrap() >= 40.0);
        // Skin-like channels (red: wide, blue: narrow) and extremes of A and d.
        for &(a, d) in &[
            (0.55, 0.9),
            (0.35, 0.25),
            (0.25, 0.06),
            (0.02, 0.015),
            (0.95, 2.5),
            (0.6, 0.012),
        ] {
            let t = burley_table(&edges, a, d);
            assert_recovers(&edges, a, d, r99(&edges, &t, a), 1e-3);
        }
    }

    #[test]
    fn recovers_known_a_and_d_per_channel() {
        let edges = bake_grid();
        let (a, d) = ([0.6, 0.35, 0.25], [1.1, 0.3, 0.12]);
        let table: Vec<[f64; 3]> = {
            let ch: Vec<Vec<f64>> = (0..3).map(|c| burley_table(&edges, a[c], d[c])).collect();
            (0..edges.len() - 1)
                .map(|k| [ch[0][k], ch[1][k], ch[2][k]])
                .collect()
        };
        let r99_mm = std::array::from_fn(|c| {
            radius_of_energy(&edges, table.iter().map(|v| v[c]), 0.99 * a[c])
        });
        let fit = fit_rgb(&edges, &table, r99_mm).unwrap();
        for c in 0..3 {
            assert!((fit[c].a / a[c] - 1.0).abs() < 1e-3, "{c}: {:?}", fit[c]);
            assert!((fit[c].d_mm / d[c] - 1.0).abs() < 1e-3, "{c}: {:?}", fit[c]);
        }
    }

    #[test]
    fn recovers_on_truncated_and_coarse_grids() {
        // The grid ends at 2 mm while d = 0.5 mm holds a third of the energy beyond it:
        // r99 is never reached (NaN), every bin counts, and the fit still finds (A, d).
        let short = RadialBins::fine_then_log(0.01, 1.05, 2.0)
            .edges_mm()
            .to_vec();
        let t = burley_table(&short, 0.5, 0.5);
        assert!(r99(&short, &t, 0.5).is_nan());
        assert_recovers(&short, 0.5, 0.5, f64::NAN, 1e-3);
        // A coarse uniform grid (MCML's 0.1 mm × 100): bins as wide as d.
        let coarse = RadialBins::uniform(0.1, 100).edges_mm().to_vec();
        let t = burley_table(&coarse, 0.4, 0.08);
        assert_recovers(&coarse, 0.4, 0.08, r99(&coarse, &t, 0.4), 1e-3);
    }

    #[test]
    fn recovers_within_one_percent_under_monte_carlo_like_noise() {
        // ±5 % uniform multiplicative noise per bin (a fixed SplitMix64 stream): the L1 fit
        // stays within 1 % of the truth.
        let mut state = 0x9E37_79B9_7F4A_7C15u64;
        let mut uniform = move || {
            state = state.wrapping_add(0x9E37_79B9_7F4A_7C15);
            let mut z = state;
            z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
            z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
            ((z ^ (z >> 31)) >> 11) as f64 / (1u64 << 53) as f64
        };
        let edges = bake_grid();
        for &(a, d) in &[(0.55, 0.9), (0.3, 0.2), (0.2, 0.07)] {
            let clean = burley_table(&edges, a, d);
            let noisy: Vec<f64> = clean
                .iter()
                .map(|v| v * (1.0 + 0.1 * (uniform() - 0.5)))
                .collect();
            let fit = fit_channel(&edges, &noisy, r99(&edges, &clean, a)).unwrap();
            assert!(
                (fit.a / a - 1.0).abs() < 0.01 && (fit.d_mm / d - 1.0).abs() < 0.01,
                "A {a} d {d}: {fit:?}"
            );
            assert!(fit.error < 0.05, "{fit:?}");
        }
    }

    #[test]
    fn error_is_the_documented_formula() {
        let edges = bake_grid();
        let t = burley_table(&edges, 0.5, 0.4);
        let r99_mm = r99(&edges, &t, 0.5);
        // Off by 10 % in A everywhere: the error is 10 % of the energy inside r99.
        let e = fit_error(&edges, &t, r99_mm, 0.55, 0.4);
        assert!((e - 0.1).abs() < 1e-12, "{e}");
        let fit = fit_channel(&edges, &t, r99_mm).unwrap();
        assert!((fit.error - fit_error(&edges, &t, r99_mm, fit.a, fit.d_mm)).abs() < 1e-15);
    }

    #[test]
    fn rejects_bad_input() {
        let edges = bake_grid();
        let zero = vec![0.0; edges.len() - 1];
        assert!(matches!(
            fit_channel(&edges, &zero, 1.0),
            Err(BurleyError::NoEnergy { .. })
        ));
        assert!(matches!(
            fit_channel(&[0.0, 2.0, 1.0], &[1.0, 1.0], 1.0),
            Err(BurleyError::Grid(_))
        ));
        assert!(matches!(
            fit_channel(&[0.0, 1.0], &[1.0, 1.0], 1.0),
            Err(BurleyError::Grid(_))
        ));
    }
}
