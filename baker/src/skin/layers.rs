//! Layered structure and its aging, §3.4.1: thickness atrophy (Table 1) and the
//! dermo-epidermal junction (Eq. 1).

use super::{decades_since_reference, SkinParams};

/// Thickness of every layer at the entry's age, mm (Table 1: linear atrophy per decade).
pub fn thickness_mm(p: &SkinParams) -> [f64; 5] {
    let decades = if p.freeze.thickness {
        0.0
    } else {
        decades_since_reference(p.age_years)
    };
    std::array::from_fn(|i| p.thickness_at_30_mm[i] * (1.0 - p.atrophy_per_decade[i] * decades))
}

/// The dermo-epidermal junction of Eq. 1:
/// z(x, y) = z̄ + A·sin(ωx·x + φx)·sin(ωy·y + φy), z positive into the skin.
/// The junction of an entry (Eq. 1), as the optics files store it.
pub use formats::OpticsJunction as Junction;

/// Rete-ridge amplitude at the entry's age, µm: the age-30 value down to 0 at 80, linearly.
///
/// §3.4.1: A decreases linearly with age; Giangreco et al. measured 100 µm to almost 0 from 20
/// to 80 years, and Table 4 uses the full amplitude at 30 and 0 at 80. We keep the full
/// amplitude up to 30 (Table 4) and reach 0 at 80 (both sources).
pub fn dej_amplitude_um(p: &SkinParams) -> f64 {
    if p.freeze.junction {
        return p.dej_amplitude_at_30_um;
    }
    let t = ((80.0 - p.age_years) / (80.0 - super::REFERENCE_AGE_YEARS)).clamp(0.0, 1.0);
    p.dej_amplitude_at_30_um * t
}

/// Eq. 1's parameters for the entry, with z̄ at the bottom of the living epidermis.
pub fn junction(p: &SkinParams, d_sc_mm: f64, d_le_mm: f64) -> Junction {
    let omega = 2.0 * std::f64::consts::PI / (p.dej_period_um * 1e-3);
    Junction {
        z_mean_mm: d_sc_mm + d_le_mm,
        amplitude_mm: dej_amplitude_um(p) * 1e-3,
        omega_x_per_mm: omega,
        omega_y_per_mm: omega,
        phi_x_rad: p.dej_phase_rad[0],
        phi_y_rad: p.dej_phase_rad[1],
    }
}
