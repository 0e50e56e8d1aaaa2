//! The non-planar dermo-epidermal junction of thesis Eq. 1 as a height field:
//! J(x, y) = z̄ + A·sin(ωx·x + φx)·sin(ωy·y + φy).
//!
//! Ray intersection marches with a bound on the curvature of the signed vertical distance
//! along the ray, so the first crossing along a segment is never stepped over, then refines
//! by regula falsi.

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

/// Newton steps before the search falls back to the bracketed refinement (they converge
/// quadratically, so this bounds only degenerate cases).
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
    // Round to the nearest quadrant with an integer cast (f64::round is a library call on
    // baseline x86-64), the ±½ by copysign rather than a branch on the sign.
    let q = x * std::f64::consts::FRAC_2_PI;
    let ki = (q + 0.5f64.copysign(q)) as i64;
    let k = ki as f64;
    let r = ((x - k * P1) - k * P2) - k * P3;
    let r2 = r * r;
    // sin r = r − r³/3! + … − r¹⁵/15!,  cos r = 1 − r²/2! + … − r¹⁴/14!
    let s = r
        * (1.0
            + r2 * (-1.0 / 6.0
                + r2 * (1.0 / 120.0
                    + r2 * (-1.0 / 5040.0
                        + r2 * (1.0 / 362_880.0
                            + r2 * (-1.0 / 39_916_800.0
                                + r2 * (1.0 / 6_227_020_800.0
                                    + r2 * (-1.0 / 1_307_674_368_000.0))))))));
    let c = 1.0
        + r2 * (-0.5
            + r2 * (1.0 / 24.0
                + r2 * (-1.0 / 720.0
                    + r2 * (1.0 / 40_320.0
                        + r2 * (-1.0 / 3_628_800.0
                            + r2 * (1.0 / 479_001_600.0 + r2 * (-1.0 / 87_178_291_200.0)))))));
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
        self.hit_counted(p, u, t_max, side, &mut 0)
    }

    /// [`HeightField::hit`], adding to `evals` how many times it evaluated the surface (the
    /// work of the search, deterministic: the photon allocation's cost model counts it).
    #[inline]
    pub fn hit_counted(
        &self,
        p: [f64; 3],
        u: [f64; 3],
        t_max: f64,
        side: f64,
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
        let n = std::cell::Cell::new(0u64);
        let g = |t: f64| {
            n.set(n.get() + 1);
            side * (p[2] + u[2] * t - self.z(p[0] + u[0] * t, p[1] + u[1] * t))
        };
        let g_and_slope = |t: f64| {
            n.set(n.get() + 1);
            let (sx, cx) = sin_cos(self.wx * (p[0] + u[0] * t) + self.px);
            let (sy, cy) = sin_cos(self.wy * (p[1] + u[1] * t) + self.py);
            let j = self.z_mean_mm + self.a * sx * sy;
            let dj = self.a * (wxu * cx * sy + wyu * sx * cy);
            (side * (p[2] + u[2] * t - j), side * (u[2] - dj))
        };
        // Along the ray, with a = ωx·ux and c = ωy·uy, sin(a·t + ·)·sin(c·t + ·) is half the
        // difference of two cosines of frequencies a − c and a + c, so
        // |J″| ≤ A/2·((a − c)² + (a + c)²) = A·(a² + c²).
        let curv = self.a * (wxu * wxu + wyu * wyu);
        // Start marching where the segment enters the slab, if it starts outside it and moves
        // towards it; from inside the slab, march from the start.
        let (top, bottom) = (self.z_mean_mm - self.a, self.z_mean_mm + self.a);
        let mut t = if p[2] < top && u[2] > 0.0 {
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
        if t > t_max {
            return None;
        }
        let mut newton_steps = 0;
        let found = loop {
            // g(t + Δ) ≥ g + g′Δ − curv·Δ²/2: its first positive root is a step that cannot pass
            // the first crossing. Large when moving away, Newton-like when approaching.
            let (gt, slope) = g_and_slope(t);
            let gt = gt.max(0.0);
            let safe = if curv > 1e-300 {
                (slope + (slope * slope + 2.0 * curv * gt).sqrt()) / curv
            } else if slope < 0.0 {
                gt / -slope
            } else {
                f64::INFINITY
            };
            if t + safe >= t_max {
                // The bound keeps g ≥ 0 up to t_max: no crossing (no need to look at the end).
                break None;
            }
            // Approaching steeply (g′² > 2·curv·g): g(t + Δ) ≤ g + g′Δ + curv·Δ²/2 also has a
            // root, so the crossing lies in [t + safe, t + upper]. The steps above are then a
            // safeguarded Newton iteration from the photon's side, converging quadratically:
            // stop once the bracket is below the tolerance.
            let disc = slope * slope - 2.0 * curv * gt;
            if slope < 0.0 && disc >= 0.0 && newton_steps < MAX_NEWTON_STEPS {
                let upper = 2.0 * gt / (disc.sqrt() - slope);
                if t + upper <= t_max {
                    if upper <= ROOT_TOL_MM {
                        break Some(t);
                    }
                    t += safe;
                    newton_steps += 1;
                    continue;
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
