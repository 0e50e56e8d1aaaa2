//! Spectral quantities: the wavelength grid and the measured tables the model is built from.
//!
//! Every table under `spectral/data/` is embedded in the binary at compile time (the baker
//! reads no data files at run time) and starts with a header naming its source and units.

pub mod colour;
pub mod grid;
pub mod table;

pub use colour::ColourMap;
pub use grid::WavelengthGrid;
pub use table::{SpectralTable, SpectralTableError};

use std::sync::OnceLock;

/// The measured spectra the skin model needs, parsed once.
#[derive(Debug)]
pub struct SpectralData {
    /// Molar extinction of oxy-hemoglobin, cm⁻¹/M (Prahl's compilation).
    pub eps_hbo2: SpectralTable,
    /// Molar extinction of deoxy-hemoglobin, cm⁻¹/M (Prahl's compilation).
    pub eps_hb: SpectralTable,
    /// Molar extinction of bilirubin, cm⁻¹/M.
    pub eps_bilirubin: SpectralTable,
    /// Molar extinction of β-carotene, cm⁻¹/M.
    pub eps_carotene: SpectralTable,
    /// Absorption coefficient of pure water, mm⁻¹.
    pub mua_water_per_mm: SpectralTable,
    /// Mass extinction of pheomelanin (Sarna & Swartz 2006), see the file header for units.
    pub ext_pheomelanin: SpectralTable,
    /// Mass extinction of eumelanin (Sarna & Swartz 2006), see the file header for units.
    pub ext_eumelanin: SpectralTable,
}

const HEMOGLOBIN: &str = include_str!("data/hemoglobin_prahl.csv");
const BILIRUBIN: &str = include_str!("data/bilirubin_li.csv");
const CAROTENE: &str = include_str!("data/beta_carotene.csv");
const WATER: &str = include_str!("data/water_popefry.csv");
const MELANIN: &str = include_str!("data/melanin_sarna.csv");

impl SpectralData {
    /// The embedded tables, parsed on first use.
    pub fn get() -> &'static SpectralData {
        static DATA: OnceLock<SpectralData> = OnceLock::new();
        DATA.get_or_init(|| {
            // The embedded files are part of the source tree and covered by tests; a parse
            // failure here is a build defect, not a user error.
            let parse = |name: &str, text: &str, col: usize| {
                SpectralTable::parse_csv(name, text, col)
                    .unwrap_or_else(|e| panic!("embedded spectral table is corrupt: {e}"))
            };
            SpectralData {
                eps_hbo2: parse("hemoglobin_prahl.csv", HEMOGLOBIN, 1),
                eps_hb: parse("hemoglobin_prahl.csv", HEMOGLOBIN, 2),
                eps_bilirubin: parse("bilirubin_li.csv", BILIRUBIN, 1),
                eps_carotene: parse("beta_carotene.csv", CAROTENE, 1),
                mua_water_per_mm: parse("water_popefry.csv", WATER, 1),
                ext_eumelanin: parse("melanin_sarna.csv", MELANIN, 1),
                ext_pheomelanin: parse("melanin_sarna.csv", MELANIN, 2),
            }
        })
    }
}

/// Every measured data table compiled into the binary, by file name (the unit cache keys
/// include their checksum: `crate::pipeline`).
pub const DATA_FILES: &[(&str, &str)] = &[
    ("hemoglobin_prahl.csv", HEMOGLOBIN),
    ("bilirubin_li.csv", BILIRUBIN),
    ("beta_carotene.csv", CAROTENE),
    ("water_popefry.csv", WATER),
    ("melanin_sarna.csv", MELANIN),
    ("cie1931_2deg.csv", include_str!("data/cie1931_2deg.csv")),
    (
        "illuminant_d65.csv",
        include_str!("data/illuminant_d65.csv"),
    ),
];
