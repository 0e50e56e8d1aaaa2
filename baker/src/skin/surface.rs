//! Surface reflection, §3.4.2 and Appendix 3.8: Beckmann roughness from the skin profile's Rz
//! and the sebum film that fills the microfacets (Eqs. 11–13).

use super::params::{Gender, SkinParams};
use super::piecewise_linear;

/// Skin profile length l_e of one Rz measurement, µm (§3.4.2, after Egawa et al.).
pub const PROFILE_LENGTH_UM: f64 = 960.0;

/// Rz (µm) against age: Fig. 33 (left) is only drawn; its values at 30, 55 and 80 years are
/// Table 4's (78, 103, 151 µm, both genders). Linear between, held outside.
pub const RZ_KNOTS_UM: [(f64, f64); 3] = [(30.0, 78.0), (55.0, 103.0), (80.0, 151.0)];

/// Sebum production (mg lipid / 10 cm² / 3 h) against age, men: Table 4 rows 29-b, 41, 29-a.
pub const SEBUM_KNOTS_MALE: [(f64, f64); 3] = [(30.0, 2.4), (55.0, 2.43), (80.0, 1.69)];
/// Women: Table 4 rows 29-d and 29-c (always below men, §3.4.2, Pochi et al.).
pub const SEBUM_KNOTS_FEMALE: [(f64, f64); 2] = [(30.0, 2.0), (80.0, 0.85)];

/// Sebum film thickness per unit production: 1 mg / 10 cm² of lipid at 1 g/cm³ is a 1 µm film
/// (Appendix 3.8 quotes 3 → 1.69 µm films for the same figures).
pub const FILM_UM_PER_SEBUM_MG: f64 = 1.0;

/// The surface parameters of an entry, as the optics files store them.
pub use formats::OpticsSurface as Surface;

/// Rz at the entry's age, µm.
pub fn rz_um(p: &SkinParams) -> f64 {
    p.rz_um
        .unwrap_or_else(|| piecewise_linear(&RZ_KNOTS_UM, surface_age(p)))
}

/// Sebum production at the entry's age.
pub fn sebum_mg(p: &SkinParams) -> f64 {
    p.sebum_mg.unwrap_or_else(|| match p.gender {
        Gender::Male => piecewise_linear(&SEBUM_KNOTS_MALE, surface_age(p)),
        Gender::Female => piecewise_linear(&SEBUM_KNOTS_FEMALE, surface_age(p)),
    })
}

fn surface_age(p: &SkinParams) -> f64 {
    if p.freeze.surface {
        super::REFERENCE_AGE_YEARS
    } else {
        p.age_years
    }
}

/// ψ_s of Eqs. 11–13 for microfacet slope `alpha_sr_rad` and sebum film `film_um`.
///
/// The sebum volume per pyramidal hole is V_s = κ·s·l² (film thickness times the hole's
/// projected area, κ calibrated; the appendix leaves V_s unspecified), l = l_e.
pub fn psi_s(alpha_sr_rad: f64, film_um: f64, kappa: f64) -> f64 {
    let l = PROFILE_LENGTH_UM;
    let v_s = kappa * film_um * l * l;
    let l_s = (3.0 * v_s / (2.0 * alpha_sr_rad.tan())).cbrt(); // Eq. 13
    let covered = (l_s * l_s / (l * l)).min(1.0); // Eq. 12
    1.0 - covered // Eq. 11
}

pub fn surface(p: &SkinParams, eta_surface: f64) -> Surface {
    let rz = rz_um(p);
    let sebum = sebum_mg(p);
    let film = sebum * FILM_UM_PER_SEBUM_MG;
    let alpha = (rz / PROFILE_LENGTH_UM).atan(); // §3.4.2
    let psi = psi_s(alpha, film, p.sebum_volume_factor);
    let r = (eta_surface - 1.0) / (eta_surface + 1.0);
    Surface {
        rz_um: rz,
        sebum_mg_per_10cm2_3h: sebum,
        sebum_film_um: film,
        alpha_sr_rad: alpha,
        psi_s: psi,
        beckmann_m: psi * alpha, // Eq. 11
        eta: eta_surface,
        f0: r * r,
    }
}
