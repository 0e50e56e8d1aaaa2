//! Sum-of-Gaussians fits of radial diffusion profiles (d'Eon, Luebke & Enderton 2007; d'Eon &
//! Luebke, GPU Gems 3 ch. 14): R(r) ≈ Σᵢ wᵢ·G(vᵢ, r), G(v, r) = exp(−r²/2v)/(2πv), with the
//! variances vᵢ shared by the three channels and non-negative weights per channel.
//!
//! The error is the one the issue and renderers care about, energy in annuli: for channel c,
//! e_c = Σₖ |fitₖ − tableₖ|·Aₖ / Σₖ tableₖ·Aₖ over the bins inside the channel's 99 % radius,
//! Aₖ = π(bₖ² − aₖ²) = 2π·rₖ·Δrₖ the area of annulus [aₖ, bₖ]. The fit is compared with the
//! table as a bin average — ∫ G 2πr dr over the annulus is exp(−a²/2v) − exp(−b²/2v) exactly —
//! so wide log-spaced bins are not mistaken for point samples.
//!
//! For given variances the weights minimise that L1 error (iteratively reweighted
//! non-negative least squares); the variances are then optimised on the error itself
//! (Nelder–Mead on log v, restarted until it stops improving), not just picked from a grid.

// Index loops mirror the formulas (rows, columns, bins); iterator chains would hide them.
#![allow(clippy::needless_range_loop)]

use super::nnls::nnls_normal;
use crate::cancel::{Cancel, Cancelled};

/// Energy of G(v, ·) in the annulus [a, b] (its integral over the annulus, mm² cancel).
#[inline]
pub fn gaussian_energy(v_mm2: f64, a_mm: f64, b_mm: f64) -> f64 {
    (-a_mm * a_mm / (2.0 * v_mm2)).exp() - (-b_mm * b_mm / (2.0 * v_mm2)).exp()
}

#[derive(Debug, Clone, PartialEq)]
pub struct GaussianFitOptions {
    /// Number of Gaussians (6 in real-time renderers).
    pub count: usize,
    /// Nelder–Mead evaluations per restart.
    pub max_evaluations: usize,
    /// Restarts after the first run (each from the best point so far).
    pub restarts: usize,
    /// Checked between simplex runs (each at most `max_evaluations` evaluations).
    pub cancel: Cancel,
}

impl Default for GaussianFitOptions {
    fn default() -> Self {
        Self {
            count: 6,
            max_evaluations: 2500,
            restarts: 4,
            cancel: Cancel::NEVER,
        }
    }
}

#[derive(Debug, Clone, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct GaussianFit {
    /// Ascending variances, mm².
    pub variance_mm2: Vec<f64>,
    /// Per Gaussian, the R, G, B weights (dimensionless: each Gaussian integrates to 1 over the
    /// plane, so Σᵢ wᵢ,c is the channel's fitted albedo).
    pub weight_rgb: Vec<[f64; 3]>,
    /// Energy-weighted relative error per channel (see the module docs).
    pub error_rgb: [f64; 3],
}

/// One channel's fitting problem: energies per bin and which bins count.
struct Channel {
    /// Table energy per bin, tableₖ·Aₖ.
    energy: Vec<f64>,
    /// Bins k < `n` count (those with aₖ < r99).
    n: usize,
    total: f64,
}

/// Energies of the Gaussians per bin, row-major: `rows[k·m + i]` for bin k, Gaussian i.
struct Basis {
    m: usize,
    rows: Vec<f64>,
}

impl Basis {
    #[inline]
    fn row(&self, k: usize) -> &[f64] {
        &self.rows[k * self.m..(k + 1) * self.m]
    }
}

struct Problem<'a> {
    edges_mm: &'a [f64],
    channels: Vec<Channel>,
}

impl Problem<'_> {
    /// Energy of each Gaussian in each bin: B[k][i] = E(edge k) − E(edge k + 1) with
    /// E(r) = exp(−r²/2v), each edge's exponentials computed once (the same values
    /// [`gaussian_energy`] gives bin by bin).
    fn basis(&self, v: &[f64], n: usize) -> Basis {
        let m = v.len();
        let tail = |r: f64| v.iter().map(move |&vi| (-r * r / (2.0 * vi)).exp());
        let mut upper: Vec<f64> = tail(self.edges_mm[0]).collect();
        let mut rows = Vec::with_capacity(n * m);
        for k in 0..n {
            for (i, lower) in tail(self.edges_mm[k + 1]).enumerate() {
                rows.push(upper[i] - lower);
                upper[i] = lower;
            }
        }
        Basis { m, rows }
    }

    /// L1-optimal non-negative weights of one channel for the first `ch.n` rows of basis `b`,
    /// and its error.
    fn weights(&self, b: &Basis, ch: &Channel) -> (Vec<f64>, f64) {
        let m = b.m;
        let e = &ch.energy[..ch.n];
        let floor = 1e-9 * ch.total.abs().max(1e-300);
        // Start from relative least squares, then reweight by 1/|residual| (IRLS for L1).
        let mut d: Vec<f64> = e.iter().map(|x| 1.0 / x.abs().max(floor)).collect();
        let mut best = (vec![0.0; m], f64::INFINITY);
        let mut g = vec![vec![0.0; m]; m];
        let mut h = vec![0.0; m];
        let mut res = vec![0.0; e.len()];
        for _ in 0..25 {
            g.iter_mut().for_each(|r| r.fill(0.0));
            h.fill(0.0);
            for (k, (&ek, &dk)) in e.iter().zip(&d).enumerate() {
                let row = b.row(k);
                for i in 0..m {
                    let di = dk * row[i];
                    h[i] += di * ek;
                    let gi = &mut g[i];
                    for j in 0..=i {
                        gi[j] += di * row[j];
                    }
                }
            }
            for i in 0..m {
                for j in i + 1..m {
                    g[i][j] = g[j][i];
                }
            }
            let w = nnls_normal(&g, &h);
            for (k, (r, ek)) in res.iter_mut().zip(e).enumerate() {
                *r = b.row(k).iter().zip(&w).map(|(a, w)| a * w).sum::<f64>() - ek;
            }
            let err = res.iter().map(|r| r.abs()).sum::<f64>() / ch.total;
            if err < best.1 * (1.0 - 1e-6) {
                best = (w, err);
            } else if err >= best.1 {
                break;
            }
            let eps = floor.max(1e-4 * best.1 * ch.total / e.len() as f64);
            for (dk, r) in d.iter_mut().zip(&res) {
                *dk = 1.0 / r.abs().max(eps);
            }
        }
        best
    }

    /// Smooth surrogate for the first phase: per channel, the least-squares misfit of the
    /// energies (one NNLS solve), relative to the channel's energy.
    fn evaluate_l2(&self, log_v: &[f64]) -> f64 {
        let v: Vec<f64> = log_v.iter().map(|x| x.exp()).collect();
        let n_max = self.channels.iter().map(|c| c.n).max().unwrap_or(0);
        let b = self.basis(&v, n_max);
        let m = v.len();
        let mut total = 0.0;
        let mut g = vec![vec![0.0; m]; m];
        let mut h = vec![0.0; m];
        for ch in &self.channels {
            let e = &ch.energy[..ch.n];
            g.iter_mut().for_each(|r| r.fill(0.0));
            h.fill(0.0);
            for (k, &ek) in e.iter().enumerate() {
                let row = b.row(k);
                for i in 0..m {
                    h[i] += row[i] * ek;
                    let gi = &mut g[i];
                    for j in 0..m {
                        gi[j] += row[i] * row[j];
                    }
                }
            }
            let w = nnls_normal(&g, &h);
            let ss: f64 = e
                .iter()
                .enumerate()
                .map(|(k, ek)| {
                    (b.row(k).iter().zip(&w).map(|(a, w)| a * w).sum::<f64>() - ek).powi(2)
                })
                .sum();
            total += ss.sqrt() / ch.total.abs().max(1e-300);
        }
        total
    }

    fn evaluate(&self, log_v: &[f64]) -> (f64, Vec<Vec<f64>>, [f64; 3]) {
        let v: Vec<f64> = log_v.iter().map(|x| x.exp()).collect();
        let n_max = self.channels.iter().map(|c| c.n).max().unwrap_or(0);
        let b = self.basis(&v, n_max);
        let mut ws = Vec::new();
        let mut errs = [0.0; 3];
        for (c, ch) in self.channels.iter().enumerate() {
            let (w, e) = self.weights(&b, ch);
            ws.push(w);
            errs[c] = e;
        }
        (errs.iter().sum(), ws, errs)
    }
}

/// The shared simplex with this fit's tolerance (relative 1e-10).
fn nelder_mead(
    f: &impl Fn(&[f64]) -> f64,
    x0: &[f64],
    step: f64,
    max_eval: usize,
) -> (Vec<f64>, f64) {
    let (x, fx, _) = super::nelder_mead(&mut |x: &[f64]| f(x), x0, step, max_eval, 1e-10);
    (x, fx)
}

/// Phase 1 on the smooth least-squares surrogate, phase 2 on the L1 error itself, from `x0`.
fn optimise(p: &Problem, x0: &[f64], o: &GaussianFitOptions) -> Result<(Vec<f64>, f64), Cancelled> {
    let f2 = |x: &[f64]| p.evaluate_l2(x);
    let (mut x, _) = nelder_mead(&f2, x0, 0.7, o.max_evaluations);
    for _ in 0..o.restarts {
        o.cancel.check()?;
        x = nelder_mead(&f2, &x, 0.3, o.max_evaluations).0;
    }
    let f = |x: &[f64]| p.evaluate(x).0;
    o.cancel.check()?;
    let (mut x, mut fx) = nelder_mead(&f, &x, 0.3, o.max_evaluations);
    for k in 0..o.restarts {
        o.cancel.check()?;
        let step = if k % 2 == 0 { 0.3 } else { 0.8 };
        let (x2, f2) = nelder_mead(&f, &x, step, o.max_evaluations);
        let improved = f2 < fx * (1.0 - 1e-4);
        if f2 < fx {
            (x, fx) = (x2, f2);
        }
        if !improved && k > 0 {
            break;
        }
    }
    Ok((x, fx))
}

/// Fits `table` (bin averages per unit area, `[nr][3]`, on annuli `edges_mm`) inside each
/// channel's 99 % radius `r99_mm`, with `o.count` shared variances; `Err` once `o.cancel` is
/// set.
pub fn fit_sum_of_gaussians(
    edges_mm: &[f64],
    table: &[[f64; 3]],
    r99_mm: [f64; 3],
    o: &GaussianFitOptions,
) -> Result<GaussianFit, Cancelled> {
    assert_eq!(edges_mm.len(), table.len() + 1, "one more edge than bins");
    assert!(o.count >= 1);
    let channels = (0..3)
        .map(|c| {
            let energy: Vec<f64> = table
                .iter()
                .zip(edges_mm.windows(2))
                .map(|(t, e)| t[c] * std::f64::consts::PI * (e[1] * e[1] - e[0] * e[0]))
                .collect();
            let n = edges_mm[..table.len()]
                .iter()
                .take_while(|&&a| a < r99_mm[c])
                .count()
                .max(1);
            let total = energy[..n].iter().sum::<f64>();
            Channel { energy, n, total }
        })
        .collect();
    let p = Problem { edges_mm, channels };
    // Start: variances spread log-uniformly from the first bin's scale to the widest
    // channel's 99 % radius (r99 ≈ 3σ for a single Gaussian). Starting from narrower or wider
    // ladders, or weighting the channels by their aims, was tried on the Fitzpatrick profiles:
    // the same optimum, or a worse red channel.
    let r_lo = edges_mm[1].max(1e-6);
    let r_hi = r99_mm
        .iter()
        .cloned()
        .fold(0.0f64, f64::max)
        .max(2.0 * r_lo)
        / 3.0;
    let (lv_lo, lv_hi) = ((r_lo * r_lo).ln(), (r_hi * r_hi).ln());
    let x0: Vec<f64> = (0..o.count)
        .map(|i| {
            if o.count == 1 {
                0.5 * (lv_lo + lv_hi)
            } else {
                lv_lo + (lv_hi - lv_lo) * i as f64 / (o.count - 1) as f64
            }
        })
        .collect();
    let (x, _) = optimise(&p, &x0, o)?;
    let (_, ws, errs) = p.evaluate(&x);
    let mut order: Vec<usize> = (0..o.count).collect();
    order.sort_by(|&a, &b| x[a].total_cmp(&x[b]));
    Ok(GaussianFit {
        variance_mm2: order.iter().map(|&i| x[i].exp()).collect(),
        weight_rgb: order
            .iter()
            .map(|&i| [ws[0][i], ws[1][i], ws[2][i]])
            .collect(),
        error_rgb: errs,
    })
}

/// The energy-weighted error of a given fit against `table` (the same formula the fit
/// minimises), for checking fits read back from a file.
pub fn fit_error(
    edges_mm: &[f64],
    table: &[[f64; 3]],
    r99_mm: [f64; 3],
    variance_mm2: &[f64],
    weight_rgb: &[[f64; 3]],
) -> [f64; 3] {
    std::array::from_fn(|c| {
        let (mut num, mut den) = (0.0, 0.0);
        for (k, t) in table.iter().enumerate() {
            let (a, b) = (edges_mm[k], edges_mm[k + 1]);
            if a >= r99_mm[c] && k > 0 {
                break;
            }
            let fit: f64 = variance_mm2
                .iter()
                .zip(weight_rgb)
                .map(|(&v, w)| w[c] * gaussian_energy(v, a, b))
                .sum();
            let e = t[c] * std::f64::consts::PI * (b * b - a * a);
            num += (fit - e).abs();
            den += e;
        }
        num / den
    })
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::transport::RadialBins;

    fn table_of(edges: &[f64], v: &[f64], w: &[[f64; 3]]) -> Vec<[f64; 3]> {
        edges
            .windows(2)
            .map(|e| {
                let area = std::f64::consts::PI * (e[1] * e[1] - e[0] * e[0]);
                std::array::from_fn(|c| {
                    v.iter()
                        .zip(w)
                        .map(|(&v, w)| w[c] * gaussian_energy(v, e[0], e[1]))
                        .sum::<f64>()
                        / area
                })
            })
            .collect()
    }

    #[test]
    fn energy_of_the_whole_plane_is_one() {
        assert!((gaussian_energy(0.3, 0.0, 1e3) - 1.0).abs() < 1e-15);
        // Annuli add up.
        let s = gaussian_energy(0.3, 0.0, 0.5) + gaussian_energy(0.3, 0.5, 2.0);
        assert!((s - gaussian_energy(0.3, 0.0, 2.0)).abs() < 1e-15);
    }

    #[test]
    fn a_known_sum_of_six_gaussians_is_recovered() {
        // d'Eon & Luebke's skin variances (GPU Gems 3, ch. 14, Fig. 14-13), mm², with
        // weights of a similar shape per channel.
        let v = [0.0064, 0.0484, 0.187, 0.567, 1.99, 7.41];
        let w = [
            [0.233, 0.455, 0.649],
            [0.100, 0.336, 0.344],
            [0.118, 0.198, 0.0],
            [0.113, 0.007, 0.007],
            [0.358, 0.004, 0.0],
            [0.078, 0.0, 0.0],
        ];
        let bins = RadialBins::fine_then_log(0.01, 1.05, 20.0);
        let table = table_of(bins.edges_mm(), &v, &w);
        let fit = fit_sum_of_gaussians(
            bins.edges_mm(),
            &table,
            [12.0, 3.0, 2.0],
            &GaussianFitOptions::default(),
        )
        .unwrap();
        for c in 0..3 {
            assert!(fit.error_rgb[c] < 2e-3, "channel {c}: {:?}", fit.error_rgb);
        }
        // Per channel the fitted albedo (Σ w) matches.
        for c in 0..3 {
            let a: f64 = w.iter().map(|w| w[c]).sum();
            let b: f64 = fit.weight_rgb.iter().map(|w| w[c]).sum();
            assert!((a - b).abs() < 5e-3 * a, "channel {c}: {a} vs {b}");
        }
        let again = fit_error(
            bins.edges_mm(),
            &table,
            [12.0, 3.0, 2.0],
            &fit.variance_mm2,
            &fit.weight_rgb,
        );
        for c in 0..3 {
            assert!((again[c] - fit.error_rgb[c]).abs() < 1e-12);
        }
    }

    #[test]
    fn fit_is_deterministic_and_weights_non_negative() {
        let v = [0.01, 0.2, 3.0];
        let w = [[0.2, 0.3, 0.4], [0.3, 0.2, 0.1], [0.1, 0.02, 0.0]];
        let bins = RadialBins::fine_then_log(0.01, 1.06, 15.0);
        let table = table_of(bins.edges_mm(), &v, &w);
        let o = GaussianFitOptions::default();
        let a = fit_sum_of_gaussians(bins.edges_mm(), &table, [8.0, 4.0, 2.0], &o).unwrap();
        let b = fit_sum_of_gaussians(bins.edges_mm(), &table, [8.0, 4.0, 2.0], &o).unwrap();
        assert_eq!(a, b);
        // A set flag stops the fit.
        let (flag, cancel) = Cancel::fresh();
        flag.store(true, std::sync::atomic::Ordering::Relaxed);
        let stopped = GaussianFitOptions { cancel, ..o };
        assert_eq!(
            fit_sum_of_gaussians(bins.edges_mm(), &table, [8.0, 4.0, 2.0], &stopped),
            Err(Cancelled)
        );
        assert!(a.weight_rgb.iter().flatten().all(|&x| x >= 0.0));
        assert!(a.variance_mm2.windows(2).all(|p| p[0] <= p[1]));
    }

    /// Issue 22: `fit_error` is the documented energy-weighted relative L1 (FORMAT.md), written
    /// out here on a hand-made table: bins from the first up to the one holding r99 (bin 0
    /// always), |fit energy − table energy| over the table energy.
    #[test]
    fn fit_error_is_the_energy_weighted_l1_inside_r99() {
        let edges = [0.0, 0.1, 0.3, 0.6, 1.0, 2.0];
        let v = [0.05, 0.4];
        let w = [[0.3, 0.2, 0.1], [0.5, 0.1, 0.0]];
        // A table that is the fit times (1 + ε_k), different per bin and channel.
        let exact = table_of(&edges, &v, &w);
        let eps = [0.1, -0.05, 0.2, 0.3, -0.4];
        let table: Vec<[f64; 3]> = exact
            .iter()
            .zip(eps)
            .map(|(t, e)| [t[0] * (1.0 + e), t[1] * (1.0 - e), t[2] * (1.0 + 2.0 * e)])
            .collect();
        let r99 = [0.7, 0.05, 5.0];
        let got = fit_error(&edges, &table, r99, &v, &w);
        for c in 0..3 {
            let (mut num, mut den) = (0.0, 0.0);
            for k in 0..5 {
                if k > 0 && edges[k] >= r99[c] {
                    break;
                }
                let area = std::f64::consts::PI * (edges[k + 1].powi(2) - edges[k].powi(2));
                num += (exact[k][c] - table[k][c]).abs() * area;
                den += table[k][c] * area;
            }
            assert!(
                (got[c] - num / den).abs() < 1e-12,
                "channel {c}: {} vs {}",
                got[c],
                num / den
            );
        }
        // Channel 1's r99 lies inside bin 0: only that bin counts (|ε0| / (1 − ε0)).
        assert!((got[1] - 0.1 / 0.9).abs() < 1e-12, "{}", got[1]);
    }

    /// The L1 weights of one channel are optimal: on a table that is an exact sum of the
    /// basis with a few outlying bins, IRLS recovers the exact weights (L1 ignores outliers,
    /// least squares would not).
    #[test]
    fn l1_weights_ignore_outliers() {
        let bins = RadialBins::fine_then_log(0.02, 1.1, 8.0);
        let v = [0.02, 0.3, 2.5];
        let w = [[0.4, 0.4, 0.4], [0.3, 0.3, 0.3], [0.2, 0.2, 0.2]];
        let mut table = table_of(bins.edges_mm(), &v, &w);
        for k in [3usize, 11, 19] {
            for c in 0..3 {
                table[k][c] *= 1.5;
            }
        }
        let o = GaussianFitOptions {
            count: 3,
            ..GaussianFitOptions::default()
        };
        let fit = fit_sum_of_gaussians(bins.edges_mm(), &table, [8.0; 3], &o).unwrap();
        for (fv, tv) in fit.variance_mm2.iter().zip(v) {
            assert!(
                (fv / tv - 1.0).abs() < 1e-3,
                "variances {:?}",
                fit.variance_mm2
            );
        }
        for (fw, tw) in fit.weight_rgb.iter().zip(w) {
            assert!((fw[0] - tw[0]).abs() < 1e-3, "weights {:?}", fit.weight_rgb);
        }
    }
}
