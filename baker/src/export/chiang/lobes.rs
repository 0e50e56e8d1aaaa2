//! The lobes of the Chiang model as mitsuba3 `hair.cpp` and `warp.h` evaluate them: the
//! longitudinal Mp (d'Eon et al. 2011, Chiang Eq. 7) and the azimuthal Np (a trimmed logistic
//! around the smooth path's azimuth, Chiang Eq. 8–10).

use std::f64::consts::{PI, TAU};

use super::safe_sqrt;

/// Lobes evaluated explicitly (R, TT, TRT); the rest is the residual term (`hair.cpp` P_MAX).
pub const P_MAX: usize = 3;

/// Longitudinal variances v₀…v₃ of β_m (`hair.cpp` `update()`; Chiang Eq. 7).
pub fn longitudinal_variances(beta_m: f64) -> [f64; P_MAX + 1] {
    let v0 = (0.726 * beta_m + 0.812 * beta_m.powi(2) + 3.7 * beta_m.powi(20)).powi(2);
    [v0, 0.25 * v0, 4.0 * v0, 4.0 * v0]
}

/// Logistic scale s of β_n (`hair.cpp` `update()`; Chiang Eq. 8).
pub fn logistic_scale(beta_n: f64) -> f64 {
    (PI / 8.0).sqrt() * (0.265 * beta_n + 1.194 * beta_n.powi(2) + 5.372 * beta_n.powi(22))
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
pub(super) fn rough_fiber_pdf(sin_i: f64, sin_o: f64, kappa: f64) -> f64 {
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

/// Logistic CDF (`hair.cpp` `logistic_cdf`).
pub(super) fn logistic_cdf(x: f64, s: f64) -> f64 {
    1.0 / (1.0 + (-x / s).exp())
}

/// Logistic density (`hair.cpp` `logistic`).
pub(super) fn logistic(x: f64, s: f64) -> f64 {
    let e = (-x.abs() / s).exp();
    e / (s * (1.0 + e) * (1.0 + e))
}

/// Φ(p, γi, γt) = 2p γt − 2γi + pπ, the azimuth of the smooth path (Chiang Eq. 9).
pub(super) fn perfect_dphi(p: usize, gamma_i: f64, gamma_t: f64) -> f64 {
    let p = p as f64;
    2.0 * p * gamma_t - 2.0 * gamma_i + p * PI
}
