//! Reduced scattering per layer, §3.4.4: Eqs. 5–7 (epidermis, dermis), Eq. 9 (collagen),
//! Eq. 10 (hypodermis). Coefficients in mm⁻¹.

use super::collagen::mie_shape;

/// Reference wavelength λr of Eqs. 6–7, nm.
pub const LAMBDA_REF_NM: f64 = 500.0;

/// Epidermal layers (SC and LE together): ρ = 0.29, μs′(λr) = 6.67 mm⁻¹, γ = 0.689 (Jacques).
pub const EPIDERMIS_RHO: f64 = 0.29;
pub const EPIDERMIS_MUSP_REF_PER_MM: f64 = 6.67;
pub const EPIDERMIS_GAMMA: f64 = 0.689;

/// Dermal layers: ρ = 0.41 (Saidi), μs′(λr) = 4.36 mm⁻¹ (Jacques); γ from collagen (Eq. 9).
pub const DERMIS_RHO: f64 = 0.41;
pub const DERMIS_MUSP_REF_PER_MM: f64 = 4.36;

/// Eqs. 5–7 with a single Mie exponent γ.
pub fn musp_power_law(lambda_nm: f64, rho: f64, musp_ref_per_mm: f64, gamma: f64) -> f64 {
    let x = lambda_nm / LAMBDA_REF_NM;
    let rayleigh = musp_ref_per_mm * x.powi(-4); // Eq. 6
    let mie = musp_ref_per_mm * x.powf(-gamma); // Eq. 7
    rho * rayleigh + (1.0 - rho) * mie // Eq. 5
}

/// μs′ of the stratum corneum and living epidermis (§3.4.4).
pub fn musp_epidermis(lambda_nm: f64) -> f64 {
    musp_power_law(
        lambda_nm,
        EPIDERMIS_RHO,
        EPIDERMIS_MUSP_REF_PER_MM,
        EPIDERMIS_GAMMA,
    )
}

/// μs′ of a dermal layer whose Mie term is averaged over collagen diameters (Eqs. 5, 6, 9).
/// `collagen_weights` come from [`super::collagen::gamma_weights`].
pub fn musp_dermis(lambda_nm: f64, collagen_weights: &[(f64, f64)]) -> f64 {
    let x = lambda_nm / LAMBDA_REF_NM;
    let rayleigh = DERMIS_MUSP_REF_PER_MM * x.powi(-4); // Eq. 6
    let mie = DERMIS_MUSP_REF_PER_MM * mie_shape(collagen_weights, x); // Eq. 9
    DERMIS_RHO * rayleigh + (1.0 - DERMIS_RHO) * mie // Eq. 5
}

/// μs′ of the hypodermis, Eq. 10: 105.06·λ^-0.68 mm⁻¹.
pub fn musp_hypodermis(lambda_nm: f64) -> f64 {
    105.06 * lambda_nm.powf(-0.68) // Eq. 10
}
