//! Skin optical properties: per-layer thickness, index and spectral μa, μs′ (JSON).
//!
//! Written by `baker optics --json` and by `baker bake` (as `optics.json`). Layout:
//!
//! ```json
//! { "format": "baker.skin-optics", "version": 1, "source": "specs/fitzpatrick.yaml",
//!   "lambda_nm": [400, 410, …],
//!   "entries": [ { "name": "…", "model": "five_layer", "inputs": { … },
//!                  "layers": [ { "name": "stratum corneum", "d_mm": 0.02, "eta": 1.53,
//!                                "mua_per_mm": [ … nλ … ], "musp_per_mm": [ … nλ … ] }, … ],
//!                  "junction": { … Eq. 1 … }, "surface": { … }, "intermediate": { … } } ] }
//! ```
//!
//! Lengths in mm, coefficients per mm, wavelengths in nm. μs′ is the reduced scattering
//! coefficient; the thesis transports it with an isotropic phase function (g = 0).

use serde::{Deserialize, Serialize};

/// Value of the `format` field.
pub const FORMAT: &str = "baker.skin-optics";
/// Current version of the layout.
pub const VERSION: u32 = 1;

#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct OpticsDocument {
    pub format: String,
    pub version: u32,
    /// The spec the document was made from.
    pub source: String,
    pub lambda_nm: Vec<f64>,
    pub entries: Vec<OpticsEntry>,
}

#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct OpticsEntry {
    pub name: String,
    /// `five_layer` or `three_layer`.
    pub model: String,
    /// Every model input of the entry (age, gender, overrides…), as resolved from the spec.
    pub inputs: serde_json::Value,
    pub layers: Vec<OpticsLayer>,
    pub junction: OpticsJunction,
    pub surface: OpticsSurface,
    /// Intermediate parameters (Table 4 of the thesis): thicknesses, chromophore fractions.
    pub intermediate: serde_json::Value,
}

#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct OpticsLayer {
    pub name: String,
    pub d_mm: f64,
    pub eta: f64,
    pub mua_per_mm: Vec<f64>,
    pub musp_per_mm: Vec<f64>,
}

/// The dermo-epidermal junction z = z̄ + A·sin(ωx·x + φx)·sin(ωy·y + φy) (z into the skin).
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct OpticsJunction {
    /// Mean depth z̄ of the living-epidermis / papillary-dermis interface, mm.
    pub z_mean_mm: f64,
    /// Peak amplitude A, mm (0 = planar).
    pub amplitude_mm: f64,
    /// Angular spatial frequencies ωx, ωy, rad/mm.
    pub omega_x_per_mm: f64,
    pub omega_y_per_mm: f64,
    /// Phases φx, φy, rad.
    pub phi_x_rad: f64,
    pub phi_y_rad: f64,
}

/// Surface reflection: Beckmann roughness m and normal-incidence Fresnel F0.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct OpticsSurface {
    /// Mean peak-to-valley height of the skin profile, µm.
    pub rz_um: f64,
    /// Sebum production, mg lipid / 10 cm² / 3 h.
    pub sebum_mg_per_10cm2_3h: f64,
    /// Sebum film thickness s, µm.
    pub sebum_film_um: f64,
    /// α_sr = arctan(Rz / l_e), rad (thesis §3.4.2).
    pub alpha_sr_rad: f64,
    /// ψ_s = 1 − a_s/a_t (thesis Eq. 11).
    pub psi_s: f64,
    /// Beckmann roughness m = ψ_s·α_sr (thesis Eq. 11).
    pub beckmann_m: f64,
    /// Refractive index of the outer surface (stratum corneum, thesis Table 1).
    pub eta: f64,
    /// Normal-incidence Fresnel reflectance from air, ((η − 1)/(η + 1))².
    pub f0: f64,
}

#[derive(Debug)]
pub enum OpticsError {
    Json(serde_json::Error),
    Format(String),
}

impl std::error::Error for OpticsError {}

impl std::fmt::Display for OpticsError {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            OpticsError::Json(e) => write!(f, "not a skin-optics JSON document: {e}"),
            OpticsError::Format(m) => write!(f, "invalid skin-optics document: {m}"),
        }
    }
}

impl OpticsDocument {
    /// Parses and checks a document (format name, version, array lengths).
    pub fn from_json(text: &str) -> Result<Self, OpticsError> {
        let doc: OpticsDocument = serde_json::from_str(text).map_err(OpticsError::Json)?;
        doc.check()?;
        Ok(doc)
    }

    /// Structural checks a reader relies on.
    pub fn check(&self) -> Result<(), OpticsError> {
        if self.format != FORMAT {
            return Err(OpticsError::Format(format!(
                "format is {:?}, expected {FORMAT:?}",
                self.format
            )));
        }
        if self.version != VERSION {
            return Err(OpticsError::Format(format!(
                "version {} is not supported (this reader: {VERSION})",
                self.version
            )));
        }
        let n = self.lambda_nm.len();
        for e in &self.entries {
            for l in &e.layers {
                if l.mua_per_mm.len() != n || l.musp_per_mm.len() != n {
                    return Err(OpticsError::Format(format!(
                        "entry {:?}, layer {:?}: spectra must have {n} values like lambda_nm",
                        e.name, l.name
                    )));
                }
            }
        }
        Ok(())
    }

    pub fn entry(&self, name: &str) -> Option<&OpticsEntry> {
        self.entries.iter().find(|e| e.name == name)
    }
}
