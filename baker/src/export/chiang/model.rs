//! The Chiang et al. 2016 BSDF of a fiber (near field at offset h, and its far-field average
//! over the width), evaluated as mitsuba3 `hair.cpp` `Hair::eval` does.

use std::f64::consts::{FRAC_PI_2, PI, TAU};

use serde::Serialize;

use super::frame::{gamma_of, local_direction, local_wi};
use super::lobes::{
    logistic, logistic_cdf, logistic_scale, longitudinal_variances, perfect_dphi, rough_fiber_pdf,
    P_MAX,
};
use super::{safe_asin, safe_sqrt};
use crate::math::fresnel;
use crate::math::quadrature::composite_gauss_legendre;

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

/// What the incidence (θi, h) fixes for every lobe and channel: the refracted angles, the
/// Fresnel factor and the chord length through the fiber.
#[derive(Debug, Clone, Copy)]
pub(super) struct Incidence {
    pub(super) gamma_i: f64,
    pub(super) gamma_t: f64,
    pub(super) fresnel: f64,
    /// 2 cos γt / cos θt, in fiber radii.
    pub(super) path: f64,
}

/// Nodes (γ, weight) of ½∫ dh over the fiber width, h = sin γ: weights include ½ cos γ and sum
/// to 1.
pub fn width_nodes(panels: usize) -> Vec<(f64, f64)> {
    composite_gauss_legendre(-FRAC_PI_2, FRAC_PI_2, panels, 8)
        .into_iter()
        .map(|(g, w)| (g, 0.5 * w * g.cos()))
        .collect()
}

/// Panels of 8 nodes in γ that resolve a logistic of scale s (≥ 12, ≤ 256).
pub(super) fn width_panels(s: f64) -> usize {
    ((PI / (1.5 * s)).ceil() as usize).clamp(12, 256)
}

/// The model with its derived constants (`hair.cpp` `update()`).
#[derive(Debug, Clone)]
pub struct Chiang {
    pub params: ChiangParams,
    pub(super) v: [f64; P_MAX + 1],
    pub(super) s: f64,
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
    pub(super) fn reframe(&self, sin_t: f64, cos_t: f64, p: usize) -> (f64, f64) {
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
    pub(super) fn incidence(&self, sin_theta_i: f64, cos_theta_i: f64, gamma_i: f64) -> Incidence {
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
        let fresnel = fresnel::dielectric_mitsuba(cos_theta_i * cos_gamma_i, eta);
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
    pub(super) fn azimuthal_cdf(&self, x: f64) -> f64 {
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

#[cfg(test)]
pub(super) mod tests {
    use super::*;
    use crate::export::chiang::{binned, FitGrid};
    use crate::math::quadrature::gauss_legendre;
    use formats::bcsdf::solid_angle;

    pub(in crate::export::chiang) fn params(sigma_a: Vec<f64>, alpha_deg: f64) -> ChiangParams {
        ChiangParams {
            eta: 1.55,
            sigma_a,
            beta_m: 0.25,
            beta_n: 0.3,
            alpha_deg,
        }
    }

    #[test]
    fn white_furnace_near_and_far_conserve_energy() {
        // σa = 0: Σ Ap = 1, so ∫ S dωo = 1 at every h (Mitsuba's test_hair.py white furnace),
        // up to the I₀ series of warp.h.
        let m = Chiang::new(params(vec![0.0], 3.0));
        let grid = FitGrid {
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
}
