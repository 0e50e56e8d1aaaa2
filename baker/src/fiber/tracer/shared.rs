//! Photons shared by neighbouring incoming directions: one photon serves a window of incoming
//! bins of the same azimuth φi and neighbouring elevations θi (`estimators.share_theta`), the
//! windows sliding along the φ column ([`Windows`]).
//!
//! # Why it is possible
//! The fiber is an extrusion along z, so the point where a beam from (θi, φi) meets it depends
//! on φi and the offset across the beam only: the beams of one φi and any θi meet the section
//! at the same points, with the same mean normal. What follows the first event depends only on
//! the direction the photon leaves it in (and that point), not on θi: the internal walk, its
//! exits, their bins (θo and Δφ = φo − φi, the same φi) and the path lengths the dyes act on.
//! Only the first event's distribution differs between the group's directions, and on rough
//! fibers the refracted lobes of θi bins 2° apart overlap closely (β = 5–17°).
//!
//! # The estimator (multi-sample importance sampling, Veach 1997 §9.2, balance heuristic)
//! Slice j's first event from ωj is split into A, entries through the first facet met, with
//! the density p_j(ω) of [`crate::fiber::Surface::entry_density`], and B, every other outcome
//! (reflections, entries after the V-cavity's other facet, fallbacks). Each photon draws `s`
//! outcomes from every slice k's own first event (the same launch numbers place ωk in its bin
//! and the photon across the beam). For slice j:
//!
//! * an A outcome ω drawn from slice k counts for j with weight p_j(ω)/Σ_l p_l(ω), whatever
//!   k (Σ_k ∫ p_k·p_j/Σ_l p_l·G = ∫ p_j·G: unbiased for A's part of slice j);
//! * a B outcome drawn from slice k counts for k alone, with weight 1 (each slice's B part is
//!   estimated from its own draws as plain tracing does).
//!
//! Each draw weighs 1/s (times the spread weight g_j of slice j's ωj). The outcomes that leave
//! are scored at once; of the M that enter, one picked uniformly goes on, with probability
//! M/(K·s) (Russian roulette, as `Setup::walk` does for one slice), carrying for every slice
//! j the weight K·g_j·c_j, c_j the pick's weight above: its walk is scored into every slice
//! at once (`SharedExits`). Every slice's estimate is unbiased; they are correlated, which
//! no table needs them not to be. Tested against plain tracing in `tests/fiber_references.rs`.
//!
//! Only for straight fibers (a cuticle's scales make the meeting point depend on θi) with a
//! rough boundary (a smooth one has no overlapping lobes: A would be a delta).

use super::{Draws, Exits, PhotonStats, Ray, Setup};
use crate::fiber::lobe::{Event, Lobe};
use crate::math::sampler::PathSampler;

/// The most incoming directions one photon serves.
pub const MAX_SHARED: usize = 8;

/// Whether a fiber's directions can share photons at all: straight (no cuticle scales) and
/// rough.
pub fn shares(surface: &crate::fiber::Surface, cuticle: Option<&crate::fiber::Cuticle>) -> bool {
    cuticle.is_none() && surface.alpha > 0.0
}

/// The windows of a column of `n` directions (neighbouring θ rows of one φ column, in order)
/// that each share a batch of photons: every run of `k` consecutive directions, including
/// the runs cut short by the column's ends, so window w holds directions
/// [w − (k − 1), w] ∩ [0, n). Each direction lies in exactly `k` windows, once at every
/// place of one: the lobes of its neighbours on both sides serve it in turn, where fixed
/// blocks of `k` leave the directions at a block's ends with one side only (they needed
/// 1.5–2× the batches of the middle ones to reach the same noise on silk at 2°).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Windows {
    pub n: usize,
    pub k: usize,
}

impl Windows {
    /// Windows of `k` (clamped to 1..=[`MAX_SHARED`]) over `n` directions.
    pub fn new(n: usize, k: usize) -> Self {
        Self {
            n,
            k: k.clamp(1, MAX_SHARED),
        }
    }

    /// How many windows there are: `n + k − 1`.
    pub fn count(&self) -> usize {
        self.n + self.k - 1
    }

    /// The directions of window `w`.
    pub fn members(&self, w: usize) -> std::ops::Range<usize> {
        let start = (w + 1).saturating_sub(self.k);
        start..(w + 1).min(self.n)
    }
}

/// Where a shared photon's branches are scored: into every slice of its group, each with its
/// own weight.
pub(crate) trait SharedExits: Exits {
    /// The weight of every slice (in group order) for what is emitted from now on.
    fn set_weights(&mut self, w: &[f64]);
}

impl Setup<'_> {
    /// Whether the setups of `group` can share photons: a straight fiber with a rough
    /// boundary, one incoming azimuth and bin width.
    pub(crate) fn can_share(group: &[Setup<'_>]) -> bool {
        let Some(s0) = group.first() else {
            return false;
        };
        s0.cuticle.is_none()
            && s0.surface.alpha > 0.0
            && group.iter().all(|s| {
                std::ptr::eq(s.section, s0.section)
                    && s.surface == s0.surface
                    && s.cuticle.is_none()
                    && s.inc.phi_rad == s0.inc.phi_rad
                    && s.inc.spread.map(|x| x.1) == s0.inc.spread.map(|x| x.1)
                    && s.inc.spread.is_some() == s0.inc.spread.is_some()
            })
    }

    /// One photon shared by the slices of `group` ([`Setup::can_share`]; the module's
    /// documentation has the estimator). Numbers from `u` as [`Setup::photon`] takes them:
    /// launch dimensions 0–2, then one block per boundary event of the main path; `draws`
    /// as there, the first event's `outside` draws spread over the slices (⌈outside/K⌉ each).
    /// `stats[k]` receives slice k's photon statistics.
    pub(crate) fn photon_shared(
        group: &[&Setup<'_>],
        u: &mut PathSampler,
        offset: Option<f64>,
        draws: Draws,
        emit: &mut impl SharedExits,
        stats: &mut [PhotonStats],
    ) {
        let n = group.len();
        debug_assert!(stats.len() == n && n <= MAX_SHARED);
        let s0 = group[0];
        let spread = s0.inc.spread.map(|_| (u.launch(0), u.launch(1)));
        let f = offset.unwrap_or_else(|| u.launch(2));
        let mut dir = [[0.0; 3]; MAX_SHARED];
        let mut g = [0.0; MAX_SHARED];
        let mut ray = None;
        // One azimuth for the group: one beam.
        let beam = s0.beam_at(spread.map(|s| s.1));
        for (k, s) in group.iter().enumerate() {
            let (r, gk) = s.launch_in(&beam, spread.map(|s| s.0), f, None);
            stats[k] = PhotonStats {
                g: gk,
                ..PhotonStats::default()
            };
            (dir[k], g[k]) = (r.dir, gk);
            ray.get_or_insert(r);
        }
        // The beams' xy paths coincide: one query finds where every slice's photon hits.
        let mut ray: Ray = ray.expect("a group has a direction");
        let Some((n_out, id, _)) = s0.advance_straight(&mut ray) else {
            return;
        };
        stats.iter_mut().for_each(|st| st.hit = true);
        u.begin_event(0);
        ray.events = 1;
        let free = s0.leaves_freely(id);
        let per = draws.outside.max(1).div_ceil(n as u32);
        let total = per * n as u32;
        let mut unit = [0.0; MAX_SHARED];
        // The first-reflection pass's window of slice k, computed when a draw needs it.
        let mut windows: [Option<Option<Lobe>>; MAX_SHARED] = Default::default();
        let (mut m, mut chosen) = (0u32, None);
        let mut first = true;
        for (k, s) in group.iter().enumerate() {
            let event = s.boundary(dir[k], n_out);
            for _ in 0..per {
                if !first {
                    u.leave_points();
                }
                first = false;
                let o = event.draw(&mut || u.uniform());
                stats[k].fallbacks += o.1 as u32;
                if o.2 {
                    m += 1;
                    if m == 1 || u.uniform() * (m as f64) < 1.0 {
                        chosen = Some((o.0, k, o.3));
                    }
                    continue;
                }
                let w = g[k] / per as f64;
                unit[k] = 1.0;
                emit.set_weights(&unit[..n]);
                unit[k] = 0.0;
                if free {
                    let ev = windows[k].get_or_insert_with(|| s.reflection_window(dir[k], n_out));
                    if !s.counted(ev, &o) {
                        emit.leave(o.0, 0.0, w);
                    }
                } else {
                    let child = Ray {
                        dir: o.0,
                        inside: false,
                        skip: id,
                        w,
                        ..ray
                    };
                    let c = s0.walk(child, Draws::PLAIN, false, u, emit);
                    stats[k].lost += c.lost;
                    stats[k].fallbacks += c.fallbacks;
                }
            }
        }
        let Some((d_in, k_in, first_facet)) = chosen else {
            return;
        };
        if m < total && u.uniform() * total as f64 >= m as f64 {
            return;
        }
        // The pick's weight per slice: K·g_j·c_j.
        let mut v = [0.0; MAX_SHARED];
        let mut p = [0.0; MAX_SHARED];
        let mut sum = 0.0;
        if first_facet {
            for (j, s) in group.iter().enumerate() {
                p[j] = s.surface.entry_density(dir[j], n_out, d_in);
                sum += p[j];
            }
        }
        if sum > 0.0 {
            for j in 0..n {
                v[j] = n as f64 * g[j] * p[j] / sum;
            }
        } else {
            v[k_in] = n as f64 * g[k_in];
        }
        emit.set_weights(&v[..n]);
        let walk = Ray {
            dir: d_in,
            inside: true,
            skip: id,
            w: 1.0,
            ..ray
        };
        let c = s0.walk(walk, draws, true, u, emit);
        for j in 0..n {
            stats[j].lost += c.lost * v[j];
            stats[j].fallbacks += c.fallbacks;
        }
    }

    /// The window of the first event's reflection lobe that the first-reflection pass scores
    /// for a photon along `d` meeting the mean normal `n_out` from outside (`None` without
    /// that pass).
    fn reflection_window(&self, d: [f64; 3], n_out: [f64; 3]) -> Option<Lobe> {
        if !self.first_reflection_pass() {
            return None;
        }
        let e = Event {
            d,
            nf: n_out,
            inside: false,
        };
        self.lobes
            .as_ref()
            .and_then(|l| l.grid.lobe(&self.surface, &e))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Every direction lies in exactly `k` windows, once at each place of a full window (and
    /// at the place its clipped windows leave it), and windows are runs of consecutive
    /// directions of at most `k`.
    #[test]
    fn every_direction_lies_in_k_windows_once_at_each_place() {
        for (n, k) in [(45, 8), (6, 4), (3, 8), (1, 1), (9, 1), (2, 2)] {
            let w = Windows::new(n, k);
            assert_eq!(w.count(), n + k - 1);
            let mut places = vec![Vec::new(); n];
            for i in 0..w.count() {
                let m = w.members(i);
                assert!(
                    !m.is_empty() && m.len() <= k && m.end <= n,
                    "{n} {k} {i}: {m:?}"
                );
                // The window's place of each member: where it would sit in the full window
                // [i + 1 − k, i].
                for j in m {
                    places[j].push(j + k - 1 - i);
                }
            }
            for (j, p) in places.iter().enumerate() {
                assert_eq!(
                    *p,
                    (0..k).rev().collect::<Vec<_>>(),
                    "n {n}, k {k}, direction {j}"
                );
            }
        }
        assert_eq!(Windows::new(5, 40).k, MAX_SHARED);
        assert_eq!(Windows::new(5, 0).k, 1);
    }
}
