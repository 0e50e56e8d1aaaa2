//! The non-planar dermo-epidermal junction of thesis Eq. 1 as a height field:
//! J(x, y) = z̄ + A·sin(ωx·x + φx)·sin(ωy·y + φy).
//!
//! Ray intersection marches with lower bounds on the signed vertical distance along the ray
//! (the curvature of the whole surface, and envelopes that keep one of its two frequencies),
//! so the first crossing along a segment is never stepped over. Once an upper bound brackets
//! a unique crossing, Newton's method inside a shrinking bracket finds it.

use super::stack::Junction;

#[derive(Debug, Clone, Copy)]
pub struct HeightField {
    pub z_mean_mm: f64,
    pub a: f64,
    pub wx: f64,
    pub wy: f64,
    pub px: f64,
    pub py: f64,
}

/// Smallest marching step, mm (0.2 µm, 1/500 of the default 100 µm ridge period). The Lipschitz
/// step g/L shrinks as a ray grazes the surface; this floor bounds the work per segment (at
/// most a few thousand steps) at the price of missing a dip to the other side shorter than
/// 0.2 µm along the ray, a set of grazing paths of negligible measure.
pub const MIN_STEP_MM: f64 = 2e-4;
/// Root refinement stops when the bracket is this narrow, mm: a tenth of a picometre, a
/// hundredth of the 10⁻⁹ mm step a packet takes off the surface after crossing it (engine's
/// `cross_junction`), so a tighter root changes nothing that follows (it cost 1.5 more
/// evaluations per crossing at 10⁻¹²).
const ROOT_TOL_MM: f64 = 1e-10;

/// Newton steps of the bracketed polish at most (they converge quadratically, so this bounds
/// only degenerate cases).
const MAX_NEWTON_STEPS: u32 = 32;

/// sin and cos of `x` for the height field: quadrant reduction (Cody–Waite, π/2 split in
/// three parts) and Taylor polynomials on [−π/4, π/4], truncation error < 1e-15. Several times
/// cheaper than the C library's general routine; the arguments here stay below ~10⁴ rad.
#[inline(always)]
pub fn sin_cos(x: f64) -> (f64, f64) {
    // π/2 = P1 + P2 + P3, P1 and P2 with 30-bit mantissas so k·P1 and k·P2 are exact.
    const P1: f64 = 1.570_796_325_802_803;
    const P2: f64 = 9.920_935_791_635_221e-10;
    const P3: f64 = 5.170_182_981_794_105e-19;
    // Round to the nearest quadrant by the 1.5·2⁵² shifter: adding it leaves the rounded
    // quotient in the low mantissa bits (|q| < 2⁵¹), with no float–integer conversions.
    const SHIFTER: f64 = 6_755_399_441_055_744.0;
    let q = x * std::f64::consts::FRAC_2_PI;
    let shifted = q + SHIFTER;
    let ki = shifted.to_bits() as i64;
    let k = shifted - SHIFTER;
    let r = ((x - k * P1) - k * P2) - k * P3;
    let z = r * r;
    let z2 = z * z;
    let z4 = z2 * z2;
    // sin r = r·Σ (−1)ⁿ zⁿ/(2n+1)!, cos r = Σ (−1)ⁿ zⁿ/(2n)!, z = r², n ≤ 7, evaluated by Estrin's
    // scheme (independent pairs, then powers of z) for a short dependency chain.
    let sp = (1.0 - z * (1.0 / 6.0))
        + z2 * (1.0 / 120.0 - z * (1.0 / 5040.0))
        + z4 * ((1.0 / 362_880.0 - z * (1.0 / 39_916_800.0))
            + z2 * (1.0 / 6_227_020_800.0 - z * (1.0 / 1_307_674_368_000.0)));
    let s = r * sp;
    let c = (1.0 - z * 0.5)
        + z2 * (1.0 / 24.0 - z * (1.0 / 720.0))
        + z4 * ((1.0 / 40_320.0 - z * (1.0 / 3_628_800.0))
            + z2 * (1.0 / 479_001_600.0 - z * (1.0 / 87_178_291_200.0)));
    // Quadrant k mod 4 gives (s, c), (c, −s), (−s, −c), (−c, s): a swap for odd k and sign
    // bits, selected without branches (the quadrant of a random ray is unpredictable).
    let pair = [s, c];
    let odd = (ki & 1) as usize;
    let sin_sign = ((ki & 2) as u64) << 62;
    let cos_sign = (((ki + 1) & 2) as u64) << 62;
    (
        f64::from_bits(pair[odd].to_bits() ^ sin_sign),
        f64::from_bits(pair[odd ^ 1].to_bits() ^ cos_sign),
    )
}

impl HeightField {
    pub fn new(j: &Junction, z_mean_mm: f64) -> Self {
        Self {
            z_mean_mm,
            a: j.amplitude_mm,
            wx: j.omega_x_per_mm,
            wy: j.omega_y_per_mm,
            px: j.phi_x_rad,
            py: j.phi_y_rad,
        }
    }

    /// J(x, y), mm.
    #[inline]
    pub fn z(&self, x: f64, y: f64) -> f64 {
        self.z_mean_mm
            + self.a * sin_cos(self.wx * x + self.px).0 * sin_cos(self.wy * y + self.py).0
    }

    /// Unit normal of the surface z − J(x, y) = 0, pointing to +z (into the deeper layer).
    pub fn normal(&self, x: f64, y: f64) -> [f64; 3] {
        let (sx, cx) = sin_cos(self.wx * x + self.px);
        let (sy, cy) = sin_cos(self.wy * y + self.py);
        let jx = self.a * self.wx * cx * sy;
        let jy = self.a * self.wy * sx * cy;
        let inv = 1.0 / (jx * jx + jy * jy + 1.0).sqrt();
        [-jx * inv, -jy * inv, inv]
    }

    /// Distance along the unit direction `u` from `p` to the first crossing of the surface within
    /// `t_max`, for a point on side `side` (−1: above, z < J; +1: below, z > J).
    pub fn hit(&self, p: [f64; 3], u: [f64; 3], t_max: f64, side: f64) -> Option<f64> {
        self.hit_counted(p, u, t_max, side, 0.0, &mut 0)
    }

    /// The slope g′ = side·(u·n)/n_z at which a ray leaves the surface at a point whose unit
    /// normal is `n` ([`HeightField::normal`]): what [`HeightField::hit_counted`] takes as
    /// `leaving_slope` for a packet that has just crossed or been reflected there.
    #[inline(always)]
    pub fn leaving_slope(n: [f64; 3], u: [f64; 3], side: f64) -> f64 {
        side * (u[0] * n[0] + u[1] * n[1] + u[2] * n[2]) / n[2]
    }

    /// [`HeightField::hit`], adding to `evals` how many times it evaluated the surface (the
    /// work of the search, deterministic: the photon allocation's cost model counts it).
    /// `leaving_slope` > 0 says that `p` lies on the surface (a step of 1 nm off it at most)
    /// and that g′ there is that value ([`HeightField::leaving_slope`]): the search then starts
    /// from g = 0 with that slope instead of evaluating the surface at `p`; 0 means unknown.
    #[inline]
    pub fn hit_counted(
        &self,
        p: [f64; 3],
        u: [f64; 3],
        t_max: f64,
        side: f64,
        leaving_slope: f64,
        evals: &mut u64,
    ) -> Option<f64> {
        // Quick reject: the segment never enters the slab |z − z̄| ≤ A.
        let (z0, z1) = (p[2], p[2] + u[2] * t_max.min(1e30));
        let (lo, hi) = if z0 < z1 { (z0, z1) } else { (z1, z0) };
        if hi < self.z_mean_mm - self.a || lo > self.z_mean_mm + self.a {
            return None;
        }
        // g(t) = side·(z(t) − J(x(t), y(t))) ≥ 0 on the photon's side, with its derivative.
        let (wxu, wyu) = (self.wx * u[0], self.wy * u[1]);
        let (ax, ay) = (self.wx * p[0] + self.px, self.wy * p[1] + self.py);
        let (g0, su, sa) = (side * (p[2] - self.z_mean_mm), side * u[2], side * self.a);
        let n = std::cell::Cell::new(0u64);
        let g = |t: f64| {
            n.set(n.get() + 1);
            g0 + su * t - sa * sin_cos(ax + wxu * t).0 * sin_cos(ay + wyu * t).0
        };
        let g_and_slope = |t: f64| {
            n.set(n.get() + 1);
            let (sx, cx) = sin_cos(ax + wxu * t);
            let (sy, cy) = sin_cos(ay + wyu * t);
            (
                g0 + su * t - sa * sx * sy,
                su - sa * (wxu * cx * sy + wyu * sx * cy),
            )
        };
        // Along the ray, with a = ωx·ux and c = ωy·uy, A·sin(a·t + α)·sin(c·t + γ) is
        // A/2·(cos((a − c)·t + α − γ) − cos((a + c)·t + α + γ)), so
        // |J″| ≤ A/2·((a − c)² + (a + c)²) = A·(a² + c²): the bound of the whole surface.
        let whole = Bounds::new(self.a * (wxu * wxu + wyu * wyu));
        // Each cosine alone: the other one bounded by its range ±A/2 gives the envelope bounds
        // g ≥ side·z − side·A/2·cos(slow) − A/2 (and the same with the fast one), whose
        // curvature is only that of the term kept. Far from the ripples of one frequency they
        // allow much longer steps.
        let (w_minus, w_plus) = (wxu - wyu, wxu + wyu);
        let half_a = 0.5 * self.a;
        let minus = Bounds::new(half_a * w_minus * w_minus);
        let plus = Bounds::new(half_a * w_plus * w_plus);
        let (mut t, t_max) = self.slab_span(p, u, t_max)?;
        // Leaving the surface: g(0) ≥ 0 and g′(0) is known; the slope, taken at the crossing,
        // may differ at p (≤ 1 nm away) by up to curv·1 nm, which the margin covers. Slopes
        // this small (grazing) are evaluated instead.
        let mut known = (leaving_slope > 1e-6 && t == 0.0)
            .then_some(leaving_slope - 2e-9 * whole.curv)
            .filter(|s| *s > 0.0);
        let found = loop {
            let (gt, slope, safe) = if let Some(s) = known.take() {
                (0.0, s, whole.ahead_min(0.0, s))
            } else {
                // g_and_slope's formulas, inlined: the envelopes need its sines and cosines.
                n.set(n.get() + 1);
                let (sx, cx) = sin_cos(ax + wxu * t);
                let (sy, cy) = sin_cos(ay + wyu * t);
                let lin = g0 + su * t;
                let gt = (lin - sa * sx * sy).max(0.0);
                let slope = su - sa * (wxu * cx * sy + wyu * sx * cy);
                // No crossing closer than the farthest of the three lower bounds' first roots.
                let mut safe = whole.ahead_min(gt, slope);
                let (c_minus, c_plus) = (cx * cy + sx * sy, cx * cy - sx * sy);
                let slow = lin - side * half_a * c_minus - half_a;
                if slow > 0.0 {
                    let d_minus = (cx * sy - sx * cy) * w_minus;
                    safe = safe.max(minus.ahead_min(slow, su - side * half_a * d_minus));
                }
                let fast = lin + side * half_a * c_plus - half_a;
                if fast > 0.0 {
                    let d_plus = -(sx * cy + cx * sy) * w_plus;
                    safe = safe.max(plus.ahead_min(fast, su + side * half_a * d_plus));
                }
                (gt, slope, safe)
            };
            if t + safe >= t_max {
                // The bounds keep g ≥ 0 up to t_max: no crossing (no need to look at the end).
                break None;
            }
            // Approaching steeply (g′² > 2·curv·g): the upper bound g + g′Δ + curv·Δ²/2 has a
            // root too, so the crossing lies in [t + safe, t + upper], where g still falls
            // (g′ + curv·Δ < 0 for Δ ≤ upper ≤ −g′/curv): the root there is unique, and the
            // first. Newton's method finds it.
            if let Some(upper) = whole.ahead_max(gt, slope) {
                if t + upper <= t_max {
                    break Some(polish(&g_and_slope, &whole, t, (gt, slope), (safe, upper)));
                }
            }
            let t_next = t + safe.max(MIN_STEP_MM);
            if t_next > t_max {
                // Check the end point too: the crossing may lie in the last partial step.
                let g_end = g(t_max);
                if g_end < 0.0 {
                    break Some(refine(&g, (t, gt), (t_max, g_end)));
                }
                break None;
            }
            if safe < MIN_STEP_MM {
                let g_next = g(t_next);
                if g_next < 0.0 {
                    break Some(refine(&g, (t, gt), (t_next, g_next)));
                }
            }
            t = t_next;
        };
        *evals += n.get();
        found
    }
    /// The part of the segment [0, t_max] from `p` along `u` where a crossing is possible:
    /// from where it enters the slab |z − z̄| ≤ A (the start, if inside) to just past where it
    /// leaves it on the far side; `None` if that part is empty.
    #[inline(always)]
    fn slab_span(&self, p: [f64; 3], u: [f64; 3], t_max: f64) -> Option<(f64, f64)> {
        // Start marching where the segment enters the slab, if it starts outside it and moves
        // towards it; from inside the slab, march from the start.
        let (top, bottom) = (self.z_mean_mm - self.a, self.z_mean_mm + self.a);
        let t = if p[2] < top && u[2] > 0.0 {
            (top - p[2]) / u[2]
        } else if p[2] > bottom && u[2] < 0.0 {
            (bottom - p[2]) / u[2]
        } else {
            0.0
        };
        // And stop where it leaves the slab on the far side: beyond it no crossing is possible.
        let t_max = if u[2] != 0.0 {
            let leave = if u[2] > 0.0 { bottom } else { top };
            t_max.min(((leave - p[2]) / u[2]).max(0.0) + MIN_STEP_MM)
        } else {
            // Horizontal ray inside the slab: the surface's period bounds the search.
            t_max.min(4.0 * std::f64::consts::PI / self.wx.min(self.wy).max(1e-9) + 1.0)
        };
        (t <= t_max).then_some((t, t_max))
    }
}

/// The quadratic bounds g + g′Δ ∓ curv·Δ²/2 on the signed distance along a ray.
struct Bounds {
    curv: f64,
}

impl Bounds {
    fn new(curv: f64) -> Self {
        Bounds { curv }
    }

    /// The first positive root of the lower bound: no crossing lies closer than this ahead of a
    /// point with g ≥ 0 and slope g′. Written 2g/(√(g′² + 2·curv·g) − g′) to stay exact as
    /// curv → 0 when approaching, (g′ + √…)/curv when moving away (infinite for a flat
    /// surface): each form free of cancellation where it is used.
    #[inline(always)]
    fn ahead_min(&self, g: f64, slope: f64) -> f64 {
        let root = (slope * slope + 2.0 * self.curv * g).sqrt();
        if slope < 0.0 {
            2.0 * g / (root - slope)
        } else if self.curv > 1e-300 {
            (slope + root) / self.curv
        } else {
            f64::INFINITY
        }
    }

    /// The first root of the upper bound g + g′Δ + curv·Δ²/2, where one exists (g′ < 0,
    /// g′² ≥ 2·curv·g): a crossing lies no farther than this.
    #[inline(always)]
    fn ahead_max(&self, g: f64, slope: f64) -> Option<f64> {
        let disc = slope * slope - 2.0 * self.curv * g;
        (slope < 0.0 && disc >= 0.0).then(|| 2.0 * g / (disc.sqrt() - slope))
    }
}

/// The unique crossing in [t + safe, t + upper] of a g that decreases there, by Newton's
/// method kept inside a bracket that the quadratic bounds at every evaluated point shrink.
/// Returns the bracket's photon-side end once it is narrower than the tolerance.
#[inline(always)]
fn polish(
    g_and_slope: &impl Fn(f64) -> (f64, f64),
    b: &Bounds,
    t: f64,
    (gt, slope): (f64, f64),
    (safe, upper): (f64, f64),
) -> f64 {
    let (mut lo, mut hi) = (t + safe, t + upper);
    let mut x = t + gt / -slope;
    for _ in 0..MAX_NEWTON_STEPS {
        if hi - lo <= ROOT_TOL_MM {
            break;
        }
        if !(x > lo && x < hi) {
            x = 0.5 * (lo + hi);
        }
        let (gx, sx) = g_and_slope(x);
        if gx >= 0.0 {
            // The crossing is ahead of x: between the roots of the two bounds from x.
            lo = lo.max(x + b.ahead_min(gx, sx));
            if let Some(up) = b.ahead_max(gx, sx) {
                hi = hi.min(x + up);
            }
        } else {
            // Behind x: the same bounds looking back, for h(τ) = −g(x − τ) (h = −g > 0 and
            // h′ = g′ at τ = 0).
            hi = hi.min(x - b.ahead_min(-gx, sx));
            if let Some(back) = b.ahead_max(-gx, sx) {
                lo = lo.max(x - back);
            }
        }
        x = if sx < 0.0 {
            x + gx / -sx
        } else {
            0.5 * (lo + hi)
        };
    }
    lo
}

/// The crossing of `g` in [lo, hi] (g(lo) ≥ 0 > g(hi), each given with its value) by the
/// Illinois variant of regula falsi (Dowell & Jarratt 1971): superlinear, and safe because the
/// bracket always shrinks. Returns the end of the bracket still on the photon's side.
fn refine(g: &impl Fn(f64) -> f64, lo: (f64, f64), hi: (f64, f64)) -> f64 {
    let ((mut a, mut fa), (mut b, mut fb)) = (lo, hi);
    fa = fa.max(0.0);
    let mut last = 0i8;
    for _ in 0..100 {
        if b - a <= ROOT_TOL_MM {
            break;
        }
        let mut c = (a * fb - b * fa) / (fb - fa);
        if !(c > a && c < b) {
            c = 0.5 * (a + b);
        }
        let fc = g(c);
        if fc < 0.0 {
            b = c;
            fb = fc;
            if last == -1 {
                fa *= 0.5;
            }
            last = -1;
        } else {
            a = c;
            fa = fc;
            if last == 1 {
                fb *= 0.5;
            }
            last = 1;
            if fc == 0.0 {
                break;
            }
        }
    }
    a
}

#[cfg(test)]
mod tests {
    use super::*;

    fn field() -> HeightField {
        HeightField::new(
            &Junction {
                upper_layer: 1,
                amplitude_mm: 0.05,
                omega_x_per_mm: 62.83,
                omega_y_per_mm: 62.83,
                phi_x_rad: 0.3,
                phi_y_rad: -0.2,
            },
            0.1,
        )
    }

    #[test]
    fn fast_sin_cos_matches_the_c_library() {
        let mut worst: f64 = 0.0;
        for i in -200_000..200_000 {
            let x = i as f64 * 0.0123457 + 0.3;
            let (s, c) = sin_cos(x);
            worst = worst.max((s - x.sin()).abs()).max((c - x.cos()).abs());
        }
        assert!(worst < 1e-13, "{worst}");
        // Large arguments (ω·x reaches ~10⁴ rad) keep full precision: the three-part π/2
        // reduction (Cody–Waite) is exact to ~10⁻¹⁹·k.
        let mut worst: f64 = 0.0;
        for i in 0..200_000 {
            let x = 5_000.0 + i as f64 * 0.0250123;
            let (s, c) = sin_cos(x);
            worst = worst.max((s - x.sin()).abs()).max((c - x.cos()).abs());
        }
        // Measured 1.2e-15 (the polynomials' truncation and libm's half ulp); dropping the
        // third part P3 of π/2 or adding it with the wrong sign gives 6.6e-15.
        assert!(worst < 2.5e-15, "{worst}");
    }

    #[test]
    fn vertical_ray_hits_at_the_height_field() {
        let f = field();
        let t = f
            .hit([0.013, 0.021, 0.0], [0.0, 0.0, 1.0], 1.0, -1.0)
            .unwrap();
        assert!((t - f.z(0.013, 0.021)).abs() < 1e-12);
    }

    #[test]
    fn oblique_rays_find_the_first_crossing() {
        let f = field();
        let u = {
            let v: [f64; 3] = [0.8, 0.3, 0.2];
            let n = (v[0] * v[0] + v[1] * v[1] + v[2] * v[2]).sqrt();
            [v[0] / n, v[1] / n, v[2] / n]
        };
        let p = [0.0, 0.0, 0.04];
        let t = f.hit(p, u, 1.0, -1.0).unwrap();
        // No crossing before t: dense sampling stays on the upper side.
        for k in 0..100_000 {
            let s = t * k as f64 / 100_000.0;
            assert!(p[2] + u[2] * s <= f.z(p[0] + u[0] * s, p[1] + u[1] * s) + 1e-12);
        }
        let q = [p[0] + u[0] * t, p[1] + u[1] * t, p[2] + u[2] * t];
        assert!((q[2] - f.z(q[0], q[1])).abs() < 1e-9);
    }

    /// Rays from random points in and around the slab, random directions and lengths: the
    /// search agrees with a dense scan (no crossing before the one it returns, none at all when
    /// it returns none, apart from dips shorter than the scan's step) and lands on the surface.
    #[test]
    fn random_rays_find_the_first_crossing_of_a_dense_scan() {
        use rand_core::Rng;
        let f = field();
        let mut rng = crate::math::rng::batch_rng(11, 0);
        let mut u01 = || crate::math::rng::uniform(rng.next_u64());
        let (mut found, mut none) = (0, 0);
        for _ in 0..3000 {
            let p = [u01() * 0.1, u01() * 0.1, 0.03 + 0.14 * u01()];
            let side = if p[2] < f.z(p[0], p[1]) { -1.0 } else { 1.0 };
            let cz = 2.0 * u01() - 1.0;
            let ph = 2.0 * std::f64::consts::PI * u01();
            let st = (1.0 - cz * cz).sqrt();
            let u = [st * ph.cos(), st * ph.sin(), cz];
            let t_max = 0.3 * u01();
            let g = |t: f64| side * (p[2] + u[2] * t - f.z(p[0] + u[0] * t, p[1] + u[1] * t));
            let scan = |to: f64| {
                let n = 20_000;
                (1..=n)
                    .map(|k| to * k as f64 / n as f64)
                    .find(|&t| g(t) < 0.0)
            };
            match f.hit(p, u, t_max, side) {
                Some(t) => {
                    found += 1;
                    assert!(t <= t_max && g(t) >= -1e-12, "t {t} g {}", g(t));
                    assert!(g(t + 1e-8) < 0.0 || g(t).abs() < 1e-9, "not at the surface");
                    if let Some(ts) = scan(t) {
                        assert!(ts >= t - 1e-9, "crossing at {ts} before {t}");
                    }
                }
                None => {
                    none += 1;
                    assert_eq!(scan(t_max), None, "missed a crossing");
                }
            }
        }
        assert!(found > 300 && none > 300, "{found} {none}");
    }

    /// Leaving the surface with the slope given: the same crossing as a search that evaluates
    /// its start, after a transmission at a random point.
    #[test]
    fn a_known_leaving_slope_finds_the_same_crossing() {
        use rand_core::Rng;
        let f = field();
        let mut rng = crate::math::rng::batch_rng(12, 0);
        let mut u01 = || crate::math::rng::uniform(rng.next_u64());
        let mut compared = 0;
        for _ in 0..3000 {
            let (x, y) = (u01() * 0.1, u01() * 0.1);
            let n = f.normal(x, y);
            let cz = 2.0 * u01() - 1.0;
            let ph = 2.0 * std::f64::consts::PI * u01();
            let st = (1.0 - cz * cz).sqrt();
            let u = [st * ph.cos(), st * ph.sin(), cz];
            // Leaving to the side the direction points to.
            let side = if u[0] * n[0] + u[1] * n[1] + u[2] * n[2] > 0.0 {
                1.0
            } else {
                -1.0
            };
            let z = f.z(x, y);
            let p = [x + u[0] * 1e-9, y + u[1] * 1e-9, z + u[2] * 1e-9];
            let slope = HeightField::leaving_slope(n, u, side);
            assert!(slope >= 0.0);
            let t_max = 0.3 * u01();
            let plain = f.hit_counted(p, u, t_max, side, 0.0, &mut 0);
            let (mut e_hint, mut e_plain) = (0, 0);
            let hinted = f.hit_counted(p, u, t_max, side, slope, &mut e_hint);
            f.hit_counted(p, u, t_max, side, 0.0, &mut e_plain);
            match (plain, hinted) {
                (Some(a), Some(b)) => assert!((a - b).abs() < 1e-9, "{a} {b}"),
                (None, None) => {}
                other => panic!("{other:?}"),
            }
            assert!(e_hint <= e_plain);
            compared += 1;
        }
        assert_eq!(compared, 3000);
    }

    /// The root finders converge superlinearly, as their comments claim: Newton's method inside
    /// its bracket and the Illinois variant of regula falsi each need a handful of evaluations
    /// to reach the 10⁻¹⁰ mm tolerance. A guard that falls back to bisection on every step, or a
    /// halving applied to the wrong end (plain regula falsi stalls), still finds the root but
    /// costs several times the evaluations, which the photon allocation pays for.
    #[test]
    fn root_finders_converge_in_few_evaluations() {
        // Newton from a bracket [0, 2] on g = 0.7 − t − 0.3·sin 2t (root ≈ 0.4466, found by
        // bisection here): |g″| ≤ 1.2 bounds the curvature, the slope is known at t = 0.
        let evals = std::cell::Cell::new(0u32);
        let g_and_slope = |t: f64| {
            evals.set(evals.get() + 1);
            (
                0.7 - t - 0.3 * (2.0 * t).sin(),
                -1.0 - 0.6 * (2.0 * t).cos(),
            )
        };
        let (mut a, mut b) = (0.0f64, 2.0f64);
        while b - a > 1e-14 {
            let m = 0.5 * (a + b);
            if g_and_slope(m).0 >= 0.0 {
                a = m
            } else {
                b = m
            }
        }
        evals.set(0);
        let root = a;
        let t = polish(
            &g_and_slope,
            &Bounds::new(1.2),
            0.0,
            (0.7, -1.6),
            (0.0, 2.0),
        );
        assert!(
            (t - root).abs() <= 2.0 * ROOT_TOL_MM && t <= root + 1e-14,
            "{t} {root}"
        );
        let newton = evals.get();
        // Illinois on a curved g whose plain regula falsi keeps one end fixed for many steps.
        evals.set(0);
        let g = |t: f64| {
            evals.set(evals.get() + 1);
            (1.0 - t).powi(3) - 0.1
        };
        let root = 1.0 - 0.1f64.cbrt();
        let t = refine(&g, (0.0, g(0.0)), (2.0, g(2.0)));
        let illinois = evals.get() - 2;
        assert!(
            (t - root).abs() <= 2.0 * ROOT_TOL_MM && t <= root,
            "{t} {root}"
        );
        assert!(newton <= 4, "Newton took {newton} evaluations (3 expected)");
        assert!(
            illinois <= 12,
            "Illinois took {illinois} evaluations (10 expected)"
        );
    }

    #[test]
    fn normal_is_perpendicular_to_the_surface() {
        let f = field();
        let (x, y, h) = (0.017, -0.009, 1e-6);
        let n = f.normal(x, y);
        let tx = [2.0 * h, 0.0, f.z(x + h, y) - f.z(x - h, y)];
        let ty = [0.0, 2.0 * h, f.z(x, y + h) - f.z(x, y - h)];
        for t in [tx, ty] {
            let dot = n[0] * t[0] + n[1] * t[1] + n[2] * t[2];
            assert!(dot.abs() < 1e-9 * h.max(1.0), "{dot}");
        }
    }
}
