//! Spectral absorption per layer, §3.4.3: Eq. 2 with the chromophore spectra of Table 5 and the
//! layer equations of Table 6. All coefficients in mm⁻¹, wavelengths in nm.

use std::f64::consts::LN_10;

use crate::spectral::SpectralData;

use super::params::{HypodermisAbsorption, PheomelaninAbsorption};

/// Molar mass of hemoglobin, g/mol. Table 5 divides by 66,500 (BioSpec's figure); Prahl's
/// molar extinction table, which we ship, is per mole of tetramer at 64,500 g/mol, and using it
/// with 66,500 would understate blood absorption by 3 %. See DECISIONS.md.
pub const HB_MOLAR_MASS_G_PER_MOL: f64 = 64_500.0;
/// Molar mass of β-carotene, g/mol (Table 5).
pub const CAROTENE_MOLAR_MASS_G_PER_MOL: f64 = 537.0;
/// Molar mass of bilirubin, g/mol (Table 5).
pub const BILIRUBIN_MOLAR_MASS_G_PER_MOL: f64 = 585.0;

/// Eq. 2 for one chromophore: μa = ln(10)·c·ε, with ε in cm⁻¹/M and c given in g/L,
/// returned in mm⁻¹.
pub fn mua_from_molar_extinction(
    eps_per_cm_per_molar: f64,
    c_g_per_l: f64,
    molar_mass: f64,
) -> f64 {
    LN_10 * eps_per_cm_per_molar * (c_g_per_l / molar_mass) / 10.0 // Eq. 2; cm⁻¹ → mm⁻¹
}

/// Eumelanin inside melanosomes, Table 5 (Jacques' melanosome fit): 6.6·10¹⁰ λ^-3.33 mm⁻¹.
pub fn mua_eumelanin(lambda_nm: f64) -> f64 {
    6.6e10 * lambda_nm.powf(-3.33) // Table 5
}

/// Pheomelanin inside melanosomes, Table 5 (Donner & Jensen's fit): 2.9·10¹⁴ λ^-4.75 mm⁻¹.
pub fn mua_pheomelanin_fit(lambda_nm: f64) -> f64 {
    2.9e14 * lambda_nm.powf(-4.75) // Table 5
}

/// Baseline absorption of depigmented tissue (Saidi), Table 5: 7.84·10⁷ λ^-3.255 mm⁻¹.
pub fn mua_baseline(lambda_nm: f64) -> f64 {
    7.84e7 * lambda_nm.powf(-3.255) // Table 5
}

/// Measured pheomelanin (Sarna & Swartz 2006) at `c_g_per_l` in the melanosome, mm⁻¹.
/// The table holds the decadic mass extinction in L·g⁻¹·cm⁻¹ (see its header).
pub fn mua_pheomelanin_measured(lambda_nm: f64, c_g_per_l: f64) -> f64 {
    LN_10 * SpectralData::get().ext_pheomelanin.at(lambda_nm) * c_g_per_l / 10.0
    // Eq. 2
}

/// Chromophore concentrations a layer equation needs, already aged.
#[derive(Debug, Clone, Copy)]
pub struct Chromophores {
    pub melanosome_fraction: f64,
    pub oxygen_saturation: f64,
    pub hemoglobin_g_per_l: f64,
    pub bilirubin_g_per_l: f64,
    pub carotene_blood_g_per_l: f64,
    pub carotene_epidermis_g_per_l: f64,
    pub pheomelanin_g_per_l: f64,
    pub pheomelanin: PheomelaninAbsorption,
}

impl Chromophores {
    /// Whole blood: oxy + deoxy hemoglobin, bilirubin and carotene (the bracket of Table 6's
    /// dermal rows), mm⁻¹.
    pub fn mua_blood(&self, lambda_nm: f64) -> f64 {
        let d = SpectralData::get();
        let s = self.oxygen_saturation;
        let c_hb = self.hemoglobin_g_per_l;
        let oxy =
            mua_from_molar_extinction(d.eps_hbo2.at(lambda_nm), s * c_hb, HB_MOLAR_MASS_G_PER_MOL);
        let deoxy = mua_from_molar_extinction(
            d.eps_hb.at(lambda_nm),
            (1.0 - s) * c_hb,
            HB_MOLAR_MASS_G_PER_MOL,
        );
        let bil = mua_from_molar_extinction(
            eps_noise_floored(&d.eps_bilirubin, lambda_nm),
            self.bilirubin_g_per_l,
            BILIRUBIN_MOLAR_MASS_G_PER_MOL,
        );
        let car = mua_from_molar_extinction(
            eps_noise_floored(&d.eps_carotene, lambda_nm),
            self.carotene_blood_g_per_l,
            CAROTENE_MOLAR_MASS_G_PER_MOL,
        );
        oxy + deoxy + bil + car // Table 6, PD/RD bracket
    }

    /// Melanosome interior: eumelanin + pheomelanin, mm⁻¹ (Table 6, LE row).
    pub fn mua_melanosome(&self, lambda_nm: f64) -> f64 {
        let ph = match self.pheomelanin {
            PheomelaninAbsorption::ThesisFit => mua_pheomelanin_fit(lambda_nm),
            PheomelaninAbsorption::Measured => {
                mua_pheomelanin_measured(lambda_nm, self.pheomelanin_g_per_l)
            }
        };
        mua_eumelanin(lambda_nm) + ph
    }
}

/// ε of a PhotochemCAD spectrum (bilirubin, β-carotene): these end at 700 nm and hold
/// instrument noise around zero above ~530 nm, so negative values read as 0 and the absorption
/// beyond the table is 0.
fn eps_noise_floored(t: &crate::spectral::SpectralTable, lambda_nm: f64) -> f64 {
    if lambda_nm > t.range_nm().1 {
        0.0
    } else {
        t.at(lambda_nm).max(0.0)
    }
}

fn mua_water(lambda_nm: f64) -> f64 {
    SpectralData::get().mua_water_per_mm.at(lambda_nm)
}

/// Water enters every layer as its volume fraction times pure-water absorption; Table 6 writes
/// "+ μa_H2O" after scaling the rest by (1 − f_H2O), whose volume-consistent reading is
/// f_H2O·μa_H2O (the two differ by < 10⁻³ mm⁻¹ in 400–700 nm).
fn with_water(tissue_mua: f64, water_fraction: f64, lambda_nm: f64) -> f64 {
    tissue_mua * (1.0 - water_fraction) + water_fraction * mua_water(lambda_nm)
}

/// Stratum corneum, Table 6 row 1.
pub fn mua_stratum_corneum(lambda_nm: f64, water_fraction: f64) -> f64 {
    let tissue = (0.1 - 0.3e-4 * lambda_nm) + 0.125 * (lambda_nm / 10.0) * mua_baseline(lambda_nm);
    with_water(tissue, water_fraction, lambda_nm) // Table 6
}

/// Living epidermis, Table 6 row 2. Carotene enters with the epidermal concentration; the
/// factor (1 − c_car) multiplies the baseline as printed (c_car in g/L, ≈ 1).
pub fn mua_living_epidermis(lambda_nm: f64, c: &Chromophores, water_fraction: f64) -> f64 {
    let vm = c.melanosome_fraction;
    let c_car = c.carotene_epidermis_g_per_l;
    let car = mua_from_molar_extinction(
        eps_noise_floored(&SpectralData::get().eps_carotene, lambda_nm),
        c_car,
        CAROTENE_MOLAR_MASS_G_PER_MOL,
    );
    let tissue = vm * c.mua_melanosome(lambda_nm)
        + (1.0 - vm) * (car + (1.0 - c_car) * mua_baseline(lambda_nm));
    with_water(tissue, water_fraction, lambda_nm) // Table 6
}

/// Papillary or reticular dermis, Table 6 rows 3–4, with blood fraction `v_hb`.
pub fn mua_dermis(lambda_nm: f64, c: &Chromophores, v_hb: f64, water_fraction: f64) -> f64 {
    let tissue = v_hb * c.mua_blood(lambda_nm) + (1.0 - v_hb) * mua_baseline(lambda_nm);
    with_water(tissue, water_fraction, lambda_nm) // Table 6
}

/// Hypodermis: water only (Table 6 row 5) or the dermal formula with its blood fraction
/// (Table 2, Table 4 caption: 5 %).
pub fn mua_hypodermis(
    lambda_nm: f64,
    c: &Chromophores,
    mode: HypodermisAbsorption,
    v_hb: f64,
    water_fraction: f64,
) -> f64 {
    match mode {
        HypodermisAbsorption::WaterOnly => water_fraction * mua_water(lambda_nm), // Table 6
        HypodermisAbsorption::Blood => mua_dermis(lambda_nm, c, v_hb, water_fraction),
    }
}
