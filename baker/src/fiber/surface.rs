//! The rough dielectric boundary of a fiber (§5.3.1, "Surface roughness"): a Beckmann
//! microfacet distribution of V-cavities [^heitz14] whose facets reflect or refract by
//! unpolarised Fresnel. Roughness is nanometric, so the boundary is a surface event, not a
//! volume.
//!
//! β = arctan(Ra/l) is the thesis's "average normal orientation" (Table 9). We read it as
//! the Beckmann slope parameter: α = tan β = Ra/l, the RMS slope of the facets (Beckmann &
//! Spizzichino 1963), so β = 0 is a smooth boundary.
//!
//! The photon is traced through the V-cavity explicitly: the facet it meets is drawn from the
//! visible-normal distribution of the V-cavity model (exact for V-cavities [^heitz14b]), the
//! Fresnel term picks reflection or refraction, and a reflected ray that the cavity masks
//! (probability 1 − G1) meets the cavity's other facet, and so on until it leaves. No energy
//! is lost at the boundary: with no absorption the fiber's albedo is 1.
//!
//! [^heitz14]: E. Heitz, "Understanding the masking-shadowing function in microfacet-based
//!     BRDFs", JCGT 3(2), 2014 (V-cavity masking, Eq. 5.4 there).
//! [^heitz14b]: E. Heitz, E. d'Eon, "Importance sampling microfacet-based BSDFs using the
//!     distribution of visible normals", EGSR 2014, §5 (V-cavity sampling).

use crate::math::avx2::avx2_dispatch;
use crate::math::exp::exp_neg_f32;
use crate::math::fresnel;
use crate::math::turns::sin_cos_turns;

/// Largest number of facet events inside one V-cavity before falling back to the mean
/// surface (only reached at extreme grazing angles; counted in [`SurfaceStats`]).
const MAX_CAVITY_BOUNCES: usize = 8;

/// A rough (or smooth) dielectric boundary.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Surface {
    /// Index of the fiber (outside is air, 1.0).
    pub eta: f64,
    /// Beckmann RMS slope α = tan β (0: smooth).
    pub alpha: f64,
}

/// Result of one boundary event.
#[derive(Debug, Clone, Copy)]
pub struct Scatter {
    pub dir: [f64; 3],
    /// True when the photon crossed the boundary.
    pub transmitted: bool,
    /// True when the V-cavity walk hit its bounce limit and the mean surface was used.
    pub fallback: bool,
    /// True when the photon left the cavity at the first facet it met (no masking bounce):
    /// the outcome [`Surface::first_facet_pdf`] describes when it leaves the boundary on the
    /// side it came from (reflection from outside) or crosses it (transmission from inside).
    pub first_facet: bool,
}

#[inline]
pub(crate) fn dot(a: [f64; 3], b: [f64; 3]) -> f64 {
    a[0] * b[0] + a[1] * b[1] + a[2] * b[2]
}

#[inline]
fn axpy(a: f64, x: [f64; 3], y: [f64; 3]) -> [f64; 3] {
    [a * x[0] + y[0], a * x[1] + y[1], a * x[2] + y[2]]
}

#[inline]
pub(crate) fn normalize(v: [f64; 3]) -> [f64; 3] {
    let k = 1.0 / dot(v, v).sqrt();
    [v[0] * k, v[1] * k, v[2] * k]
}

/// Orthonormal basis around unit `n` (Duff et al., JCGT 6(1), 2017).
#[inline]
pub(crate) fn basis(n: [f64; 3]) -> ([f64; 3], [f64; 3]) {
    let s = 1.0f64.copysign(n[2]);
    let a = -1.0 / (s + n[2]);
    let b = n[0] * n[1] * a;
    (
        [1.0 + s * n[0] * n[0] * a, s * b, -s * n[0]],
        [b, s + n[1] * n[1] * a, -n[1]],
    )
}

impl Surface {
    /// A photon travelling along `d` meets the boundary whose mean normal `nf` faces it
    /// (d·nf < 0); `inside` says it travels in the fiber. `u` gives uniform numbers in (0, 1).
    #[inline]
    pub fn scatter(
        &self,
        d: [f64; 3],
        nf: [f64; 3],
        inside: bool,
        u: impl FnMut() -> f64,
    ) -> Scatter {
        self.crossing(d, nf, inside).scatter(u)
    }

    /// The constants of one boundary event, for drawing it many times
    /// ([`Crossing::scatter`]; a split event of the tracer draws it `split` or `exit_draws`
    /// times).
    #[inline]
    pub fn crossing(&self, d: [f64; 3], nf: [f64; 3], inside: bool) -> Crossing {
        let (n1, n2) = if inside {
            (self.eta, 1.0)
        } else {
            (1.0, self.eta)
        };
        let (t, b) = basis(nf);
        Crossing {
            alpha: self.alpha,
            d,
            nf,
            t,
            b,
            n1,
            n2,
            e: n1 / n2,
        }
    }

    /// Density per steradian of leaving a rough boundary in direction `wo` at the first facet
    /// met ([`Scatter::first_facet`]), for a photon travelling along `d` onto the mean normal
    /// `nf` that faces it: from inside, refraction out through the facet; from outside,
    /// reflection that the V-cavity does not mask. Zero for a smooth boundary (a delta) and for
    /// `wo` on the wrong side. This is the sampling process of [`Surface::scatter`] written as
    /// a density (Walter et al. 2007, Eqs. 14–17 for the half-vector Jacobians):
    ///
    /// p(wo) = p_vis(m)·(1 − F(wi·m))·|wo·m|/|η wi + wo|²   (inside, m ∝ η wi + wo)
    /// p(wo) = p_vis(m)·F(wi·m)·G1(wo, m)/(4|wo·m|)        (outside, m ∝ wi + wo)
    ///
    /// with wi = −d and the V-cavity's visible-normal density (Heitz & d'Eon 2014 §5) of the
    /// facet the sampler picks: m from D(m)(m·n), then m or its mirror m′ in
    /// proportion to ⟨wi·m⟩ and ⟨wi·m′⟩, so p_vis(m) = 2 D(m)(m·n)⟨wi·m⟩/(⟨wi·m⟩ + ⟨wi·m′⟩).
    #[inline]
    pub fn first_facet_pdf(&self, d: [f64; 3], nf: [f64; 3], inside: bool, wo: [f64; 3]) -> f64 {
        if self.alpha == 0.0 {
            return 0.0;
        }
        FacetPdf::new(self, d, nf, inside).eval(wo)
    }

    /// Density per steradian of entering a rough boundary in direction `wo` through the first
    /// facet met ([`Scatter::first_facet`] and transmitted), for a photon from the air
    /// travelling along `d` onto the mean normal `nf` that faces it: the sampling process of
    /// [`Surface::scatter`] restricted to that outcome, in double precision (the shared-entry
    /// estimator's multiple-importance weights, [`crate::fiber::tracer::shared`]):
    ///
    /// p(wo) = p_vis(m)·(1 − F(wi·m))·η²|wo·m|/|wi + η wo|²   (m ∝ −(wi + η wo))
    ///
    /// (Walter et al. 2007, Eqs. 16–17, with n1 = 1 and n2 = η), p_vis the V-cavity's
    /// visible-normal density of [`Surface::first_facet_pdf`], and zero unless wo goes below the
    /// mean surface (wo·nf < 0: the sampler follows a facet's refraction that does not into the
    /// cavity's other facet). Zero for a smooth boundary (a delta).
    pub fn entry_density(&self, d: [f64; 3], nf: [f64; 3], wo: [f64; 3]) -> f64 {
        let wi = [-d[0], -d[1], -d[2]];
        if self.alpha == 0.0 || dot(wo, nf) >= 0.0 {
            return 0.0;
        }
        let h = axpy(self.eta, wo, wi);
        let h2 = dot(h, h);
        if h2.is_nan() || h2 <= 0.0 {
            return 0.0;
        }
        let inv = 1.0 / h2.sqrt();
        // The facet normal on the side of wi (η > 1 turns wi + η wo away from it).
        let m = [-h[0] * inv, -h[1] * inv, -h[2] * inv];
        let (cos_m, a, wom) = (dot(m, nf), dot(wi, m), dot(wo, m));
        if cos_m <= 0.0 || a <= 0.0 || wom >= 0.0 {
            return 0.0;
        }
        let a2 = (2.0 * cos_m * dot(wi, nf) - a).max(0.0);
        let c2 = cos_m * cos_m;
        let alpha2 = self.alpha * self.alpha;
        let d_m = (-(1.0 - c2) / c2 / alpha2).exp() / (std::f64::consts::PI * alpha2 * c2 * c2);
        let p_vis = 2.0 * d_m * cos_m * a / (a + a2);
        let t = 1.0 - fresnel::dielectric(1.0, self.eta, a).0;
        p_vis * t * self.eta * self.eta * (-wom) / h2
    }
}

/// One boundary event's constants ([`Surface::crossing`]): the photon's direction, the mean
/// normal facing it and its basis, the indices on either side and their ratio. Each
/// [`Crossing::scatter`] is one independent draw of the event, the same operations as a fresh
/// [`Surface::scatter`], so results do not depend on how often the event is drawn.
#[derive(Debug, Clone, Copy)]
pub struct Crossing {
    alpha: f64,
    d: [f64; 3],
    nf: [f64; 3],
    /// Tangent and bitangent of `nf` ([`basis`]).
    t: [f64; 3],
    b: [f64; 3],
    /// From index n1 into n2, e = n1/n2.
    n1: f64,
    n2: f64,
    e: f64,
}

impl Crossing {
    /// One draw of the event: the V-cavity walk of [`Surface`]'s module docs. `u` gives
    /// uniform numbers in (0, 1).
    #[inline]
    pub fn scatter(&self, mut u: impl FnMut() -> f64) -> Scatter {
        let (d, nf) = (self.d, self.nf);
        if self.alpha == 0.0 {
            return self.facet(d, nf, u());
        }
        let wi = [-d[0], -d[1], -d[2]];
        let mut m = self.sample_visible(wi, &mut u);
        let mut wi = wi;
        for bounce in 0..MAX_CAVITY_BOUNCES {
            let mut s = self.facet([-wi[0], -wi[1], -wi[2]], m, u());
            s.first_facet = bounce == 0;
            if s.transmitted {
                if dot(s.dir, nf) < 0.0 {
                    return s;
                }
            } else if dot(s.dir, nf) > 0.0 && g1_passes(s.dir, m, nf, u()) {
                return s;
            }
            // Masked: the ray meets the cavity's other facet, the mirror of m about nf.
            let m2 = axpy(2.0 * dot(m, nf), nf, [-m[0], -m[1], -m[2]]);
            let next_wi = [-s.dir[0], -s.dir[1], -s.dir[2]];
            if s.transmitted || dot(next_wi, m2) <= 0.0 {
                break;
            }
            m = m2;
            wi = next_wi;
        }
        let mut s = self.facet(d, nf, u());
        s.fallback = true;
        s.first_facet = false;
        s
    }

    /// A facet normal of the V-cavity distribution visible from `wi` (Heitz & d'Eon 2014 §5):
    /// m from D(m)(m·n), then m or its mirror m′ with probabilities ∝ ⟨wi·m⟩, ⟨wi·m′⟩.
    #[inline]
    fn sample_visible(&self, wi: [f64; 3], u: &mut impl FnMut() -> f64) -> [f64; 3] {
        let (n, t, b) = (self.nf, self.t, self.b);
        let (cos_t, sin_t, (sp, cp)) = sample_beckmann(self.alpha, u(), u());
        let m = [
            sin_t * cp * t[0] + sin_t * sp * b[0] + cos_t * n[0],
            sin_t * cp * t[1] + sin_t * sp * b[1] + cos_t * n[1],
            sin_t * cp * t[2] + sin_t * sp * b[2] + cos_t * n[2],
        ];
        let m2 = axpy(2.0 * cos_t, n, [-m[0], -m[1], -m[2]]);
        let a = dot(wi, m).max(0.0);
        let a2 = dot(wi, m2).max(0.0);
        // A select, not a branch: the choice is a coin toss for a slightly rough surface.
        let pick = u() * (a + a2) < a2;
        [0, 1, 2].map(|i| select(pick, m2[i], m[i]))
    }

    /// Reflection or refraction of direction `d` at a smooth facet with normal `m` facing it
    /// (d·m < 0), chosen by the unpolarised Fresnel reflectance with the uniform number `u`.
    #[inline]
    fn facet(&self, d: [f64; 3], m: [f64; 3], u: f64) -> Scatter {
        let cos_i = -dot(d, m);
        let (reflected, cos_t) = fresnel::reflects(self.n1, self.n2, cos_i, u);
        let transmitted = !reflected;
        Scatter {
            dir: if transmitted {
                refract(d, m, self.e, cos_i, cos_t)
            } else {
                reflect(d, m, cos_i)
            },
            transmitted,
            fallback: false,
            first_facet: true,
        }
    }
}

/// [`Surface::first_facet_pdf`] of one boundary event, for many outgoing directions: the
/// event's constants once, then a density per direction without branches (each condition a
/// select, the exponential [`exp_neg_f32`]), so [`FacetPdf::eval_many`] vectorises.
///
/// In single precision: the densities are Monte Carlo integrands of the exit lobes
/// ([`crate::fiber::lobe`]), whose noise (percents) is orders above what f32 changes (within
/// 3·10⁻⁴ relative plus 10⁻⁶ sr⁻¹ of the double-precision formula, tested; a window's mass
/// moves by less than 10⁻⁴ of itself), and f32 lanes are twice as many per vector register as
/// f64 lanes, with faster divisions and square roots.
#[derive(Debug, Clone, Copy)]
pub struct FacetPdf {
    /// wi = −d, the mean normal facing the photon, and wi·nf.
    wi: [f32; 3],
    nf: [f32; 3],
    win: f32,
    eta: f32,
    /// 1/α² and 1/(π α²) of the Beckmann distribution D(m).
    inv_alpha2: f32,
    inv_pi_alpha2: f32,
    inside: bool,
}

#[inline(always)]
fn dot32(a: [f32; 3], b: [f32; 3]) -> f32 {
    a[0] * b[0] + a[1] * b[1] + a[2] * b[2]
}

#[inline(always)]
fn f32s(v: [f64; 3]) -> [f32; 3] {
    [v[0] as f32, v[1] as f32, v[2] as f32]
}

impl FacetPdf {
    /// The event of a photon travelling along `d` onto the mean normal `nf` facing it, on a
    /// rough surface (α > 0).
    pub fn new(s: &Surface, d: [f64; 3], nf: [f64; 3], inside: bool) -> Self {
        let wi = [-d[0], -d[1], -d[2]];
        let alpha2 = s.alpha * s.alpha;
        Self {
            wi: f32s(wi),
            nf: f32s(nf),
            win: dot(wi, nf) as f32,
            eta: s.eta as f32,
            inv_alpha2: (1.0 / alpha2) as f32,
            inv_pi_alpha2: (1.0 / (std::f64::consts::PI * alpha2)) as f32,
            inside,
        }
    }

    /// The density at the unit direction `wo` (the value [`FacetPdf::eval_many`] gives there).
    #[inline(always)]
    pub fn eval(&self, wo: [f64; 3]) -> f64 {
        let wo = f32s(wo);
        f64::from(if self.inside {
            self.eval_inside(wo)
        } else {
            self.eval_outside(wo)
        })
    }

    avx2_dispatch! {
        /// `out[i]` = the density at (`x[i]`, `y[i]`, `z[i]`) where `mask[i]` is set, else 0,
        /// for i below `out.len()`: bit for bit the values of [`FacetPdf::eval`], in one pass
        /// the compiler vectorises (8 lanes where the processor has AVX2: the same IEEE
        /// operations lane by lane, no fused multiply-add, so the same bits on every x86-64
        /// machine).
        pub fn eval_many(
            &self as FacetPdf,
            x: &[f32],
            y: &[f32],
            z: &[f32],
            mask: &[bool],
            out: &mut [f32],
        ) => FacetPdf::eval_many_lanes
    }

    #[inline(always)]
    fn eval_many_lanes(&self, x: &[f32], y: &[f32], z: &[f32], mask: &[bool], out: &mut [f32]) {
        let n = out.len();
        let (x, y, z, mask) = (&x[..n], &y[..n], &z[..n], &mask[..n]);
        if self.inside {
            for i in 0..n {
                let p = self.eval_inside([x[i], y[i], z[i]]);
                out[i] = if mask[i] { p } else { 0.0 };
            }
        } else {
            for i in 0..n {
                let p = self.eval_outside([x[i], y[i], z[i]]);
                out[i] = if mask[i] { p } else { 0.0 };
            }
        }
    }

    /// The visible-normal density p_vis(m) of the facet m ∝ `h` and the cosines the Fresnel
    /// and Jacobian factors need: (p_vis, wi·m, wo·m, n·m, 1/|h|), p_vis = 0 (or NaN, which
    /// the callers' `p_vis > 0` test also rejects) where m faces away from the mean normal or
    /// from wi.
    #[inline(always)]
    fn visible(&self, h: [f32; 3], wo: [f32; 3]) -> (f32, f32, f32, f32, f32) {
        let h2 = dot32(h, h);
        let inv = 1.0 / h2.sqrt();
        let m = [h[0] * inv, h[1] * inv, h[2] * inv];
        let cos_m = dot32(m, self.nf);
        let a = dot32(self.wi, m);
        let wom = dot32(wo, m);
        let a2 = (2.0 * cos_m * self.win - a).max(0.0);
        let c2 = cos_m * cos_m;
        let inv_c2 = 1.0 / c2;
        // D(m) = exp(−tan²θm/α²)/(π α² cos⁴θm), tan²θm = (1 − cos²θm)/cos²θm.
        let d_m = exp_neg_f32(-(1.0 - c2) * inv_c2 * self.inv_alpha2)
            * self.inv_pi_alpha2
            * inv_c2
            * inv_c2;
        let p_vis = 2.0 * d_m * cos_m * a / (a + a2);
        let ok = h2 > 0.0 && cos_m > 0.0 && a > 0.0;
        (if ok { p_vis } else { 0.0 }, a, wom, cos_m, inv)
    }

    /// From inside: refraction out, m ∝ η wi + wo (Walter et al. 2007, Eq. 16–17).
    #[inline(always)]
    fn eval_inside(&self, wo: [f32; 3]) -> f32 {
        let won = dot32(wo, self.nf);
        let h = [
            self.eta * self.wi[0] + wo[0],
            self.eta * self.wi[1] + wo[1],
            self.eta * self.wi[2] + wo[2],
        ];
        let (p_vis, a, wom, _, inv) = self.visible(h, wo);
        // Fresnel from the fiber (η) into air, total internal reflection included.
        let r = fresnel::reflectance_branch_free(self.eta, 1.0, a);
        let p = p_vis * (1.0 - r) * (-wom) * inv * inv;
        if won < 0.0 && wom < 0.0 && p_vis > 0.0 {
            p
        } else {
            0.0
        }
    }

    /// From outside: reflection the V-cavity does not mask, m ∝ wi + wo (Eq. 14–15).
    #[inline(always)]
    fn eval_outside(&self, wo: [f32; 3]) -> f32 {
        let won = dot32(wo, self.nf);
        let h = [self.wi[0] + wo[0], self.wi[1] + wo[1], self.wi[2] + wo[2]];
        let (p_vis, a, wom, cos_m, _) = self.visible(h, wo);
        // Fresnel from air into the fiber.
        let r = fresnel::reflectance_branch_free(1.0, self.eta, a);
        // V-cavity G1(wo, m) (Heitz 2014, Eq. 5.4 there), [`g1_vcavity`] without its branch.
        let g1 = (2.0 * cos_m * won / wom).min(1.0);
        let p = p_vis * r * g1 / (4.0 * wom);
        if won > 0.0 && wom > 0.0 && p_vis > 0.0 {
            p
        } else {
            0.0
        }
    }
}

/// A Beckmann facet normal with pdf D(m)(m·n) dω: tan²θm = −α² ln u1 (the slopes are
/// Gaussian, so tan²θm is exponential with mean α²; Walter et al. 2007, Eq. 28), φm = 2π u2.
/// Returns (cos θm, sin θm, (sin φm, cos φm)), the azimuth's by [`sin_cos_turns`] (every
/// boundary draw takes one). sin θm = tan θm·cos θm: its square root runs beside cos θm's
/// instead of after it, and keeps its relative accuracy near the normal, where √(1 − cos²θm)
/// cancels. Its density over θm is [`beckmann_pdf_theta`].
#[inline]
pub fn sample_beckmann(alpha: f64, u1: f64, u2: f64) -> (f64, f64, (f64, f64)) {
    let tan2 = -alpha * alpha * u1.ln();
    let cos_t = 1.0 / (1.0 + tan2).sqrt();
    (cos_t, tan2.sqrt() * cos_t, sin_cos_turns(u2))
}

/// Density over θm of [`sample_beckmann`]'s normals, D(m) cos θm sin θm · 2π with the
/// Beckmann distribution D(m) = exp(−tan²θm/α²)/(π α² cos⁴θm) (Walter et al. 2007, Eq. 25).
pub fn beckmann_pdf_theta(alpha: f64, theta_m: f64) -> f64 {
    let (s, c) = theta_m.sin_cos();
    if c <= 0.0 {
        return 0.0;
    }
    let t2 = (s / c) * (s / c);
    let d = (-t2 / (alpha * alpha)).exp() / (std::f64::consts::PI * alpha * alpha * c.powi(4));
    d * c * s * std::f64::consts::TAU
}

/// V-cavity masking G1(w, m) = min(1, 2 (n·m)(n·w)/(w·m)) (Heitz 2014, Eq. 5.4 there).
#[inline]
pub fn g1_vcavity(w: [f64; 3], m: [f64; 3], n: [f64; 3]) -> f64 {
    let wm = dot(w, m);
    let wn = dot(w, n);
    if wm <= 0.0 || wn <= 0.0 {
        return 0.0;
    }
    (2.0 * dot(n, m) * wn / wm).min(1.0)
}

/// Whether a uniform number `u` in [0, 1) passes the V-cavity's masking, u < G1(w, m):
/// u·(w·m) < 2 (n·m)(n·w) where w·m and n·w are positive ([`g1_vcavity`] without its
/// division; u < 1 makes its min(1, ·) irrelevant).
#[inline]
fn g1_passes(w: [f64; 3], m: [f64; 3], n: [f64; 3], u: f64) -> bool {
    let wm = dot(w, m);
    let wn = dot(w, n);
    wm > 0.0 && wn > 0.0 && u * wm < 2.0 * dot(n, m) * wn
}

/// `b` where `pick`, else `a`, as a bitwise blend (no branch to mispredict).
#[inline(always)]
fn select(pick: bool, b: f64, a: f64) -> f64 {
    let mask = (pick as u64).wrapping_neg();
    f64::from_bits((b.to_bits() & mask) | (a.to_bits() & !mask))
}

/// Direction `d` mirrored at a facet with normal `m` facing it, cos θi = `cos_i` = −d·m.
#[inline]
pub(crate) fn reflect(d: [f64; 3], m: [f64; 3], cos_i: f64) -> [f64; 3] {
    axpy(2.0 * cos_i, m, d)
}

/// Direction `d` refracted through a facet with normal `m` facing it, relative index
/// `e` = n1/n2, cos θi = `cos_i`, cos θt = `cos_t` (from [`fresnel::dielectric`]): Snell in
/// vector form, renormalised against rounding (a Newton step: d and m must be unit vectors).
#[inline]
pub(crate) fn refract(d: [f64; 3], m: [f64; 3], e: f64, cos_i: f64, cos_t: f64) -> [f64; 3] {
    let v = [
        e * d[0] + (e * cos_i - cos_t) * m[0],
        e * d[1] + (e * cos_i - cos_t) * m[1],
        e * d[2] + (e * cos_i - cos_t) * m[2],
    ];
    // |v|² = 1 + ε with ε of a few ulps for unit d and m: one Newton step for 1/√x from 1,
    // (3 − x)/2, leaves 3ε²/8 (far below an ulp) and needs neither a square root nor a division.
    let k = 0.5 * (3.0 - dot(v, v));
    [v[0] * k, v[1] * k, v[2] * k]
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::math::rng::{batch_rng, uniform};
    use rand_core::Rng;

    #[test]
    fn smooth_boundary_reflects_and_refracts_by_fresnel() {
        let s = Surface {
            eta: 1.5,
            alpha: 0.0,
        };
        let d = normalize([0.6, 0.0, -0.8]);
        let n = [0.0, 0.0, 1.0];
        let r = s.scatter(d, n, false, || 0.0);
        assert!(!r.transmitted && (r.dir[2] - 0.8).abs() < 1e-12);
        let t = s.scatter(d, n, false, || 0.999_999);
        assert!(t.transmitted);
        // Snell: sin θt = sin θi / η.
        assert!((t.dir[0] - 0.6 / 1.5).abs() < 1e-12);
    }

    /// Issue 22: the Beckmann lobe width. The sampled facet normals follow D(m)(m·n) written
    /// out independently (θm by χ²; φm uniform by χ²), at two roughnesses, so α² → α or a lost
    /// square root in the sampler fails here.
    #[test]
    fn beckmann_normals_follow_d_m_cos_theta_m() {
        let mut rng = batch_rng(11, 0);
        for beta_deg in [6.5f64, 15.0] {
            let alpha = beta_deg.to_radians().tan();
            let (mut theta, mut phi) = (Vec::new(), Vec::new());
            for _ in 0..200_000 {
                let (c, _, (sp, cp)) =
                    sample_beckmann(alpha, uniform(rng.next_u64()), uniform(rng.next_u64()));
                theta.push(c.acos());
                phi.push(sp.atan2(cp).rem_euclid(std::f64::consts::TAU));
            }
            let hi = (alpha * 5.0).atan();
            crate::stats::chi2::chi2_test_1d(
                &theta,
                0.0,
                hi,
                41,
                |t| beckmann_pdf_theta(alpha, t),
                &format!("beckmann_theta_{beta_deg}"),
            );
            crate::stats::chi2::chi2_test_1d(
                &phi,
                0.0,
                std::f64::consts::TAU,
                37,
                |_| 1.0 / std::f64::consts::TAU,
                &format!("beckmann_phi_{beta_deg}"),
            );
            // The mean of tan²θm is α² (the second moment of the slopes).
            let m = theta.iter().map(|t| t.tan().powi(2)).sum::<f64>() / theta.len() as f64;
            assert!(
                (m / (alpha * alpha) - 1.0).abs() < 0.02,
                "E[tan²θm] = {m} vs α² = {}",
                alpha * alpha
            );
        }
    }

    /// Issue 22: the rough boundary's reflected and transmitted lobes against Mitsuba 3's
    /// `roughdielectric` (Beckmann, same α, η = 1.55), integrated over 40 z × 18 φ bins in
    /// `tests/surfaces/rough_dielectric_beckmann.csv` (provenance in that folder's README). Our
    /// V-cavity walk and Mitsuba's single-scattering Smith model differ where masking or a
    /// second facet event matters (grazing incidence, rougher surfaces:
    /// `validation/check_rough_interface.py` measures from which sample count); these six
    /// cases agree below what 200,000 samples can detect, and still catch a 5 % error in α.
    #[test]
    fn rough_lobes_match_mitsuba_roughdielectric() {
        let text = std::fs::read_to_string(
            std::path::Path::new(env!("CARGO_MANIFEST_DIR"))
                .join("../tests/surfaces/rough_dielectric_beckmann.csv"),
        )
        .unwrap();
        let cases = [
            (6.5f64, false, 0.0f64),
            (6.5, false, 30.0),
            (6.5, true, 0.0),
            (6.5, true, 30.0),
            (15.0, false, 0.0),
            (15.0, true, 0.0),
        ];
        let (nz, nphi) = (40usize, 18usize);
        let mut rng = batch_rng(21, 0);
        for (beta_deg, inside, theta_deg) in cases {
            let alpha = beta_deg.to_radians().tan();
            let side = if inside { "inside" } else { "outside" };
            let mut p = vec![0.0; nz * nphi];
            let mut loss = 0.0;
            for line in text.lines().filter(|l| !l.starts_with('#')) {
                let f: Vec<&str> = line.split(',').collect();
                let a: f64 = f[0].parse().unwrap();
                if (a - alpha).abs() > 1e-12
                    || f[2] != side
                    || f[3].parse::<f64>().unwrap() != theta_deg
                {
                    continue;
                }
                let (iz, ip): (i64, i64) = (f[4].parse().unwrap(), f[5].parse().unwrap());
                let v: f64 = f[6].parse().unwrap();
                if iz < 0 {
                    loss = v;
                } else {
                    p[iz as usize * nphi + ip as usize] = v;
                }
            }
            assert!(
                p.iter().sum::<f64>() > 0.99,
                "fixture rows for β {beta_deg} {side} {theta_deg}"
            );
            let s = Surface { eta: 1.55, alpha };
            let n = 200_000usize;
            let th = theta_deg.to_radians();
            let d = [th.sin(), 0.0, -th.cos()];
            let mut observed = vec![0.0; nz * nphi];
            let mut u = || uniform(rng.next_u64());
            for _ in 0..n {
                let w = s.scatter(d, [0.0, 0.0, 1.0], inside, &mut u).dir;
                let iz = (((w[2] + 1.0) / 0.05) as usize).min(nz - 1);
                let ip = ((w[1].abs().atan2(w[0]) / 10f64.to_radians()) as usize).min(nphi - 1);
                observed[iz * nphi + ip] += 1.0;
            }
            // Mitsuba's lobe renormalised by what its single-scattering model loses (≤ 2e-5 here).
            assert!(loss.abs() < 1e-4, "loss {loss}");
            let expected: Vec<f64> = p.iter().map(|x| x * n as f64 / (1.0 - loss)).collect();
            let labels: Vec<f64> = (0..nz * nphi).map(|b| b as f64).collect();
            crate::stats::chi2::chi2_test_bins(
                &observed,
                &expected,
                &labels,
                &format!("mitsuba_roughdielectric_{beta_deg}_{side}_{theta_deg}"),
            );
        }
    }

    #[test]
    fn rough_boundary_conserves_photons_and_respects_sides() {
        let s = Surface {
            eta: 1.55,
            alpha: (15f64).to_radians().tan(),
        };
        let mut rng = batch_rng(3, 0);
        let mut u = || uniform(rng.next_u64());
        let n = [0.0, 0.0, 1.0];
        let mut fallbacks = 0;
        for k in 0..20_000 {
            let th = (k % 89) as f64 * std::f64::consts::PI / 180.0;
            for inside in [false, true] {
                let nf = if inside { [0.0, 0.0, -1.0] } else { n };
                let d = [th.sin(), 0.0, -th.cos() * nf[2]];
                let r = s.scatter(d, nf, inside, &mut u);
                fallbacks += r.fallback as usize;
                let side = dot(r.dir, nf);
                assert!(if r.transmitted {
                    side < 0.0
                } else {
                    side > 0.0
                });
                assert!((dot(r.dir, r.dir) - 1.0).abs() < 1e-12);
            }
        }
        // Fallbacks happen only near grazing incidence (up to 88° here).
        assert!(fallbacks < 200, "{fallbacks} fallbacks in 40000 events");
    }

    /// [`Surface::entry_density`] is the density of the sampler's first-facet entries: the
    /// entries of 200,000 events per case, binned over the lower hemisphere (0.5° in the angle
    /// from −n × 15° in azimuth), against the density integrated over each cell (8 × 8
    /// midpoints), for β = 6.5° and 15° at 0°, 40° and 75° incidence; and the entries' share
    /// against the density's integral. Planted: a Jacobian without η² fails every case.
    #[test]
    fn entry_density_is_the_first_facet_entry_density() {
        let mut rng = batch_rng(21, 0);
        let mut u = || uniform(rng.next_u64());
        let nf = [0.0, 0.0, 1.0];
        let (nm, np, sub) = (180usize, 24usize, 8usize);
        for beta in [6.5f64, 15.0] {
            let s = Surface {
                eta: 1.55,
                alpha: beta.to_radians().tan(),
            };
            for inc in [0.0f64, 40.0, 75.0] {
                let t = inc.to_radians();
                let d = [t.sin(), 0.0, -t.cos()];
                let n = 200_000usize;
                let mut count = vec![0f64; nm * np];
                let mut entered = 0usize;
                let (dth, dphi) = (
                    std::f64::consts::FRAC_PI_2 / nm as f64,
                    std::f64::consts::TAU / np as f64,
                );
                for _ in 0..n {
                    let r = s.scatter(d, nf, false, &mut u);
                    if r.transmitted && r.first_facet {
                        let th = (-r.dir[2]).clamp(-1.0, 1.0).acos();
                        let phi = r.dir[1].atan2(r.dir[0]).rem_euclid(std::f64::consts::TAU);
                        let i = ((th / dth) as usize).min(nm - 1);
                        let j = ((phi / std::f64::consts::TAU * np as f64) as usize).min(np - 1);
                        count[i * np + j] += 1.0;
                        entered += 1;
                    }
                }
                let mut total = 0.0;
                let (mut chi2, mut dof, mut zmax) = (0.0, 0, 0f64);
                for i in 0..nm {
                    for j in 0..np {
                        let mut mass = 0.0;
                        for a in 0..sub {
                            for b in 0..sub {
                                let th = (i as f64 + (a as f64 + 0.5) / sub as f64) * dth;
                                let phi = (j as f64 + (b as f64 + 0.5) / sub as f64) * dphi;
                                let (st, ct) = th.sin_cos();
                                let wo = [st * phi.cos(), st * phi.sin(), -ct];
                                mass += s.entry_density(d, nf, wo) * st;
                            }
                        }
                        let e = n as f64 * mass * dth * dphi / (sub * sub) as f64;
                        total += e;
                        if e > 50.0 {
                            let z = (count[i * np + j] - e) / e.sqrt();
                            chi2 += z * z;
                            dof += 1;
                            zmax = zmax.max(z.abs());
                        }
                    }
                }
                let z_share = (entered as f64 - total) / total.sqrt();
                assert!(dof > 20, "β {beta} θ {inc}: {dof} cells");
                assert!(
                    zmax < 5.0 && chi2 / (dof as f64) < 1.5 && z_share.abs() < 4.0,
                    "β {beta} θ {inc}: max |z| {zmax:.2}, χ²/dof {:.3} over {dof}, share z {z_share:.2} ({entered} vs {total:.0})",
                    chi2 / dof as f64
                );
            }
        }
    }

    /// The density written out with branches, the library's exp, [`fresnel::dielectric`] and
    /// [`g1_vcavity`] (the formula of [`Surface::first_facet_pdf`]'s documentation, as it was
    /// computed before [`FacetPdf`]).
    fn reference_pdf(s: &Surface, d: [f64; 3], nf: [f64; 3], inside: bool, wo: [f64; 3]) -> f64 {
        let wi = [-d[0], -d[1], -d[2]];
        let won = dot(wo, nf);
        if (inside && won >= 0.0) || (!inside && won <= 0.0) {
            return 0.0;
        }
        let h = axpy(if inside { s.eta } else { 1.0 }, wi, wo);
        let inv = 1.0 / dot(h, h).sqrt();
        let m = [h[0] * inv, h[1] * inv, h[2] * inv];
        let (cos_m, a, wom) = (dot(m, nf), dot(wi, m), dot(wo, m));
        if cos_m <= 0.0 || a <= 0.0 {
            return 0.0;
        }
        let a2 = (2.0 * cos_m * dot(wi, nf) - a).max(0.0);
        let c2 = cos_m * cos_m;
        let alpha2 = s.alpha * s.alpha;
        let d_m = (-(1.0 - c2) / c2 / alpha2).exp() / (std::f64::consts::PI * alpha2 * c2 * c2);
        let p_vis = 2.0 * d_m * cos_m * a / (a + a2);
        if inside {
            if wom >= 0.0 {
                return 0.0;
            }
            p_vis * (1.0 - fresnel::dielectric(s.eta, 1.0, a).0) * (-wom) * inv * inv
        } else {
            if wom <= 0.0 {
                return 0.0;
            }
            p_vis * fresnel::dielectric(1.0, s.eta, a).0 * g1_vcavity(wo, m, nf) / (4.0 * wom)
        }
    }

    /// [`FacetPdf`]: its branch-free single-precision density is the double-precision reference
    /// formula's to 3·10⁻⁴ relative plus 10⁻⁶ sr⁻¹ (zero exactly where the reference is, unless
    /// both are below 10⁻⁶ sr⁻¹; the lobes' peaks are 1–100 sr⁻¹) for directions all around both
    /// sides of the boundary, from inside and outside, through total internal reflection, at
    /// roughnesses down to β = 3.1°, where the tightest lobes amplify f32's rounding of cos θm
    /// most; `eval_many` (vectorised) gives `eval`'s bits, and 0 where a direction is masked.
    #[test]
    fn facet_pdf_is_the_reference_density_in_every_lane() {
        let mut rng = batch_rng(11, 0);
        let mut u = || uniform(rng.next_u64());
        let mut nonzero = 0;
        let mut worst = 0.0f64;
        for (beta, eta) in [(3.1f64, 1.57), (6.5, 1.55), (15.5, 1.53)] {
            let s = Surface {
                eta,
                alpha: beta.to_radians().tan(),
            };
            for inside in [true, false] {
                for _ in 0..40 {
                    let nf = normalize([u() - 0.5, u() - 0.5, 0.3 * (u() - 0.5)]);
                    // A direction onto the boundary (d·nf < 0), grazing ones included.
                    let mut d = normalize([u() - 0.5, u() - 0.5, u() - 0.5]);
                    if dot(d, nf) > 0.0 {
                        d = [-d[0], -d[1], -d[2]];
                    }
                    let pdf = FacetPdf::new(&s, d, nf, inside);
                    let n = 61;
                    let (mut x, mut y, mut z, mut mask) = (vec![], vec![], vec![], vec![]);
                    for i in 0..n {
                        let w = normalize([u() - 0.5, u() - 0.5, u() - 0.5]);
                        let p = pdf.eval(w);
                        let r = reference_pdf(&s, d, nf, inside, w);
                        // f32's rounding of cos θm, amplified by 1/α² in the exponent, leaves
                        // relative errors up to ~10 % in the far tail (densities ~10⁻⁹ sr⁻¹ and
                        // below), so the bound there is absolute.
                        assert!(
                            (p - r).abs() <= 3e-4 * r + 1e-6
                                && ((p == 0.0) == (r == 0.0) || p.max(r) < 1e-6),
                            "β {beta}, inside {inside}: {p} against {r}"
                        );
                        if r > 1e-2 {
                            worst = worst.max((p - r).abs() / r);
                        }
                        nonzero += (p > 0.0) as usize;
                        x.push(w[0]);
                        y.push(w[1]);
                        z.push(w[2]);
                        mask.push(i % 7 != 3);
                    }
                    let mut out = vec![f32::NAN; n];
                    let f32s = |v: &[f64]| v.iter().map(|&a| a as f32).collect::<Vec<_>>();
                    pdf.eval_many(&f32s(&x), &f32s(&y), &f32s(&z), &mask, &mut out);
                    for i in 0..n {
                        let want = if mask[i] {
                            pdf.eval([x[i], y[i], z[i]])
                        } else {
                            0.0
                        };
                        assert_eq!(f64::from(out[i]).to_bits(), want.to_bits(), "lane {i}");
                    }
                }
            }
        }
        eprintln!("worst relative difference from the reference above 0.01 sr⁻¹: {worst:.2e}");
        assert!(nonzero > 500, "only {nonzero} directions with a density");
    }
}
