//! Chromophore concentrations and their decline with age, §3.4.3 (Eqs. 3 and 4).

use super::{decades_since_reference, SkinParams};

/// Melanin decline rate r_ϑm: 8 % per decade (Gilchrest et al., §3.4.3).
pub const MELANIN_DECLINE_PER_DECADE: f64 = 0.08;
/// Intrinsic hemoglobin decline r_ϑHbi: 6 % per decade (§3.4.3).
pub const HB_INTRINSIC_DECLINE_PER_DECADE: f64 = 0.06;
/// Extrinsic hemoglobin decline r_ϑHbe: 10 % per decade, weighted by ξ (§3.4.3).
pub const HB_EXTRINSIC_DECLINE_PER_DECADE: f64 = 0.10;

/// Melanosome volume fraction ϑm of the living epidermis at the entry's age (Eq. 3).
pub fn melanosome_fraction(p: &SkinParams) -> f64 {
    let dt = if p.freeze.melanin {
        0.0
    } else {
        decades_since_reference(p.age_years)
    };
    let m30 = p.melanosome_fraction_at_30();
    m30 - dt * MELANIN_DECLINE_PER_DECADE * m30 // Eq. 3
}

/// Factor Eq. 4 applies to a dermal blood fraction at the entry's age.
pub fn hemoglobin_factor(p: &SkinParams) -> f64 {
    let dt = if p.freeze.hemoglobin {
        0.0
    } else {
        decades_since_reference(p.age_years)
    };
    1.0 - dt * (HB_INTRINSIC_DECLINE_PER_DECADE + p.xi * HB_EXTRINSIC_DECLINE_PER_DECADE)
    // Eq. 4
}

/// Blood volume fractions ϑHb (papillary, reticular dermis) at the entry's age (Eq. 4).
pub fn dermal_blood_fractions(p: &SkinParams) -> (f64, f64) {
    let f = hemoglobin_factor(p);
    (p.blood_fraction_pd * f, p.blood_fraction_rd * f)
}
