//! Fresnel reflection and refraction at an index mismatch (unpolarised light).

/// Reflectance for a ray arriving with cos θi = `cos_i` (> 0) from index `ni` into `nt`, and the
/// cosine of the transmitted angle (0 under total internal reflection).
#[inline]
pub fn fresnel(ni: f64, nt: f64, cos_i: f64) -> (f64, f64) {
    if ni == nt {
        return (0.0, cos_i);
    }
    let eta = ni / nt;
    let sin_t2 = eta * eta * (1.0 - cos_i * cos_i);
    if sin_t2 >= 1.0 {
        return (1.0, 0.0);
    }
    let cos_t = (1.0 - sin_t2).sqrt();
    let rs = (ni * cos_i - nt * cos_t) / (ni * cos_i + nt * cos_t);
    let rp = (ni * cos_t - nt * cos_i) / (ni * cos_t + nt * cos_i);
    (0.5 * (rs * rs + rp * rp), cos_t)
}

/// Specular reflectance at normal incidence, ((n1 − n2)/(n1 + n2))².
pub fn normal_reflectance(n1: f64, n2: f64) -> f64 {
    let r = (n1 - n2) / (n1 + n2);
    r * r
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn normal_incidence_matches_closed_form() {
        let (r, c) = fresnel(1.0, 1.5, 1.0);
        assert!((r - 0.04).abs() < 1e-15 && (c - 1.0).abs() < 1e-15);
    }

    #[test]
    fn total_internal_reflection_beyond_critical_angle() {
        let crit = (1.0f64 / 1.5).asin();
        assert_eq!(fresnel(1.5, 1.0, (crit + 0.01).cos()).0, 1.0);
        assert!(fresnel(1.5, 1.0, (crit - 0.01).cos()).0 < 1.0);
    }

    #[test]
    fn reflectance_is_reciprocal() {
        // R(ni→nt, θi) = R(nt→ni, θt).
        let (r1, cos_t) = fresnel(1.0, 1.4, 0.6);
        let (r2, _) = fresnel(1.4, 1.0, cos_t);
        assert!((r1 - r2).abs() < 1e-12);
    }
}
