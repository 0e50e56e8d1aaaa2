//! Fresnel reflectance of unpolarised light at a dielectric interface: R = ½(rs² + rp²) with
//! the amplitude ratios of the Fresnel equations (Born & Wolf, *Principles of Optics*, §1.5.2).
//!
//! Two formulas, on purpose. [`dielectric`] (Monte Carlo transport in skin layers and the
//! fiber's facets) takes both indices; [`dielectric_mitsuba`] (the Chiang hair model of the
//! fiber export) is mitsuba3 `fresnel.h` `fresnel`, which takes their ratio and divides the
//! amplitude ratios through by the incident index. They are the same physics but not the same
//! floating-point operations: for light from air at η ∈ {1.33, …, 1.635} about 6 % of cosines
//! give results one ulp or so apart. Every table, export and Monte Carlo result is pinned bit
//! for bit, so each caller keeps its formula; neither is rewritten in terms of the other.

/// [`dielectric`]'s reflectance in single precision and with no branch, so a loop over many
/// cosines vectorises eight lanes wide (the exit-lobe densities of `fiber::surface::FacetPdf`):
/// under total internal reflection cos θt is 0 and the amplitude ratios are ±1, R = 1 exactly.
/// Needs `ni` ≠ `nt` and `cos_i` > 0 (otherwise a meaningless value, which callers mask out).
#[inline(always)]
pub fn reflectance_branch_free(ni: f32, nt: f32, cos_i: f32) -> f32 {
    let eta = ni / nt;
    let sin_t2 = eta * eta * (1.0 - cos_i * cos_i);
    let cos_t = (1.0 - sin_t2).max(0.0).sqrt();
    let rs = (ni * cos_i - nt * cos_t) / (ni * cos_i + nt * cos_t);
    let rp = (ni * cos_t - nt * cos_i) / (ni * cos_t + nt * cos_i);
    0.5 * (rs * rs + rp * rp)
}

/// Reflectance for a ray arriving with cos θi = `cos_i` (> 0) from index `ni` into `nt`, and the
/// cosine of the transmitted angle (0 under total internal reflection).
#[inline]
pub fn dielectric(ni: f64, nt: f64, cos_i: f64) -> (f64, f64) {
    if ni == nt {
        return (0.0, cos_i);
    }
    let Some(([a, b, c, d], cos_t)) = amplitude_terms(ni, nt, cos_i) else {
        return (1.0, 0.0);
    };
    let rs = a / b;
    let rp = c / d;
    (0.5 * (rs * rs + rp * rp), cos_t)
}

/// Whether a uniform number `u` in [0, 1) picks reflection, u < R with R [`dielectric`]'s
/// reflectance, decided without a division: with the amplitude ratios rs = A/B and rp = C/D
/// (B, D > 0), R = ½(A²/B² + C²/D²), so u < R ⟺ 2u·B²D² < A²D² + C²B².
/// Returns the choice and cos θt (0 under total internal reflection, which always reflects).
/// The same choice as `u < dielectric(ni, nt, cos_i).0` except within rounding of u = R
/// (tested); the Monte Carlo samplers of the fiber's facets draw with it (two divisions
/// fewer per draw).
#[inline]
pub fn reflects(ni: f64, nt: f64, cos_i: f64, u: f64) -> (bool, f64) {
    if ni == nt {
        return (false, cos_i);
    }
    let Some(([a, b, c, d], cos_t)) = amplitude_terms(ni, nt, cos_i) else {
        return (true, 0.0);
    };
    let (b2, d2) = (b * b, d * d);
    (2.0 * u * b2 * d2 < a * a * d2 + c * c * b2, cos_t)
}

/// The amplitude ratios' numerators and denominators, rs = A/B and rp = C/D with
/// A = ni cos θi − nt cos θt, B = ni cos θi + nt cos θt, C = ni cos θt − nt cos θi and
/// D = ni cos θt + nt cos θi, and cos θt by Snell; `None` under total internal reflection.
#[inline]
fn amplitude_terms(ni: f64, nt: f64, cos_i: f64) -> Option<([f64; 4], f64)> {
    let eta = ni / nt;
    // Snell: sin²θt = (ni/nt)²·(1 − cos²θi)
    let sin_t2 = eta * eta * (1.0 - cos_i * cos_i);
    if sin_t2 >= 1.0 {
        return None;
    }
    let cos_t = (1.0 - sin_t2).sqrt();
    Some((
        [
            ni * cos_i - nt * cos_t,
            ni * cos_i + nt * cos_t,
            ni * cos_t - nt * cos_i,
            ni * cos_t + nt * cos_i,
        ],
        cos_t,
    ))
}

/// Specular reflectance at normal incidence, ((n1 − n2)/(n1 + n2))².
pub fn normal_reflectance(n1: f64, n2: f64) -> f64 {
    let r = (n1 - n2) / (n1 + n2);
    r * r
}

/// Unpolarised Fresnel reflectance of a dielectric of relative index `eta` (inside over
/// outside) for cos θi = `cos_theta_i`, negative from inside (mitsuba3 `fresnel.h` `fresnel`).
pub fn dielectric_mitsuba(cos_theta_i: f64, eta: f64) -> f64 {
    let outside = cos_theta_i >= 0.0;
    let (eta_it, eta_ti) = if outside {
        (eta, 1.0 / eta)
    } else {
        (1.0 / eta, eta)
    };
    let cos_t_sqr = 1.0 - (1.0 - cos_theta_i * cos_theta_i) * eta_ti * eta_ti;
    let ci = cos_theta_i.abs();
    let ct = cos_t_sqr.max(0.0).sqrt();
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

#[cfg(test)]
mod tests {
    use super::*;
    use crate::math::rng::{batch_rng, uniform};
    use rand_core::Rng;

    #[test]
    fn reflects_is_the_reflectance_draw() {
        // Against `u < R` over random cosines and numbers, both sides of every interface (a
        // planted slip, the factor 2 dropped, fails it).
        let mut rng = batch_rng(7, 0);
        let mut next = || uniform(rng.next_u64());
        let mut near = 0;
        for (ni, nt) in [(1.0, 1.53), (1.53, 1.0), (1.0, 1.33), (1.635, 1.0)] {
            for _ in 0..200_000 {
                let cos_i = next().max(1e-300);
                let u = next() * next().sqrt();
                let (r, cos_t) = dielectric(ni, nt, cos_i);
                let (refl, cos_t2) = reflects(ni, nt, cos_i, u);
                assert_eq!(cos_t, cos_t2);
                if (u - r).abs() <= 1e-14 {
                    near += 1;
                    continue;
                }
                assert_eq!(refl, u < r, "ni {ni} nt {nt} cos_i {cos_i} u {u} R {r}");
            }
        }
        assert!(near < 10, "{near} draws within rounding of R");
        assert_eq!(reflects(1.0, 1.0, 0.3, 0.0), (false, 0.3));
        assert!(
            reflects(1.5, 1.0, 0.1, 0.999_999).0,
            "total internal reflection"
        );
    }

    #[test]
    fn normal_incidence_matches_closed_form() {
        let (r, c) = dielectric(1.0, 1.5, 1.0);
        assert!((r - 0.04).abs() < 1e-15 && (c - 1.0).abs() < 1e-15);
    }

    #[test]
    fn total_internal_reflection_beyond_critical_angle() {
        let crit = (1.0f64 / 1.5).asin();
        assert_eq!(dielectric(1.5, 1.0, (crit + 0.01).cos()).0, 1.0);
        assert!(dielectric(1.5, 1.0, (crit - 0.01).cos()).0 < 1.0);
    }

    #[test]
    fn reflectance_is_reciprocal() {
        // R(ni→nt, θi) = R(nt→ni, θt).
        let (r1, cos_t) = dielectric(1.0, 1.4, 0.6);
        let (r2, _) = dielectric(1.4, 1.0, cos_t);
        assert!((r1 - r2).abs() < 1e-12);
    }

    #[test]
    fn both_formulas_are_the_same_physics() {
        // Equal to rounding from air and from inside, total internal reflection included.
        for &eta in &[1.33, 1.55, 1.635] {
            for i in 0..=100 {
                let c = i as f64 / 100.0;
                let (outside, _) = dielectric(1.0, eta, c);
                let (inside, _) = dielectric(eta, 1.0, c);
                assert!(
                    (dielectric_mitsuba(c, eta) - outside).abs() < 1e-14,
                    "{eta} {c}"
                );
                if c > 0.0 {
                    assert!(
                        (dielectric_mitsuba(-c, eta) - inside).abs() < 1e-14,
                        "{eta} -{c}"
                    );
                }
            }
        }
        assert_eq!(dielectric_mitsuba(0.3, 1.0), 0.0);
        assert_eq!(normal_reflectance(1.0, 1.5), dielectric(1.0, 1.5, 1.0).0);
    }
}
