//! Dermal collagen fiber diameters and the Mie exponent γ they produce, §3.4.4 (Eqs. 8–9).

use super::params::{CollagenAging, SkewNormal};
use super::piecewise_linear;

/// Fiber diameter range of the γ(d) mapping, µm (§3.4.4).
pub const D_MIN_UM: f64 = 1.15;
pub const D_MAX_UM: f64 = 35.0;
/// γ at the thinnest and thickest fibers (§3.4.4, after Zhao et al.).
pub const GAMMA_MAX: f64 = 4.0;
pub const GAMMA_MIN: f64 = 0.2;
/// Quadrature nodes over [D_MIN_UM, D_MAX_UM] for Eq. 9's sums.
pub const N_DIAMETERS: usize = 512;

/// γ(d): the "inverse linear approximation" of §3.4.4, γ = a/d + b, through
/// (D_MIN_UM, GAMMA_MAX) and (D_MAX_UM, GAMMA_MIN). Thin fibers scatter with a steep
/// wavelength dependence, thick ones almost flat.
pub fn gamma_of_diameter(d_um: f64) -> f64 {
    let a = (GAMMA_MAX - GAMMA_MIN) / (1.0 / D_MIN_UM - 1.0 / D_MAX_UM);
    let b = GAMMA_MIN - a / D_MAX_UM;
    a / d_um + b
}

/// Standard normal pdf φ.
fn phi(z: f64) -> f64 {
    (-0.5 * z * z).exp() / (2.0 * std::f64::consts::PI).sqrt()
}

/// Standard normal cdf Φ (Abramowitz & Stegun 7.1.26 through erf, |error| < 1.5e-7).
fn big_phi(z: f64) -> f64 {
    0.5 * (1.0 + erf(z / std::f64::consts::SQRT_2))
}

fn erf(x: f64) -> f64 {
    // Abramowitz & Stegun 7.1.26.
    let t = 1.0 / (1.0 + 0.327_591_1 * x.abs());
    let y = 1.0
        - (((((1.061_405_429 * t - 1.453_152_027) * t) + 1.421_413_741) * t - 0.284_496_736) * t
            + 0.254_829_592)
            * t
            * (-x * x).exp();
    if x >= 0.0 {
        y
    } else {
        -y
    }
}

/// Eq. 8: h(d) = 2·φ(z)·Φ(ζ·z)/σ with z = (d − d̄)/σ, the skew-normal density with location d̄,
/// scale σ and shape ζ (Eq. 8 as printed writes Φ(ζd; d̄, σ); we use the standard
/// parametrisation, which it abbreviates).
pub fn skew_normal_pdf(s: &SkewNormal, d_um: f64) -> f64 {
    let z = (d_um - s.location_um) / s.scale_um;
    2.0 * phi(z) * big_phi(s.shape * z) / s.scale_um // Eq. 8
}

/// The distribution at `age_years`: parameters linear from 30 to 80, held outside (§3.4.4).
pub fn distribution_at(c: &CollagenAging, age_years: f64) -> SkewNormal {
    let lerp = |a: f64, b: f64| piecewise_linear(&[(30.0, a), (80.0, b)], age_years);
    SkewNormal {
        location_um: lerp(c.at_30.location_um, c.at_80.location_um),
        scale_um: lerp(c.at_30.scale_um, c.at_80.scale_um),
        shape: lerp(c.at_30.shape, c.at_80.shape),
    }
}

/// Eq. 9's weights: (γ(d), h(d)/Σh) at midpoint nodes over the diameter range.
pub fn gamma_weights(s: &SkewNormal) -> Vec<(f64, f64)> {
    let dd = (D_MAX_UM - D_MIN_UM) / N_DIAMETERS as f64;
    let nodes: Vec<(f64, f64)> = (0..N_DIAMETERS)
        .map(|i| {
            let d = D_MIN_UM + (i as f64 + 0.5) * dd;
            (gamma_of_diameter(d), skew_normal_pdf(s, d))
        })
        .collect();
    let total: f64 = nodes.iter().map(|n| n.1).sum();
    nodes.into_iter().map(|(g, h)| (g, h / total)).collect()
}

/// Eq. 9: the Mie term's spectral shape (λ/λr)^-γ averaged over the diameter distribution.
pub fn mie_shape(weights: &[(f64, f64)], lambda_over_ref: f64) -> f64 {
    weights
        .iter()
        .map(|&(g, w)| w * lambda_over_ref.powf(-g))
        .sum() // Eq. 9
}

/// Single γ with the same (λ/λr)^-γ at `lambda_over_ref` as the distribution: a summary for
/// reports and plots.
pub fn effective_gamma(weights: &[(f64, f64)], lambda_over_ref: f64) -> f64 {
    -mie_shape(weights, lambda_over_ref).ln() / lambda_over_ref.ln()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn gamma_mapping_hits_its_end_points() {
        assert!((gamma_of_diameter(D_MIN_UM) - GAMMA_MAX).abs() < 1e-12);
        assert!((gamma_of_diameter(D_MAX_UM) - GAMMA_MIN).abs() < 1e-12);
    }

    #[test]
    fn skew_normal_integrates_to_one_and_skews_right() {
        let s = SkewNormal {
            location_um: 10.0,
            scale_um: 2.0,
            shape: 4.0,
        };
        let n = 20_000;
        let (lo, hi) = (-10.0, 40.0);
        let dx = (hi - lo) / n as f64;
        let (mut mass, mut mean) = (0.0, 0.0);
        for i in 0..n {
            let x = lo + (i as f64 + 0.5) * dx;
            mass += skew_normal_pdf(&s, x) * dx;
            mean += x * skew_normal_pdf(&s, x) * dx;
        }
        assert!((mass - 1.0).abs() < 1e-6, "{mass}");
        // Mean of a skew normal: ξ + ω·δ·√(2/π), δ = α/√(1+α²).
        let delta = 4.0 / 17f64.sqrt();
        let expected = 10.0 + 2.0 * delta * (2.0 / std::f64::consts::PI).sqrt();
        assert!((mean - expected).abs() < 1e-4, "{mean} vs {expected}");
    }

    #[test]
    fn thicker_fibers_flatten_the_spectrum() {
        let young = gamma_weights(&crate::skin::params::COLLAGEN_RD_DEFAULT.at_30);
        let old = gamma_weights(&crate::skin::params::COLLAGEN_RD_DEFAULT.at_80);
        assert!(effective_gamma(&old, 0.8) < effective_gamma(&young, 0.8));
    }
}
