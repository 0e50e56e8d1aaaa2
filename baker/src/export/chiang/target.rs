//! What the fit samples from a table: a few θi rows, each averaged over a few φi
//! ([`FitTarget`]), and the table's own Monte Carlo noise in the fit's error measure.

use std::f64::consts::PI;

use formats::bcsdf::{direction, solid_angle, Bcsdf};
use formats::table::TableError;

use super::binning::FitGrid;

/// How the fit samples the table.
#[derive(Debug, Clone, PartialEq)]
pub struct ChiangFitOptions {
    /// θi rows used (even; half on each side of 0).
    pub theta_i_rows: usize,
    /// |θi| limit of those rows, degrees (grazing rows are where the model is weakest and
    /// renderers look least).
    pub max_theta_i_deg: f64,
    /// φi samples averaged per θi.
    pub phi_i_samples: usize,
    /// η held fixed (the table's metadata); `None` fits it.
    pub eta: Option<f64>,
    /// Nelder–Mead evaluations per run.
    pub max_evaluations: usize,
}

impl Default for ChiangFitOptions {
    fn default() -> Self {
        Self {
            theta_i_rows: 8,
            max_theta_i_deg: 80.0,
            phi_i_samples: 6,
            eta: None,
            max_evaluations: 400,
        }
    }
}

/// Errors of the fit.
#[derive(Debug, thiserror::Error)]
pub enum FitError {
    #[error("reading the table: {0}")]
    Table(#[from] TableError),
    #[error("variant {index} out of range (table has {count})")]
    Variant { index: usize, count: usize },
    #[error("the table has no θi row with |θi| ≤ {max_deg}°")]
    NoRows { max_deg: f64 },
    #[error("the table scatters nothing in variant {variant:?}")]
    Empty { variant: String },
}

/// The table values the fit compares with: for each sampled θi, f = Λ·f̂ averaged over φi.
#[derive(Debug, Clone)]
pub struct FitTarget {
    pub grid: FitGrid,
    pub channels: Vec<String>,
    pub theta_i_deg: Vec<f64>,
    pub phi_i_deg: Vec<f64>,
    /// `[θi][channel][row][column]`, sr⁻¹.
    pub values: Vec<f64>,
    /// `[θi][channel]`: the table's Λ averaged over φi.
    pub albedo: Vec<f64>,
    /// Per θi, how many distinct stored slices the φi samples read (their noise averages).
    pub distinct_slices: Vec<usize>,
}

impl FitTarget {
    /// Samples `variant` of `table`.
    pub fn from_table(
        table: &Bcsdf,
        variant: usize,
        opts: &ChiangFitOptions,
    ) -> Result<Self, FitError> {
        let d = &table.dir;
        if variant >= d.variants.len() {
            return Err(FitError::Variant {
                index: variant,
                count: d.variants.len(),
            });
        }
        let grid = FitGrid {
            res_deg: d.res_deg,
            n_theta: d.n_theta,
            n_phi: d.n_phi,
        };
        // Positive half of the eligible rows, evenly thinned, then mirrored.
        let positive: Vec<f64> = (0..grid.n_theta)
            .map(|r| grid.theta_centre(r).to_degrees())
            .filter(|&t| t > 0.0 && t <= opts.max_theta_i_deg + 1e-9)
            .collect();
        if positive.is_empty() {
            return Err(FitError::NoRows {
                max_deg: opts.max_theta_i_deg,
            });
        }
        let half = (opts.theta_i_rows / 2).clamp(1, positive.len());
        let picked: Vec<f64> = (0..half)
            .map(|i| positive[((i as f64 + 0.5) * positive.len() as f64 / half as f64) as usize])
            .collect();
        let mut theta_i_deg: Vec<f64> = picked.iter().rev().map(|t| -t).collect();
        theta_i_deg.extend(&picked);
        let nphi = opts.phi_i_samples.clamp(1, grid.n_phi);
        let phi_i_deg: Vec<f64> = (0..nphi)
            .map(|j| {
                let k = ((j as f64 + 0.5) * grid.n_phi as f64 / nphi as f64) as usize;
                grid.phi_centre(k).to_degrees()
            })
            .collect();
        let nc = d.channels.len();
        let bins = grid.bins();
        let mut values = vec![0.0; theta_i_deg.len() * nc * bins];
        let mut albedo = vec![0.0; theta_i_deg.len() * nc];
        let inv = 1.0 / phi_i_deg.len() as f64;
        let mut distinct_slices = Vec::with_capacity(theta_i_deg.len());
        for (i, &ti) in theta_i_deg.iter().enumerate() {
            let mut stored: Vec<usize> = Vec::new();
            for &pi in &phi_i_deg {
                let (ti, pi) = (ti.to_radians(), pi.to_radians());
                let wi = direction(ti, pi);
                let (index, ..) = table.locate(wi);
                if !stored.contains(&index) {
                    stored.push(index);
                }
                for (c, a) in table.albedo(wi, variant)?.into_iter().enumerate() {
                    albedo[i * nc + c] += inv * a as f64;
                }
                for r in 0..grid.n_theta {
                    for k in 0..grid.n_phi {
                        let wo = direction(grid.theta_centre(r), pi + grid.phi_centre(k));
                        let f = table.eval(wi, wo, variant)?;
                        for (c, x) in f.into_iter().enumerate() {
                            values[(i * nc + c) * bins + r * grid.n_phi + k] += inv * x as f64;
                        }
                    }
                }
            }
            distinct_slices.push(stored.len());
        }
        if values.iter().all(|&x| x <= 0.0) {
            return Err(FitError::Empty {
                variant: d.variants[variant].clone(),
            });
        }
        Ok(Self {
            grid,
            channels: d.channels.clone(),
            theta_i_deg,
            phi_i_deg,
            values,
            albedo,
            distinct_slices,
        })
    }

    /// Expected relative L1 distance between the table and its noise-free limit if each stored
    /// slice were a histogram of `photons` unweighted photons: Σ √(2/π)·√(q(1−q)/N) over bins
    /// of probability q = f̂·ΔΩ, averaged like the fit's error (and divided by √(distinct
    /// slices) where φi samples average several). Weighted photons only add noise, so read it
    /// as a floor: no smooth model can get much below it.
    pub fn noise_l1(&self, photons: f64) -> f64 {
        let d_omega = self.d_omega();
        let nc = self.channels.len();
        let (mut num, mut den) = (0.0, 0.0);
        for i in 0..self.theta_i_deg.len() {
            let k = (2.0 / PI).sqrt() / (self.distinct_slices[i] as f64).sqrt();
            for c in 0..nc {
                let tab = self.slice(i, c);
                let total: f64 = tab
                    .iter()
                    .enumerate()
                    .map(|(b, t)| t * d_omega[b / self.grid.n_phi])
                    .sum();
                if total <= 0.0 {
                    continue;
                }
                let noise: f64 = tab
                    .iter()
                    .enumerate()
                    .map(|(b, t)| {
                        // max(0): RGB tables converted from spectra can dip below 0.
                        let q = (t * d_omega[b / self.grid.n_phi] / total).clamp(0.0, 1.0);
                        k * (q * (1.0 - q) / photons).sqrt()
                    })
                    .sum();
                num += noise * total;
                den += total;
            }
        }
        num / den
    }

    pub(super) fn slice(&self, i: usize, c: usize) -> &[f64] {
        let (nc, bins) = (self.channels.len(), self.grid.bins());
        &self.values[(i * nc + c) * bins..(i * nc + c + 1) * bins]
    }

    /// Solid angle of each θ row's bins.
    pub(super) fn d_omega(&self) -> Vec<f64> {
        (0..self.grid.n_theta)
            .map(|r| solid_angle(self.grid.res_deg, r))
            .collect()
    }
}
