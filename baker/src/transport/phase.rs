//! Henyey–Greenstein phase function: sampler, pdf and inverse, in pbrt's threes.

/// Henyey–Greenstein with anisotropy `g`, its constants computed once (the sampler runs at
/// every scattering event).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Hg {
    pub g: f64,
    one_minus_g2: f64,
    one_minus_g: f64,
    two_g: f64,
    one_plus_g2: f64,
    inv_two_g: f64,
}

impl Hg {
    pub fn new(g: f64) -> Self {
        Self {
            g,
            one_minus_g2: 1.0 - g * g,
            one_minus_g: 1.0 - g,
            two_g: 2.0 * g,
            one_plus_g2: 1.0 + g * g,
            inv_two_g: 0.5 / g,
        }
    }

    /// cos θ for a uniform `u` in (0, 1] (Jacques' inversion, as in MCML's SpinTheta).
    #[inline(always)]
    pub fn sample(&self, u: f64) -> f64 {
        if self.g.abs() < 1e-6 {
            return 2.0 * u - 1.0;
        }
        let t = self.one_minus_g2 / (self.one_minus_g + self.two_g * u);
        ((self.one_plus_g2 - t * t) * self.inv_two_g).clamp(-1.0, 1.0)
    }
}

/// cos θ sampled from HG with anisotropy `g` for a uniform `u` in (0, 1] ([`Hg::sample`]).
#[inline]
pub fn sample_hg(g: f64, u: f64) -> f64 {
    Hg::new(g).sample(u)
}

/// HG density in cos θ (integrates to 1 over [−1, 1]).
pub fn hg_pdf(g: f64, cos_theta: f64) -> f64 {
    0.5 * (1.0 - g * g) / (1.0 + g * g - 2.0 * g * cos_theta).powf(1.5)
}

/// The `u` that [`sample_hg`] maps to `cos_theta` (its CDF).
pub fn invert_hg_sample(g: f64, cos_theta: f64) -> f64 {
    if g.abs() < 1e-6 {
        return 0.5 * (cos_theta + 1.0);
    }
    let t = (1.0 + g * g - 2.0 * g * cos_theta).sqrt();
    ((1.0 - g * g) / t - (1.0 - g)) / (2.0 * g)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::stats::chi2::chi2_test_1d;

    #[test]
    fn sampler_inverts_its_cdf() {
        for g in [-0.7, 0.0, 0.5, 0.9] {
            for u in [0.01, 0.3, 0.77, 1.0] {
                assert!(
                    (invert_hg_sample(g, sample_hg(g, u)) - u).abs() < 1e-9,
                    "g {g} u {u}"
                );
            }
        }
    }

    #[test]
    fn sampler_matches_pdf_chi2() {
        use rand_core::Rng;
        for g in [0.0, 0.75, 0.9, -0.5] {
            let mut rng = crate::math::rng::batch_rng(7, 0);
            let samples: Vec<f64> = (0..200_000)
                .map(|_| sample_hg(g, crate::math::rng::uniform(rng.next_u64())))
                .collect();
            chi2_test_1d(
                &samples,
                -1.0,
                1.0,
                51,
                |c| hg_pdf(g, c),
                &format!("hg_g{g}"),
            );
        }
    }

    #[test]
    fn mean_cosine_is_g() {
        // ∫ cos θ p(cos θ) d cos θ = g, by midpoint quadrature.
        for g in [0.3, 0.9] {
            let n = 200_000;
            let m: f64 = (0..n)
                .map(|i| {
                    let c = -1.0 + (i as f64 + 0.5) * 2.0 / n as f64;
                    c * hg_pdf(g, c) * 2.0 / n as f64
                })
                .sum();
            assert!((m - g).abs() < 1e-4, "{m}");
        }
    }
}
