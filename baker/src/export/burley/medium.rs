//! The medium behind a Burley (A, d) profile for engines without a BSSRDF (Mitsuba 3): the
//! single-scattering albedo of an index-matched half-space of isotropic scatterers whose
//! normal-incidence albedo is A, through Chandrasekhar's H-function.

use std::f64::consts::PI;

use crate::math::quadrature::gauss_legendre_to;

/// Chandrasekhar's H-function of isotropic scattering at μ = 1 for single-scattering albedo
/// α < 1, from its explicit integral form (S. Chandrasekhar, "Radiative Transfer", 1950/1960;
/// the H-function of isotropic scattering):
/// ln H(μ) = −(μ/π)·∫₀^(π/2) ln(1 − α·θ·cot θ) / (cos²θ + μ²·sin²θ) dθ, at μ = 1 (64-point
/// Gauss–Legendre; the integrand is smooth for α < 1).
pub fn chandrasekhar_h1(alpha: f64) -> f64 {
    let (x, w) = gauss_legendre_64();
    let half = 0.25 * PI; // [0, π/2] = half·(x + 1)
    let integral: f64 = x
        .iter()
        .zip(w.iter())
        .map(|(&xi, &wi)| {
            let t = half * (xi + 1.0);
            wi * half * (1.0 - alpha * t / t.tan()).ln()
        })
        .sum();
    (-integral / PI).exp()
}

/// Albedo for normal incidence of an index-matched half-space of isotropic scatterers with
/// single-scattering albedo α: R = 1 − H(1)·√(1 − α) (Chandrasekhar, "Radiative Transfer":
/// the plane albedo of a semi-infinite atmosphere, 1 − H(μ₀)·√(1 − ϖ₀), at μ₀ = 1). This is the
/// quantity our tables hold (a pencil beam at normal incidence), where van de Hulst's relation
/// quoted by OpenPBR is the albedo under uniform illumination (larger: 0.356 against 0.299 at
/// α = 0.814).
pub fn normal_incidence_albedo(alpha: f64) -> f64 {
    if alpha >= 1.0 {
        return 1.0;
    }
    1.0 - chandrasekhar_h1(alpha) * (1.0 - alpha).max(0.0).sqrt()
}

/// The single-scattering albedo α whose [`normal_incidence_albedo`] is `a` (bisection; `a` is
/// clamped to \[0, 1\]).
pub fn single_scattering_albedo(a: f64) -> f64 {
    let a = a.clamp(0.0, 1.0);
    let (mut lo, mut hi) = (0.0f64, 1.0f64);
    for _ in 0..60 {
        let mid = 0.5 * (lo + hi);
        if normal_incidence_albedo(mid) < a {
            lo = mid;
        } else {
            hi = mid;
        }
    }
    0.5 * (lo + hi)
}

/// Nodes (descending) and weights of 64-point Gauss–Legendre quadrature on \[−1, 1\],
/// computed once: [`gauss_legendre_to`] with Newton stopped below 1e-16, finer than
/// [`gauss_legendre`]'s 1e-15 (six of the 64 weights differ in their last bits between the
/// two), in the descending order [`chandrasekhar_h1`] has always summed them: the H-function
/// feeds the single-scattering albedo of the Mitsuba skin export, pinned bit for bit.
///
/// [`gauss_legendre`]: crate::math::quadrature::gauss_legendre
fn gauss_legendre_64() -> &'static (Vec<f64>, Vec<f64>) {
    static NODES: std::sync::OnceLock<(Vec<f64>, Vec<f64>)> = std::sync::OnceLock::new();
    NODES.get_or_init(|| {
        let (mut x, mut w) = gauss_legendre_to(64, 1e-16);
        x.reverse();
        w.reverse();
        (x, w)
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn h_function_matches_its_integral_equation() {
        // Independent route: iterate H(μ) = 1 / (1 − (α/2)·μ·∫₀¹ H(μ′)/(μ + μ′) dμ′) on a
        // 200-point midpoint grid, then evaluate at μ = 1.
        let n = 400;
        let mu: Vec<f64> = (0..n).map(|i| (i as f64 + 0.5) / n as f64).collect();
        for &alpha in &[0.3, 0.814, 0.95] {
            let mut h = vec![1.0; n];
            for _ in 0..500 {
                h = mu
                    .iter()
                    .map(|&m| {
                        let s: f64 = mu.iter().zip(&h).map(|(&m2, &h2)| h2 / (m + m2)).sum();
                        1.0 / (1.0 - 0.5 * alpha * m * s / n as f64)
                    })
                    .collect();
            }
            let s: f64 = mu.iter().zip(&h).map(|(&m2, &h2)| h2 / (1.0 + m2)).sum();
            let h1 = 1.0 / (1.0 - 0.5 * alpha * s / n as f64);
            let ours = chandrasekhar_h1(alpha);
            assert!((ours / h1 - 1.0).abs() < 1e-4, "α {alpha}: {ours} vs {h1}");
        }
        // Conservative limit H(1) = 2.9078 (Chandrasekhar's table for ϖ₀ = 1).
        assert!((chandrasekhar_h1(1.0 - 1e-12) - 2.9078).abs() < 2e-3);
    }

    #[test]
    fn normal_incidence_albedo_inverts() {
        for i in 1..100 {
            let a = i as f64 / 100.0;
            let alpha = single_scattering_albedo(a);
            assert!(
                (normal_incidence_albedo(alpha) - a).abs() < 1e-12,
                "A {a}: α {alpha}"
            );
        }
        assert_eq!(normal_incidence_albedo(0.0), 0.0);
        assert!(single_scattering_albedo(1.0) > 1.0 - 1e-12);
        // A Monte Carlo half-space (isotropic, index-matched, normal incidence) gives
        // 0.2986 ± 0.001 at α = 0.814 (validation/check_export_skin.py renders the same in
        // Mitsuba 3).
        assert!((normal_incidence_albedo(0.814) - 0.2990).abs() < 5e-4);
    }

    #[test]
    fn gauss_legendre_64_is_the_node_by_node_table() {
        // The table this module computed before it shared the quadrature: every node by
        // Newton from its own start (the negative ones too, not mirrored), stopped below
        // 1e-16, in descending order. Bit for bit, so the Mitsuba export keeps its bytes.
        const N: usize = 64;
        let (x, w) = gauss_legendre_64();
        for i in 0..N {
            let mut z = (PI * (i as f64 + 0.75) / (N as f64 + 0.5)).cos();
            let mut dp = 1.0;
            for _ in 0..100 {
                let (mut p0, mut p1) = (1.0, z);
                for k in 2..=N {
                    let k = k as f64;
                    (p0, p1) = (p1, ((2.0 * k - 1.0) * z * p1 - (k - 1.0) * p0) / k);
                }
                dp = N as f64 * (z * p1 - p0) / (z * z - 1.0);
                let dz = p1 / dp;
                z -= dz;
                if dz.abs() < 1e-16 {
                    break;
                }
            }
            assert_eq!(x[i].to_bits(), z.to_bits(), "node {i}");
            let wi = 2.0 / ((1.0 - z * z) * dp * dp);
            assert_eq!(w[i].to_bits(), wi.to_bits(), "weight {i}");
        }
    }
}
