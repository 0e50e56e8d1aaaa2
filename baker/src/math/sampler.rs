//! Where a photon's uniform numbers come from: an independent random stream, or a randomised
//! quasi-Monte Carlo point set whose leading coordinates stratify a batch of photons jointly.
//!
//! **Randomised Sobol' points.** Photon j of a batch takes the j-th point of the Sobol' sequence
//! (Joe & Kuo 2008 direction numbers, as tabulated by the `sobol_burley` crate) for its first
//! coordinates, scrambled in two steps per batch and dimension d:
//! 1. a hash-based nested scramble (Burley, "Practical hash-based Owen scrambling", JCGT 9(4),
//!    2020): every output bit is the input bit flipped by a function of the bits above it, so
//!    the first 2^m points stay a (t, m, s)-net (each elementary box holds its share of points);
//! 2. an XOR with a uniform random word s_d (a random digital shift), also a nested scramble.
//!
//! Step 2 makes every point *exactly* uniform on the cube whatever step 1 does: for fixed
//! x, x ⊕ s with s uniform on 32-bit words is uniform, and the shifts of different dimensions
//! are independent, so each photon's coordinates are jointly uniform. Each photon is therefore
//! distributed exactly as with independent random numbers and every estimate stays unbiased;
//! only the correlation *between* the photons of a batch changes, and that lowers the variance
//! of their mean wherever the score is a regular function of the stratified coordinates.
//! Batches use independent scrambles, so the spread of batch means remains an unbiased
//! estimate of the error (Owen 1997; L'Ecuyer & Lemieux 2002, "randomised QMC").
//!
//! **Which coordinates.** A photon's walk draws a varying number of uniforms, so coordinates
//! are assigned by role rather than by order: the launch (incidence within the bin, the offset
//! across the beam, the axial position) takes dimensions 0–3, and boundary event k of the
//! photon's main path takes the [`EVENT_DIMS`] dimensions from 4 + k·[`EVENT_DIMS`] on, in the
//! order the boundary draws them (facet slope, facet azimuth, V-cavity side, Fresnel choice,
//! masking). Draws beyond those, events after [`QMC_EVENTS`], extra draws of a split event
//! and branches come from the batch's random stream.

use rand_core::Rng;
use sobol_burley::parts::{hash, owen_scramble_rev, sobol_rev};

use super::rng::{uniform, BatchRng};

/// Sobol' dimensions of the launch: incidence θ and φ within the bin, offset, axial position.
pub const LAUNCH_DIMS: u32 = 4;
/// Sobol' dimensions per boundary event.
pub const EVENT_DIMS: u32 = 6;
/// Boundary events of a photon's main path that draw from the Sobol' point.
pub const QMC_EVENTS: u32 = 6;
/// Sobol' dimensions in all.
pub const QMC_DIMS: u32 = LAUNCH_DIMS + EVENT_DIMS * QMC_EVENTS;
/// Largest batch a scrambled Sobol' point set serves (the direction numbers have 16 bits).
pub const MAX_QMC_BATCH: u64 = 1 << 16;

/// The scrambles of one batch: a nested-scramble seed and a digital shift per dimension.
#[derive(Debug, Clone)]
pub struct Scramble {
    seeds: [u32; QMC_DIMS as usize],
    shifts: [u32; QMC_DIMS as usize],
}

impl Scramble {
    /// Independent scrambles drawn from the batch's stream.
    pub fn draw(rng: &mut BatchRng) -> Self {
        let mut seeds = [0; QMC_DIMS as usize];
        let mut shifts = [0; QMC_DIMS as usize];
        for (s, t) in seeds.iter_mut().zip(shifts.iter_mut()) {
            let w = rng.next_u64();
            *s = hash(w as u32);
            *t = (w >> 32) as u32;
        }
        Self { seeds, shifts }
    }

    /// Coordinate `dim` of point `index` (< 2¹⁶), as a uniform number in (0, 1).
    #[inline]
    pub fn coordinate(&self, index: u32, dim: u32) -> f64 {
        let d = dim as usize;
        let x = owen_scramble_rev(sobol_rev(index.reverse_bits(), dim), self.seeds[d])
            .reverse_bits()
            ^ self.shifts[d];
        (x as f64 + 0.5) * (1.0 / 4_294_967_296.0)
    }
}

/// The uniform numbers of one photon.
pub struct PathSampler<'a> {
    rng: &'a mut BatchRng,
    qmc: Option<(&'a Scramble, u32)>,
    /// Next Sobol' dimension and the end of the current block of them.
    dim: u32,
    end: u32,
}

impl<'a> PathSampler<'a> {
    /// Every number from the random stream (plain Monte Carlo).
    pub fn random(rng: &'a mut BatchRng) -> Self {
        Self {
            rng,
            qmc: None,
            dim: 0,
            end: 0,
        }
    }

    /// Photon `index` of a batch scrambled by `scramble`: launch coordinates first.
    pub fn sobol(rng: &'a mut BatchRng, scramble: &'a Scramble, index: u32) -> Self {
        debug_assert!((index as u64) < MAX_QMC_BATCH);
        Self {
            rng,
            qmc: Some((scramble, index)),
            dim: 0,
            end: LAUNCH_DIMS,
        }
    }

    /// The next uniform number in (0, 1). The random stream's path stays inline (plain
    /// tracing calls this a dozen times per photon); the Sobol' coordinate is a call.
    #[inline(always)]
    pub fn uniform(&mut self) -> f64 {
        if self.dim < self.end {
            if let Some((s, i)) = self.qmc {
                return self.coordinate(s, i);
            }
        }
        uniform(self.rng.next_u64())
    }

    #[inline(never)]
    fn coordinate(&mut self, s: &Scramble, i: u32) -> f64 {
        self.dim += 1;
        s.coordinate(i, self.dim - 1)
    }

    /// A number from the random stream, whatever the point set (for draws that are not part
    /// of the path, such as the offset of an expected-value quadrature).
    #[inline]
    pub fn stream(&mut self) -> f64 {
        uniform(self.rng.next_u64())
    }

    /// The numbers that follow are boundary event `k`'s (0 = the first the photon meets).
    #[inline]
    pub fn begin_event(&mut self, k: u32) {
        if k < QMC_EVENTS {
            self.dim = LAUNCH_DIMS + k * EVENT_DIMS;
            self.end = self.dim + EVENT_DIMS;
        } else {
            self.end = 0;
        }
    }

    /// The numbers that follow come from the random stream until the next event.
    #[inline]
    pub fn leave_points(&mut self) {
        self.end = 0;
    }

    /// Launch dimension `dim` (< [`LAUNCH_DIMS`]) directly.
    #[inline]
    pub fn launch(&mut self, dim: u32) -> f64 {
        match self.qmc {
            Some((s, i)) => s.coordinate(i, dim),
            None => uniform(self.rng.next_u64()),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::math::rng::batch_rng;

    /// The first 2^m points stay a net: in each dimension pair of the launch and first event,
    /// every one of the 2^m elementary boxes of shape 2^a × 2^(m−a) holds exactly one point
    /// (t = 0 for Sobol's first two dimensions; checked for the shapes each pair attains).
    #[test]
    fn scrambled_points_stratify_each_coordinate() {
        let mut rng = batch_rng(3, 0);
        let s = Scramble::draw(&mut rng);
        let n = 1u32 << 10;
        for d in 0..QMC_DIMS {
            let mut seen = vec![false; n as usize];
            for i in 0..n {
                let k = (s.coordinate(i, d) * n as f64) as usize;
                assert!(!seen[k], "dimension {d}: two points in stratum {k}");
                seen[k] = true;
            }
        }
        // Dimensions 0 and 1 form a (0, m, 2)-net: every 2^5 × 2^5 box holds one point.
        let mut seen = vec![false; n as usize];
        for i in 0..n {
            let a = (s.coordinate(i, 0) * 32.0) as usize;
            let b = (s.coordinate(i, 1) * 32.0) as usize;
            assert!(!seen[a * 32 + b], "box ({a}, {b}) twice");
            seen[a * 32 + b] = true;
        }
    }

    /// Each coordinate of one point is uniform over scrambles (the digital shift): the mean
    /// and variance of coordinate (index 5, dimension d) over 20,000 batches' scrambles match
    /// U(0, 1) within 5 standard errors, and two dimensions are uncorrelated.
    #[test]
    fn one_point_is_uniform_over_scrambles() {
        let n = 20_000;
        for d in [0, 1, 7, QMC_DIMS - 1] {
            let (mut s1, mut s2, mut s12) = (0.0, 0.0, 0.0);
            for b in 0..n {
                let mut rng = batch_rng(9, b);
                let s = Scramble::draw(&mut rng);
                let x = s.coordinate(5, d);
                let y = s.coordinate(5, (d + 1) % QMC_DIMS);
                s1 += x;
                s2 += x * x;
                s12 += (x - 0.5) * (y - 0.5);
            }
            let nf = n as f64;
            let mean = s1 / nf;
            let var = s2 / nf - mean * mean;
            assert!(
                (mean - 0.5).abs() < 5.0 * (1.0f64 / 12.0 / nf).sqrt(),
                "d {d}: mean {mean}"
            );
            // Var of the sample variance of U(0,1): (1/80 − 1/144)/n.
            assert!(
                (var - 1.0 / 12.0).abs() < 5.0 * ((1.0 / 80.0 - 1.0 / 144.0) / nf).sqrt(),
                "d {d}: variance {var}"
            );
            assert!(
                (s12 / nf).abs() < 5.0 / 12.0 / nf.sqrt(),
                "d {d}: correlation"
            );
        }
    }
}
