//! Expected-value exit scoring: where a path leaves a fiber through a rough boundary, score the
//! exit lobe's mass over the outgoing bins instead of one sampled direction.
//!
//! A rough boundary spreads every exit over a lobe (6–17° Beckmann facets: many 2° bins), and
//! a plain photon puts all its weight into the one bin its draw lands in. Here, at a boundary
//! event whose exit leaves the fiber for good ([`super::Section::leaves_freely`]), the part of
//! the event's outcome that has a density, leaving at the first facet met
//! ([`super::Surface::first_facet_pdf`]: refraction out from inside, unmasked reflection from
//! outside), is scored in expectation over a window W of bins around the lobe:
//!
//!   E[bin b] = w · ∫_b p(ωo) dωo  for every b ∈ W,
//!
//! each integral estimated without bias by the density at one point of the bin, uniform in
//! solid angle, times the bin's solid angle (one random offset (u, v) per event, shared by the
//! window's bins: a randomly shifted product rule). The event is then drawn as before and its
//! outcome scored *unless* it is a first-facet exit landing in W, which the expectation has
//! already counted; a path that stays goes on unchanged. So for any window the expected score
//! of every bin is plain tracing's (the window only decides how much is scored in expectation
//! and how much by the draw), and the path's continuation is plain tracing's draw by draw.
//!
//! The window is the bounding box, in (θo, Δφ) bins, of the exits through facets whose slope
//! is [`WINDOW_SLOPES`]·α in a ring of directions, plus a bin on each side; the Beckmann
//! slopes are Gaussian, so facets beyond that radius carry exp(−WINDOW_SLOPES²) of the lobe,
//! which the draw then scores. Windows near a pole span every Δφ; a window larger than
//! [`MAX_WINDOW_BINS`] is not evaluated (its event is drawn plainly), which bounds the cost.
//!
//! Only a photon's main path scores in expectation. The plain branches a split event starts
//! (weight w/split each, [`super::tracer`]'s children) score their exits by their draw, as
//! unbiased: a window costs the same whatever the weight it scores, and cotton's lumen-facing
//! events start about 29 branches each. Cotton reaches the thesis's noise 1.56× sooner so;
//! silk, whose concavities start few, as soon (record 2026-12-08-fiber-dispatch-macro).
//!
//! Cost: a window holds tens (polyester at 2°) to thousands (cotton) of bins, so the densities
//! dominate. The bins' directions come from per-grid tables (sin and cos of the θ edges and of
//! the column steps, the ring's azimuths), and the densities of 64 bins at a time from one
//! branch-free, vectorised pass in single precision ([`FacetPdf::eval_many`]: the same bits
//! on every machine).

use std::f64::consts::{FRAC_PI_2, PI, TAU};

use smallvec::SmallVec;

use super::surface::{basis, dot, normalize, reflect, refract, FacetPdf};
use super::Surface;
use crate::math::avx2::avx2_dispatch;
use formats::AngularGrid;

/// Slope radius of the window's ring, in units of the RMS slope α.
pub const WINDOW_SLOPES: f64 = 2.0;
/// Azimuths of the ring.
const RING: usize = 16;
/// Largest window evaluated, bins.
pub const MAX_WINDOW_BINS: usize = 4096;

/// The outgoing grid of one incoming bin, ready to evaluate exit lobes on.
#[derive(Debug, Clone)]
pub struct LobeGrid {
    grid: AngularGrid,
    /// Azimuth Δφ is measured from, radians.
    phi_c: f64,
    res: f64,
    /// sin and cos of the θ edges, `n_theta + 1`.
    sin_edges: Vec<f64>,
    cos_edges: Vec<f64>,
    /// (cos, sin) of j·res for every column offset j (the window's columns by angle
    /// addition, [`LobeGrid::spread`]).
    col_steps: Vec<(f64, f64)>,
    /// (cos, sin) of the ring's azimuths.
    ring: [(f64, f64); RING],
}

/// One boundary event: the photon's direction `d`, the mean normal `nf` facing it, and its side.
#[derive(Debug, Clone, Copy)]
pub struct Event {
    pub d: [f64; 3],
    pub nf: [f64; 3],
    pub inside: bool,
}

impl LobeGrid {
    pub fn new(grid: AngularGrid, phi_c_rad: f64) -> Self {
        let res = grid.res_deg.to_radians();
        let edge = |i: usize| (-FRAC_PI_2 + i as f64 * res).sin_cos();
        Self {
            grid,
            phi_c: phi_c_rad,
            res,
            sin_edges: (0..=grid.n_theta)
                .map(|i| edge(i).0.clamp(-1.0, 1.0))
                .collect(),
            cos_edges: (0..=grid.n_theta).map(|i| edge(i).1.max(0.0)).collect(),
            col_steps: (0..grid.n_phi)
                .map(|j| {
                    let (s, c) = (j as f64 * res).sin_cos();
                    (c, s)
                })
                .collect(),
            ring: std::array::from_fn(|k| {
                let (s, c) = (TAU * k as f64 / RING as f64).sin_cos();
                (c, s)
            }),
        }
    }

    avx2_dispatch! {
        /// The lobe of event `e`: a cone about the exit through the mean normal (reflection
        /// from outside, refraction from inside) as wide as the exits through facets of slope
        /// [`WINDOW_SLOPES`]·α, and the bins its bounding box covers. None when the surface is
        /// smooth, the mean normal reflects the photon back inside (total internal
        /// reflection), or the window would exceed [`MAX_WINDOW_BINS`].
        ///
        /// Under AVX2 (`avx2_dispatch!`) the facet loop runs 4 lanes wide and `floor` is one
        /// instruction: the same IEEE operations (no fused multiply-add), so the same bits.
        pub fn lobe(&self as LobeGrid, s: &Surface, e: &Event) -> Option<Lobe>
            => LobeGrid::lobe_in
    }

    #[inline(always)]
    fn lobe_in(&self, s: &Surface, e: &Event) -> Option<Lobe> {
        if s.alpha == 0.0 {
            return None;
        }
        // Exits through the mean normal and through facets on rings of slope α and
        // WINDOW_SLOPES·α: the cone's axis is their mean direction, its half-angle reaches the
        // farthest. Under total internal reflection at the mean normal the exits come from the
        // tilted facets only (grazing lobes), which the rings still find.
        let (t, b) = basis(e.nf);
        let mut ring = Ring::default();
        for (r, radius) in [s.alpha, WINDOW_SLOPES * s.alpha].into_iter().enumerate() {
            for (k, &(ca, sa)) in self.ring.iter().enumerate() {
                let lane = 1 + r * RING + k;
                (ring.sx[lane], ring.sy[lane]) = (radius * ca, radius * sa);
            }
        }
        ring.exits(s, e, (t, b));
        let exit = |l: usize| [ring.w[0][l], ring.w[1][l], ring.w[2][l]];
        let mut sum = [0.0; 3];
        for l in (0..RING_LANES).filter(|&l| ring.ok[l]) {
            let w = exit(l);
            sum = [sum[0] + w[0], sum[1] + w[1], sum[2] + w[2]];
        }
        // No exit at all leaves the sum 0.
        if dot(sum, sum) < 1e-12 {
            return None;
        }
        let axis = normalize(sum);
        let cos_rho = (0..RING_LANES)
            .filter(|&l| ring.ok[l])
            .map(|l| dot(exit(l), axis))
            .fold(1.0f64, f64::min);
        // The window holds at least the cone's solid angle 2π(1 − cos ρ) in bins of at most
        // res² each: past the limit already, it is not laid out.
        if TAU * (1.0 - cos_rho) > MAX_WINDOW_BINS as f64 * self.res * self.res {
            return None;
        }
        let rho = cos_rho.clamp(-1.0, 1.0).acos();
        let g = &self.grid;
        let theta_a = axis[2].clamp(-1.0, 1.0).asin();
        let phi_a = axis[1].atan2(axis[0]);
        let it0 = ((theta_a - rho + FRAC_PI_2) / self.res).floor().max(0.0) as usize;
        let it1 =
            (((theta_a + rho + FRAC_PI_2) / self.res).floor().max(0.0) as usize).min(g.n_theta - 1);
        // Per θ row, the columns of the cone's arc: at latitude θ the cone holds the azimuths
        // with cos(φ − φa) ≥ (cos ρ − sin θ sin θa)/(cos θ cos θa); the widest arc of a row is
        // at the latitude nearest to the one where the arc is widest, sin θ = sin θa / cos ρ.
        // The half-angle is acos of x = (cos ρ − sin θ sin θa)/(cos θ cos θa), decreasing in
        // x: a row's widest arc is acos of the least x over its edges and the two latitudes
        // above where they fall inside it (x = −∞ where the cone holds every azimuth).
        let (sa, ca) = theta_a.sin_cos();
        let x_at = |st: f64, ct: f64| -> f64 {
            let den = ct * ca;
            if den <= 1e-12 {
                f64::NEG_INFINITY
            } else {
                (cos_rho - st * sa) / den
            }
        };
        let widest = if cos_rho > 0.0 {
            (sa / cos_rho).clamp(-1.0, 1.0).asin()
        } else {
            theta_a
        };
        let mut rows = SmallVec::new();
        let mut bins = 0;
        let mut x_lo = x_at(self.sin_edges[it0], self.cos_edges[it0]);
        for it in it0..=it1 {
            let lo = -FRAC_PI_2 + it as f64 * self.res;
            let hi = lo + self.res;
            let x_hi = x_at(self.sin_edges[it + 1], self.cos_edges[it + 1]);
            let mut x = x_lo.min(x_hi);
            for th in [widest, theta_a] {
                if th > lo && th < hi {
                    let (st, ct) = th.sin_cos();
                    x = x.min(x_at(st, ct));
                }
            }
            x_lo = x_hi;
            let half = if x <= -1.0 {
                PI
            } else if x >= 1.0 {
                0.0
            } else {
                x.acos()
            };
            let (jp0, np) = if half >= PI - self.res {
                (0, g.n_phi)
            } else {
                let (_, j_lo) = g.cell(0.0, phi_a - half - self.phi_c);
                let span = ((2.0 * half) / self.res).floor() as usize + 2;
                (j_lo, span.min(g.n_phi))
            };
            bins += np;
            rows.push((jp0 as u32, np as u32));
        }
        (bins <= MAX_WINDOW_BINS).then_some(Lobe {
            it0,
            rows,
            bins,
            axis,
            cos_rho,
        })
    }

    /// Whether direction `wo` lies in the cone of `lobe` (what [`LobeGrid::spread`] scores).
    #[inline]
    pub fn covers(&self, lobe: &Lobe, wo: [f64; 3]) -> bool {
        dot(wo, lobe.axis) >= lobe.cos_rho
    }

    /// Calls `f(bin, mass)` for every bin of the lobe's window with an unbiased estimate of
    /// the probability of a first-facet exit into the part of the bin inside the cone: the
    /// density inside the cone at the point (u, v) of the bin (uniform in sin θ and φ) times
    /// the bin's solid angle.
    pub fn spread(
        &self,
        lobe: &Lobe,
        s: &Surface,
        e: &Event,
        (u, v): (f64, f64),
        mut f: impl FnMut(u32, f64),
    ) {
        let g = &self.grid;
        if s.alpha == 0.0 {
            return;
        }
        let pdf = FacetPdf::new(s, e.d, e.nf, e.inside);
        // The window's directions in chunks of CHUNK (in row order, so `f` sees the bins in
        // the order a bin-by-bin loop would): each chunk's densities in one vectorised pass.
        let mut ch = Chunk::default();
        // Column jp's azimuth is φ0 + jp·res: its cos and sin by angle addition.
        let (s0p, c0p) = (self.phi_c - PI + v * self.res).sin_cos();
        for (r, &(jp0, np)) in lobe.rows.iter().enumerate() {
            let it = lobe.it0 + r;
            let (s0, s1) = (self.sin_edges[it], self.sin_edges[it + 1]);
            let st = s0 + u * (s1 - s0);
            let ct = (1.0 - st * st).max(0.0).sqrt();
            let omega = self.res * (s1 - s0);
            // The arc wraps at ±180° at most once (jp0 < n_phi, np ≤ n_phi).
            for c in 0..np as usize {
                let mut jp = jp0 as usize + c;
                if jp >= g.n_phi {
                    jp -= g.n_phi;
                }
                let (cj, sj) = self.col_steps[jp];
                let (cp, sp) = (c0p * cj - s0p * sj, s0p * cj + c0p * sj);
                let wo = [ct * cp, ct * sp, st];
                let k = ch.n;
                ch.x[k] = wo[0] as f32;
                ch.y[k] = wo[1] as f32;
                ch.z[k] = wo[2] as f32;
                // Only the cone is scored (what `covers` tells the draws), decided in double
                // precision as `covers` decides it.
                ch.mask[k] = dot(wo, lobe.axis) >= lobe.cos_rho;
                ch.bin[k] = (it * g.n_phi + jp) as u32;
                ch.omega[k] = omega;
                ch.n += 1;
                if ch.n == CHUNK {
                    ch.flush(&pdf, &mut f);
                }
            }
        }
        ch.flush(&pdf, &mut f);
    }
}

/// Directions per vectorised pass of [`LobeGrid::spread`].
const CHUNK: usize = 64;

/// A chunk of a window's directions (structure of arrays) and their densities.
struct Chunk {
    n: usize,
    x: [f32; CHUNK],
    y: [f32; CHUNK],
    z: [f32; CHUNK],
    mask: [bool; CHUNK],
    p: [f32; CHUNK],
    omega: [f64; CHUNK],
    bin: [u32; CHUNK],
}

impl Chunk {
    /// Evaluates the chunk's densities and hands each bin with mass to `f`; empties it.
    #[inline]
    fn flush(&mut self, pdf: &FacetPdf, f: &mut impl FnMut(u32, f64)) {
        let n = self.n;
        pdf.eval_many(&self.x, &self.y, &self.z, &self.mask, &mut self.p[..n]);
        for i in 0..n {
            if self.p[i] > 0.0 {
                f(self.bin[i], f64::from(self.p[i]) * self.omega[i]);
            }
        }
        self.n = 0;
    }
}

impl Default for Chunk {
    fn default() -> Self {
        Self {
            n: 0,
            x: [0.0; CHUNK],
            y: [0.0; CHUNK],
            z: [0.0; CHUNK],
            mask: [false; CHUNK],
            p: [0.0; CHUNK],
            omega: [0.0; CHUNK],
            bin: [0; CHUNK],
        }
    }
}

/// The first-facet exit lobe of one boundary event: the cone it is scored over in expectation
/// and the window of bins that holds the cone.
#[derive(Debug, Clone)]
pub struct Lobe {
    /// First θ row, and per row from it the first Δφ column and the number of columns (the
    /// cone's arc in that row, wrapping at ±180°).
    pub it0: usize,
    pub rows: SmallVec<[(u32, u32); 64]>,
    /// Bins in all rows.
    pub bins: usize,
    /// Unit axis of the cone (the exit through the mean normal) and cos of its half-angle.
    pub axis: [f64; 3],
    pub cos_rho: f64,
}

/// Facets probed per event: the mean normal, then [`RING`] on each of the two rings.
const RING_LANES: usize = 1 + 2 * RING;

/// The facet normals [`LobeGrid::lobe`] probes (structure of arrays) and the directions a
/// photon leaves in through each, where it leaves there.
struct Ring {
    /// Slopes of the facets along the basis vectors t, b of the mean normal (lane 0: 0, 0).
    sx: [f64; RING_LANES],
    sy: [f64; RING_LANES],
    w: [[f64; RING_LANES]; 3],
    ok: [bool; RING_LANES],
}

impl Default for Ring {
    fn default() -> Self {
        Self {
            sx: [0.0; RING_LANES],
            sy: [0.0; RING_LANES],
            w: [[0.0; RING_LANES]; 3],
            ok: [false; RING_LANES],
        }
    }
}

impl Ring {
    /// For every facet m ∝ nf + sx·t + sy·b (lane 0: the mean normal nf itself): the exit of
    /// event `e` through it, refracted out from inside (none under total internal reflection),
    /// reflected from outside, and whether it leaves the boundary. Lane by lane without branches, so the loop vectorises (same IEEE operations
    /// with or without AVX2, no fused multiply-add: the same bits on every x86-64 machine).
    #[inline(always)]
    fn exits(&mut self, s: &Surface, e: &Event, (t, b): ([f64; 3], [f64; 3])) {
        let (d, nf, eta) = (e.d, e.nf, s.eta);
        for l in 0..RING_LANES {
            let (sx, sy) = (self.sx[l], self.sy[l]);
            let m = normalize([
                nf[0] + sx * t[0] + sy * b[0],
                nf[1] + sx * t[1] + sy * b[1],
                nf[2] + sx * t[2] + sy * b[2],
            ]);
            let m = if l == 0 { nf } else { m };
            let cos_i = -dot(d, m);
            // Snell from inside (fresnel::dielectric's sin²θt, the fiber's η into air).
            let sin_t2 = eta * eta * (1.0 - cos_i * cos_i);
            let cos_t = (1.0 - sin_t2).max(0.0).sqrt();
            let w = if e.inside {
                refract(d, m, eta, cos_i, cos_t)
            } else {
                reflect(d, m, cos_i)
            };
            let side = dot(w, nf);
            let leaves = if e.inside {
                sin_t2 < 1.0 && side < 0.0
            } else {
                side > 0.0
            };
            self.ok[l] = cos_i > 0.0 && leaves;
            (self.w[0][l], self.w[1][l], self.w[2][l]) = (w[0], w[1], w[2]);
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::math::rng::{batch_rng, uniform};
    use rand_core::Rng;

    fn in_window(w: &Lobe, g: &AngularGrid, b: usize) -> bool {
        let (it, jp) = (b / g.n_phi, b % g.n_phi);
        if it < w.it0 || it >= w.it0 + w.rows.len() {
            return false;
        }
        let (jp0, np) = w.rows[it - w.it0];
        (jp + g.n_phi - jp0 as usize) % g.n_phi < np as usize
    }

    /// The density is the sampler's: first-facet exits drawn by `Surface::scatter` land in the
    /// bins of a 2° grid as the spread masses say (χ² over the window's bins, plus the mass
    /// outside it), from inside and from outside, at two roughnesses and tilted normals.
    #[test]
    fn first_facet_exits_follow_the_spread_masses() {
        let grid = AngularGrid::new(2.0).unwrap();
        let lg = LobeGrid::new(grid, 0.3);
        let mut rng = batch_rng(5, 0);
        let cases = [
            (6.5f64, true, [0.8, -0.4, 0.3], [-0.9, 0.3, 0.0]),
            (6.5, false, [0.5, -0.7, -0.2], [-0.2, 0.98, 0.0]),
            (15.0, true, [0.1, 0.95, 0.3], [0.0, -1.0, 0.0]),
            (10.0, false, [-0.6, -0.7, 0.3], [0.8, 0.6, 0.0]),
        ];
        for (beta, inside, d, nf) in cases {
            let s = Surface {
                eta: 1.56,
                alpha: beta.to_radians().tan(),
            };
            let e = Event {
                d: normalize(d),
                nf: normalize(nf),
                inside,
            };
            let lobe = lg.lobe(&s, &e).expect("a lobe");
            let w = &lobe;
            let mut expected = vec![0.0; grid.bins()];
            // The bin integrals by a 16 × 16 midpoint rule over the point (u, v).
            let k = 16;
            for i in 0..k * k {
                let uv = (
                    ((i / k) as f64 + 0.5) / k as f64,
                    ((i % k) as f64 + 0.5) / k as f64,
                );
                lg.spread(&lobe, &s, &e, uv, |b, m| {
                    expected[b as usize] += m / (k * k) as f64
                });
            }
            let n = 400_000;
            let mut observed = vec![0.0; grid.bins()];
            let mut outside = 0.0;
            let mut u = || uniform(rng.next_u64());
            for _ in 0..n {
                let r = s.scatter(e.d, e.nf, inside, &mut u);
                let leaves = r.transmitted == inside;
                if r.first_facet && leaves {
                    if lg.covers(&lobe, r.dir) {
                        let b = grid.bin(r.dir, 0.3) as usize;
                        assert!(in_window(w, &grid, b), "a covered exit outside the window");
                        observed[b] += 1.0;
                    } else {
                        outside += 1.0;
                    }
                }
            }
            let (mut obs, mut exp) = (vec![outside], vec![0.0]);
            let total: f64 = expected.iter().sum();
            // Bins of the window with enough expected counts; the rest pooled.
            let (mut po, mut pe) = (0.0, 0.0);
            for b in 0..grid.bins() {
                if !in_window(w, &grid, b) {
                    continue;
                }
                let x = expected[b] * n as f64;
                if x >= 20.0 {
                    obs.push(observed[b]);
                    exp.push(x);
                } else {
                    po += observed[b];
                    pe += x;
                }
            }
            obs.push(po);
            exp.push(pe);
            // The mass outside the window is what the first-facet exits leave beyond it:
            // the observed rate itself (it is not known in closed form), so it adds no χ²
            // term; the window's total must match the observed window fraction.
            exp[0] = outside;
            let labels: Vec<f64> = (0..obs.len()).map(|i| i as f64).collect();
            crate::stats::chi2::chi2_test_bins(
                &obs,
                &exp,
                &labels,
                &format!("first_facet_lobe_{beta}_{inside}"),
            );
            assert!(total > 0.02 && w.bins > 9, "window {w:?} holds {total}");
        }
    }
}
