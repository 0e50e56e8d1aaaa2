//! The photon loop and the batch runner.

use std::time::Instant;

use rand_core::Rng;
use rand_distr::{Distribution, Exp1};
use rayon::prelude::*;

use super::boundary::{fresnel, normal_reflectance};
use super::junction::HeightField;
use super::phase::Hg;
use super::stack::{Stack, StackError, MAX_LAYERS};
use super::tally::{McResult, RadialTally};
use crate::math::rng::{batch_rng, symmetric_pair, uniform, BatchRng};

/// Russian roulette: packets below this weight play (MCML's WEIGHT = 1e-4)…
pub const ROULETTE_WEIGHT: f64 = 1e-4;
/// …and survive with this chance, their weight divided by it (MCML's CHANCE = 0.1).
pub const ROULETTE_CHANCE: f64 = 0.1;
/// In white runs roulette plays on the weight under the reference (least) absorption, and
/// already below 1 %: such a packet has lost 99 % of its weight under every absorption set,
/// and half of a non-escaping packet's events would otherwise come after this point (weight
/// 1e-2 → 1e-4 is as long a path as 1 → 1e-2). Unbiased for any threshold; on the default
/// database it lowers the work for the same RGB noise by 1.2× (profile/DECISIONS.md, row 12).
pub const WHITE_ROULETTE_WEIGHT: f64 = 1e-2;
/// Boundary hits in a row without an interaction before a packet is stopped and reported as
/// lost (only a clear layer trapping light by total internal reflection gets there).
const MAX_BOUNCES: u32 = 100_000;

/// How a run is split and seeded.
#[derive(Debug, Clone)]
pub struct McOptions {
    pub photons: u64,
    pub seed: u64,
    /// Worker threads; `None` uses every core.
    pub threads: Option<usize>,
    /// Photons per batch (one RNG stream each). Results depend on it, not on the threads.
    pub batch_size: u64,
    /// Where finished photon packets are reported (a bake shows one bar over all its
    /// simulations; `baker mc` one per run).
    pub progress: crate::progress::Reporter,
    /// With a junction: each packet enters at a uniformly random point of the junction's
    /// period cell, and radii are measured from that point. The result is the profile averaged
    /// over where the beam meets the papillae, what a renderer applying one profile everywhere
    /// needs; off, the beam always enters above a node of Eq. 1 (MCML-like, x = y = 0).
    pub random_entry: bool,
    /// Checked before every batch: once set, the run stops and returns
    /// [`crate::cancel::Cancelled`] (no partial result).
    pub cancel: crate::cancel::Cancel,
}

impl McOptions {
    pub fn new(photons: u64, seed: u64) -> Self {
        Self {
            photons,
            seed,
            threads: None,
            batch_size: 10_000,
            progress: None,
            random_entry: false,
            cancel: crate::cancel::Cancel::NEVER,
        }
    }
}

#[derive(Debug, Clone, Copy, PartialEq)]
pub(crate) enum Hit {
    Top,
    Bottom,
    Junction,
}

/// The stack in the form the photon loop reads: flat arrays, boundaries precomputed.
#[derive(Debug, Clone)]
pub(crate) struct Prepared {
    pub nl: usize,
    pub z: [f64; MAX_LAYERS + 1],
    pub n: [f64; MAX_LAYERS + 2],
    pub mua: [f64; MAX_LAYERS],
    pub mus: [f64; MAX_LAYERS],
    pub mut_: [f64; MAX_LAYERS],
    /// 1/μt and 1/μs (∞ where the coefficient is 0): free path per unit optical depth.
    pub inv_mut: [f64; MAX_LAYERS],
    pub inv_mus: [f64; MAX_LAYERS],
    /// μa/μt: the fraction of weight absorbed at an interaction.
    pub absorb_frac: [f64; MAX_LAYERS],
    /// Henyey–Greenstein sampler per layer.
    pub hg: [Hg; MAX_LAYERS],
    pub junction: Option<(usize, HeightField)>,
    pub dr_mm: f64,
    pub nr: usize,
    pub rsp: f64,
    /// Period cell (x, y) in which packets enter at a random point (see
    /// [`McOptions::random_entry`]); `None`: every packet enters at the origin.
    pub entry_cell_mm: Option<[f64; 2]>,
}

impl Prepared {
    pub fn new(s: &Stack) -> Result<Self, StackError> {
        s.validate()?;
        let nl = s.layers.len();
        let zs = s.boundaries_mm();
        let mut p = Prepared {
            nl,
            z: [0.0; MAX_LAYERS + 1],
            // n[0] is the medium above, n[i + 1] layer i, n[nl + 1] the medium below.
            n: [1.0; MAX_LAYERS + 2],
            mua: [0.0; MAX_LAYERS],
            mus: [0.0; MAX_LAYERS],
            mut_: [0.0; MAX_LAYERS],
            inv_mut: [f64::INFINITY; MAX_LAYERS],
            inv_mus: [f64::INFINITY; MAX_LAYERS],
            absorb_frac: [0.0; MAX_LAYERS],
            hg: [Hg::new(0.0); MAX_LAYERS],
            junction: None,
            dr_mm: s.grid.dr_mm,
            nr: s.grid.nr,
            rsp: normal_reflectance(s.n_above, s.layers[0].eta),
            entry_cell_mm: None,
        };
        p.z[..=nl].copy_from_slice(&zs);
        p.n[0] = s.n_above;
        p.n[nl + 1] = s.n_below;
        for (i, l) in s.layers.iter().enumerate() {
            p.n[i + 1] = l.eta;
            p.mua[i] = l.mua_per_mm;
            p.mus[i] = l.mus_per_mm;
            p.mut_[i] = l.mua_per_mm + l.mus_per_mm;
            if p.mut_[i] > 0.0 {
                p.inv_mut[i] = 1.0 / p.mut_[i];
                p.absorb_frac[i] = l.mua_per_mm / p.mut_[i];
            }
            if l.mus_per_mm > 0.0 {
                p.inv_mus[i] = 1.0 / l.mus_per_mm;
            }
            p.hg[i] = Hg::new(l.g);
        }
        if let Some(j) = &s.junction {
            if j.amplitude_mm > 0.0 {
                p.junction = Some((j.upper_layer, HeightField::new(j, zs[j.upper_layer + 1])));
            }
        }
        Ok(p)
    }

    /// Applies [`McOptions::random_entry`] for stack `s`: the junction's period cell, if any.
    pub fn set_random_entry(&mut self, s: &Stack, on: bool) {
        self.entry_cell_mm = match (&s.junction, on) {
            (Some(j), true) if j.amplitude_mm > 0.0 => {
                let period = |w: f64| {
                    if w > 0.0 {
                        std::f64::consts::TAU / w
                    } else {
                        0.0
                    }
                };
                Some([period(j.omega_x_per_mm), period(j.omega_y_per_mm)])
            }
            _ => None,
        };
    }

    /// Distance to the boundary the photon would reach first, up to `step`, and which one.
    #[inline(always)]
    fn boundary(
        &self,
        layer: usize,
        pos: &[f64; 3],
        u: &[f64; 3],
        step: f64,
        leaving_slope: f64,
        evals: &mut u64,
    ) -> (f64, Hit) {
        // Common case first: the step ends inside a planar layer; no division needed.
        let z_end = pos[2] + u[2] * step;
        let junction_layer =
            matches!(&self.junction, Some((ju, _)) if layer == *ju || layer == ju + 1);
        if !junction_layer && z_end > self.z[layer] && z_end < self.z[layer + 1] {
            return (f64::INFINITY, Hit::Top);
        }
        // The plane ahead, chosen without a branch on the direction (as random as a coin).
        let up = u[2] < 0.0;
        let z_plane = if up { self.z[layer] } else { self.z[layer + 1] };
        let d = if u[2] != 0.0 {
            ((z_plane - pos[2]) / u[2]).max(0.0)
        } else {
            f64::INFINITY
        };
        let best = (d, if up { Hit::Top } else { Hit::Bottom });
        if let Some((ju, hf)) = &self.junction {
            // The planar interface at z̄ between layers ju and ju+1 is replaced by J(x, y).
            let Some(side) = junction_side(*ju, layer) else {
                return best;
            };
            let planar_is_junction =
                (side < 0.0 && best.1 == Hit::Bottom) || (side > 0.0 && best.1 == Hit::Top);
            let t_max = if planar_is_junction {
                step
            } else {
                best.0.min(step)
            };
            match hf.hit_counted(*pos, *u, t_max, side, leaving_slope, evals) {
                Some(t) => return (t, Hit::Junction),
                None if planar_is_junction => return (f64::INFINITY, Hit::Junction),
                None => {}
            }
        }
        best
    }
}

impl Prepared {
    /// Whether `pos` lies in `layer` as the geometry defines it: between its planes, and on
    /// its side of the junction J(x, y) where the junction bounds it (within `tol_mm`, for
    /// dips shorter than [`super::junction::MIN_STEP_MM`] the march does not resolve). Checked
    /// by a `debug_assert!` at every interaction: a packet that missed a crossing is caught
    /// wherever it next interacts.
    pub(crate) fn holds(&self, layer: usize, pos: &[f64; 3], tol_mm: f64) -> bool {
        let (mut lo, mut hi) = (self.z[layer], self.z[layer + 1]);
        if let Some((ju, hf)) = &self.junction {
            let j = hf.z(pos[0], pos[1]);
            if layer == *ju {
                hi = j;
            } else if layer == ju + 1 {
                lo = j;
            }
        }
        pos[2] >= lo - tol_mm && pos[2] <= hi + tol_mm
    }
}

/// The side of the junction below layer `ju` that `layer` lies on, in the sign convention of
/// [`HeightField::hit`] (−1 above, in layer `ju`; +1 below, in `ju + 1`); `None` for other layers.
#[inline(always)]
fn junction_side(ju: usize, layer: usize) -> Option<f64> {
    if layer == ju {
        Some(-1.0)
    } else if layer == ju + 1 {
        Some(1.0)
    } else {
        None
    }
}

/// A packet leaving the stack.
pub(crate) struct Exit<'a> {
    /// Through the surface (else the bottom).
    pub top: bool,
    /// After at least one scattering event.
    pub scattered: bool,
    pub weight: f64,
    /// Where it leaves, relative to its entry point, mm.
    pub pos: [f64; 3],
    /// cos θ outside the stack.
    pub cos_out: f64,
    /// Path length per layer, mm (white mode only; zeros otherwise).
    pub path: &'a [f64],
}

impl Exit<'_> {
    /// Distance from the entry point in the surface plane, mm.
    #[inline(always)]
    pub fn radius_mm(&self) -> f64 {
        (self.pos[0] * self.pos[0] + self.pos[1] * self.pos[1]).sqrt()
    }
}

/// Receives what a photon does.
pub(crate) trait Scorer {
    /// Weight `dw` absorbed in `layer` at `pos`.
    fn absorb(&mut self, layer: usize, dw: f64, pos: &[f64; 3]);
    /// The packet leaves the stack.
    fn escape(&mut self, exit: &Exit);
    fn lost(&mut self, weight: f64);
    /// Weight Russian roulette added to the packet (9w for a survivor at CHANCE = 0.1, −w
    /// for a packet it ended): direct runs score it so that the energy balance is exact.
    #[inline(always)]
    fn roulette(&mut self, _dw: f64) {}
    fn photon_done(&mut self);
}

/// MCML's Spin: new direction after scattering by θ (HG) and a uniform azimuth.
#[inline(always)]
fn spin(u: &mut [f64; 3], hg: &Hg, rng: &mut BatchRng) {
    if hg.g == 0.0 {
        // Isotropic (the thesis transports μs′ with g = 0): the new direction does not depend
        // on the old one, so sample the sphere directly (Marsaglia 1972) with no rotation.
        loop {
            let (a, b) = symmetric_pair(rng.next_u64());
            let s = a * a + b * b;
            if s < 1.0 {
                let k = 2.0 * (1.0 - s).sqrt();
                *u = [a * k, b * k, 1.0 - 2.0 * s];
                return;
            }
        }
    }
    let cost = hg.sample(uniform(rng.next_u64()));
    let sint = (1.0 - cost * cost).max(0.0).sqrt();
    // Uniform azimuth without trigonometry: a point in the unit disk gives angle 2φ.
    let (cosp, sinp) = loop {
        let (a, b) = symmetric_pair(rng.next_u64());
        let r2 = a * a + b * b;
        if r2 <= 1.0 && r2 > 1e-12 {
            let inv = 1.0 / r2;
            break ((a * a - b * b) * inv, 2.0 * a * b * inv);
        }
    };
    let [ux, uy, uz] = *u;
    if uz.abs() > 0.99999 {
        *u = [sint * cosp, sint * sinp, cost * uz.signum()];
    } else {
        let temp = (1.0 - uz * uz).sqrt();
        let k = sint / temp;
        *u = [
            k * (ux * uz * cosp - uy * sinp) + ux * cost,
            k * (uy * uz * cosp + ux * sinp) + uy * cost,
            -sint * cosp * temp + uz * cost,
        ];
    }
}

/// One photon packet in flight.
struct Packet {
    /// Entry point on the surface: radii are measured from it.
    origin: [f64; 2],
    pos: [f64; 3],
    u: [f64; 3],
    w: f64,
    layer: usize,
    /// At least one scattering event so far.
    scattered: bool,
    /// Optical depth left to the next interaction (≤ 0: draw a new one).
    s_left: f64,
    /// Path length per layer, mm (white mode only).
    path: [f64; MAX_LAYERS],
    /// ln of the weight under the reference absorption (white mode only).
    log_w_ref: f64,
    /// Boundary hits since the last interaction.
    bounces: u32,
    /// After a junction crossing or reflection, the slope at which the packet leaves the
    /// surface ([`HeightField::leaving_slope`]); 0 otherwise.
    leaving_slope: f64,
}

impl Packet {
    /// A packet entering the surface along +z with weight 1 − Rsp, at the origin or (random
    /// entry) at a uniform point of the junction's period cell.
    #[inline(always)]
    fn launch(p: &Prepared, rng: &mut BatchRng) -> Packet {
        let origin = match p.entry_cell_mm {
            Some([px, py]) => [uniform(rng.next_u64()) * px, uniform(rng.next_u64()) * py],
            None => [0.0, 0.0],
        };
        let w = 1.0 - p.rsp;
        Packet {
            origin,
            pos: [origin[0], origin[1], 0.0],
            u: [0.0f64, 0.0, 1.0],
            w,
            layer: 0usize,
            scattered: false,
            s_left: 0.0f64,
            path: [0.0f64; MAX_LAYERS],
            log_w_ref: w.ln(),
            bounces: 0u32,
            leaving_slope: 0.0,
        }
    }

    /// Position relative to the entry point.
    #[inline(always)]
    fn rel(&self) -> [f64; 3] {
        [
            self.pos[0] - self.origin[0],
            self.pos[1] - self.origin[1],
            self.pos[2],
        ]
    }

    /// Moves `db` to the boundary ahead, spending optical depth at `coeff`.
    #[inline(always)]
    fn move_to_boundary<const WHITE: bool>(
        &mut self,
        db: f64,
        coeff: f64,
        mua_ref: &[f64; MAX_LAYERS],
    ) {
        let (pos, u) = (&mut self.pos, &self.u);
        pos[0] += u[0] * db;
        pos[1] += u[1] * db;
        pos[2] += u[2] * db;
        if WHITE {
            self.path[self.layer] += db;
            self.log_w_ref -= mua_ref[self.layer] * db;
        }
        if coeff > 0.0 {
            self.s_left -= db * coeff;
        }
        self.bounces += 1;
    }

    /// Fresnel reflection or refraction at the planar top (`up`) or bottom of the layer.
    /// Returns cos θ outside when the packet leaves the stack through it.
    #[inline(always)]
    fn cross_planar(&mut self, p: &Prepared, up: bool, rng: &mut BatchRng) -> Option<f64> {
        let layer = self.layer;
        let u = &mut self.u;
        let (ni, nt) = (p.n[layer + 1], if up { p.n[layer] } else { p.n[layer + 2] });
        self.pos[2] = if up { p.z[layer] } else { p.z[layer + 1] };
        let (r, cos_t) = fresnel(ni, nt, u[2].abs());
        if r > 0.0 && (r >= 1.0 || uniform(rng.next_u64()) <= r) {
            u[2] = -u[2];
            return None;
        }
        let k = ni / nt;
        u[0] *= k;
        u[1] *= k;
        u[2] = if up { -cos_t } else { cos_t };
        let escaped = if up { layer == 0 } else { layer + 1 == p.nl };
        if escaped {
            return Some(cos_t);
        }
        self.layer = if up { layer - 1 } else { layer + 1 };
        None
    }

    /// Fresnel reflection or refraction at the junction J(x, y) (thesis Eq. 1), about its
    /// local normal, then a step off the surface.
    #[inline(always)]
    fn cross_junction(&mut self, p: &Prepared, rng: &mut BatchRng) {
        let (pos, u) = (&mut self.pos, &mut self.u);
        let layer = self.layer;
        let (ju, hf) = p.junction.as_ref().unwrap();
        let other = if layer == *ju { ju + 1 } else { *ju };
        let nv = hf.normal(pos[0], pos[1]);
        let c = u[0] * nv[0] + u[1] * nv[1] + u[2] * nv[2];
        let (ni, nt) = (p.n[layer + 1], p.n[other + 1]);
        let cos_i = c.abs().min(1.0);
        let (r, cos_t) = fresnel(ni, nt, cos_i);
        if r > 0.0 && (r >= 1.0 || uniform(rng.next_u64()) <= r) {
            for k in 0..3 {
                u[k] -= 2.0 * c * nv[k];
            }
        } else {
            let sg = c.signum();
            let eta = ni / nt;
            let a = cos_t - eta * cos_i;
            let mut t = [0.0; 3];
            for k in 0..3 {
                t[k] = eta * u[k] + a * sg * nv[k];
            }
            let inv = 1.0 / (t[0] * t[0] + t[1] * t[1] + t[2] * t[2]).sqrt();
            *u = [t[0] * inv, t[1] * inv, t[2] * inv];
            self.layer = other;
        }
        // The packet is in layer ju or ju + 1 here, on one side or the other.
        let side = junction_side(*ju, self.layer).unwrap_or(1.0);
        self.leaving_slope = HeightField::leaving_slope(nv, *u, side);
        // Step off the surface so the next search starts on the right side.
        for k in 0..3 {
            pos[k] += u[k] * 1e-9;
        }
    }

    /// Moves the whole `step` and interacts there: absorption (direct mode) or path length
    /// (white mode), then a new direction. Returns whether the packet survives roulette.
    #[inline(always)]
    fn interact<const WHITE: bool, S: Scorer>(
        &mut self,
        p: &Prepared,
        step: f64,
        mua_ref: &[f64; MAX_LAYERS],
        ln_roulette: f64,
        rng: &mut BatchRng,
        s: &mut S,
    ) -> bool {
        let layer = self.layer;
        self.pos[0] += self.u[0] * step;
        self.pos[1] += self.u[1] * step;
        self.pos[2] += self.u[2] * step;
        self.s_left = 0.0;
        self.bounces = 0;
        debug_assert!(
            p.holds(layer, &self.pos, 1e-5),
            "packet at {:?} is not in layer {layer}",
            self.pos
        );
        if WHITE {
            self.path[layer] += step;
            self.log_w_ref -= mua_ref[layer] * step;
        } else {
            let dw = self.w * p.absorb_frac[layer];
            self.w -= dw;
            s.absorb(layer, dw, &self.rel());
        }
        debug_assert!(self.w.is_finite());
        spin(&mut self.u, &p.hg[layer], rng);
        self.scattered = true;
        self.roulette::<WHITE, S>(ln_roulette, rng, s)
    }

    /// Unbiased Russian roulette (MCML's WEIGHT and CHANCE) on the weight, or in white mode on
    /// the weight under the reference absorption. Returns whether the packet survives.
    #[inline(always)]
    fn roulette<const WHITE: bool, S: Scorer>(
        &mut self,
        ln_roulette: f64,
        rng: &mut BatchRng,
        s: &mut S,
    ) -> bool {
        if WHITE {
            if self.log_w_ref < ln_roulette {
                if uniform(rng.next_u64()) <= ROULETTE_CHANCE {
                    self.w /= ROULETTE_CHANCE;
                    self.log_w_ref -= ROULETTE_CHANCE.ln();
                } else {
                    return false;
                }
            }
        } else if self.w < ROULETTE_WEIGHT {
            let w0 = self.w;
            if w0 > 0.0 && uniform(rng.next_u64()) <= ROULETTE_CHANCE {
                self.w /= ROULETTE_CHANCE;
                s.roulette(self.w - w0);
            } else {
                s.roulette(-w0);
                return false;
            }
        }
        true
    }
}

/// What tracing packets took, in deterministic counts (a cost model for choosing how many
/// packets to trace, which wall-clock time cannot be: it would make results depend on the
/// machine).
#[derive(Debug, Default, Clone, Copy, PartialEq)]
pub struct Work {
    /// Scattering events.
    pub events: u64,
    /// Evaluations of the junction's height field while searching for crossings.
    pub junction_evals: u64,
}

/// Traces one photon packet.
///
/// `WHITE = false`: MCML's scheme. Free paths from μt, weight × albedo at each interaction, the
/// rest scored as absorbed.
/// `WHITE = true`: free paths from μs only, no absorption. Per-layer path lengths are recorded
/// so any μa applies later as exp(−Σ μa,i·Li). Roulette plays against the reference absorption
/// `mua_ref` (weights corrected exactly), which bounds the cost.
#[inline(always)]
pub(crate) fn trace<const WHITE: bool, S: Scorer>(
    p: &Prepared,
    mua_ref: &[f64; MAX_LAYERS],
    rng: &mut BatchRng,
    s: &mut S,
    work: &mut Work,
) {
    let mut k = Packet::launch(p, rng);
    let ln_roulette = if WHITE {
        WHITE_ROULETTE_WEIGHT.ln()
    } else {
        ROULETTE_WEIGHT.ln()
    };
    loop {
        if k.s_left <= 0.0 {
            // An exponential optical depth: ziggurat sampling (Marsaglia & Tsang 2000, as
            // rand_distr implements it), twice as fast as −ln u and exactly Exp(1).
            k.s_left = Exp1.sample(rng);
        }
        let layer = k.layer;
        let coeff = if WHITE { p.mus[layer] } else { p.mut_[layer] };
        let step = k.s_left
            * if WHITE {
                p.inv_mus[layer]
            } else {
                p.inv_mut[layer]
            };
        let leaving = std::mem::take(&mut k.leaving_slope);
        let (db, hit) = p.boundary(layer, &k.pos, &k.u, step, leaving, &mut work.junction_evals);
        if db.is_infinite() && step.is_infinite() {
            // Travelling parallel to the layers through a clear layer: it never arrives (MCML
            // kills such packets too).
            s.lost(k.w);
            s.photon_done();
            return;
        }
        if db < step {
            k.move_to_boundary::<WHITE>(db, coeff, mua_ref);
            if k.bounces > MAX_BOUNCES {
                s.lost(k.w);
                s.photon_done();
                return;
            }
            match hit {
                Hit::Top | Hit::Bottom => {
                    let up = hit == Hit::Top;
                    if let Some(cos_t) = k.cross_planar(p, up, rng) {
                        s.escape(&Exit {
                            top: up,
                            scattered: k.scattered,
                            weight: k.w,
                            pos: k.rel(),
                            cos_out: cos_t,
                            path: &k.path[..p.nl],
                        });
                        s.photon_done();
                        return;
                    }
                }
                Hit::Junction => k.cross_junction(p, rng),
            }
        } else {
            let alive = k.interact::<WHITE, S>(p, step, mua_ref, ln_roulette, rng, s);
            work.events += 1;
            if !alive {
                s.photon_done();
                return;
            }
        }
    }
}

/// Scores a direct (absorbing) run into a [`RadialTally`].
pub(crate) struct DirectScorer<'a> {
    pub t: &'a mut RadialTally,
    pub absorbed: [f64; MAX_LAYERS],
    /// Weight roulette added to the current photon.
    pub roulette: f64,
    pub dr_mm: f64,
}

impl Scorer for DirectScorer<'_> {
    #[inline(always)]
    fn absorb(&mut self, layer: usize, dw: f64, _pos: &[f64; 3]) {
        self.absorbed[layer] += dw;
    }
    fn escape(&mut self, e: &Exit) {
        if !e.top {
            self.t.tt.add(e.weight);
        } else if !e.scattered {
            self.t.rd_unscattered.add(e.weight);
        } else {
            self.t.rd.add(e.weight);
            let ir = (e.radius_mm() / self.dr_mm) as usize;
            if let Some(b) = self.t.rd_r.get_mut(ir) {
                b.add(e.weight);
            }
        }
    }
    fn lost(&mut self, weight: f64) {
        self.t.lost.add(weight);
    }
    #[inline(always)]
    fn roulette(&mut self, dw: f64) {
        self.roulette += dw;
    }
    fn photon_done(&mut self) {
        self.t.photons += 1;
        if self.roulette != 0.0 {
            self.t.roulette.add(self.roulette);
            self.roulette = 0.0;
        }
        let mut total = 0.0;
        for (a, s) in self.absorbed.iter_mut().zip(self.t.absorbed.iter_mut()) {
            if *a != 0.0 {
                total += *a;
                s.add(*a);
                *a = 0.0;
            }
        }
        if total != 0.0 {
            self.t.absorbed_total.add(total);
        }
    }
}

/// Runs batches `0..n_batches` on `threads` and reduces their outputs in batch order, a chunk
/// at a time so memory stays bounded for any photon count.
pub(crate) fn run_batches<T: Send>(
    chunk_per_thread: u64,
    o: &McOptions,
    work: impl Fn(u64, u64) -> T + Sync,
    mut reduce: impl FnMut(T),
) -> anyhow::Result<usize> {
    let (photons, batch_size) = (o.photons, o.batch_size.max(1));
    let n_batches = photons.div_ceil(batch_size);
    let pool = rayon::ThreadPoolBuilder::new()
        .num_threads(o.threads.unwrap_or(0))
        .build()?;
    let used = pool.current_num_threads();
    let chunk = chunk_per_thread.max(1) * used as u64;
    let mut start = 0;
    while start < n_batches {
        let end = (start + chunk).min(n_batches);
        // A batch that sees the flag is skipped; the whole run then reports cancellation.
        let outs: Vec<Option<T>> = pool.install(|| {
            (start..end)
                .into_par_iter()
                .map(|b| {
                    if o.cancel.is_set() {
                        return None;
                    }
                    let n = batch_size.min(photons - b * batch_size);
                    let out = work(b, n);
                    crate::progress::advance(&o.progress, n);
                    Some(out)
                })
                .collect()
        });
        if o.cancel.is_set() || outs.iter().any(Option::is_none) {
            return Err(crate::cancel::Cancelled.into());
        }
        outs.into_iter().flatten().for_each(&mut reduce);
        start = end;
    }
    Ok(used)
}

/// Direct simulation of `stack`: every tally with its standard error.
pub fn run(stack: &Stack, o: &McOptions) -> anyhow::Result<McResult> {
    let mut p = Prepared::new(stack)?;
    p.set_random_entry(stack, o.random_entry);
    let nl = p.nl;
    let no_ref = [0.0; MAX_LAYERS];
    let t0 = Instant::now();
    let mut total = RadialTally::new(nl, p.nr);
    let threads = run_batches(
        64,
        o,
        |b, n| {
            let mut rng = batch_rng(o.seed, b);
            let mut t = RadialTally::new(nl, p.nr);
            let mut work = Work::default();
            {
                let mut s = DirectScorer {
                    t: &mut t,
                    absorbed: [0.0; MAX_LAYERS],
                    roulette: 0.0,
                    dr_mm: p.dr_mm,
                };
                for _ in 0..n {
                    trace::<false, _>(&p, &no_ref, &mut rng, &mut s, &mut work);
                }
            }
            t.scattering_events = work.events;
            t
        },
        |t| total.merge(&t),
    )?;
    Ok(McResult::from_tally(
        &total,
        p.rsp,
        p.dr_mm,
        threads,
        t0.elapsed().as_secs_f64(),
    ))
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::stats::chi2::chi2_test_1d;

    /// Scores nothing but what roulette adds.
    struct RouletteOnly(f64);
    impl Scorer for RouletteOnly {
        fn absorb(&mut self, _: usize, _: f64, _: &[f64; 3]) {}
        fn escape(&mut self, _: &Exit) {}
        fn lost(&mut self, _: f64) {}
        fn roulette(&mut self, dw: f64) {
            self.0 += dw;
        }
        fn photon_done(&mut self) {}
    }

    /// Russian roulette is unbiased in both modes: over many packets below the threshold the
    /// surviving weight averages the weight before (survival 1/10, weight ×10), within 4 SE;
    /// a white packet keeps ln w_ref in step with its weight, and direct runs score exactly
    /// what roulette added.
    #[test]
    fn roulette_keeps_the_expected_weight() {
        let mut rng = batch_rng(43, 0);
        let p = Prepared::new(&Stack::in_air(
            crate::transport::Layer {
                name: "slab".into(),
                d_mm: 1.0,
                eta: 1.0,
                mua_per_mm: 1.0,
                mus_per_mm: 1.0,
                g: 0.0,
            },
            0.01,
            10,
        ))
        .unwrap();
        for white in [false, true] {
            let n = 200_000;
            let w0 = 5e-5;
            let (mut sum, mut sum2, mut survivors) = (0.0, 0.0, 0);
            let mut scored = RouletteOnly(0.0);
            for _ in 0..n {
                let mut k = Packet::launch(&p, &mut rng);
                k.w = w0;
                k.log_w_ref = (w0 * 100.0f64).ln() - 5.0; // below the white threshold, 10⁻²
                let before = k.log_w_ref;
                let alive = if white {
                    k.roulette::<true, _>(WHITE_ROULETTE_WEIGHT.ln(), &mut rng, &mut scored)
                } else {
                    k.roulette::<false, _>(ROULETTE_WEIGHT.ln(), &mut rng, &mut scored)
                };
                let w = if alive { k.w } else { 0.0 };
                if alive {
                    survivors += 1;
                    if white {
                        let grown = k.log_w_ref - before;
                        assert!((grown - 10f64.ln()).abs() < 1e-12 && (w / w0 - 10.0).abs() < 1e-9);
                    }
                }
                sum += w;
                sum2 += w * w;
            }
            let mean = sum / n as f64;
            let se = ((sum2 / n as f64 - mean * mean) / n as f64).sqrt();
            assert!(survivors > 0 && survivors < n / 5, "{survivors}");
            assert!(
                (mean - w0).abs() < 4.0 * se,
                "white {white}: {mean} vs {w0} ± {se}"
            );
            if !white {
                // What roulette added equals the weight change, to rounding.
                assert!((scored.0 - (sum - n as f64 * w0)).abs() < 1e-9 * n as f64 * w0);
            }
        }
    }

    /// Issue 22: a scattering event turns the direction by θ with cos θ drawn from
    /// Henyey–Greenstein and by an azimuth uniform around the old direction, and keeps it a
    /// unit vector: for vertical, oblique and nearly vertical incoming directions and g of both
    /// signs, the cosine to the old direction against the HG density (χ²) and the azimuth
    /// against the uniform one (χ², measured in a frame written out here).
    #[test]
    fn spin_turns_by_hg_and_a_uniform_azimuth() {
        let mut rng = batch_rng(41, 0);
        for g in [0.0, 0.8, -0.4] {
            let hg = Hg::new(g);
            for u0 in [
                [0.0, 0.0, 1.0],
                [0.0, 0.0, -1.0],
                [0.6, 0.0, 0.8],
                [0.36, -0.48, -0.8],
                [1e-4, 0.0, (1.0f64 - 1e-8).sqrt()],
            ] {
                let (mut cos, mut azi) = (Vec::new(), Vec::new());
                // A frame around u0: e1 ⟂ u0 in the plane of u0 and x (or y), e2 = u0 × e1.
                let pick = if u0[0].abs() < 0.9 {
                    [1.0, 0.0, 0.0]
                } else {
                    [0.0, 1.0, 0.0]
                };
                let d = pick[0] * u0[0] + pick[1] * u0[1] + pick[2] * u0[2];
                let e1 = {
                    let v = [
                        pick[0] - d * u0[0],
                        pick[1] - d * u0[1],
                        pick[2] - d * u0[2],
                    ];
                    let n = (v[0] * v[0] + v[1] * v[1] + v[2] * v[2]).sqrt();
                    [v[0] / n, v[1] / n, v[2] / n]
                };
                let e2 = [
                    u0[1] * e1[2] - u0[2] * e1[1],
                    u0[2] * e1[0] - u0[0] * e1[2],
                    u0[0] * e1[1] - u0[1] * e1[0],
                ];
                for _ in 0..100_000 {
                    let mut u = u0;
                    spin(&mut u, &hg, &mut rng);
                    let norm = u[0] * u[0] + u[1] * u[1] + u[2] * u[2];
                    assert!(
                        (norm - 1.0).abs() < 1e-9,
                        "|u|² = {norm} from {u0:?}, g {g}"
                    );
                    let c = u[0] * u0[0] + u[1] * u0[1] + u[2] * u0[2];
                    cos.push(c);
                    let (x, y) = (
                        u[0] * e1[0] + u[1] * e1[1] + u[2] * e1[2],
                        u[0] * e2[0] + u[1] * e2[1] + u[2] * e2[2],
                    );
                    if 1.0 - c * c > 1e-6 {
                        azi.push(y.atan2(x));
                    }
                }
                let name = format!("spin_g{g}_{:.2}_{:.2}_{:.2}", u0[0], u0[1], u0[2]);
                chi2_test_1d(
                    &cos,
                    -1.0,
                    1.0,
                    41,
                    |c| crate::transport::phase::hg_pdf(g, c),
                    &name,
                );
                chi2_test_1d(
                    &azi,
                    -std::f64::consts::PI,
                    std::f64::consts::PI,
                    37,
                    |_| 0.5 / std::f64::consts::PI,
                    &format!("{name}_azimuth"),
                );
            }
        }
    }
}
