//! Scores of exiting photons over the outgoing sphere (§5.3.2: "collected in an infinite
//! sphere bounding the fiber, as a function of ωo = ⟨φo, θo⟩"), binned on an [`AngularGrid`]
//! (its conventions: fiber axis +z; θ = asin(ω·z) ∈ [−90°, 90°]; φ = atan2(ω·y, ω·x); outgoing
//! azimuths relative to the incident one, Δφ = φo − φi wrapped to [−180°, 180°)).

use formats::AngularGrid;

/// Σw and Σw² per bin for each absorption coefficient of a trace, plus photon counts.
#[derive(Debug, Clone, PartialEq)]
pub struct DirectionTally {
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

impl DirectionTally {
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
    pub fn merge(&mut self, o: &DirectionTally) {
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
