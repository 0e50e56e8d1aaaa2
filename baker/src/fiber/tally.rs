//! Binning of exiting photons over the outgoing sphere (§5.3.2: "collected in an infinite
//! sphere bounding the fiber, as a function of ωo = ⟨φo, θo⟩").
//!
//! Conventions: fiber axis +z; θ = asin(ω·z) ∈ [−90°, 90°]; φ = atan2(ω·y, ω·x). Outgoing
//! azimuths are stored relative to the incident one, Δφ = φo − φi wrapped to [−180°, 180°).

use std::f64::consts::{FRAC_PI_2, PI, TAU};

/// Bins of θo × Δφ at a resolution that divides 180°.
#[derive(Debug, Clone, Copy, PartialEq, serde::Serialize)]
pub struct AngularGrid {
    pub res_deg: f64,
    pub n_theta: usize,
    pub n_phi: usize,
}

impl AngularGrid {
    /// `res_deg` must divide 180 into a whole number of bins (0.25°–30°).
    pub fn new(res_deg: f64) -> Result<Self, String> {
        let n = 180.0 / res_deg;
        if !(0.25..=30.0).contains(&res_deg) || (n - n.round()).abs() > 1e-9 {
            return Err(format!(
                "resolution {res_deg}° must divide 180° into whole bins, within [0.25°, 30°]"
            ));
        }
        let n = n.round() as usize;
        Ok(Self {
            res_deg,
            n_theta: n,
            n_phi: 2 * n,
        })
    }

    pub fn bins(&self) -> usize {
        self.n_theta * self.n_phi
    }

    /// Flat bin index (θ row-major) of direction `dir` leaving a fiber lit from `phi_i_rad`.
    #[inline]
    pub fn bin(&self, dir: [f64; 3], phi_i_rad: f64) -> u32 {
        let res = self.res_deg.to_radians();
        let theta = dir[2].clamp(-1.0, 1.0).asin();
        let it = (((theta + FRAC_PI_2) / res) as usize).min(self.n_theta - 1);
        let mut dphi = dir[1].atan2(dir[0]) - phi_i_rad;
        dphi -= TAU * ((dphi + PI) / TAU).floor();
        let ip = (((dphi + PI) / res) as usize).min(self.n_phi - 1);
        (it * self.n_phi + ip) as u32
    }

    pub fn theta_edges_deg(&self) -> Vec<f64> {
        (0..=self.n_theta)
            .map(|i| -90.0 + i as f64 * self.res_deg)
            .collect()
    }

    pub fn dphi_edges_deg(&self) -> Vec<f64> {
        (0..=self.n_phi)
            .map(|i| -180.0 + i as f64 * self.res_deg)
            .collect()
    }

    /// Solid angle of θ row `it` (one Δφ bin), sr.
    pub fn solid_angle(&self, it: usize) -> f64 {
        let r = self.res_deg.to_radians();
        let t0 = -FRAC_PI_2 + it as f64 * r;
        r * ((t0 + r).sin() - t0.sin())
    }
}

/// Σw and Σw² per bin for each absorption coefficient of a trace, plus photon counts.
#[derive(Debug, Clone, PartialEq)]
pub struct Tally {
    pub grid: AngularGrid,
    /// The absorption coefficients scored, per µm.
    pub mua_per_um: Vec<f64>,
    /// `sum[k][bin]`: Σ exp(−μa_k ℓ) over photons leaving into `bin`.
    pub sum: Vec<Vec<f64>>,
    pub sum2: Vec<Vec<f64>>,
    /// Photons launched across the beam.
    pub launched: u64,
    /// Photons that met the fiber (the normalisation of every fraction).
    pub intercepted: u64,
    /// Photons stopped by the event limit (counted as absorbed).
    pub lost: u64,
    /// Boundary events that fell back to the mean surface ([`super::surface`]).
    pub fallbacks: u64,
    /// Σ ℓ and Σ ℓ² of the path length inside the fiber over exiting photons, µm.
    pub path_sum_um: f64,
    pub path_sum2_um2: f64,
}

impl Tally {
    pub fn new(grid: AngularGrid, mua_per_um: &[f64]) -> Self {
        let k = mua_per_um.len();
        Self {
            grid,
            mua_per_um: mua_per_um.to_vec(),
            sum: vec![vec![0.0; grid.bins()]; k],
            sum2: vec![vec![0.0; grid.bins()]; k],
            launched: 0,
            intercepted: 0,
            lost: 0,
            fallbacks: 0,
            path_sum_um: 0.0,
            path_sum2_um2: 0.0,
        }
    }

    /// Scores one exiting photon of weight `g` (1 for a single incident direction).
    #[inline]
    pub fn score(&mut self, bin: u32, path_um: f64, g: f64) {
        let b = bin as usize;
        self.path_sum_um += path_um;
        self.path_sum2_um2 += path_um * path_um;
        for k in 0..self.mua_per_um.len() {
            let mua = self.mua_per_um[k];
            // Beer–Lambert along the recorded path (§5.3.1): the walk itself does not depend on μa.
            let w = if mua == 0.0 {
                g
            } else {
                g * (-mua * path_um).exp()
            };
            self.sum[k][b] += w;
            self.sum2[k][b] += w * w;
        }
    }

    /// Adds another tally (same grid and μa list) in place.
    pub fn merge(&mut self, o: &Tally) {
        for k in 0..self.sum.len() {
            for (a, b) in self.sum[k].iter_mut().zip(&o.sum[k]) {
                *a += b;
            }
            for (a, b) in self.sum2[k].iter_mut().zip(&o.sum2[k]) {
                *a += b;
            }
        }
        self.launched += o.launched;
        self.intercepted += o.intercepted;
        self.lost += o.lost;
        self.fallbacks += o.fallbacks;
        self.path_sum_um += o.path_sum_um;
        self.path_sum2_um2 += o.path_sum2_um2;
    }

    /// Mean and standard error of a per-photon score with sums `s`, `s2` over N intercepted.
    fn mean_se(&self, s: f64, s2: f64) -> (f64, f64) {
        let n = self.intercepted.max(1) as f64;
        let m = s / n;
        (m, ((s2 / n - m * m).max(0.0) / n).sqrt())
    }

    /// Directional albedo: the fraction of the intercepted power that leaves the fiber, and its
    /// standard error.
    pub fn albedo(&self, k: usize) -> (f64, f64) {
        self.mean_se(self.sum[k].iter().sum(), self.sum2[k].iter().sum())
    }

    /// Fractions of the intercepted power per (θo, Δφ) bin, row-major, and standard errors.
    pub fn hist2d(&self, k: usize) -> (Vec<f64>, Vec<f64>) {
        self.sum[k]
            .iter()
            .zip(&self.sum2[k])
            .map(|(&s, &s2)| self.mean_se(s, s2))
            .unzip()
    }

    /// Fractions per Δφ bin summed over θo (each photon lands in one θ row, so the Σw² add).
    pub fn dphi_hist(&self, k: usize) -> (Vec<f64>, Vec<f64>) {
        let g = self.grid;
        (0..g.n_phi)
            .map(|j| {
                let s: f64 = (0..g.n_theta).map(|i| self.sum[k][i * g.n_phi + j]).sum();
                let s2: f64 = (0..g.n_theta).map(|i| self.sum2[k][i * g.n_phi + j]).sum();
                self.mean_se(s, s2)
            })
            .unzip()
    }

    /// Mean path length inside the fiber of the photons that left, µm.
    pub fn mean_path_um(&self) -> f64 {
        let n = (self.intercepted - self.lost).max(1) as f64;
        self.path_sum_um / n
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn bins_follow_the_conventions() {
        let g = AngularGrid::new(2.0).unwrap();
        assert_eq!((g.n_theta, g.n_phi), (90, 180));
        // Straight back towards the light (Δφ = 0) at θ = 0: θ row 45, Δφ column 90.
        let b = g.bin([1.0, 0.0, 0.0], 0.0);
        assert_eq!(b as usize, 45 * 180 + 90);
        // Forward (Δφ = ±180° wraps to −180°): column 0.
        let b = g.bin([-1.0, 0.0, 0.0], 0.0);
        assert_eq!(b as usize % 180, 0);
        assert!(AngularGrid::new(7.0).is_err());
        let total: f64 = (0..g.n_theta).map(|i| g.solid_angle(i)).sum::<f64>() * g.n_phi as f64;
        assert!((total - 4.0 * PI).abs() < 1e-9);
    }
}
