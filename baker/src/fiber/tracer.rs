//! Brute-force photon tracing through one straight fiber in the far field (§5.3.2): a beam of
//! parallel rays as wide as the fiber's projection arrives from ωi; each photon random-walks
//! through rough-dielectric reflections and refractions until it leaves, and is binned by its
//! outgoing direction with the path length it travelled inside.
//!
//! The fiber is an extrusion along z, so a 3D ray meets it where its xy projection meets the
//! section: the walk runs in 2D plus the axial component (the xy part of a unit direction
//! advances the same ray parameter t, so 3D lengths come for free). Wool's cuticles scale the
//! section along z; within one scale the ray's image in section coordinates (x/s, y/s) is
//! again a straight segment (a projective map of a line), so the same 2D query serves.
//!
//! Absorption is applied afterwards from the recorded path length ([`super::DirectionTally::score`]):
//! the walk of a photon does not depend on μa, so one trace serves every dye, depth of shade
//! and wavelength (Beer–Lambert weights exp(−μa·ℓ)).

use std::time::Instant;

use rand_core::Rng;
use rayon::prelude::*;

use super::tally::DirectionTally;
use super::{Fiber, Section, Surface};
use crate::math::rng::{batch_rng, uniform, BatchRng};
use formats::AngularGrid;

/// Photons per batch: one RNG stream and one partial tally each.
pub const BATCH: u64 = 1 << 15;
/// Batches traced in parallel before their tallies are added (in batch order).
const GROUP: u64 = 32;
/// Boundary events after which a photon is counted as lost (absorbed): far beyond any
/// physical path (a photon trapped by total internal reflection in a perfect ellipse).
pub const MAX_EVENTS: u32 = 10_000;

/// The incident direction ωi (pointing towards the light).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Incident {
    pub theta_rad: f64,
    pub phi_rad: f64,
    /// When set, (Δθ, Δφ) in radians: each photon's ωi is drawn uniformly over the solid angle
    /// of the bin [θ ± Δθ/2] × [φ ± Δφ/2] and weighted by W(φ)·cos θ / (W(φc)·cos θc), the
    /// power the fiber intercepts from there relative to the bin centre. Outgoing Δφ is then
    /// measured from the centre φc, so the table is a bin-to-bin average (as a 4D table
    /// needs; also what makes reciprocity testable bin against bin).
    pub spread: Option<(f64, f64)>,
}

impl Incident {
    pub fn from_deg(theta_deg: f64, phi_deg: f64) -> Self {
        Self {
            theta_rad: theta_deg.to_radians(),
            phi_rad: phi_deg.to_radians(),
            spread: None,
        }
    }

    /// The same centre, averaged over a bin of `dtheta_deg` × `dphi_deg`.
    pub fn with_spread_deg(mut self, dtheta_deg: f64, dphi_deg: f64) -> Self {
        self.spread = Some((dtheta_deg.to_radians(), dphi_deg.to_radians()));
        self
    }
}

/// What to trace and score.
#[derive(Debug, Clone)]
pub struct TraceOptions {
    /// Photons launched across the beam.
    pub photons: u64,
    pub seed: u64,
    pub grid: AngularGrid,
    /// Absorption coefficients to score from the one trace, per µm.
    pub mua_per_um: Vec<f64>,
    /// Where finished photons are reported.
    pub progress: crate::progress::Reporter,
}

/// A finished trace.
#[derive(Debug, Clone)]
pub struct TraceResult {
    pub tally: DirectionTally,
    pub incident: Incident,
    /// A(ωi): exact projected width per unit length from the outline, µm.
    pub projected_width_um: f64,
    /// Width of the launched beam, µm (≥ the projected width for cuticle scales).
    pub beam_width_um: f64,
    pub seconds: f64,
}

impl TraceResult {
    /// Launched photons per second of wall time.
    pub fn photons_per_s(&self) -> f64 {
        self.tally.launched as f64 / self.seconds.max(1e-9)
    }

    /// Shadow width seen by the beam, estimated from the hit fraction, and its standard error.
    pub fn intercepted_width_um(&self) -> (f64, f64) {
        let n = self.tally.launched.max(1) as f64;
        let p = self.tally.intercepted as f64 / n;
        (
            self.beam_width_um * p,
            self.beam_width_um * (p * (1.0 - p) / n).sqrt(),
        )
    }
}

/// The state of one photon branch.
#[derive(Debug, Clone, Copy)]
struct Ray {
    p: [f64; 3],
    dir: [f64; 3],
    inside: bool,
    /// Path travelled inside the fiber so far, µm.
    path: f64,
    events: u32,
    skip: Option<u32>,
    /// Cuticle period the photon is in (straight fibers ignore it).
    period: i64,
    /// Weight of the branch (1 for an unsplit photon).
    w: f64,
}

/// What one photon (with all its branches) did, besides what it emitted.
#[derive(Debug, Clone, Copy, Default)]
pub struct PhotonStats {
    /// The beam met the fiber.
    pub hit: bool,
    /// Weight stopped by the event limit (counted as absorbed).
    pub lost: f64,
    pub fallbacks: u32,
    /// Launch weight of the photon (the spread weight g; 1 without spread).
    pub g: f64,
}

impl PhotonStats {
    fn add(&mut self, o: PhotonStats) {
        self.hit |= o.hit;
        self.lost += o.lost;
        self.fallbacks += o.fallbacks;
    }
}

/// Draws per boundary event of a photon's main path: `outside` for events met from the air
/// (the reflection lobe R and the entry), `inside` for events met from within the fiber (every
/// exit lobe TT, TRT, … and the internal reflections). 1 and 1 is plain tracing.
#[derive(Debug, Clone, Copy, PartialEq, Eq, serde::Serialize)]
pub struct Draws {
    pub outside: u32,
    pub inside: u32,
}

impl Draws {
    /// One draw per event: plain tracing.
    pub const PLAIN: Draws = Draws {
        outside: 1,
        inside: 1,
    };

    /// Draws for an event met from inside (`true`) or outside the fiber.
    #[inline]
    fn at(self, inside: bool) -> u32 {
        if inside {
            self.inside.max(1)
        } else {
            self.outside.max(1)
        }
    }
}

/// Per-trace constants.
pub(crate) struct Setup<'a> {
    section: &'a Section,
    inc: Incident,
    s_max: f64,
    /// W(φc)·cos θc, the normalisation of spread weights.
    w_centre: f64,
    surface: Surface,
    /// Unit direction of travel, −ωi.
    d: [f64; 3],
    /// Unit xy direction of travel and the beam's cross axis.
    dhat: [f64; 2],
    e_perp: [f64; 2],
    beam: (f64, f64),
    r_start: f64,
    /// Cuticle: (scale length L, ds/dz, s_max, bounding radius of the section).
    cuticle: Option<(f64, f64, f64, f64)>,
}

#[inline]
fn dot3(a: [f64; 3], b: [f64; 3]) -> f64 {
    a[0] * b[0] + a[1] * b[1] + a[2] * b[2]
}

/// Exit parameter of o + t·d from the circle of radius r about the origin, if the ray reaches
/// the circle's inside at some t > 0.
#[inline]
fn circle_exit(o: [f64; 2], d: [f64; 2], r: f64) -> Option<f64> {
    let a = d[0] * d[0] + d[1] * d[1];
    if a == 0.0 {
        return None;
    }
    let b = o[0] * d[0] + o[1] * d[1];
    let c = o[0] * o[0] + o[1] * o[1] - r * r;
    let disc = b * b - a * c;
    if disc <= 0.0 {
        return None;
    }
    let t = (-b + disc.sqrt()) / a;
    (t > 0.0).then_some(t)
}

impl<'a> Setup<'a> {
    pub(crate) fn new(fiber: &'a Fiber, inc: Incident) -> Self {
        let (st, ct) = inc.theta_rad.sin_cos();
        let (sp, cp) = inc.phi_rad.sin_cos();
        let d = [-ct * cp, -ct * sp, -st];
        let dhat = [-cp, -sp];
        let e_perp = [-dhat[1], dhat[0]];
        let cut = fiber.cuticle_slope();
        let s_max = cut.map_or(1.0, |c| c.1);
        let (lo, hi) = fiber.section.extent(e_perp);
        let rb = fiber.section.bound_radius_um();
        Self {
            section: &fiber.section,
            inc,

            w_centre: (hi - lo) * s_max * ct,
            surface: fiber.surface,
            d,
            dhat,
            e_perp,
            beam: (lo * s_max, hi * s_max),
            s_max,
            r_start: rb * s_max * 1.01 + 1.0,
            cuticle: fiber
                .cuticle
                .zip(cut)
                .map(|(c, (k, s))| (c.length_um, k, s, rb)),
        }
    }

    /// Width of the launched beam at the centre direction, µm.
    pub(crate) fn beam_width_um(&self) -> f64 {
        self.beam.1 - self.beam.0
    }

    /// One photon of the beam. `offset` places it across the beam (uniform in [0, 1); drawn
    /// when `None`); `draws` splits every boundary event of the photon's main path into that
    /// many draws ([`Draws`]). `emit(dir, path_um, weight)` receives
    /// every branch that leaves; the weights include the spread weight.
    #[inline]
    pub(crate) fn photon(
        &self,
        rng: &mut BatchRng,
        offset: Option<f64>,
        draws: Draws,
        emit: &mut impl FnMut([f64; 3], f64, f64),
    ) -> PhotonStats {
        let mut u = || uniform(rng.next_u64());
        let (d, dhat, e_perp, beam, g) = match self.inc.spread {
            None => (self.d, self.dhat, self.e_perp, self.beam, 1.0),
            Some((dt, dp)) => {
                // Uniform in solid angle: uniform in sin θ and φ.
                let (s0, s1) = (
                    (self.inc.theta_rad - 0.5 * dt).sin(),
                    (self.inc.theta_rad + 0.5 * dt).sin(),
                );
                let st = s0 + (s1 - s0) * u();
                let ct = (1.0 - st * st).max(0.0).sqrt();
                let phi = self.inc.phi_rad + dp * (u() - 0.5);
                let (sp, cp) = phi.sin_cos();
                let dhat = [-cp, -sp];
                let e_perp = [sp, -cp];
                let (lo, hi) = self.section.extent(e_perp);
                let beam = (lo * self.s_max, hi * self.s_max);
                let g = (beam.1 - beam.0) * ct / self.w_centre;
                ([-ct * cp, -ct * sp, -st], dhat, e_perp, beam, g)
            }
        };
        let f = offset.unwrap_or_else(&mut u);
        let h = beam.0 + (beam.1 - beam.0) * f;
        let o = [
            h * e_perp[0] - self.r_start * dhat[0],
            h * e_perp[1] - self.r_start * dhat[1],
        ];
        let z = self.cuticle.map_or(0.0, |c| c.0 * u());
        let ray = Ray {
            p: [o[0], o[1], z],
            dir: d,
            inside: false,
            path: 0.0,
            events: 0,
            skip: None,
            period: self.cuticle.map_or(0, |c| (z / c.0).floor() as i64),
            w: g,
        };
        let mut st = self.walk(ray, draws, &mut u, emit);
        st.g = g;
        st
    }

    /// Follows a branch until it leaves (emitting it), is lost, or ends in roulette.
    fn walk(
        &self,
        mut ray: Ray,
        draws: Draws,
        u: &mut impl FnMut() -> f64,
        emit: &mut impl FnMut([f64; 3], f64, f64),
    ) -> PhotonStats {
        let mut st = PhotonStats::default();
        loop {
            let Some((n_out, id, step)) = (match self.cuticle {
                None => self.advance_straight(&mut ray),
                Some(c) => self.advance_cuticle(&mut ray, c),
            }) else {
                // Left the fiber's neighbourhood.
                if ray.events > 0 {
                    st.hit = true;
                    if ray.inside {
                        st.lost += ray.w;
                    } else {
                        emit(ray.dir, ray.path, ray.w);
                    }
                }
                return st;
            };
            st.hit = true;
            ray.events += 1;
            if ray.events >= MAX_EVENTS {
                st.lost += ray.w;
                return st;
            }
            let free = self.leaves_freely(id);
            let split = draws.at(ray.inside);
            if split <= 1 {
                let s = self.boundary(ray.dir, n_out, u);
                st.fallbacks += s.1 as u32;
                if !s.2 && free {
                    // Outward through the convex hull: no ray query needed to know it leaves.
                    emit(s.0, ray.path, ray.w);
                    return st;
                }
                if s.2 != ray.inside {
                    ray.period += step;
                }
                ray.dir = s.0;
                ray.inside = s.2;
                ray.skip = id;
                continue;
            }
            // Splitting: `split` draws of the event; the branches that leave are followed
            // (unsplit) at weight w/split. The m draws that stay (enter, or reflect inside)
            // carry w·m/split together: one of them, picked uniformly, goes on at the full
            // weight w with probability m/split (Russian roulette, unbiased for their sum),
            // so the main path lives as long as a plain photon's and each event costs
            // `split` draws, not a tree of them.
            let mut m = 0u32;
            let mut chosen = None;
            let kw = ray.w / split as f64;
            for _ in 0..split {
                let s = self.boundary(ray.dir, n_out, u);
                st.fallbacks += s.1 as u32;
                if s.2 {
                    m += 1;
                    if m == 1 || u() * (m as f64) < 1.0 {
                        chosen = Some(s.0);
                    }
                } else if free {
                    emit(s.0, ray.path, kw);
                } else {
                    let child = Ray {
                        dir: s.0,
                        inside: false,
                        skip: id,
                        w: kw,
                        period: ray.period + if ray.inside { step } else { 0 },
                        ..ray
                    };
                    st.add(self.walk(child, Draws::PLAIN, u, emit));
                }
            }
            let Some(d) = chosen else { return st };
            if m < split && u() * split as f64 >= m as f64 {
                return st;
            }
            if !ray.inside {
                ray.period += step;
            }
            ray.dir = d;
            ray.inside = true;
            ray.skip = id;
        }
    }

    /// True when a branch leaving outward through surface `id` can be scored at once: a
    /// straight fiber ([`Section::leaves_freely`]); cuticle steps can catch a leaving ray.
    #[inline]
    fn leaves_freely(&self, id: Option<u32>) -> bool {
        self.cuticle.is_none() && id.is_some_and(|i| self.section.leaves_freely(i))
    }

    /// Moves a ray in a straight extrusion to its next boundary event: returns the outward
    /// normal and the edge id, or `None` when nothing is hit.
    #[inline]
    fn advance_straight(&self, ray: &mut Ray) -> Option<([f64; 3], Option<u32>, i64)> {
        let d2 = [ray.dir[0], ray.dir[1]];
        let p = [ray.p[0], ray.p[1]];
        let hit = self.section.intersect(p, d2, f64::INFINITY, ray.skip)?;
        ray.p = [p[0] + hit.t * d2[0], p[1] + hit.t * d2[1], 0.0];
        if ray.inside {
            ray.path += hit.t;
        }
        Some(([hit.n[0], hit.n[1], 0.0], Some(hit.id), 0))
    }

    /// A boundary event at outward normal `n_out`: returns the new direction, whether the
    /// fallback was used, and whether the photon is now inside. The side is read from the
    /// direction, so a numerical slip cannot desynchronise it.
    #[inline]
    fn boundary(
        &self,
        dir: [f64; 3],
        n_out: [f64; 3],
        u: &mut impl FnMut() -> f64,
    ) -> ([f64; 3], bool, bool) {
        let from_inside = dot3(dir, n_out) > 0.0;
        let nf = if from_inside {
            [-n_out[0], -n_out[1], -n_out[2]]
        } else {
            n_out
        };
        let s = self.surface.scatter(dir, nf, from_inside, &mut *u);
        (s.dir, s.fallback, from_inside != s.transmitted)
    }

    /// Moves a ray along a fiber with cuticle scales (see [`super::Cuticle`]) period by period
    /// to its next boundary event: a hit of the scaled section (edge id) or a step face at a
    /// scale edge (no id). `None` when it leaves the bounding cylinder.
    fn advance_cuticle(
        &self,
        ray: &mut Ray,
        (len, k, s_max, rb): (f64, f64, f64, f64),
    ) -> Option<([f64; 3], Option<u32>, i64)> {
        let r_bound = rb * s_max;
        let dir = ray.dir;
        for _ in 0..10_000_000u32 {
            let p = ray.p;
            let z_lo = ray.period as f64 * len;
            let t_plane = if dir[2] > 0.0 {
                (z_lo + len - p[2]) / dir[2]
            } else if dir[2] < 0.0 {
                (z_lo - p[2]) / dir[2]
            } else {
                f64::INFINITY
            };
            let t_circle = circle_exit([p[0], p[1]], [dir[0], dir[1]], r_bound)?;
            let t1 = t_plane.min(t_circle);
            let s0 = 1.0 + k * (p[2] - z_lo);
            let p1 = [p[0] + t1 * dir[0], p[1] + t1 * dir[1], p[2] + t1 * dir[2]];
            let s1 = 1.0 + k * (p1[2] - z_lo).clamp(0.0, len);
            let q0 = [p[0] / s0, p[1] / s0];
            let q1 = [p1[0] / s1, p1[1] / s1];
            if let Some(hit) =
                self.section
                    .intersect(q0, [q1[0] - q0[0], q1[1] - q0[1]], 1.0, ray.skip)
            {
                // Back from the section's segment parameter to the ray's.
                let uu = hit.t;
                let tau = uu * s0 / ((1.0 - uu) * s1 + uu * s0);
                let t = tau * t1;
                ray.p = [p[0] + t * dir[0], p[1] + t * dir[1], p[2] + t * dir[2]];
                if ray.inside {
                    ray.path += t;
                }
                // Surface n·(x, y) = c·s(z): gradient (n, −c·ds/dz).
                let nz = -hit.c * k;
                let inv = 1.0 / (1.0 + nz * nz).sqrt();
                return Some(([hit.n[0] * inv, hit.n[1] * inv, nz * inv], Some(hit.id), 0));
            }
            if t_circle <= t_plane {
                // Left the bounding cylinder without meeting the fiber.
                return None;
            }
            // Cross the scale edge plane.
            ray.p = p1;
            if ray.inside {
                ray.path += t1;
            }
            let up = dir[2] > 0.0;
            ray.p[2] = if up { z_lo + len } else { z_lo };
            let s_after = if up { 1.0 } else { s_max };
            let inside_after = self
                .section
                .contains([ray.p[0] / s_after, ray.p[1] / s_after]);
            ray.skip = None;
            let step = if up { 1 } else { -1 };
            if inside_after == ray.inside {
                ray.period += step;
                continue;
            }
            // The step face of a scale edge, normal ±z, material on the photon's side if
            // inside. The period advances by `step` if the photon crosses it ([`Self::walk`]).
            let sign = if up { 1.0 } else { -1.0 };
            let n_out = if ray.inside {
                [0.0, 0.0, sign]
            } else {
                [0.0, 0.0, -sign]
            };
            return Some((n_out, None, step));
        }
        None
    }
}
/// Traces `o.photons` photons of the beam from `inc` through `fiber`. Batches run in parallel
/// on the current rayon pool; batch b draws from `batch_rng(seed, b)` and partial tallies are
/// added in batch order, so the result is bit-identical for any thread count.
pub fn trace(fiber: &Fiber, inc: Incident, o: &TraceOptions) -> TraceResult {
    let start = Instant::now();
    let setup = Setup::new(fiber, inc);
    let n_batches = o.photons.div_ceil(BATCH);
    let mut total = DirectionTally::new(o.grid, &o.mua_per_um);
    let mut b0 = 0;
    while b0 < n_batches {
        let b1 = (b0 + GROUP).min(n_batches);
        let parts: Vec<DirectionTally> = (b0..b1)
            .into_par_iter()
            .map(|b| {
                let n = BATCH.min(o.photons - b * BATCH);
                let t = trace_batch(&setup, inc, o, b, n);
                crate::progress::advance(&o.progress, n);
                t
            })
            .collect();
        for p in &parts {
            total.merge(p);
        }
        b0 = b1;
    }
    TraceResult {
        tally: total,
        incident: inc,
        projected_width_um: fiber.projected_width_um(inc.phi_rad),
        beam_width_um: setup.beam_width_um(),
        seconds: start.elapsed().as_secs_f64(),
    }
}

fn trace_batch(
    setup: &Setup,
    inc: Incident,
    o: &TraceOptions,
    batch: u64,
    n: u64,
) -> DirectionTally {
    let mut rng = batch_rng(o.seed, batch);
    let mut t = DirectionTally::new(o.grid, &o.mua_per_um);
    t.launched = n;
    let grid = o.grid;
    for _ in 0..n {
        let st = setup.photon(&mut rng, None, Draws::PLAIN, &mut |dir, path, w| {
            t.score(grid.bin(dir, inc.phi_rad), path, w)
        });
        t.fallbacks += st.fallbacks as u64;
        if st.hit {
            t.intercepted += 1;
        }
        if st.lost > 0.0 {
            t.lost += 1;
        }
    }
    t
}
