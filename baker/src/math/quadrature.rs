//! Gauss–Legendre quadrature on \[−1, 1\] and its composite form on an interval.
//!
//! The nodes are the roots of the Legendre polynomial Pₙ, found by Newton's method on
//! Bonnet's recurrence k·Pₖ(z) = (2k − 1)·z·Pₖ₋₁(z) − (k − 1)·Pₖ₋₂(z), started from
//! cos(π(i + ¾)/(n + ½)); the weights are wᵢ = 2/((1 − zᵢ²)·Pₙ′(zᵢ)²) (Abramowitz & Stegun
//! 25.4.29), with Pₙ′(z) = n·(z·Pₙ(z) − Pₙ₋₁(z))/(z² − 1). Only the roots z > 0 are iterated;
//! the others are their mirror images, so the rule is exactly symmetric.

use std::f64::consts::PI;

/// Newton stopping step of [`gauss_legendre`]: iteration ends once a step is below it.
pub const NEWTON_TOLERANCE: f64 = 1e-15;

/// Gauss–Legendre nodes (ascending) and weights on \[−1, 1\] (Newton on the Legendre
/// recurrence, [`NEWTON_TOLERANCE`]).
pub fn gauss_legendre(n: usize) -> (Vec<f64>, Vec<f64>) {
    gauss_legendre_to(n, NEWTON_TOLERANCE)
}

/// [`gauss_legendre`] with Newton's iteration stopped at the first step below `tolerance`.
///
/// The weight uses Pₙ′ at the last iterate *before* the final step, so the tolerance shows in
/// the weights' last bits (at n = 64, 1e-16 and 1e-15 give the same nodes but six weights one
/// or a few ulps apart); callers whose outputs depend on those bits keep their tolerance.
pub fn gauss_legendre_to(n: usize, tolerance: f64) -> (Vec<f64>, Vec<f64>) {
    let (mut x, mut w) = (vec![0.0; n], vec![0.0; n]);
    for i in 0..n.div_ceil(2) {
        let mut z = (PI * (i as f64 + 0.75) / (n as f64 + 0.5)).cos();
        let mut dp = 1.0;
        for _ in 0..100 {
            let (mut p0, mut p1) = (1.0, z);
            for k in 2..=n {
                // k·Pₖ = (2k − 1)·z·Pₖ₋₁ − (k − 1)·Pₖ₋₂
                let p2 = ((2 * k - 1) as f64 * z * p1 - (k - 1) as f64 * p0) / k as f64;
                p0 = p1;
                p1 = p2;
            }
            let pn = if n == 1 { z } else { p1 };
            let pm = if n == 1 { 1.0 } else { p0 };
            // Pₙ′(z) = n·(z·Pₙ − Pₙ₋₁)/(z² − 1)
            dp = n as f64 * (z * pn - pm) / (z * z - 1.0);
            let dz = pn / dp;
            z -= dz;
            if dz.abs() < tolerance {
                break;
            }
        }
        x[i] = -z;
        x[n - 1 - i] = z;
        // wᵢ = 2/((1 − zᵢ²)·Pₙ′(zᵢ)²) (A&S 25.4.29)
        w[i] = 2.0 / ((1.0 - z * z) * dp * dp);
        w[n - 1 - i] = w[i];
    }
    (x, w)
}

/// Composite Gauss–Legendre on \[a, b\]: `panels` equal panels of `order` nodes each, as
/// (node, weight) pairs in ascending order.
pub fn composite_gauss_legendre(a: f64, b: f64, panels: usize, order: usize) -> Vec<(f64, f64)> {
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

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn gauss_legendre_integrates_polynomials_exactly() {
        let (x, w) = gauss_legendre(6);
        let integral: f64 = x.iter().zip(&w).map(|(x, w)| w * x.powi(10)).sum();
        assert!((integral - 2.0 / 11.0).abs() < 1e-13, "{integral}");
        assert!((w.iter().sum::<f64>() - 2.0).abs() < 1e-13);
    }

    #[test]
    fn the_tolerance_moves_only_weight_bits() {
        // The two tolerances in use (fiber fit 1e-15, Chandrasekhar's H 1e-16) at n = 64:
        // identical nodes, weights equal to the last few bits (so each caller keeps its own).
        let (x15, w15) = gauss_legendre_to(64, 1e-15);
        let (x16, w16) = gauss_legendre_to(64, 1e-16);
        assert!(x15
            .iter()
            .zip(&x16)
            .all(|(a, b)| a.to_bits() == b.to_bits()));
        let differ = w15
            .iter()
            .zip(&w16)
            .filter(|(a, b)| a.to_bits() != b.to_bits())
            .count();
        assert_eq!(differ, 6);
        assert!(w15.iter().zip(&w16).all(|(a, b)| (a - b).abs() < 1e-15));
        // Symmetric: x(n−1−i) = −x(i), w(n−1−i) = w(i).
        for i in 0..64 {
            assert_eq!(x16[63 - i].to_bits(), (-x16[i]).to_bits());
            assert_eq!(w16[63 - i].to_bits(), w16[i].to_bits());
        }
    }

    #[test]
    fn composite_rule_integrates_each_panel() {
        let nodes = composite_gauss_legendre(-1.0, 3.0, 4, 3);
        assert_eq!(nodes.len(), 12);
        let integral: f64 = nodes.iter().map(|(x, w)| w * x.powi(5)).sum();
        assert!(
            (integral - (3f64.powi(6) - 1.0) / 6.0).abs() < 1e-10,
            "{integral}"
        );
    }
}
