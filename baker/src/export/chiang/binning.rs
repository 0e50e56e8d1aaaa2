//! The far-field model averaged over the bins of a table's grid (`[channel][row][column]`,
//! sr⁻¹): Δφ through the logistic's CDF, θo by Gauss–Legendre within each row, h by composite
//! Gauss–Legendre in γ. What the fit compares with the table, bin by bin.

use std::f64::consts::{FRAC_PI_2, PI, TAU};

use super::lobes::{perfect_dphi, rough_fiber_pdf, P_MAX};
use super::model::{width_nodes, width_panels, Chiang};
use crate::math::quadrature::gauss_legendre;

/// The grid of a table, as the fit bins the model on it: `n_theta` θo rows from −90° and `n_phi` Δφ columns from −180°, `res_deg`
/// wide.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct FitGrid {
    pub res_deg: f64,
    pub n_theta: usize,
    pub n_phi: usize,
}

impl FitGrid {
    pub fn bins(&self) -> usize {
        self.n_theta * self.n_phi
    }

    pub(super) fn res(&self) -> f64 {
        self.res_deg.to_radians()
    }

    /// Lower edge of θ row `r`, radians.
    pub(super) fn theta_lo(&self, r: usize) -> f64 {
        -FRAC_PI_2 + r as f64 * self.res()
    }

    /// Lower edge of Δφ column `k`, radians.
    pub(super) fn phi_lo(&self, k: usize) -> f64 {
        -PI + k as f64 * self.res()
    }

    /// Centre of θ row `r`, radians.
    pub fn theta_centre(&self, r: usize) -> f64 {
        self.theta_lo(r) + 0.5 * self.res()
    }

    /// Centre of φ column `k`, radians.
    pub fn phi_centre(&self, k: usize) -> f64 {
        self.phi_lo(k) + 0.5 * self.res()
    }
}

/// Width panels for bin averages on `grid`: bins as wide as the grid's are smooth in h even
/// when the logistic is not, so about one panel per Δφ column is enough (relative L1 < 0.3 %
/// against 512 panels at β_n = 0.02, 10° bins; far less at larger β_n).
pub(super) fn bin_panels(s: f64, grid: &FitGrid) -> usize {
    width_panels(s).min(grid.n_phi.max(12))
}

/// The parts of the bin-averaged far-field model that do not depend on σa, for one θi.
pub(super) struct ShapeSlice {
    /// `[p][row]`: ∫ Mp cos θo dθo over the row / Δ(sin θo).
    mbar: [Vec<f64>; P_MAX + 1],
    /// Per width node: weight, Fresnel factor, chord length.
    nodes: Vec<(f64, f64, f64)>,
    /// `[p][node][column]`: ∫ Np dφ over the column / Δφ, for p < 3.
    d: [Vec<f64>; P_MAX],
    /// Σ_nodes w·A₀·D₀ per column (A₀ = f does not depend on σa).
    n0: Vec<f64>,
    /// `[p]`: Σ over rows of M̄p·Δ(sin θo), the lobe's longitudinal integral (1 up to the I₀
    /// series and the rows' quadrature).
    mtot: [f64; P_MAX + 1],
    /// `[p][node]`: Σ over columns of the column integrals of Np (1 up to rounding).
    dtot: [Vec<f64>; P_MAX],
}

impl Chiang {
    /// The σa-independent parts of the bin averages at θi.
    pub(super) fn shape_slice(&self, grid: &FitGrid, theta_i: f64, panels: usize) -> ShapeSlice {
        let (st, ct) = theta_i.sin_cos();
        let res = grid.res();
        let mut mbar: [Vec<f64>; P_MAX + 1] = Default::default();
        for p in 0..=P_MAX {
            let (sp, _) = self.reframe(st, ct, p);
            let kappa = 1.0 / self.v[p];
            // Enough nodes per row for a lobe of angular width √v.
            let order = ((3.0 * res / self.v[p].sqrt()).ceil() as usize).clamp(3, 48);
            let (x, w) = gauss_legendre(order);
            // The residual's pdf already holds 1/2π; the others get the 2π of hair.cpp.
            let scale = if p == P_MAX { 1.0 } else { TAU };
            mbar[p] = (0..grid.n_theta)
                .map(|r| {
                    let (a, b) = (grid.theta_lo(r), grid.theta_lo(r) + res);
                    let mut acc = 0.0;
                    for (xi, wi) in x.iter().zip(&w) {
                        let t = 0.5 * (a + b) + 0.5 * (b - a) * xi;
                        acc += 0.5 * (b - a) * wi * rough_fiber_pdf(sp, t.sin(), kappa) * t.cos();
                    }
                    scale * acc / (b.sin() - a.sin())
                })
                .collect();
        }
        let width = width_nodes(panels);
        let mut nodes = Vec::with_capacity(width.len());
        let mut d: [Vec<f64>; P_MAX] = Default::default();
        for dp in d.iter_mut() {
            dp.reserve(width.len() * grid.n_phi);
        }
        let mut edges = vec![0.0; grid.n_phi + 1];
        for &(g, w) in &width {
            let inc = self.incidence(st, ct, g);
            nodes.push((w, inc.fresnel, inc.path));
            for p in 0..P_MAX {
                let phi0 = perfect_dphi(p, inc.gamma_i, inc.gamma_t);
                for (k, e) in edges.iter_mut().enumerate() {
                    *e = self.azimuthal_cdf(-PI + k as f64 * res - phi0);
                }
                for k in 0..grid.n_phi {
                    d[p].push((edges[k + 1] - edges[k]) / res);
                }
            }
        }
        let mut n0 = vec![0.0; grid.n_phi];
        for (j, &(w, f, _)) in nodes.iter().enumerate() {
            for k in 0..grid.n_phi {
                n0[k] += w * f * d[0][j * grid.n_phi + k];
            }
        }
        let mut mtot = [0.0; P_MAX + 1];
        for p in 0..=P_MAX {
            for r in 0..grid.n_theta {
                let (a, b) = (grid.theta_lo(r), grid.theta_lo(r) + res);
                mtot[p] += mbar[p][r] * (b.sin() - a.sin());
            }
        }
        let dtot: [Vec<f64>; P_MAX] = std::array::from_fn(|p| {
            d[p].chunks(grid.n_phi)
                .map(|row| row.iter().sum::<f64>() * res)
                .collect()
        });
        ShapeSlice {
            mbar,
            nodes,
            d,
            n0,
            mtot,
            dtot,
        }
    }
}

impl ShapeSlice {
    /// Σ over bins of the model's bin average × ΔΩ (its albedo on the grid) for absorption σa,
    /// without filling the bins.
    pub(super) fn albedo(&self, sigma_a: f64) -> f64 {
        let mut acc = [0.0; P_MAX + 1];
        for (j, &(w, f, path)) in self.nodes.iter().enumerate() {
            let t = (-sigma_a * path).exp();
            let a1 = (1.0 - f) * (1.0 - f) * t;
            let a2 = a1 * t * f;
            let a3 = a2 * f * t / (1.0 - t * f);
            acc[0] += w * f * self.dtot[0][j];
            acc[1] += w * a1 * self.dtot[1][j];
            acc[2] += w * a2 * self.dtot[2][j];
            if a3.is_finite() {
                // uniform in Δφ: its 2π columns hold 2π × (the 1/2π of the residual's pdf)
                acc[3] += w * a3 * TAU;
            }
        }
        (0..=P_MAX).map(|p| self.mtot[p] * acc[p]).sum()
    }

    /// Bin averages `[row][column]` of one channel of the far-field model for absorption σa.
    pub(super) fn channel(&self, grid: &FitGrid, sigma_a: f64, out: &mut [f64]) {
        let np = grid.n_phi;
        let mut n1 = vec![0.0; np];
        let mut n2 = vec![0.0; np];
        let mut n3 = 0.0;
        for (j, &(w, f, path)) in self.nodes.iter().enumerate() {
            let t = (-sigma_a * path).exp();
            let a1 = (1.0 - f) * (1.0 - f) * t;
            let a2 = a1 * t * f;
            let a3 = a2 * f * t / (1.0 - t * f);
            if a3.is_finite() {
                n3 += w * a3;
            }
            let (d1, d2) = (
                &self.d[1][j * np..(j + 1) * np],
                &self.d[2][j * np..(j + 1) * np],
            );
            for k in 0..np {
                n1[k] += w * a1 * d1[k];
                n2[k] += w * a2 * d2[k];
            }
        }
        for r in 0..grid.n_theta {
            let m = [
                self.mbar[0][r],
                self.mbar[1][r],
                self.mbar[2][r],
                self.mbar[3][r],
            ];
            for k in 0..np {
                out[r * np + k] = m[0] * self.n0[k] + m[1] * n1[k] + m[2] * n2[k] + m[3] * n3;
            }
        }
    }
}

/// Bin averages of the far-field model at θi on `grid`, `[channel][row][column]`, sr⁻¹: the
/// quantity a table stores.
pub fn binned(model: &Chiang, grid: &FitGrid, theta_i: f64) -> Vec<f64> {
    binned_with(model, grid, theta_i, bin_panels(model.s, grid))
}

/// [`binned`] with `panels` × 8 width nodes.
fn binned_with(model: &Chiang, grid: &FitGrid, theta_i: f64, panels: usize) -> Vec<f64> {
    let slice = model.shape_slice(grid, theta_i, panels);
    let mut out = vec![0.0; model.channels() * grid.bins()];
    for (c, &sa) in model.params.sigma_a.iter().enumerate() {
        slice.channel(grid, sa, &mut out[c * grid.bins()..(c + 1) * grid.bins()]);
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::export::chiang::model::tests::params;
    use crate::export::chiang::ChiangParams;
    use crate::math::quadrature::gauss_legendre;
    use formats::bcsdf::solid_angle;

    #[test]
    fn bin_panels_resolve_the_width_average() {
        // The documented accuracy of bin_panels: relative L1 < 0.3 % against 512 panels,
        // even at β_n = 0.02 on 10° bins.
        let grid = FitGrid {
            res_deg: 10.0,
            n_theta: 18,
            n_phi: 36,
        };
        for &bn in &[0.02, 0.1, 0.4] {
            let m = Chiang::new(ChiangParams {
                eta: 1.635,
                sigma_a: vec![0.05, 1.0],
                beta_m: 0.15,
                beta_n: bn,
                alpha_deg: 0.0,
            });
            for &ti in &[-75.0f64, -15.0] {
                let reference = binned_with(&m, &grid, ti.to_radians(), 512);
                let v = binned(&m, &grid, ti.to_radians());
                let e: f64 = v
                    .iter()
                    .zip(&reference)
                    .map(|(a, b)| (a - b).abs())
                    .sum::<f64>()
                    / reference.iter().sum::<f64>();
                assert!(e < 3e-3, "β_n {bn} θi {ti}: {e}");
            }
        }
    }

    #[test]
    fn slice_albedo_is_the_sum_of_the_bins() {
        let m = Chiang::new(params(vec![0.0, 0.4, 3.0], 2.0));
        let grid = FitGrid {
            res_deg: 10.0,
            n_theta: 18,
            n_phi: 36,
        };
        for &ti in &[-1.2, -0.3, 0.5] {
            let slice = m.shape_slice(&grid, ti, bin_panels(m.s, &grid));
            let b = binned(&m, &grid, ti);
            for (c, &sa) in m.params.sigma_a.iter().enumerate() {
                let sum: f64 = b[c * grid.bins()..(c + 1) * grid.bins()]
                    .iter()
                    .enumerate()
                    .map(|(i, x)| x * solid_angle(grid.res_deg, i / grid.n_phi))
                    .sum();
                let fast = slice.albedo(sa);
                assert!((sum - fast).abs() < 1e-12, "{sum} {fast}");
                assert!(
                    (fast - m.albedo(ti)[c]).abs() < 2e-3,
                    "{fast} {:?}",
                    m.albedo(ti)
                );
            }
        }
    }

    #[test]
    fn bin_averages_match_the_point_model_integrated_over_the_bin() {
        // The fit's fast path (CDF in Δφ, Gauss–Legendre in θo) against eval_far integrated
        // numerically over a few bins.
        let m = Chiang::new(params(vec![0.2, 2.0], -4.0));
        let grid = FitGrid {
            res_deg: 10.0,
            n_theta: 18,
            n_phi: 36,
        };
        let ti = f64::to_radians(-35.0);
        let b = binned(&m, &grid, ti);
        let res = grid.res();
        for &(r, k) in &[(12usize, 18usize), (12, 20), (11, 2), (13, 35), (9, 27)] {
            let (x, w) = gauss_legendre(6);
            let mut acc = [0.0; 2];
            for (xu, wu) in x.iter().zip(&w) {
                let (s0, s1) = (grid.theta_lo(r).sin(), (grid.theta_lo(r) + res).sin());
                let to = (0.5 * (s0 + s1) + 0.5 * (s1 - s0) * xu).asin();
                for (xp, wp) in x.iter().zip(&w) {
                    let dphi = grid.phi_lo(k) + 0.5 * res * (1.0 + xp);
                    let v = m.eval_far(ti, to, dphi, Some(96));
                    for c in 0..2 {
                        acc[c] += 0.25 * wu * wp * v[c];
                    }
                }
            }
            for c in 0..2 {
                let fast = b[c * grid.bins() + r * grid.n_phi + k];
                assert!(
                    (fast - acc[c]).abs() < 0.02 * acc[c] + 1e-4,
                    "bin ({r}, {k}) channel {c}: binned {fast} vs integrated {}",
                    acc[c]
                );
            }
        }
    }
}
