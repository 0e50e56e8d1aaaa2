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

pub mod shared;

use std::time::Instant;

use rayon::prelude::*;

use super::exit_bins::ExitBins;
use super::lobe::{Event, Lobe, LobeGrid};
use super::surface::Crossing;
use super::tally::DirectionTally;
use super::{Fiber, Section, Surface};
use crate::math::rng::batch_rng;
use crate::math::sampler::PathSampler;
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

/// A boundary event met by a ray ([`Setup::boundary`]): its constants and the side it is met
/// from.
#[derive(Clone, Copy)]
struct Boundary {
    crossing: Crossing,
    from_inside: bool,
}

impl Boundary {
    /// One draw of the event: the new direction, whether the fallback was used, whether the
    /// photon is now inside, and whether it left the cavity at its first facet
    /// ([`super::surface::Scatter::first_facet`]).
    #[inline]
    fn draw(&self, u: &mut impl FnMut() -> f64) -> ([f64; 3], bool, bool, bool) {
        let s = self.crossing.scatter(&mut *u);
        (
            s.dir,
            s.fallback,
            self.from_inside != s.transmitted,
            s.first_facet,
        )
    }
}

/// The part of a launch that depends on its azimuth only ([`Setup::beam_at`]).
#[derive(Debug, Clone, Copy)]
struct Beam {
    /// Unit xy direction of travel and the beam's cross axis.
    dhat: [f64; 2],
    e_perp: [f64; 2],
    /// The beam's extent along `e_perp`, µm.
    beam: (f64, f64),
    /// (sin φ, cos φ) of a spread launch's azimuth (`None`: the centre's direction).
    trig: Option<(f64, f64)>,
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

/// Where the branches that leave a fiber are scored.
pub(crate) trait Exits {
    /// Weight `w` leaves along `dir` after `path_um` inside the fiber.
    fn leave(&mut self, dir: [f64; 3], path_um: f64, w: f64);
    /// Weight `w` leaves through bin `bin` of the outgoing grid (expected-value scoring,
    /// [`super::lobe`]).
    fn leave_bin(&mut self, bin: u32, path_um: f64, w: f64);
}

/// Expected-value exit scoring ([`super::lobe`]) on the outgoing grid: at events met from
/// inside (the exit lobes TT, TRT, …) and, by a pass of its own, at the first event (the
/// reflection lobe R).
#[derive(Debug, Clone)]
pub(crate) struct ExpectedExits {
    pub grid: LobeGrid,
    pub inside: bool,
    /// The first event's reflection lobe is scored by a separate pass of launches
    /// ([`Setup::first_reflection`]), not per photon.
    pub first_reflection: bool,
}

/// Per-trace constants.
pub(crate) struct Setup<'a> {
    /// Expected-value exit scoring, when on.
    lobes: Option<ExpectedExits>,
    section: &'a Section,
    inc: Incident,
    s_max: f64,
    /// W(φc)·cos θc, the normalisation of spread weights.
    w_centre: f64,
    /// sin of the spread bin's lower and upper elevation, when the incident has a spread.
    sin_bounds: Option<(f64, f64)>,
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
            lobes: None,
            section: &fiber.section,
            inc,

            w_centre: (hi - lo) * s_max * ct,
            sin_bounds: inc.spread.map(|(dt, _)| {
                (
                    (inc.theta_rad - 0.5 * dt).sin(),
                    (inc.theta_rad + 0.5 * dt).sin(),
                )
            }),
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

    /// Scores first-facet exits in expectation on `grid` (binned from the incident centre's
    /// azimuth) at events met from inside (`inside`), and leaves the first event's reflection
    /// lobe to [`Setup::first_reflection`] (`first_reflection`).
    pub(crate) fn with_expected_exits(
        mut self,
        grid: formats::AngularGrid,
        inside: bool,
        first_reflection: bool,
    ) -> Self {
        let phi_c = self.inc.phi_rad;
        self.lobes = (inside || first_reflection).then(|| ExpectedExits {
            grid: LobeGrid::new(grid, phi_c),
            inside,
            first_reflection,
        });
        self
    }

    /// Width of the launched beam at the centre direction, µm.
    pub(crate) fn beam_width_um(&self) -> f64 {
        self.beam.1 - self.beam.0
    }

    /// One photon of the beam. `offset` places it across the beam (uniform in [0, 1); drawn
    /// when `None`); `draws` splits every boundary event of the photon's main path into that
    /// many draws ([`Draws`]). Its uniform numbers come from `u` ([`PathSampler`]: launch
    /// dimensions 0–3, then one block per boundary event of the main path).
    /// `emit` receives every branch that leaves ([`Exits`]); the weights include the spread
    /// weight.
    #[inline]
    pub(crate) fn photon(
        &self,
        u: &mut PathSampler,
        offset: Option<f64>,
        draws: Draws,
        emit: &mut impl Exits,
    ) -> PhotonStats {
        let (ray, g) = self.launch(u, offset);
        let mut st = self.walk(ray, draws, true, u, emit);
        st.g = g;
        st
    }

    /// The first-event reflection lobe of one launch, scored in expectation with weight
    /// `scale`·g: the part of [`Setup::photon`]'s score that the photons leave to this pass
    /// when the setup scores it so ([`ExpectedExits::first_reflection`]). Draws from `u` as a
    /// launch does, then the quadrature offset as the first event's two numbers (a Sobol'
    /// point's, for a point set).
    pub(crate) fn first_reflection(
        &self,
        u: &mut PathSampler,
        offset: Option<f64>,
        scale: f64,
        emit: &mut impl Exits,
    ) {
        let Some(lg) = self.lobes.as_ref().filter(|_| self.first_reflection_pass()) else {
            return;
        };
        let (mut ray, g) = self.launch(u, offset);
        let Some((n_out, id, _)) = self.advance_straight(&mut ray) else {
            return;
        };
        if !self.leaves_freely(id) {
            return;
        }
        let e = Event {
            d: ray.dir,
            nf: n_out,
            inside: false,
        };
        let Some(lobe) = lg.grid.lobe(&self.surface, &e) else {
            return;
        };
        u.begin_event(0);
        let uv = (u.uniform(), u.uniform());
        lg.grid.spread(&lobe, &self.surface, &e, uv, |bin, mass| {
            emit.leave_bin(bin, 0.0, scale * g * mass)
        });
    }

    /// A photon's ray at launch and its spread weight g.
    #[inline]
    fn launch(&self, u: &mut PathSampler, offset: Option<f64>) -> (Ray, f64) {
        let spread = self.inc.spread.map(|_| (u.launch(0), u.launch(1)));
        let f = offset.unwrap_or_else(|| u.launch(2));
        let z = self.cuticle.map(|_| u.launch(3));
        self.launch_at(spread, f, z)
    }

    /// [`Setup::launch`] at given launch numbers: `spread`, the uniform numbers that place ωi
    /// in its bin (used when the incident has a spread), `f` the offset across the beam and
    /// `z` the uniform number of the height along a cuticle period.
    #[inline]
    fn launch_at(&self, spread: Option<(f64, f64)>, f: f64, z: Option<f64>) -> (Ray, f64) {
        let beam = self.beam_at(spread.map(|s| s.1));
        self.launch_in(&beam, spread.map(|s| s.0), f, z)
    }

    /// The beam of a launch, which depends on its azimuth only: the centre's without a spread
    /// (or without `u1`), else φ = φc + Δφ·(u1 − ½) of the spread's bin. The setups of a
    /// shared group ([`shared`]) have one azimuth and one section, so one beam serves them all.
    #[inline]
    fn beam_at(&self, u1: Option<f64>) -> Beam {
        match self.inc.spread.zip(u1) {
            None => Beam {
                dhat: self.dhat,
                e_perp: self.e_perp,
                beam: self.beam,
                trig: None,
            },
            Some(((_, dp), u1)) => {
                let phi = self.inc.phi_rad + dp * (u1 - 0.5);
                let (sp, cp) = phi.sin_cos();
                let dhat = [-cp, -sp];
                let e_perp = [sp, -cp];
                let (lo, hi) = self.section.extent(e_perp);
                Beam {
                    dhat,
                    e_perp,
                    beam: (lo * self.s_max, hi * self.s_max),
                    trig: Some((sp, cp)),
                }
            }
        }
    }

    /// A photon's ray in `beam` at elevation number `u0` (used when the incident has a
    /// spread: uniform in sin θ over the bin), offset `f` across the beam and cuticle height
    /// number `z`, and its spread weight g = W(φ)·cos θ / (W(φc)·cos θc).
    #[inline]
    fn launch_in(&self, beam: &Beam, u0: Option<f64>, f: f64, z: Option<f64>) -> (Ray, f64) {
        let (d, g) = match (beam.trig, u0, self.sin_bounds) {
            (Some((sp, cp)), Some(u0), Some((s0, s1))) => {
                // Uniform in solid angle: uniform in sin θ and φ.
                let st = s0 + (s1 - s0) * u0;
                let ct = (1.0 - st * st).max(0.0).sqrt();
                let g = (beam.beam.1 - beam.beam.0) * ct / self.w_centre;
                ([-ct * cp, -ct * sp, -st], g)
            }
            _ => (self.d, 1.0),
        };
        let (dhat, e_perp, b) = (beam.dhat, beam.e_perp, beam.beam);
        let h = b.0 + (b.1 - b.0) * f;
        let o = [
            h * e_perp[0] - self.r_start * dhat[0],
            h * e_perp[1] - self.r_start * dhat[1],
        ];
        let z = self.cuticle.zip(z).map_or(0.0, |(c, uz)| c.0 * uz);
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
        (ray, g)
    }

    /// Follows a branch until it leaves (emitting it), is lost, or ends in roulette. The
    /// photon's main path (`main`) draws each event's numbers from that event's block of
    /// the sampler; branches split off it draw from the random stream.
    fn walk(
        &self,
        mut ray: Ray,
        draws: Draws,
        main: bool,
        u: &mut PathSampler,
        emit: &mut impl Exits,
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
                        emit.leave(ray.dir, ray.path, ray.w);
                    }
                }
                return st;
            };
            st.hit = true;
            if main {
                u.begin_event(ray.events);
            } else {
                u.leave_points();
            }
            ray.events += 1;
            if ray.events >= MAX_EVENTS {
                st.lost += ray.w;
                return st;
            }
            let free = self.leaves_freely(id);
            // Exit lobes in expectation on the main path only; children draw ([`super::lobe`]).
            let ev = if free && main {
                self.expected(&ray, n_out, u, emit)
            } else {
                None
            };
            // Draws of an event scored in expectation score only what it leaves out: from
            // inside ⌈draws·(1 − covered)⌉ (≥ 1); at the first event all (they split the entry).
            let split = match &ev {
                Some((_, Some(covered))) => {
                    let d = draws.at(ray.inside);
                    ((d as f64 * (1.0 - covered)).ceil() as u32).clamp(1, d)
                }
                _ => draws.at(ray.inside),
            };
            let ev = ev.map(|(lobe, _)| lobe);
            let event = self.boundary(ray.dir, n_out);
            if split <= 1 {
                let s = event.draw(&mut || u.uniform());
                st.fallbacks += s.1 as u32;
                if !s.2 && free {
                    // Outward through the convex hull: no ray query needed to know it leaves.
                    if !self.counted(&ev, &s) {
                        emit.leave(s.0, ray.path, ray.w);
                    }
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
            for k in 0..split {
                if k > 0 {
                    u.leave_points();
                }
                let s = event.draw(&mut || u.uniform());
                st.fallbacks += s.1 as u32;
                if s.2 {
                    m += 1;
                    if m == 1 || u.uniform() * (m as f64) < 1.0 {
                        chosen = Some(s.0);
                    }
                } else if free {
                    if !self.counted(&ev, &s) {
                        emit.leave(s.0, ray.path, kw);
                    }
                } else {
                    let child = Ray {
                        dir: s.0,
                        inside: false,
                        skip: id,
                        w: kw,
                        period: ray.period + if ray.inside { step } else { 0 },
                        ..ray
                    };
                    st.add(self.walk(child, Draws::PLAIN, false, u, emit));
                }
            }
            let Some(d) = chosen else { return st };
            if m < split && u.uniform() * split as f64 >= m as f64 {
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

    /// The lobe of a freely leaving event that is scored in expectation: the first event's
    /// reflection, scored by the first-reflection pass ([`Setup::first_reflection`]), or an
    /// exit from inside, scored here ([`Setup::expected_exits`]) with the share of the event
    /// it scored (its probability estimate).
    #[inline]
    fn expected(
        &self,
        ray: &Ray,
        n_out: [f64; 3],
        u: &mut PathSampler,
        emit: &mut impl Exits,
    ) -> Option<(Lobe, Option<f64>)> {
        if ray.events == 1 && self.first_reflection_pass() {
            let e = Event {
                d: ray.dir,
                nf: n_out,
                inside: false,
            };
            self.lobes
                .as_ref()
                .and_then(|l| l.grid.lobe(&self.surface, &e))
                .map(|lobe| (lobe, None))
        } else {
            self.expected_exits(ray, n_out, u, emit)
                .map(|(lobe, covered)| (lobe, Some(covered)))
        }
    }

    /// Scores in expectation the first-facet exits of the event a ray meets from inside at
    /// the outward normal `n_out` (when the setup scores exits so and the boundary is rough)
    /// and returns the lobe it covered and the probability it scored there (an unbiased
    /// estimate, ≤ 1 up to its noise).
    #[inline]
    fn expected_exits(
        &self,
        ray: &Ray,
        n_out: [f64; 3],
        u: &mut PathSampler,
        emit: &mut impl Exits,
    ) -> Option<(Lobe, f64)> {
        let lg = self.lobes.as_ref().filter(|l| l.inside)?;
        if dot3(ray.dir, n_out) <= 0.0 {
            return None;
        }
        let e = Event {
            d: ray.dir,
            nf: [-n_out[0], -n_out[1], -n_out[2]],
            inside: true,
        };
        let w = lg.grid.lobe(&self.surface, &e)?;
        let uv = (u.stream(), u.stream());
        let mut covered = 0.0;
        lg.grid.spread(&w, &self.surface, &e, uv, |bin, mass| {
            covered += mass;
            emit.leave_bin(bin, ray.path, ray.w * mass)
        });
        Some((w, covered))
    }

    /// Whether the first event's reflection lobe is left to [`Setup::first_reflection`].
    #[inline]
    fn first_reflection_pass(&self) -> bool {
        self.cuticle.is_none() && self.lobes.as_ref().is_some_and(|l| l.first_reflection)
    }

    /// Whether the outcome `s` of an event whose first-facet exits were scored in expectation
    /// over window `ev` is one of them (a first-facet exit into the window), not to be scored
    /// again.
    #[inline]
    fn counted(&self, ev: &Option<Lobe>, s: &([f64; 3], bool, bool, bool)) -> bool {
        match (ev, &self.lobes) {
            (Some(w), Some(lg)) => s.3 && lg.grid.covers(w, s.0),
            _ => false,
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

    /// A boundary event at outward normal `n_out`, to be drawn once or many times
    /// ([`Boundary::draw`]). The side is read from the direction, so a numerical slip cannot
    /// desynchronise it.
    #[inline]
    fn boundary(&self, dir: [f64; 3], n_out: [f64; 3]) -> Boundary {
        let from_inside = dot3(dir, n_out) > 0.0;
        let nf = if from_inside {
            [-n_out[0], -n_out[1], -n_out[2]]
        } else {
            n_out
        };
        Boundary {
            crossing: self.surface.crossing(dir, nf, from_inside),
            from_inside,
        }
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
    let bins = ExitBins::new(&o.grid, inc.phi_rad);
    let n_batches = o.photons.div_ceil(BATCH);
    let mut total = DirectionTally::new(o.grid, &o.mua_per_um);
    let mut b0 = 0;
    while b0 < n_batches {
        let b1 = (b0 + GROUP).min(n_batches);
        let parts: Vec<DirectionTally> = (b0..b1)
            .into_par_iter()
            .map(|b| {
                let n = BATCH.min(o.photons - b * BATCH);
                let t = trace_batch(&setup, &bins, o, b, n);
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
    bins: &ExitBins,
    o: &TraceOptions,
    batch: u64,
    n: u64,
) -> DirectionTally {
    let mut rng = batch_rng(o.seed, batch);
    let mut t = DirectionTally::new(o.grid, &o.mua_per_um);
    t.launched = n;
    let mut exits = TallyExits { t: &mut t, bins };
    for _ in 0..n {
        let st = setup.photon(
            &mut PathSampler::random(&mut rng),
            None,
            Draws::PLAIN,
            &mut exits,
        );
        let t = &mut *exits.t;
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

/// The plain tracer's scoring: every exit into its bin of a [`DirectionTally`].
struct TallyExits<'a> {
    t: &'a mut DirectionTally,
    bins: &'a ExitBins,
}

impl Exits for TallyExits<'_> {
    fn leave(&mut self, dir: [f64; 3], path_um: f64, w: f64) {
        self.t.score(self.bins.bin(dir), path_um, w)
    }

    fn leave_bin(&mut self, bin: u32, path_um: f64, w: f64) {
        self.t.score(bin, path_um, w)
    }
}
