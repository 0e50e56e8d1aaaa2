//! The Chiang et al. 2016 hair model[^chiang16] as Mitsuba 3's `hair` plugin evaluates it,
//! and its fit to a baked fiber BCSDF table (`.bcsdf`, thesis §5.5).
//!
//! # The model
//! The fiber is a rough dielectric cylinder of index η with an absorbing interior. Light that
//! enters at offset h ∈ \[−1, 1\] (h = sin γi across the width) leaves after p internal paths
//! (R, TT, TRT, and a residual for p ≥ 3):
//!
//! S(ωi, ωo; h) = Σ_{p<3} Mp(θi′ₚ, θo)·Ap(θi, h)·Np(Δφ; h) + M₃(θi, θo)·A₃(θi, h)/(2π)
//!
//! - Mp: d'Eon et al.'s[^deon11] longitudinal lobe with the log-Bessel form for small
//!   variance; variances v₀ = (0.726 βm + 0.812 βm² + 3.7 βm²⁰)², v₁ = v₀/4, v₂ = v₃ = 4 v₀
//!   (Chiang Eq. 7).
//! - θi′ₚ: the cuticle tilt α shifts the longitudinal angle by −2α (R), +α (TT), +4α (TRT).
//! - Ap: Fresnel reflectance f at cos θi·cos γi and the transmittance T = exp(−σa·2 cos γt /
//!   cos θt) of one chord (Chiang Eq. 3–6); σa is per unit fiber *radius* (the chord length
//!   2 cos γt is that of a unit-radius circle).
//! - Np: a logistic of scale s = √(π/8)·(0.265 βn + 1.194 βn² + 5.372 βn²²) around
//!   Φ(p, h) = 2p γt − 2γi + pπ, trimmed to \[−π, π\] (Chiang Eq. 8–10).
//!
//! Every formula follows mitsuba3 `src/bsdfs/hair.cpp` (v3.9, `Hair::eval`, `attenuation`,
//! `reframe_with_scales`, `azimuthal_scattering`, `update`) and `include/mitsuba/core/warp.h`
//! (`square_to_rough_fiber_pdf`, its 10-term I₀ series and asymptotic log I₀ above 12, the
//! constant 0.6931), so [`Chiang::eval_local`] returns what Mitsuba's `eval` returns, including
//! its lack of a cosine factor (∫ S dωo = Σ Ap; Mitsuba's `test_hair.py` white furnace).
//! `validation/check_export_hair.py` compares the two at the directions listed by
//! [`test_evaluations`].
//!
//! # Frames
//! Mitsuba's local frame (`hair.cpp`): the fiber tangent is local **y**, the surface normal
//! local **z**; sin θ = ω·y, φ = atan2(ω·z, ω·x) and h = sin γ(wi) with γ the angle between
//! wi's projection on the x–z plane and z, negative for x > 0, so h = −x/√(x² + z²). On a
//! `bsplinecurve` (Mitsuba 3.9) the shading frame's s = ∂p/∂u goes around the fiber and
//! t = ∂p/∂v along it, so local y is the curve direction (first to last control point) and h
//! follows the hit point. The table frame (fiber axis +z, θ = asin(ω·z), φ = atan2(ω·y, ω·x))
//! maps to it by (x, y, z)table = (x, z, y)Mitsuba: same θ, same φ, same Δφ. The model's α
//! sign is Mitsuba's and pbrt-v4's: the R lobe peaks at θi + θo = 2α about that axis.
//!
//! # Far field and the table
//! A table stores f = Λ·f̂: the fraction of the power the fiber intercepts from ωi that
//! leaves per steradian around ωo, averaged over the fiber width. Chiang's model integrates
//! over the width the same way (uniform in h, the projected width): the far-field
//! S̄(ωi, ωo) = ½∫ S(ωi, ωo; h) dh has ∫ S̄ dωo = the albedo, like ∫ f dωo = Λ, so the fit
//! compares S̄ with f directly, bin by bin (no cosine). The table's ωi (towards the light)
//! plays the role of the engine's `wi` (Mitsuba's `si.wi`, pbrt's `wo`: the direction the
//! path arrived from); by the reciprocity of the fiber (cos θi·f(ωi, ωo) = cos θo·f(ωo, ωi))
//! that is exactly the radiance a renderer needs, L(ωo) = ∫ S̄(ωo, ωi) L(ωi) dωi.
//!
//! Chiang's model is rotation invariant: it depends on Δφ only, and S̄ is even in Δφ. A table of
//! a non-round section depends on φi too; the fit is to its average over φi (a fiber seen at
//! every orientation), and so is the error reported.
//!
//! # The fit
//! Parameters: σa per channel, βm, βn, α, and η unless the table's metadata gives it (the
//! spec's mean index, used as is). For every θi of a subsample of the table's rows (default
//! 8, symmetric about 0, |θi| ≤ 80°) and every bin (θo row, Δφ column) the model is integrated
//! exactly over the bin — Δφ through the logistic's CDF, θo by Gauss–Legendre within the row,
//! h by composite Gauss–Legendre in γ — and compared with the table's value averaged over a
//! few φi. The objective is the **relative L1 error of f over the bins**,
//! Σ |S̄ − f|·ΔΩ / Σ f·ΔΩ summed over θi and channels: the fraction of scattered energy the
//! fit puts in the wrong bins (0 = exact; 2 = disjoint). The relative L2 error
//! √(Σ (S̄ − f)²·ΔΩ / Σ f²·ΔΩ) and the albedo of both are reported as well.
//!
//! Each channel's σa is not free: for given shape parameters (η, βm, βn, α) it is the one
//! that gives the model the table's albedo (summed over the sampled θi), found by bisection.
//! The fit so keeps every channel's energy — the fiber's colour — and spends its freedom on
//! the angular distribution; a free L1 fit trades energy for shape where the shapes differ
//! (on the trilobal polyester it would drop 40 % of the red). Where even σa → 0 gives less
//! than the table (a table albedo above the smooth cylinder's), σa is 0. The
//! shape parameters come from Nelder–Mead (Lagarias et al. 1998 coefficients) started from
//! the best of a small grid.
//!
//! [^chiang16]: M. J.-Y. Chiang, B. Bitterli, C. Tappan, B. Burley, "A Practical and
//!   Controllable Hair and Fur Model for Production Path Tracing", Computer Graphics Forum
//!   35(2), 2016.
//! [^deon11]: E. d'Eon, G. Francois, M. Hill, J. Letteri, J.-M. Aubry, "An Energy-Conserving
//!   Hair Reflectance Model", Computer Graphics Forum 30(4), 2011.

// Index loops mirror the formulas (lobes, nodes, bins); iterator chains would hide them.
#![allow(clippy::needless_range_loop)]

use std::f64::consts::{FRAC_PI_2, PI, TAU};

use formats::bcsdf::{direction, solid_angle, Bcsdf};
use formats::table::TableError;
use serde::Serialize;

/// Lobes evaluated explicitly (R, TT, TRT); the rest is the residual term (`hair.cpp` P_MAX).
pub const P_MAX: usize = 3;

/// Lower bound of β_m and β_n in the fit (Mitsuba, pbrt-v4 and Cycles accept \[0, 1\]; below
/// this the lobes are far narrower than any table bin).
pub const BETA_MIN: f64 = 0.02;

/// The model's parameters, in the units of Mitsuba 3's `hair` plugin.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct ChiangParams {
    /// Index of refraction of the fiber relative to the outside (Mitsuba `int_ior / ext_ior`).
    pub eta: f64,
    /// Absorption coefficient per channel, per unit fiber radius (dimensionless μa·r).
    pub sigma_a: Vec<f64>,
    /// Longitudinal roughness β_m ∈ \[0, 1\].
    pub beta_m: f64,
    /// Azimuthal roughness β_n ∈ \[0, 1\].
    pub beta_n: f64,
    /// Cuticle tilt α, degrees (Mitsuba `scale_tilt`, pbrt-v4 `alpha`).
    pub alpha_deg: f64,
}

/// Longitudinal variances v₀…v₃ of β_m (`hair.cpp` `update()`; Chiang Eq. 7).
pub fn longitudinal_variances(beta_m: f64) -> [f64; P_MAX + 1] {
    let v0 = (0.726 * beta_m + 0.812 * beta_m.powi(2) + 3.7 * beta_m.powi(20)).powi(2);
    [v0, 0.25 * v0, 4.0 * v0, 4.0 * v0]
}

/// Logistic scale s of β_n (`hair.cpp` `update()`; Chiang Eq. 8).
pub fn logistic_scale(beta_n: f64) -> f64 {
    (PI / 8.0).sqrt() * (0.265 * beta_n + 1.194 * beta_n.powi(2) + 5.372 * beta_n.powi(22))
}

fn safe_sqrt(x: f64) -> f64 {
    x.max(0.0).sqrt()
}

fn safe_asin(x: f64) -> f64 {
    x.clamp(-1.0, 1.0).asin()
}

/// I₀ by the 10-term series of mitsuba3 `warp.h` (`detail::i0`).
fn bessel_i0(x: f64) -> f64 {
    let (mut result, x2) = (1.0, x * x);
    let (mut xi, mut denom) = (x2, 4.0);
    for i in 1..=10 {
        let factor = (i + 1) as f64;
        result += xi / denom;
        xi *= x2;
        denom *= 4.0 * factor * factor;
    }
    result
}

/// log I₀, asymptotic above 12 (`warp.h` `detail::log_i0`).
fn log_bessel_i0(x: f64) -> f64 {
    if x > 12.0 {
        x + 0.5 * ((1.0 / (TAU * x)).ln() + 1.0 / (8.0 * x))
    } else {
        bessel_i0(x).ln()
    }
}

/// `warp::square_to_rough_fiber_pdf` (d'Eon et al. 2011 with the log form for κ > 10), sr⁻¹:
/// a density on the sphere, so 2π times it is Chiang's Mp. `sin_i`, `sin_o` are the sines of
/// the longitudinal angles (Mitsuba's dot products with the tangent), κ = 1/v.
fn rough_fiber_pdf(sin_i: f64, sin_o: f64, kappa: f64) -> f64 {
    let (cos_i, cos_o) = (
        safe_sqrt(1.0 - sin_i * sin_i),
        safe_sqrt(1.0 - sin_o * sin_o),
    );
    let c = sin_i * sin_o * kappa;
    let s = cos_i * cos_o * kappa;
    if kappa > 10.0 {
        // warp.h: exp(−c + log I₀(s) − κ + 0.6931 + log(κ/2)) / 2π; its 0.6931 (≈ ln 2) is
        // kept so the values are Mitsuba's to the last digit it has.
        #[allow(clippy::approx_constant)]
        let ln2 = 0.6931;
        (-c + log_bessel_i0(s) - kappa + ln2 + (kappa / 2.0).ln()).exp() / TAU
    } else {
        (-c).exp() * bessel_i0(s) * kappa / (2.0 * kappa.sinh()) / TAU
    }
}

/// Unpolarised Fresnel reflectance of a dielectric (mitsuba3 `fresnel.h` `fresnel`).
pub fn fresnel_dielectric(cos_theta_i: f64, eta: f64) -> f64 {
    let outside = cos_theta_i >= 0.0;
    let (eta_it, eta_ti) = if outside {
        (eta, 1.0 / eta)
    } else {
        (1.0 / eta, eta)
    };
    let cos_t_sqr = 1.0 - (1.0 - cos_theta_i * cos_theta_i) * eta_ti * eta_ti;
    let ci = cos_theta_i.abs();
    let ct = safe_sqrt(cos_t_sqr);
    if eta == 1.0 {
        return 0.0;
    }
    if ci == 0.0 {
        return 1.0;
    }
    let a_s = (ci - eta_it * ct) / (ci + eta_it * ct);
    let a_p = (ct - eta_it * ci) / (ct + eta_it * ci);
    0.5 * (a_s * a_s + a_p * a_p)
}

/// Logistic CDF (`hair.cpp` `logistic_cdf`).
fn logistic_cdf(x: f64, s: f64) -> f64 {
    1.0 / (1.0 + (-x / s).exp())
}

/// Logistic density (`hair.cpp` `logistic`).
fn logistic(x: f64, s: f64) -> f64 {
    let e = (-x.abs() / s).exp();
    e / (s * (1.0 + e) * (1.0 + e))
}

/// Φ(p, γi, γt) = 2p γt − 2γi + pπ, the azimuth of the smooth path (Chiang Eq. 9).
fn perfect_dphi(p: usize, gamma_i: f64, gamma_t: f64) -> f64 {
    let p = p as f64;
    2.0 * p * gamma_t - 2.0 * gamma_i + p * PI
}

/// What the incidence (θi, h) fixes for every lobe and channel: the refracted angles, the
/// Fresnel factor and the chord length through the fiber.
#[derive(Debug, Clone, Copy)]
struct Incidence {
    gamma_i: f64,
    gamma_t: f64,
    fresnel: f64,
    /// 2 cos γt / cos θt, in fiber radii.
    path: f64,
}

/// Fiber tangent `y`, normal `z`: Mitsuba's local direction of longitudinal angle θ and
/// azimuth φ (`hair.cpp`: sin θ = w.y, φ = atan2(w.z, w.x)).
pub fn local_direction(theta: f64, phi: f64) -> [f64; 3] {
    let (st, ct) = theta.sin_cos();
    let (sp, cp) = phi.sin_cos();
    [ct * cp, st, ct * sp]
}

/// Mitsuba's local incident direction for longitudinal angle θi and offset h ∈ \[−1, 1\]
/// (on the lit side, z ≥ 0): the inverse of `hair.cpp`'s h = sin γ(wi).
pub fn local_wi(theta_i: f64, h: f64) -> [f64; 3] {
    let (st, ct) = theta_i.sin_cos();
    [-h * ct, st, safe_sqrt(1.0 - h * h) * ct]
}

/// Table-frame vector (fiber axis +z) → Mitsuba local vector (fiber axis +y): (x, z, y).
pub fn table_to_local(w: [f64; 3]) -> [f64; 3] {
    [w[0], w[2], w[1]]
}

/// `hair.cpp` `gamma()`: signed angle between w's projection on the x–z plane and z.
fn gamma_of(w: [f64; 3]) -> f64 {
    let r = safe_sqrt(w[0] * w[0] + w[2] * w[2]);
    if r == 0.0 {
        return 0.0;
    }
    let g = (w[2] / r).clamp(-1.0, 1.0).acos();
    if w[0] < 0.0 {
        g
    } else {
        -g
    }
}

/// Gauss–Legendre nodes and weights on \[−1, 1\] (Newton on the Legendre recurrence).
pub fn gauss_legendre(n: usize) -> (Vec<f64>, Vec<f64>) {
    let (mut x, mut w) = (vec![0.0; n], vec![0.0; n]);
    for i in 0..n.div_ceil(2) {
        let mut z = (PI * (i as f64 + 0.75) / (n as f64 + 0.5)).cos();
        let mut dp = 1.0;
        for _ in 0..100 {
            let (mut p0, mut p1) = (1.0, z);
            for k in 2..=n {
                let p2 = ((2 * k - 1) as f64 * z * p1 - (k - 1) as f64 * p0) / k as f64;
                p0 = p1;
                p1 = p2;
            }
            let pn = if n == 1 { z } else { p1 };
            let pm = if n == 1 { 1.0 } else { p0 };
            dp = n as f64 * (z * pn - pm) / (z * z - 1.0);
            let dz = pn / dp;
            z -= dz;
            if dz.abs() < 1e-15 {
                break;
            }
        }
        x[i] = -z;
        x[n - 1 - i] = z;
        w[i] = 2.0 / ((1.0 - z * z) * dp * dp);
        w[n - 1 - i] = w[i];
    }
    (x, w)
}

/// Composite Gauss–Legendre on \[a, b\]: `panels` panels of `order` nodes.
fn composite_gl(a: f64, b: f64, panels: usize, order: usize) -> Vec<(f64, f64)> {
    let (x, w) = gauss_legendre(order);
    let width = (b - a) / panels as f64;
    let mut out = Vec::with_capacity(panels * order);
    for k in 0..panels {
        let mid = a + (k as f64 + 0.5) * width;
        for (xi, wi) in x.iter().zip(&w) {
            out.push((mid + 0.5 * width * xi, 0.5 * width * wi));
        }
    }
    out
}

/// Nodes (γ, weight) of ½∫ dh over the fiber width, h = sin γ: weights include ½ cos γ and sum
/// to 1.
pub fn width_nodes(panels: usize) -> Vec<(f64, f64)> {
    composite_gl(-FRAC_PI_2, FRAC_PI_2, panels, 8)
        .into_iter()
        .map(|(g, w)| (g, 0.5 * w * g.cos()))
        .collect()
}

/// Panels of 8 nodes in γ that resolve a logistic of scale s (≥ 12, ≤ 256).
fn width_panels(s: f64) -> usize {
    ((PI / (1.5 * s)).ceil() as usize).clamp(12, 256)
}

/// Width panels for bin averages on `grid`: bins as wide as the grid's are smooth in h even
/// when the logistic is not, so about one panel per Δφ column is enough (relative L1 < 0.3 %
/// against 512 panels at β_n = 0.02, 10° bins; far less at larger β_n).
fn bin_panels(s: f64, grid: &Grid) -> usize {
    width_panels(s).min(grid.n_phi.max(12))
}

/// The model with its derived constants (`hair.cpp` `update()`).
#[derive(Debug, Clone)]
pub struct Chiang {
    pub params: ChiangParams,
    v: [f64; P_MAX + 1],
    s: f64,
    sin_2k_alpha: [f64; 3],
    cos_2k_alpha: [f64; 3],
}

impl Chiang {
    pub fn new(params: ChiangParams) -> Self {
        let v = longitudinal_variances(params.beta_m);
        let s = logistic_scale(params.beta_n);
        // hair.cpp update(): sin/cos of α, 2α, 4α by double-angle steps
        let mut sin_2k_alpha = [params.alpha_deg.to_radians().sin(), 0.0, 0.0];
        let mut cos_2k_alpha = [safe_sqrt(1.0 - sin_2k_alpha[0].powi(2)), 0.0, 0.0];
        for i in 1..3 {
            sin_2k_alpha[i] = 2.0 * cos_2k_alpha[i - 1] * sin_2k_alpha[i - 1];
            cos_2k_alpha[i] = cos_2k_alpha[i - 1].powi(2) - sin_2k_alpha[i - 1].powi(2);
        }
        Self {
            params,
            v,
            s,
            sin_2k_alpha,
            cos_2k_alpha,
        }
    }

    /// Number of channels (length of σa).
    pub fn channels(&self) -> usize {
        self.params.sigma_a.len()
    }

    /// Longitudinal angle of lobe p tilted by the cuticle scales: (sin, |cos|)
    /// (`hair.cpp` `reframe_with_scales`: −2α for R, +α for TT, +4α for TRT).
    fn reframe(&self, sin_t: f64, cos_t: f64, p: usize) -> (f64, f64) {
        let (s, c) = (&self.sin_2k_alpha, &self.cos_2k_alpha);
        let (sp, cp) = match p {
            0 => (sin_t * c[1] - cos_t * s[1], cos_t * c[1] + sin_t * s[1]),
            1 => (sin_t * c[0] + cos_t * s[0], cos_t * c[0] - sin_t * s[0]),
            2 => (sin_t * c[2] + cos_t * s[2], cos_t * c[2] - sin_t * s[2]),
            _ => (sin_t, cos_t),
        };
        (sp, cp.abs())
    }

    /// `hair.cpp` `eval`, up to `attenuation`: refraction angles, Fresnel, chord length.
    fn incidence(&self, sin_theta_i: f64, cos_theta_i: f64, gamma_i: f64) -> Incidence {
        let eta = self.params.eta;
        let h = gamma_i.sin();
        let sin_theta_t = sin_theta_i / eta;
        let cos_theta_t = safe_sqrt(1.0 - sin_theta_t * sin_theta_t);
        // Modified index in the normal plane (Bravais): η′ = √(η² − sin²θi)/cos θi
        let eta_p = safe_sqrt(eta * eta - sin_theta_i * sin_theta_i) / cos_theta_i;
        let sin_gamma_t = h / eta_p;
        let cos_gamma_t = safe_sqrt(1.0 - sin_gamma_t * sin_gamma_t);
        let gamma_t = safe_asin(sin_gamma_t);
        // attenuation(): Fresnel at cos θi·cos γi
        let cos_gamma_i = safe_sqrt(1.0 - h * h);
        let fresnel = fresnel_dielectric(cos_theta_i * cos_gamma_i, eta);
        Incidence {
            gamma_i,
            gamma_t,
            fresnel,
            path: 2.0 * cos_gamma_t / cos_theta_t,
        }
    }

    /// A₀…A₃ of one channel (`hair.cpp` `attenuation`; Chiang Eq. 3–6).
    fn attenuation(inc: &Incidence, sigma_a: f64) -> [f64; P_MAX + 1] {
        let f = inc.fresnel;
        let t = (-sigma_a * inc.path).exp();
        let a1 = (1.0 - f) * (1.0 - f) * t;
        let a2 = a1 * t * f;
        [f, a1, a2, a2 * f * t / (1.0 - t * f)]
    }

    /// Np(Δφ) (`hair.cpp` `azimuthal_scattering`: offset from Φ wrapped to (−π, π], trimmed
    /// logistic).
    fn azimuthal(&self, dphi: f64, p: usize, gamma_i: f64, gamma_t: f64) -> f64 {
        let mut phi = (dphi - perfect_dphi(p, gamma_i, gamma_t)) % TAU;
        if phi < PI {
            phi += TAU;
        }
        if phi > PI {
            phi -= TAU;
        }
        logistic(phi, self.s) / (logistic_cdf(PI, self.s) - logistic_cdf(-PI, self.s))
    }

    /// Periodic CDF of the trimmed logistic in the wrapped variable: G(x + 2π) = G(x) + 1,
    /// G(−π) = 0, so ∫ₐᵇ Np dφ = G(b − Φ) − G(a − Φ).
    fn azimuthal_cdf(&self, x: f64) -> f64 {
        let k = ((x + PI) / TAU).floor();
        let y = x - k * TAU;
        let (lo, hi) = (logistic_cdf(-PI, self.s), logistic_cdf(PI, self.s));
        k + (logistic_cdf(y, self.s) - lo) / (hi - lo)
    }

    /// S(wi, wo) in Mitsuba's local frame, per channel: what `Hair::eval` returns for
    /// `si.wi = wi` and `wo` (the near-field model at h = sin γ(wi)). NaN or ∞ become 0 as
    /// there.
    pub fn eval_local(&self, wi: [f64; 3], wo: [f64; 3]) -> Vec<f64> {
        let gamma_i = gamma_of(wi);
        let sin_theta_i = wi[1];
        let cos_theta_i = safe_sqrt(1.0 - sin_theta_i * sin_theta_i);
        let phi_i = wi[2].atan2(wi[0]);
        let phi_o = wo[2].atan2(wo[0]);
        let inc = self.incidence(sin_theta_i, cos_theta_i, gamma_i);
        let dphi = phi_o - phi_i;
        let mut m = [0.0; P_MAX + 1];
        let mut n = [0.0; P_MAX];
        for p in 0..P_MAX {
            let (sp, _) = self.reframe(sin_theta_i, cos_theta_i, p);
            // 2π·pdf = Mp; hair.cpp multiplies by TwoPi
            m[p] = rough_fiber_pdf(sp, wo[1], 1.0 / self.v[p]) * TAU;
            n[p] = self.azimuthal(dphi, p, inc.gamma_i, inc.gamma_t);
        }
        // Residual: untilted, uniform in φ (the 1/2π of the pdf)
        m[P_MAX] = rough_fiber_pdf(sin_theta_i, wo[1], 1.0 / self.v[P_MAX]);
        self.params
            .sigma_a
            .iter()
            .map(|&sa| {
                let a = Self::attenuation(&inc, sa);
                let mut val = m[P_MAX] * a[P_MAX];
                for p in 0..P_MAX {
                    val += m[p] * a[p] * n[p];
                }
                if val.is_finite() {
                    val
                } else {
                    0.0
                }
            })
            .collect()
    }

    /// The near-field S at offset h, longitudinal angles θi, θo and Δφ = φo − φi (radians).
    pub fn eval_near(&self, theta_i: f64, h: f64, theta_o: f64, dphi: f64) -> Vec<f64> {
        let wi = local_wi(theta_i, h);
        let phi_i = wi[2].atan2(wi[0]);
        self.eval_local(wi, local_direction(theta_o, phi_i + dphi))
    }

    /// The far-field S̄(θi, θo, Δφ) = ½∫ S dh over the width, sr⁻¹ per channel: what the
    /// table stores (f = Λ·f̂). `panels` × 8 Gauss–Legendre nodes in γ = asin h; `None`
    /// picks enough for the azimuthal roughness (point values need more than bin averages).
    pub fn eval_far(
        &self,
        theta_i: f64,
        theta_o: f64,
        dphi: f64,
        panels: Option<usize>,
    ) -> Vec<f64> {
        let panels = panels.unwrap_or_else(|| 4 * width_panels(self.s));
        let mut out = vec![0.0; self.channels()];
        for (g, w) in width_nodes(panels) {
            let v = self.eval_near(theta_i, g.sin(), theta_o, dphi);
            for (o, x) in out.iter_mut().zip(v) {
                *o += w * x;
            }
        }
        out
    }

    /// Directional albedo of the far-field model, ½∫ Σp Ap dh, per channel (Mp and Np
    /// integrate to 1 up to Mitsuba's I₀ approximations).
    pub fn albedo(&self, theta_i: f64) -> Vec<f64> {
        let (st, ct) = theta_i.sin_cos();
        let mut out = vec![0.0; self.channels()];
        for (g, w) in width_nodes(32) {
            let inc = self.incidence(st, ct, g);
            for (o, &sa) in out.iter_mut().zip(&self.params.sigma_a) {
                *o += w * Self::attenuation(&inc, sa).iter().sum::<f64>();
            }
        }
        out
    }
}

/// A table's grid: `n_theta` θo rows from −90° and `n_phi` Δφ columns from −180°, `res_deg`
/// wide.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Grid {
    pub res_deg: f64,
    pub n_theta: usize,
    pub n_phi: usize,
}

impl Grid {
    pub fn bins(&self) -> usize {
        self.n_theta * self.n_phi
    }

    fn res(&self) -> f64 {
        self.res_deg.to_radians()
    }

    /// Lower edge of θ row `r`, radians.
    fn theta_lo(&self, r: usize) -> f64 {
        -FRAC_PI_2 + r as f64 * self.res()
    }

    /// Lower edge of Δφ column `k`, radians.
    fn phi_lo(&self, k: usize) -> f64 {
        -PI + k as f64 * self.res()
    }

    /// Centre of θ row `r`, radians.
    pub fn theta_centre(&self, r: usize) -> f64 {
        self.theta_lo(r) + 0.5 * self.res()
    }

    /// Centre of φ column `k`, radians.
    pub fn phi_centre(&self, k: usize) -> f64 {
        self.phi_lo(k) + 0.5 * self.res()
    }
}

/// The parts of the bin-averaged far-field model that do not depend on σa, for one θi.
struct ShapeSlice {
    /// `[p][row]`: ∫ Mp cos θo dθo over the row / Δ(sin θo).
    mbar: [Vec<f64>; P_MAX + 1],
    /// Per width node: weight, Fresnel factor, chord length.
    nodes: Vec<(f64, f64, f64)>,
    /// `[p][node][column]`: ∫ Np dφ over the column / Δφ, for p < 3.
    d: [Vec<f64>; P_MAX],
    /// Σ_nodes w·A₀·D₀ per column (A₀ = f does not depend on σa).
    n0: Vec<f64>,
    /// `[p]`: Σ over rows of M̄p·Δ(sin θo), the lobe's longitudinal integral (1 up to the I₀
    /// series and the rows' quadrature).
    mtot: [f64; P_MAX + 1],
    /// `[p][node]`: Σ over columns of the column integrals of Np (1 up to rounding).
    dtot: [Vec<f64>; P_MAX],
}

impl Chiang {
    /// The σa-independent parts of the bin averages at θi.
    fn shape_slice(&self, grid: &Grid, theta_i: f64, panels: usize) -> ShapeSlice {
        let (st, ct) = theta_i.sin_cos();
        let res = grid.res();
        let mut mbar: [Vec<f64>; P_MAX + 1] = Default::default();
        for p in 0..=P_MAX {
            let (sp, _) = self.reframe(st, ct, p);
            let kappa = 1.0 / self.v[p];
            // Enough nodes per row for a lobe of angular width √v.
            let order = ((3.0 * res / self.v[p].sqrt()).ceil() as usize).clamp(3, 48);
            let (x, w) = gauss_legendre(order);
            // The residual's pdf already holds 1/2π; the others get the 2π of hair.cpp.
            let scale = if p == P_MAX { 1.0 } else { TAU };
            mbar[p] = (0..grid.n_theta)
                .map(|r| {
                    let (a, b) = (grid.theta_lo(r), grid.theta_lo(r) + res);
                    let mut acc = 0.0;
                    for (xi, wi) in x.iter().zip(&w) {
                        let t = 0.5 * (a + b) + 0.5 * (b - a) * xi;
                        acc += 0.5 * (b - a) * wi * rough_fiber_pdf(sp, t.sin(), kappa) * t.cos();
                    }
                    scale * acc / (b.sin() - a.sin())
                })
                .collect();
        }
        let width = width_nodes(panels);
        let mut nodes = Vec::with_capacity(width.len());
        let mut d: [Vec<f64>; P_MAX] = Default::default();
        for dp in d.iter_mut() {
            dp.reserve(width.len() * grid.n_phi);
        }
        let mut edges = vec![0.0; grid.n_phi + 1];
        for &(g, w) in &width {
            let inc = self.incidence(st, ct, g);
            nodes.push((w, inc.fresnel, inc.path));
            for p in 0..P_MAX {
                let phi0 = perfect_dphi(p, inc.gamma_i, inc.gamma_t);
                for (k, e) in edges.iter_mut().enumerate() {
                    *e = self.azimuthal_cdf(-PI + k as f64 * res - phi0);
                }
                for k in 0..grid.n_phi {
                    d[p].push((edges[k + 1] - edges[k]) / res);
                }
            }
        }
        let mut n0 = vec![0.0; grid.n_phi];
        for (j, &(w, f, _)) in nodes.iter().enumerate() {
            for k in 0..grid.n_phi {
                n0[k] += w * f * d[0][j * grid.n_phi + k];
            }
        }
        let mut mtot = [0.0; P_MAX + 1];
        for p in 0..=P_MAX {
            for r in 0..grid.n_theta {
                let (a, b) = (grid.theta_lo(r), grid.theta_lo(r) + res);
                mtot[p] += mbar[p][r] * (b.sin() - a.sin());
            }
        }
        let dtot: [Vec<f64>; P_MAX] = std::array::from_fn(|p| {
            d[p].chunks(grid.n_phi)
                .map(|row| row.iter().sum::<f64>() * res)
                .collect()
        });
        ShapeSlice {
            mbar,
            nodes,
            d,
            n0,
            mtot,
            dtot,
        }
    }
}

impl ShapeSlice {
    /// Σ over bins of the model's bin average × ΔΩ (its albedo on the grid) for absorption σa,
    /// without filling the bins.
    fn albedo(&self, sigma_a: f64) -> f64 {
        let mut acc = [0.0; P_MAX + 1];
        for (j, &(w, f, path)) in self.nodes.iter().enumerate() {
            let t = (-sigma_a * path).exp();
            let a1 = (1.0 - f) * (1.0 - f) * t;
            let a2 = a1 * t * f;
            let a3 = a2 * f * t / (1.0 - t * f);
            acc[0] += w * f * self.dtot[0][j];
            acc[1] += w * a1 * self.dtot[1][j];
            acc[2] += w * a2 * self.dtot[2][j];
            if a3.is_finite() {
                // uniform in Δφ: its 2π columns hold 2π × (the 1/2π of the residual's pdf)
                acc[3] += w * a3 * TAU;
            }
        }
        (0..=P_MAX).map(|p| self.mtot[p] * acc[p]).sum()
    }

    /// Bin averages `[row][column]` of one channel of the far-field model for absorption σa.
    fn channel(&self, grid: &Grid, sigma_a: f64, out: &mut [f64]) {
        let np = grid.n_phi;
        let mut n1 = vec![0.0; np];
        let mut n2 = vec![0.0; np];
        let mut n3 = 0.0;
        for (j, &(w, f, path)) in self.nodes.iter().enumerate() {
            let t = (-sigma_a * path).exp();
            let a1 = (1.0 - f) * (1.0 - f) * t;
            let a2 = a1 * t * f;
            let a3 = a2 * f * t / (1.0 - t * f);
            if a3.is_finite() {
                n3 += w * a3;
            }
            let (d1, d2) = (
                &self.d[1][j * np..(j + 1) * np],
                &self.d[2][j * np..(j + 1) * np],
            );
            for k in 0..np {
                n1[k] += w * a1 * d1[k];
                n2[k] += w * a2 * d2[k];
            }
        }
        for r in 0..grid.n_theta {
            let m = [
                self.mbar[0][r],
                self.mbar[1][r],
                self.mbar[2][r],
                self.mbar[3][r],
            ];
            for k in 0..np {
                out[r * np + k] = m[0] * self.n0[k] + m[1] * n1[k] + m[2] * n2[k] + m[3] * n3;
            }
        }
    }
}

/// Bin averages of the far-field model at θi on `grid`, `[channel][row][column]`, sr⁻¹: the
/// quantity a table stores.
pub fn binned(model: &Chiang, grid: &Grid, theta_i: f64) -> Vec<f64> {
    binned_with(model, grid, theta_i, bin_panels(model.s, grid))
}

/// [`binned`] with `panels` × 8 width nodes.
fn binned_with(model: &Chiang, grid: &Grid, theta_i: f64, panels: usize) -> Vec<f64> {
    let slice = model.shape_slice(grid, theta_i, panels);
    let mut out = vec![0.0; model.channels() * grid.bins()];
    for (c, &sa) in model.params.sigma_a.iter().enumerate() {
        slice.channel(grid, sa, &mut out[c * grid.bins()..(c + 1) * grid.bins()]);
    }
    out
}

/// How the fit samples the table.
#[derive(Debug, Clone, PartialEq)]
pub struct FitOptions {
    /// θi rows used (even; half on each side of 0).
    pub theta_i_rows: usize,
    /// |θi| limit of those rows, degrees (grazing rows are where the model is weakest and
    /// renderers look least).
    pub max_theta_i_deg: f64,
    /// φi samples averaged per θi.
    pub phi_i_samples: usize,
    /// η held fixed (the table's metadata); `None` fits it.
    pub eta: Option<f64>,
    /// Nelder–Mead evaluations per run.
    pub max_evaluations: usize,
}

impl Default for FitOptions {
    fn default() -> Self {
        Self {
            theta_i_rows: 8,
            max_theta_i_deg: 80.0,
            phi_i_samples: 6,
            eta: None,
            max_evaluations: 400,
        }
    }
}

/// Errors of the fit.
#[derive(Debug, thiserror::Error)]
pub enum FitError {
    #[error("reading the table: {0}")]
    Table(#[from] TableError),
    #[error("variant {index} out of range (table has {count})")]
    Variant { index: usize, count: usize },
    #[error("the table has no θi row with |θi| ≤ {max_deg}°")]
    NoRows { max_deg: f64 },
    #[error("the table scatters nothing in variant {variant:?}")]
    Empty { variant: String },
}

/// The table values the fit compares with: for each sampled θi, f = Λ·f̂ averaged over φi.
#[derive(Debug, Clone)]
pub struct FitTarget {
    pub grid: Grid,
    pub channels: Vec<String>,
    pub theta_i_deg: Vec<f64>,
    pub phi_i_deg: Vec<f64>,
    /// `[θi][channel][row][column]`, sr⁻¹.
    pub values: Vec<f64>,
    /// `[θi][channel]`: the table's Λ averaged over φi.
    pub albedo: Vec<f64>,
    /// Per θi, how many distinct stored slices the φi samples read (their noise averages).
    pub distinct_slices: Vec<usize>,
}

impl FitTarget {
    /// Samples `variant` of `table`.
    pub fn from_table(table: &Bcsdf, variant: usize, opts: &FitOptions) -> Result<Self, FitError> {
        let d = &table.dir;
        if variant >= d.variants.len() {
            return Err(FitError::Variant {
                index: variant,
                count: d.variants.len(),
            });
        }
        let grid = Grid {
            res_deg: d.res_deg,
            n_theta: d.n_theta,
            n_phi: d.n_phi,
        };
        // Positive half of the eligible rows, evenly thinned, then mirrored.
        let positive: Vec<f64> = (0..grid.n_theta)
            .map(|r| grid.theta_centre(r).to_degrees())
            .filter(|&t| t > 0.0 && t <= opts.max_theta_i_deg + 1e-9)
            .collect();
        if positive.is_empty() {
            return Err(FitError::NoRows {
                max_deg: opts.max_theta_i_deg,
            });
        }
        let half = (opts.theta_i_rows / 2).clamp(1, positive.len());
        let picked: Vec<f64> = (0..half)
            .map(|i| positive[((i as f64 + 0.5) * positive.len() as f64 / half as f64) as usize])
            .collect();
        let mut theta_i_deg: Vec<f64> = picked.iter().rev().map(|t| -t).collect();
        theta_i_deg.extend(&picked);
        let nphi = opts.phi_i_samples.clamp(1, grid.n_phi);
        let phi_i_deg: Vec<f64> = (0..nphi)
            .map(|j| {
                let k = ((j as f64 + 0.5) * grid.n_phi as f64 / nphi as f64) as usize;
                grid.phi_centre(k).to_degrees()
            })
            .collect();
        let nc = d.channels.len();
        let bins = grid.bins();
        let mut values = vec![0.0; theta_i_deg.len() * nc * bins];
        let mut albedo = vec![0.0; theta_i_deg.len() * nc];
        let inv = 1.0 / phi_i_deg.len() as f64;
        let mut distinct_slices = Vec::with_capacity(theta_i_deg.len());
        for (i, &ti) in theta_i_deg.iter().enumerate() {
            let mut stored: Vec<usize> = Vec::new();
            for &pi in &phi_i_deg {
                let (ti, pi) = (ti.to_radians(), pi.to_radians());
                let wi = direction(ti, pi);
                let (index, ..) = table.locate(wi);
                if !stored.contains(&index) {
                    stored.push(index);
                }
                for (c, a) in table.albedo(wi, variant)?.into_iter().enumerate() {
                    albedo[i * nc + c] += inv * a as f64;
                }
                for r in 0..grid.n_theta {
                    for k in 0..grid.n_phi {
                        let wo = direction(grid.theta_centre(r), pi + grid.phi_centre(k));
                        let f = table.eval(wi, wo, variant)?;
                        for (c, x) in f.into_iter().enumerate() {
                            values[(i * nc + c) * bins + r * grid.n_phi + k] += inv * x as f64;
                        }
                    }
                }
            }
            distinct_slices.push(stored.len());
        }
        if values.iter().all(|&x| x <= 0.0) {
            return Err(FitError::Empty {
                variant: d.variants[variant].clone(),
            });
        }
        Ok(Self {
            grid,
            channels: d.channels.clone(),
            theta_i_deg,
            phi_i_deg,
            values,
            albedo,
            distinct_slices,
        })
    }

    /// Expected relative L1 distance between the table and its noise-free limit if each stored
    /// slice were a histogram of `photons` unweighted photons: Σ √(2/π)·√(q(1−q)/N) over bins
    /// of probability q = f̂·ΔΩ, averaged like the fit's error (and divided by √(distinct
    /// slices) where φi samples average several). Weighted photons only add noise, so read it
    /// as a floor: no smooth model can get much below it.
    pub fn noise_l1(&self, photons: f64) -> f64 {
        let d_omega = self.d_omega();
        let nc = self.channels.len();
        let (mut num, mut den) = (0.0, 0.0);
        for i in 0..self.theta_i_deg.len() {
            let k = (2.0 / PI).sqrt() / (self.distinct_slices[i] as f64).sqrt();
            for c in 0..nc {
                let tab = self.slice(i, c);
                let total: f64 = tab
                    .iter()
                    .enumerate()
                    .map(|(b, t)| t * d_omega[b / self.grid.n_phi])
                    .sum();
                if total <= 0.0 {
                    continue;
                }
                let noise: f64 = tab
                    .iter()
                    .enumerate()
                    .map(|(b, t)| {
                        // max(0): RGB tables converted from spectra can dip below 0.
                        let q = (t * d_omega[b / self.grid.n_phi] / total).clamp(0.0, 1.0);
                        k * (q * (1.0 - q) / photons).sqrt()
                    })
                    .sum();
                num += noise * total;
                den += total;
            }
        }
        num / den
    }

    fn slice(&self, i: usize, c: usize) -> &[f64] {
        let (nc, bins) = (self.channels.len(), self.grid.bins());
        &self.values[(i * nc + c) * bins..(i * nc + c + 1) * bins]
    }

    /// Solid angle of each θ row's bins.
    fn d_omega(&self) -> Vec<f64> {
        (0..self.grid.n_theta)
            .map(|r| solid_angle(self.grid.res_deg, r))
            .collect()
    }
}

/// Sums over bins of |model − table|·ΔΩ, (model − table)²·ΔΩ, model·ΔΩ.
fn bin_errors(model: &[f64], table: &[f64], d_omega: &[f64], n_phi: usize) -> (f64, f64, f64) {
    let (mut l1, mut l2, mut e) = (0.0, 0.0, 0.0);
    for (b, (&m, &t)) in model.iter().zip(table).enumerate() {
        let dw = d_omega[b / n_phi];
        l1 += (m - t).abs() * dw;
        l2 += (m - t) * (m - t) * dw;
        e += m * dw;
    }
    (l1, l2, e)
}

/// What the fit found and how close it is.
#[derive(Debug, Clone, Serialize)]
pub struct FitReport {
    pub params: ChiangParams,
    /// η came from the table's metadata (not fitted).
    pub eta_fixed: bool,
    /// Σ |S̄ − f|·ΔΩ / Σ f·ΔΩ over the sampled θi, bins and channels.
    pub rel_l1: f64,
    /// √(Σ (S̄ − f)²·ΔΩ / Σ f²·ΔΩ), same bins.
    pub rel_l2: f64,
    pub rel_l1_per_channel: Vec<f64>,
    pub rel_l2_per_channel: Vec<f64>,
    /// Per channel, the mean over the sampled θi of the table's Λ (φi-averaged).
    pub albedo_table: Vec<f64>,
    /// Per channel, the mean over the sampled θi of the model's Σ S̄·ΔΩ.
    pub albedo_model: Vec<f64>,
    pub theta_i_deg: Vec<f64>,
    pub phi_i_deg: Vec<f64>,
    /// Objective evaluations (shape parameter sets tried).
    pub evaluations: usize,
}

/// Shape parameters in the optimiser's unbounded coordinates.
#[derive(Debug, Clone, Copy)]
struct Shape {
    eta: f64,
    beta_m: f64,
    beta_n: f64,
    alpha_deg: f64,
}

const ALPHA_MAX_DEG: f64 = 15.0;

fn sigmoid(x: f64) -> f64 {
    1.0 / (1.0 + (-x).exp())
}

fn logit(y: f64) -> f64 {
    (y / (1.0 - y)).ln()
}

impl Shape {
    fn from_x(x: &[f64], eta: Option<f64>) -> Self {
        let beta = |x: f64| BETA_MIN + (1.0 - BETA_MIN) * sigmoid(x);
        Shape {
            beta_m: beta(x[0]),
            beta_n: beta(x[1]),
            alpha_deg: ALPHA_MAX_DEG * x[2].tanh(),
            eta: eta.unwrap_or_else(|| (1.0 + x[3].exp()).min(3.0)),
        }
    }

    fn to_x(self, fit_eta: bool) -> Vec<f64> {
        let inv_beta = |b: f64| logit(((b - BETA_MIN) / (1.0 - BETA_MIN)).clamp(1e-6, 1.0 - 1e-6));
        let mut x = vec![
            inv_beta(self.beta_m),
            inv_beta(self.beta_n),
            (self.alpha_deg / ALPHA_MAX_DEG)
                .clamp(-0.999, 0.999)
                .atanh(),
        ];
        if fit_eta {
            x.push((self.eta - 1.0).max(1e-3).ln());
        }
        x
    }
}

/// Range of ln σa searched per channel.
const LN_SIGMA_RANGE: (f64, f64) = (-9.0, 6.5);

struct Problem<'a> {
    target: &'a FitTarget,
    d_omega: Vec<f64>,
    /// Σ f·ΔΩ over all sampled θi and channels.
    norm_l1: f64,
}

impl<'a> Problem<'a> {
    fn new(target: &'a FitTarget) -> Self {
        let d_omega = target.d_omega();
        let n_phi = target.grid.n_phi;
        let norm_l1 = target
            .values
            .iter()
            .enumerate()
            .map(|(b, &t)| t * d_omega[(b % target.grid.bins()) / n_phi])
            .sum();
        Self {
            target,
            d_omega,
            norm_l1,
        }
    }

    fn slices(&self, shape: Shape) -> Vec<ShapeSlice> {
        let model = Chiang::new(ChiangParams {
            eta: shape.eta,
            sigma_a: vec![],
            beta_m: shape.beta_m,
            beta_n: shape.beta_n,
            alpha_deg: shape.alpha_deg,
        });
        self.target
            .theta_i_deg
            .iter()
            .map(|t| {
                model.shape_slice(
                    &self.target.grid,
                    t.to_radians(),
                    bin_panels(model.s, &self.target.grid),
                )
            })
            .collect()
    }

    /// L1 numerator of channel c for absorption σa.
    fn channel_l1(&self, slices: &[ShapeSlice], c: usize, sigma_a: f64, buf: &mut [f64]) -> f64 {
        let grid = &self.target.grid;
        let mut l1 = 0.0;
        for (i, s) in slices.iter().enumerate() {
            s.channel(grid, sigma_a, buf);
            l1 += bin_errors(buf, self.target.slice(i, c), &self.d_omega, grid.n_phi).0;
        }
        l1
    }

    /// σa of channel c that gives the model the table's albedo (Σ over the sampled θi of
    /// Σ S̄·ΔΩ = Σ of the table's), by bisection on ln σa (the albedo falls as σa grows), and
    /// the channel's L1 numerator there.
    fn best_sigma(&self, slices: &[ShapeSlice], c: usize, buf: &mut [f64]) -> (f64, f64) {
        let nc = self.target.channels.len();
        let want: f64 = (0..slices.len())
            .map(|i| self.target.albedo[i * nc + c])
            .sum();
        let albedo = |x: f64| -> f64 { slices.iter().map(|s| s.albedo(x.exp())).sum() };
        let (mut lo, mut hi) = LN_SIGMA_RANGE;
        if albedo(lo) <= want {
            // Even a clear fiber is darker than the table: no absorption at all.
            return (0.0, self.channel_l1(slices, c, 0.0, buf));
        }
        let x = if albedo(hi) >= want {
            hi
        } else {
            for _ in 0..48 {
                let mid = 0.5 * (lo + hi);
                if albedo(mid) > want {
                    lo = mid;
                } else {
                    hi = mid;
                }
            }
            0.5 * (lo + hi)
        };
        (x.exp(), self.channel_l1(slices, c, x.exp(), buf))
    }

    /// Objective of a shape: relative L1 with each channel's best σa.
    fn objective(&self, shape: Shape) -> (f64, Vec<f64>) {
        let slices = self.slices(shape);
        let mut buf = vec![0.0; self.target.grid.bins()];
        let mut total = 0.0;
        let mut sigma = Vec::with_capacity(self.target.channels.len());
        for c in 0..self.target.channels.len() {
            let (s, l1) = self.best_sigma(&slices, c, &mut buf);
            total += l1;
            sigma.push(s);
        }
        (total / self.norm_l1, sigma)
    }
}

/// Fits the model to `target` (see the module docs for the objective).
pub fn fit(target: &FitTarget, opts: &FitOptions) -> FitReport {
    let problem = Problem::new(target);
    let fit_eta = opts.eta.is_none();
    let mut evaluations = 0usize;
    // Start: the best of a small grid of shapes.
    let mut start = None;
    for &bm in &[0.08, 0.2, 0.45] {
        for &bn in &[0.15, 0.35, 0.7] {
            for &eta in if fit_eta { &[1.4, 1.6][..] } else { &[0.0][..] } {
                let shape = Shape {
                    eta: opts.eta.unwrap_or(eta),
                    beta_m: bm,
                    beta_n: bn,
                    alpha_deg: 0.0,
                };
                let (v, _) = problem.objective(shape);
                evaluations += 1;
                if start.as_ref().is_none_or(|(best, _)| v < *best) {
                    start = Some((v, shape));
                }
            }
        }
    }
    let (_, shape0) = start.expect("the grid is not empty");
    let mut objective = |x: &[f64]| problem.objective(Shape::from_x(x, opts.eta)).0;
    let (mut x, mut fx, n) = crate::fit::nelder_mead(
        &mut objective,
        &shape0.to_x(fit_eta),
        0.6,
        opts.max_evaluations,
        1e-7,
    );
    evaluations += n;
    // Restart from the best point until it stops improving.
    for step in [0.3, 0.15] {
        let (x2, f2, n) =
            crate::fit::nelder_mead(&mut objective, &x, step, opts.max_evaluations, 1e-7);
        evaluations += n;
        let better = f2 < fx * (1.0 - 1e-4);
        if f2 < fx {
            x = x2;
            fx = f2;
        }
        if !better {
            break;
        }
    }
    let shape = Shape::from_x(&x, opts.eta);
    let (_, sigma_a) = problem.objective(shape);
    let params = ChiangParams {
        eta: shape.eta,
        sigma_a,
        beta_m: shape.beta_m,
        beta_n: shape.beta_n,
        alpha_deg: shape.alpha_deg,
    };
    let mut report = evaluate(target, &params);
    report.eta_fixed = !fit_eta;
    report.evaluations = evaluations;
    report
}

/// The errors and albedos of `params` against `target` (a [`FitReport`] with no fitting).
pub fn evaluate(target: &FitTarget, params: &ChiangParams) -> FitReport {
    let model = Chiang::new(params.clone());
    let problem = Problem::new(target);
    let grid = &target.grid;
    let nc = target.channels.len();
    let (mut l1, mut l2, mut t1, mut t2) =
        (vec![0.0; nc], vec![0.0; nc], vec![0.0; nc], vec![0.0; nc]);
    let mut albedo_model = vec![0.0; nc];
    let mut albedo_table = vec![0.0; nc];
    let n_ti = target.theta_i_deg.len() as f64;
    let zeros = vec![0.0; grid.bins()];
    for (i, t) in target.theta_i_deg.iter().enumerate() {
        let m = binned(&model, grid, t.to_radians());
        for c in 0..nc {
            let tab = target.slice(i, c);
            let mc = &m[c * grid.bins()..(c + 1) * grid.bins()];
            let (a, b, e) = bin_errors(mc, tab, &problem.d_omega, grid.n_phi);
            l1[c] += a;
            l2[c] += b;
            albedo_model[c] += e / n_ti;
            albedo_table[c] += target.albedo[i * nc + c] / n_ti;
            // Against zero: Σ f·ΔΩ and Σ f²·ΔΩ, the normalisers.
            let (n1, n2, _) = bin_errors(&zeros, tab, &problem.d_omega, grid.n_phi);
            t1[c] += n1;
            t2[c] += n2;
        }
    }
    let ratio = |a: &[f64], b: &[f64]| a.iter().sum::<f64>() / b.iter().sum::<f64>();
    FitReport {
        params: params.clone(),
        eta_fixed: false,
        rel_l1: ratio(&l1, &t1),
        rel_l2: ratio(&l2, &t2).sqrt(),
        rel_l1_per_channel: l1.iter().zip(&t1).map(|(a, b)| a / b).collect(),
        rel_l2_per_channel: l2.iter().zip(&t2).map(|(a, b)| (a / b).sqrt()).collect(),
        albedo_table,
        albedo_model,
        theta_i_deg: target.theta_i_deg.clone(),
        phi_i_deg: target.phi_i_deg.clone(),
        evaluations: 0,
    }
}

/// One evaluation of the fitted model, for checking an engine against it.
#[derive(Debug, Clone, Serialize)]
pub struct TestEvaluation {
    /// `near`: Mitsuba's `eval` at `wi_local`, `wo_local` (offset h); `far`: the h average.
    pub kind: &'static str,
    pub theta_i_deg: f64,
    pub theta_o_deg: f64,
    pub dphi_deg: f64,
    /// Offset across the fiber (near only).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub h: Option<f64>,
    /// Mitsuba local frame (tangent y, normal z), near only.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub wi_local: Option<[f64; 3]>,
    #[serde(skip_serializing_if = "Option::is_none")]
    pub wo_local: Option<[f64; 3]>,
    /// Far only: the h average is over `panels` × 8 Gauss–Legendre nodes in γ = asin h on
    /// \[−π/2, π/2\], weights ½ cos γ (converged to < 0.1 % for the model's β_n).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub panels: Option<usize>,
    /// S or S̄ per channel, sr⁻¹.
    pub value: Vec<f64>,
}

/// Directions where an engine's evaluation must match the model: near-field values at the
/// centres of the R, TT and TRT lobes and beside them, for a few θi and h, and far-field
/// values (h averages) at a few (θi, θo, Δφ).
pub fn test_evaluations(model: &Chiang) -> Vec<TestEvaluation> {
    let mut out = Vec::new();
    let alpha = model.params.alpha_deg;
    // Lobe centres in θo: R at −θi + 2α, TT at −θi − α, TRT at −θi − 4α (hair.cpp reframe).
    let shift = [2.0 * alpha, -alpha, -4.0 * alpha];
    for &(ti, h) in &[(-50.0, -0.6), (-15.0, 0.25), (20.0, 0.8), (45.0, -0.1)] {
        let theta_i = f64::to_radians(ti);
        let inc = model.incidence(theta_i.sin(), theta_i.cos(), safe_asin(h));
        for p in 0..P_MAX {
            for &(dt, dp) in &[(0.0, 0.0), (4.0, 0.15)] {
                let to = -ti + shift[p] + dt;
                let dphi = perfect_dphi(p, inc.gamma_i, inc.gamma_t) + dp;
                let dphi = dphi - TAU * ((dphi + PI) / TAU).floor();
                let wi = local_wi(theta_i, h);
                let phi_i = wi[2].atan2(wi[0]);
                let wo = local_direction(to.to_radians(), phi_i + dphi);
                out.push(TestEvaluation {
                    kind: "near",
                    theta_i_deg: ti,
                    theta_o_deg: to,
                    dphi_deg: dphi.to_degrees(),
                    h: Some(h),
                    wi_local: Some(wi),
                    wo_local: Some(wo),
                    panels: None,
                    value: model.eval_local(wi, wo),
                });
            }
        }
    }
    for &(ti, to, dphi) in &[
        (-40.0, 40.0, 0.0),
        (-40.0, 35.0, 60.0),
        (-20.0, 22.0, 180.0),
        (10.0, -12.0, 150.0),
        (30.0, -30.0, 120.0),
        (60.0, -55.0, 30.0),
    ] {
        let panels = 4 * width_panels(model.s);
        out.push(TestEvaluation {
            kind: "far",
            theta_i_deg: ti,
            theta_o_deg: to + 2.0 * alpha,
            dphi_deg: dphi,
            h: None,
            wi_local: None,
            wo_local: None,
            panels: Some(panels),
            value: model.eval_far(
                f64::to_radians(ti),
                f64::to_radians(to + 2.0 * alpha),
                f64::to_radians(dphi),
                Some(panels),
            ),
        });
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;
    use formats::bcsdf::{Directory, Precision, Writer, FLIP_THETA, KIND};

    fn params(sigma_a: Vec<f64>, alpha_deg: f64) -> ChiangParams {
        ChiangParams {
            eta: 1.55,
            sigma_a,
            beta_m: 0.25,
            beta_n: 0.3,
            alpha_deg,
        }
    }

    #[test]
    fn bin_panels_resolve_the_width_average() {
        // The documented accuracy of bin_panels: relative L1 < 0.3 % against 512 panels,
        // even at β_n = 0.02 on 10° bins.
        let grid = Grid {
            res_deg: 10.0,
            n_theta: 18,
            n_phi: 36,
        };
        for &bn in &[0.02, 0.1, 0.4] {
            let m = Chiang::new(ChiangParams {
                eta: 1.635,
                sigma_a: vec![0.05, 1.0],
                beta_m: 0.15,
                beta_n: bn,
                alpha_deg: 0.0,
            });
            for &ti in &[-75.0f64, -15.0] {
                let reference = binned_with(&m, &grid, ti.to_radians(), 512);
                let v = binned(&m, &grid, ti.to_radians());
                let e: f64 = v
                    .iter()
                    .zip(&reference)
                    .map(|(a, b)| (a - b).abs())
                    .sum::<f64>()
                    / reference.iter().sum::<f64>();
                assert!(e < 3e-3, "β_n {bn} θi {ti}: {e}");
            }
        }
    }

    #[test]
    fn gauss_legendre_integrates_polynomials_exactly() {
        let (x, w) = gauss_legendre(6);
        let integral: f64 = x.iter().zip(&w).map(|(x, w)| w * x.powi(10)).sum();
        assert!((integral - 2.0 / 11.0).abs() < 1e-13, "{integral}");
        assert!((w.iter().sum::<f64>() - 2.0).abs() < 1e-13);
    }

    #[test]
    fn white_furnace_near_and_far_conserve_energy() {
        // σa = 0: Σ Ap = 1, so ∫ S dωo = 1 at every h (Mitsuba's test_hair.py white furnace),
        // up to the I₀ series of warp.h.
        let m = Chiang::new(params(vec![0.0], 3.0));
        let grid = Grid {
            res_deg: 2.0,
            n_theta: 90,
            n_phi: 180,
        };
        for &ti in &[-60.0f64, -10.0, 35.0] {
            let ti = ti.to_radians();
            for &h in &[-0.7, 0.0, 0.4] {
                let mut total = 0.0;
                let (xt, wt) = gauss_legendre(64);
                for (u, wu) in xt.iter().zip(&wt) {
                    // θo by Gauss–Legendre on sin θo (dω = d sin θo dφ), φ on a fine grid
                    let st = *u;
                    let to = st.asin();
                    for k in 0..grid.n_phi {
                        let dphi = grid.phi_centre(k);
                        total += wu * grid.res() * m.eval_near(ti, h, to, dphi)[0];
                    }
                }
                assert!(
                    (total - 1.0).abs() < 5e-3,
                    "θi {ti} h {h}: ∫ S dω = {total}"
                );
            }
            assert!((m.albedo(ti)[0] - 1.0).abs() < 1e-9);
            let b = binned(&m, &grid, ti);
            let total: f64 = b
                .iter()
                .enumerate()
                .map(|(i, x)| x * solid_angle(grid.res_deg, i / grid.n_phi))
                .sum();
            assert!((total - 1.0).abs() < 5e-3, "binned: {total}");
        }
    }

    #[test]
    fn slice_albedo_is_the_sum_of_the_bins() {
        let m = Chiang::new(params(vec![0.0, 0.4, 3.0], 2.0));
        let grid = Grid {
            res_deg: 10.0,
            n_theta: 18,
            n_phi: 36,
        };
        for &ti in &[-1.2, -0.3, 0.5] {
            let slice = m.shape_slice(&grid, ti, bin_panels(m.s, &grid));
            let b = binned(&m, &grid, ti);
            for (c, &sa) in m.params.sigma_a.iter().enumerate() {
                let sum: f64 = b[c * grid.bins()..(c + 1) * grid.bins()]
                    .iter()
                    .enumerate()
                    .map(|(i, x)| x * solid_angle(grid.res_deg, i / grid.n_phi))
                    .sum();
                let fast = slice.albedo(sa);
                assert!((sum - fast).abs() < 1e-12, "{sum} {fast}");
                assert!(
                    (fast - m.albedo(ti)[c]).abs() < 2e-3,
                    "{fast} {:?}",
                    m.albedo(ti)
                );
            }
        }
    }

    #[test]
    fn far_values_of_the_tests_are_converged() {
        for &bn in &[0.02, 0.3] {
            let m = Chiang::new(ChiangParams {
                beta_n: bn,
                ..params(vec![0.4], -2.0)
            });
            let panels = 4 * width_panels(m.s);
            for &(ti, to, dp) in &[
                (-0.7f64, 0.7f64, 0.0f64),
                (0.2, -0.25, 2.6),
                (0.5, -0.4, 1.0),
            ] {
                let a = m.eval_far(ti, to, dp, Some(panels))[0];
                let b = m.eval_far(ti, to, dp, Some(2 * panels))[0];
                assert!((a - b).abs() < 1e-3 * b, "β_n {bn}: {a} vs {b}");
            }
        }
    }

    #[test]
    fn far_field_is_even_in_dphi_and_mirror_symmetric_without_tilt() {
        let m = Chiang::new(params(vec![0.3, 1.5], 0.0));
        for &(ti, to, dp) in &[
            (-30.0f64, 25.0f64, 40.0f64),
            (50.0, -10.0, 170.0),
            (5.0, 5.0, 95.0),
        ] {
            let (ti, to, dp) = (ti.to_radians(), to.to_radians(), dp.to_radians());
            let a = m.eval_far(ti, to, dp, Some(64));
            let b = m.eval_far(ti, to, -dp, Some(64));
            let c = m.eval_far(-ti, -to, dp, Some(64));
            for k in 0..2 {
                assert!((a[k] - b[k]).abs() <= 1e-9 * a[k].max(1e-12), "{a:?} {b:?}");
                assert!((a[k] - c[k]).abs() <= 1e-9 * a[k].max(1e-12), "{a:?} {c:?}");
            }
        }
        // Near field: h → −h mirrors Δφ.
        let x = m.eval_near(0.3, 0.45, -0.2, 0.7);
        let y = m.eval_near(0.3, -0.45, -0.2, -0.7);
        assert!((x[0] - y[0]).abs() < 1e-12 * x[0].max(1e-12));
    }

    #[test]
    fn bin_averages_match_the_point_model_integrated_over_the_bin() {
        // The fit's fast path (CDF in Δφ, Gauss–Legendre in θo) against eval_far integrated
        // numerically over a few bins.
        let m = Chiang::new(params(vec![0.2, 2.0], -4.0));
        let grid = Grid {
            res_deg: 10.0,
            n_theta: 18,
            n_phi: 36,
        };
        let ti = f64::to_radians(-35.0);
        let b = binned(&m, &grid, ti);
        let res = grid.res();
        for &(r, k) in &[(12usize, 18usize), (12, 20), (11, 2), (13, 35), (9, 27)] {
            let (x, w) = gauss_legendre(6);
            let mut acc = [0.0; 2];
            for (xu, wu) in x.iter().zip(&w) {
                let (s0, s1) = (grid.theta_lo(r).sin(), (grid.theta_lo(r) + res).sin());
                let to = (0.5 * (s0 + s1) + 0.5 * (s1 - s0) * xu).asin();
                for (xp, wp) in x.iter().zip(&w) {
                    let dphi = grid.phi_lo(k) + 0.5 * res * (1.0 + xp);
                    let v = m.eval_far(ti, to, dphi, Some(96));
                    for c in 0..2 {
                        acc[c] += 0.25 * wu * wp * v[c];
                    }
                }
            }
            for c in 0..2 {
                let fast = b[c * grid.bins() + r * grid.n_phi + k];
                assert!(
                    (fast - acc[c]).abs() < 0.02 * acc[c] + 1e-4,
                    "bin ({r}, {k}) channel {c}: binned {fast} vs integrated {}",
                    acc[c]
                );
            }
        }
    }

    /// A `.bcsdf` whose values are the binned model itself (round fiber: one stored ωi per θi
    /// row, mirrored rows flagged).
    fn table_of(model: &Chiang, res_deg: f64) -> Bcsdf {
        let n_theta = (180.0 / res_deg) as usize;
        let grid = Grid {
            res_deg,
            n_theta,
            n_phi: 2 * n_theta,
        };
        let nc = model.channels();
        let mut wi_map = vec![0u32; grid.bins()];
        let mut wi_deg = Vec::new();
        let mut slices = Vec::new();
        let mut albedo = Vec::new();
        for r in 0..n_theta {
            let ti = grid.theta_centre(r);
            let b = binned(model, &grid, ti);
            let mut values = Vec::with_capacity(b.len());
            for c in 0..nc {
                let part = &b[c * grid.bins()..(c + 1) * grid.bins()];
                let a: f64 = part
                    .iter()
                    .enumerate()
                    .map(|(i, x)| x * solid_angle(res_deg, i / grid.n_phi))
                    .sum();
                albedo.push(a as f32);
                values.extend(part.iter().map(|x| x / a));
            }
            for k in 0..grid.n_phi {
                wi_map[r * grid.n_phi + k] = r as u32;
            }
            wi_deg.push([ti.to_degrees(), -180.0 + 0.5 * res_deg]);
            slices.push(values);
        }
        // Exercise the mirror flag: the top row reuses the bottom row with θo flipped (exact
        // for α = 0).
        if model.params.alpha_deg == 0.0 {
            wi_map[(n_theta - 1) * grid.n_phi..].fill(FLIP_THETA);
        }
        let dir = Directory {
            kind: KIND.into(),
            res_deg,
            n_theta,
            n_phi: grid.n_phi,
            wi_deg,
            wi_map,
            variants: vec!["model".into()],
            channels: (0..nc).map(|c| format!("c{c}")).collect(),
            dtype: Precision::F32,
            keep_bits: 23,
            scale: vec![],
            albedo,
            albedo_se: vec![0.0; n_theta * nc],
            area_um: vec![10.0; grid.n_phi],
            chunks: vec![],
            metadata: serde_json::json!({"eta": model.params.eta}),
        };
        let mut w = Writer::new(dir, 1);
        for s in &slices {
            w.push(s).unwrap();
        }
        Bcsdf::from_bytes(w.finish().unwrap()).unwrap()
    }

    #[test]
    fn fit_recovers_the_parameters_of_a_table_made_by_the_model() {
        let truth = ChiangParams {
            eta: 1.55,
            sigma_a: vec![0.15, 0.8, 2.5],
            beta_m: 0.3,
            beta_n: 0.4,
            alpha_deg: -3.0,
        };
        let table = table_of(&Chiang::new(truth.clone()), 15.0);
        let opts = FitOptions {
            theta_i_rows: 6,
            phi_i_samples: 2,
            eta: Some(1.55),
            max_evaluations: 250,
            ..FitOptions::default()
        };
        let target = FitTarget::from_table(&table, 0, &opts).unwrap();
        let exact = evaluate(&target, &truth);
        assert!(
            exact.rel_l1 < 1e-5,
            "the table is the model: {}",
            exact.rel_l1
        );
        let r = fit(&target, &opts);
        let p = &r.params;
        assert!(r.rel_l1 < 0.01, "rel L1 {}", r.rel_l1);
        assert!((p.beta_m - 0.3).abs() < 0.02, "{p:?}");
        assert!((p.beta_n - 0.4).abs() < 0.02, "{p:?}");
        assert!((p.alpha_deg + 3.0).abs() < 0.5, "{p:?}");
        for (a, b) in p.sigma_a.iter().zip(&truth.sigma_a) {
            assert!((a / b - 1.0).abs() < 0.05, "{p:?}");
        }
        for (a, b) in r.albedo_model.iter().zip(&r.albedo_table) {
            assert!((a - b).abs() < 0.01, "{r:?}");
        }
    }

    #[test]
    fn mirrored_rows_read_back_through_the_flags() {
        let m = Chiang::new(params(vec![0.5], 0.0));
        let table = table_of(&m, 30.0);
        let opts = FitOptions {
            theta_i_rows: 6,
            max_theta_i_deg: 90.0,
            phi_i_samples: 1,
            ..FitOptions::default()
        };
        let target = FitTarget::from_table(&table, 0, &opts).unwrap();
        assert!(evaluate(&target, &m.params).rel_l1 < 1e-5);
        assert!(FitTarget::from_table(&table, 1, &opts).is_err());
    }
}
