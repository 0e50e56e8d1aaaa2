//! The normalized profile of Christensen & Burley (cb15): R/A, its CDF F, the exit-radius
//! density, its sampling and annulus energies.

use std::f64::consts::PI;

/// R(r)/A, the normalized profile at `r_mm`, mm⁻² (cb15, Eq. 3; integrates to 1).
pub fn burley_rd(r_mm: f64, d_mm: f64) -> f64 {
    let x = r_mm / d_mm;
    ((-x).exp() + (-x / 3.0).exp()) / (8.0 * PI * d_mm * r_mm)
}

/// F(r): the fraction of the profile's energy inside radius `r_mm` (cb15, Eq. 11).
pub fn burley_cdf(r_mm: f64, d_mm: f64) -> f64 {
    let x = r_mm / d_mm;
    1.0 - 0.25 * (-x).exp() - 0.75 * (-x / 3.0).exp()
}

/// dF/dr, the density of the exit radius, mm⁻¹ (Eq. 3 times 2πr, as Cycles'
/// `bssrdf_burley_eval`).
pub fn burley_radius_pdf(r_mm: f64, d_mm: f64) -> f64 {
    let x = r_mm / d_mm;
    ((-x).exp() + (-x / 3.0).exp()) / (4.0 * d_mm)
}

/// Samples an exit radius from [`burley_radius_pdf`]: the closed-form inverse of F (E. Golubev,
/// "Sampling Burley's Normalized Diffusion Profiles", 2019,
/// <https://zero-radiance.github.io/post/sampling-diffusion/>; also Unity HDRP
/// `DiffusionProfileSettings.cs`, `SampleBurleyDiffusionProfile`). `u` in \[0, 1).
pub fn sample_burley_radius(u: f64, d_mm: f64) -> f64 {
    let v = 1.0 - u; // the complementary CDF, in (0, 1]
    let g = 1.0 + 4.0 * v * (2.0 * v + (1.0 + 4.0 * v * v).sqrt());
    let n = g.powf(-1.0 / 3.0);
    let c = 1.0 + g * n * n + n; // 1 + g^(1/3) + g^(−1/3)
    3.0 * (c / (4.0 * v)).ln() * d_mm
}

/// Energy of the normalized profile in the annulus \[a, b\]: F(b) − F(a), written as a sum of
/// positive differences so thin annuli far out keep their digits.
#[inline]
pub fn burley_energy(d_mm: f64, a_mm: f64, b_mm: f64) -> f64 {
    let d3 = 3.0 * d_mm;
    0.25 * ((-a_mm / d_mm).exp() - (-b_mm / d_mm).exp())
        + 0.75 * ((-a_mm / d3).exp() - (-b_mm / d3).exp())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn closed_forms_agree() {
        let d = 0.37;
        // F is the integral of the pdf, the pdf is 2πr·R, and F(∞) = 1.
        let (mut r, h) = (0.0, 1e-4);
        let mut f = 0.0;
        while r < 30.0 * d {
            f += 0.5 * h * (burley_radius_pdf(r, d) + burley_radius_pdf(r + h, d));
            r += h;
            let rm = r - 0.5 * h;
            let diff = burley_radius_pdf(rm, d) - 2.0 * PI * rm * burley_rd(rm, d);
            assert!(diff.abs() < 1e-9, "pdf vs profile at {rm}: {diff}");
        }
        assert!(
            (f - burley_cdf(r, d)).abs() < 1e-7,
            "{f} vs {}",
            burley_cdf(r, d)
        );
        assert!((burley_cdf(1e6, d) - 1.0).abs() < 1e-15);
        assert_eq!(burley_cdf(0.0, d), 0.0);
        let (a, b) = (1.3, 1.4);
        assert!((burley_energy(d, a, b) - (burley_cdf(b, d) - burley_cdf(a, d))).abs() < 1e-15);
    }

    #[test]
    fn sampling_inverts_the_cdf() {
        for &d in &[0.05, 1.0, 7.5] {
            for i in 0..1000 {
                let u = (i as f64 + 0.5) / 1000.0;
                let r = sample_burley_radius(u, d);
                assert!(
                    (burley_cdf(r, d) - u).abs() < 1e-12,
                    "d {d} u {u}: F(r) = {}",
                    burley_cdf(r, d)
                );
            }
        }
        assert_eq!(sample_burley_radius(0.0, 1.0), 0.0);
    }
}
