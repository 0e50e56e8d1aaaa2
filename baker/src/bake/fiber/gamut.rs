//! Energy of RGB tables: no channel albedo above one.
//!
//! An RGB channel is a fixed linear map of the spectral result, Λ_c = Σλ M_cλ Λ(λ) (linear
//! sRGB under D65, white = 1; [`crate::spectral::ColourMap`]). Every Λ(λ) ≤ 1, but M has
//! negative entries, so a saturated dye's spectrum lies outside the sRGB gamut and one channel
//! can exceed one (measured before this mapping: 1.13 for silk, 1.08 for wool). A renderer
//! would then create energy.
//!
//! The mapping, per table, stored direction and *dyed* variant: when m = max_c Λ_c > 1,
//! every channel's fractions (hence f = Λ·f̂ and Λ) are divided by m. The chromaticity
//! (ratios of the channels) is kept, the normalised f̂ = P/(Λ·ΔΩ) is unchanged, and the
//! standard errors scale with the values. It is the smallest uniform scaling that brings the
//! variant within [0, 1] ("hue-preserving clipping" by scaling towards black).
//!
//! Undyed variants (white maps to R = G = B = the spectral albedo) are scaled the same way
//! when their albedo exceeds one, which only the noise of an estimator that does not conserve
//! each photon's weight exactly can make it do (splitting with Russian roulette, expected-value
//! exits: Λ of a fiber that absorbs nothing is then 1 ± its standard error; measured up to
//! 1.017 in `specs/fibers.yaml`'s silk). It cannot hide an energy bug: an undyed albedo more
//! than [`UNDYED_NOISE_LIMIT`] above one, or a dyed channel above what any spectrum ≤ 1 can
//! give, Σλ max(M_cλ, 0), is an error, not clipped. Spectral tables are never scaled.

use crate::fiber::slices::SliceResult;
use crate::spectral::ColourMap;

/// Relative slack on the gamut bound: the channel weights are interpolated over path length
/// (≤ 5·10⁻⁵ of their value, [`crate::fiber::sweep`]).
const BOUND_SLACK: f64 = 1e-3;

/// How far above one an undyed albedo may be scaled back as noise: far above the noise of
/// any table (≤ 2 % at 4,096 photons a direction with every estimator); more is an energy
/// bug and an error.
pub const UNDYED_NOISE_LIMIT: f64 = 0.1;

/// The mapping of one entry's RGB tables.
#[derive(Debug, Clone)]
pub struct GamutClip {
    /// Per channel (R, G, B): the largest Λ_c a spectrum with every Λ(λ) ≤ 1 can map to.
    bound: [f64; 3],
    /// Per variant: whether it is undyed (scaled only within [`UNDYED_NOISE_LIMIT`]).
    undyed: Vec<bool>,
}

/// A channel albedo no spectrum ≤ 1 can produce (dyed), or an undyed albedo more than
/// [`UNDYED_NOISE_LIMIT`] above one: an energy bug upstream.
#[derive(Debug, thiserror::Error, PartialEq)]
#[error(
    "variant {variant} channel {channel}: albedo {albedo} exceeds {bound}, more than any \
     spectral albedo ≤ 1 and its noise give (energy is created before the RGB mapping)"
)]
pub struct BeyondGamut {
    pub variant: usize,
    pub channel: usize,
    pub albedo: f64,
    pub bound: f64,
}

impl GamutClip {
    /// The mapping for RGB channels from spectra on `lambda_nm`; `undyed[v]` marks the
    /// undyed variants.
    pub fn new(lambda_nm: &[f64], undyed: Vec<bool>) -> GamutClip {
        let cm = ColourMap::new(lambda_nm);
        let bound = std::array::from_fn(|c| cm.rgb_weights.iter().map(|w| w[c].max(0.0)).sum());
        GamutClip { bound, undyed }
    }

    /// Scales every variant of `r` whose largest channel albedo exceeds one (3 channels per
    /// variant, `bins` per channel); returns the factor m ≥ 1 each variant was divided by
    /// (1 where untouched).
    pub fn apply(&self, r: &mut SliceResult, bins: usize) -> Result<Vec<f64>, BeyondGamut> {
        let mut factors = vec![1.0; self.undyed.len()];
        for (v, &undyed) in self.undyed.iter().enumerate() {
            let chans = 3 * v..3 * v + 3;
            for (c, k) in chans.clone().enumerate() {
                let bound = self.bound[c] * (1.0 + BOUND_SLACK);
                if r.albedo[k] > bound {
                    return Err(BeyondGamut {
                        variant: v,
                        channel: c,
                        albedo: r.albedo[k],
                        bound: self.bound[c],
                    });
                }
            }
            let m = r.albedo[chans.clone()].iter().copied().fold(0.0, f64::max);
            if m <= 1.0 {
                continue;
            }
            if undyed && m > 1.0 + UNDYED_NOISE_LIMIT {
                let k = chans.start
                    + (0..3)
                        .find(|&c| r.albedo[chans.start + c] == m)
                        .unwrap_or(0);
                return Err(BeyondGamut {
                    variant: v,
                    channel: k - chans.start,
                    albedo: m,
                    bound: 1.0 + UNDYED_NOISE_LIMIT,
                });
            }
            // The divisor is itself an estimate: Λ_c/m has, to first order, the variance
            // (SE_c² + (Λ_c/m)²·SE_m² − 2(Λ_c/m)·cov)/m². The channels share their photons,
            // so cov ≥ 0 and dropping it bounds the error from above (the max channel
            // itself keeps SE_m/m).
            let km = chans.start
                + (0..3)
                    .max_by(|&a, &b| {
                        r.albedo[chans.start + a].total_cmp(&r.albedo[chans.start + b])
                    })
                    .unwrap_or(0);
            let se_m = r.albedo_se[km];
            for k in chans {
                r.fraction[k * bins..(k + 1) * bins]
                    .iter_mut()
                    .for_each(|x| *x /= m);
                r.albedo[k] /= m;
                r.albedo_se[k] = if k == km {
                    r.albedo_se[k] / m
                } else {
                    r.albedo_se[k].hypot(r.albedo[k] * se_m) / m
                };
            }
            // `density_se` is the error of variant 0's density: it follows its values.
            if v == 0 {
                r.density_se.iter_mut().for_each(|x| *x /= m);
            }
            factors[v] = m;
        }
        Ok(factors)
    }
}

/// What the mapping did to one table (or an entry's tables).
#[derive(Debug, Clone, PartialEq, serde::Serialize)]
pub struct ClipStats {
    /// Stored directions with at least one variant scaled.
    pub directions: usize,
    /// (Direction, variant) slices scaled (over the entry's tables in the manifest).
    pub slices: usize,
    /// Largest factor divided by (the largest channel albedo before the mapping); 1 if none.
    pub max_factor: f64,
}

impl Default for ClipStats {
    fn default() -> ClipStats {
        ClipStats {
            directions: 0,
            slices: 0,
            max_factor: 1.0,
        }
    }
}

impl ClipStats {
    /// Merges the stats of another table of the same entry (directions are counted per
    /// table, so the sum can count a direction more than once).
    pub fn merge(&mut self, o: &ClipStats) {
        self.directions += o.directions;
        self.slices += o.slices;
        self.max_factor = self.max_factor.max(o.max_factor);
    }

    /// Adds one direction's factors (from [`GamutClip::apply`]).
    pub fn add(&mut self, factors: &[f64]) {
        let n = factors.iter().filter(|&&m| m > 1.0).count();
        self.directions += usize::from(n > 0);
        self.slices += n;
        self.max_factor = factors.iter().copied().fold(self.max_factor, f64::max);
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::fiber::slices::Noise;
    use formats::AngularGrid;

    fn lambda() -> Vec<f64> {
        (0..31).map(|i| 400.0 + 10.0 * i as f64).collect()
    }

    /// A slice of two variants (undyed, dyed) × RGB on a 30° grid: variant v channel c has
    /// a shape of its own scaled to albedo `alb[v][c]`.
    fn slice(alb: [[f64; 3]; 2]) -> (SliceResult, AngularGrid) {
        let grid = AngularGrid::new(30.0).unwrap();
        let bins = grid.bins();
        let mut fraction = vec![0.0; 6 * bins];
        for k in 0..6 {
            let shape: Vec<f64> = (0..bins)
                .map(|b| 1.0 + ((b * (k + 3)) % 5) as f64)
                .collect();
            let s: f64 = shape.iter().sum();
            for b in 0..bins {
                fraction[k * bins + b] = alb[k / 3][k % 3] * shape[b] / s;
            }
        }
        let albedo: Vec<f64> = (0..6)
            .map(|k| fraction[k * bins..(k + 1) * bins].iter().sum())
            .collect();
        let r = SliceResult {
            fraction,
            albedo_se: albedo.iter().map(|a| 0.01 * a).collect(),
            albedo,
            density_se: vec![0.001; bins],
            dphi_se: vec![],
            noise: Noise::default(),
            launched: 1,
            intercepted: 1,
            lost_weight: 0.0,
            seconds: 0.0,
        };
        (r, grid)
    }

    /// A dyed variant above one is divided by its largest channel: max channel exactly one,
    /// the channels' ratios and f̂ kept, its errors scaled alike; the undyed variant and a
    /// dyed one within gamut are untouched.
    #[test]
    fn a_dyed_channel_above_one_is_scaled_keeping_hue_and_normalised_bcsdf() {
        let clip = GamutClip::new(&lambda(), vec![true, false]);
        let (mut r, grid) = slice([[1.0, 1.0, 1.0], [1.13, 0.42, 0.2]]);
        let before = r.clone();
        let f_hat = r.normalised(&grid);
        let m = clip.apply(&mut r, grid.bins()).unwrap();
        assert_eq!(m[0], 1.0);
        assert!((m[1] - 1.13).abs() < 1e-12, "{m:?}");
        let a = &r.albedo;
        assert!((a[3] - 1.0).abs() < 1e-12 && a[3] <= 1.0, "{a:?}");
        assert!((a[4] / a[3] - 0.42 / 1.13).abs() < 1e-12);
        assert!((a[5] / a[4] - 0.2 / 0.42).abs() < 1e-12);
        assert_eq!(&r.albedo[..3], &before.albedo[..3]);
        assert_eq!(
            &r.fraction[..3 * grid.bins()],
            &before.fraction[..3 * grid.bins()]
        );
        for (k, (x, y)) in r.normalised(&grid).iter().zip(&f_hat).enumerate() {
            assert!((x - y).abs() <= 1e-12 * y.abs(), "f̂[{k}] {x} vs {y}");
        }
        // The max channel's relative error is kept; the others add the divisor's
        // (1 % relative each here): √(0.01² + 0.01²) relative.
        assert!((r.albedo_se[3] / r.albedo[3] - 0.01).abs() < 1e-12);
        for k in 4..6 {
            let rel = r.albedo_se[k] / r.albedo[k];
            assert!((rel - 0.01f64.hypot(0.01)).abs() < 1e-12, "{rel}");
        }
        assert_eq!(r.density_se, before.density_se, "variant 0 was not scaled");
        // Within gamut: nothing moves.
        let (mut r, grid) = slice([[1.0, 1.0, 1.0], [0.9, 0.42, 0.2]]);
        let before = r.clone();
        assert_eq!(clip.apply(&mut r, grid.bins()).unwrap(), vec![1.0, 1.0]);
        assert_eq!(r.fraction, before.fraction);
    }

    /// An undyed variant a little above one (an estimator's noise) is scaled back to one
    /// like a dyed one, grey kept grey; one more than [`UNDYED_NOISE_LIMIT`] above is an
    /// error (an energy bug), and so is a channel beyond what any spectrum ≤ 1 can map to.
    #[test]
    fn undyed_noise_is_scaled_and_impossible_albedo_is_an_error() {
        let clip = GamutClip::new(&lambda(), vec![true, false]);
        let (mut r, grid) = slice([[1.02, 1.02, 1.01], [0.5, 0.5, 0.5]]);
        let f = clip.apply(&mut r, grid.bins()).unwrap();
        assert!((f[0] - 1.02).abs() < 1e-12 && f[1] == 1.0, "{f:?}");
        assert!((r.albedo[0] - 1.0).abs() < 1e-12 && (r.albedo[2] - 1.01 / 1.02).abs() < 1e-12);
        let (mut r, grid) = slice([[1.0, 1.0 + 1.5 * UNDYED_NOISE_LIMIT, 1.0], [0.5, 0.5, 0.5]]);
        let e = clip.apply(&mut r, grid.bins()).unwrap_err();
        assert_eq!((e.variant, e.channel), (0, 1), "{e}");
        let (mut r, grid) = slice([[1.0, 1.0, 1.0], [0.5, 2.5, 0.5]]);
        let e = clip.apply(&mut r, grid.bins()).unwrap_err();
        assert_eq!((e.variant, e.channel), (1, 1));
        assert!(e.bound > 1.0 && e.bound < 2.5, "{e}");
    }

    #[test]
    fn stats_count_directions_and_slices() {
        let mut s = ClipStats::default();
        s.add(&[1.0, 1.0]);
        assert_eq!(s.max_factor, 1.0);
        s.add(&[1.0, 1.05, 1.1]);
        s.add(&[1.02]);
        assert_eq!(
            s,
            ClipStats {
                directions: 2,
                slices: 3,
                max_factor: 1.1
            }
        );
    }
}
