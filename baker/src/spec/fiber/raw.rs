//! The fiber spec as written: serde structs that keep the location of every value and reject
//! unknown fields. Ranges and meaning are checked by the resolver ([`super`]).

use serde::Deserialize;

use crate::spec::yaml::Spanned;

#[derive(Debug, Deserialize, Default)]
#[serde(deny_unknown_fields)]
pub struct RawFiberSpec {
    pub version: Option<Spanned<u32>>,
    #[serde(default)]
    pub dyes: Vec<Spanned<RawDye>>,
    #[serde(default)]
    pub fibers: Vec<Spanned<RawFiber>>,
    pub bake: Option<Spanned<RawBake>>,
    /// Resource budgets ([`crate::spec::limits`]).
    pub limits: Option<Spanned<crate::spec::limits::RawLimits>>,
}

/// `bake:` — how `baker bake` tabulates the BCSDFs (all optional).
#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct RawBake {
    pub resolution_deg: Option<Spanned<f64>>,
    pub photons_per_direction: Option<Spanned<f64>>,
    pub seed: Option<Spanned<f64>>,
    pub split: Option<Spanned<f64>>,
    pub precision: Option<Spanned<String>>,
    pub keep_bits: Option<Spanned<f64>>,
    pub channels: Option<Spanned<String>>,
    pub lambda_nm: Option<Spanned<RawLambda>>,
}

#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct RawLambda {
    pub start: Spanned<f64>,
    pub end: Spanned<f64>,
    pub step: Spanned<f64>,
}

/// `sweep:` — every dye × every depth of shade, from the same trace.
#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct RawSweep {
    pub dyes: Spanned<Vec<Spanned<String>>>,
    pub depth_of_shade_percent: Spanned<Vec<Spanned<f64>>>,
    pub undyed: Option<Spanned<bool>>,
}

/// `{name, class, bands: [{peak_nm, fwhm_nm, peak_eps_l_per_mg_cm}]}` or `{name, class, csv}`.
#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct RawDye {
    pub name: Spanned<String>,
    pub class: Spanned<String>,
    pub bands: Option<Spanned<Vec<Spanned<RawBand>>>>,
    pub csv: Option<Spanned<String>>,
    pub source: Option<Spanned<String>>,
}

#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct RawBand {
    pub peak_nm: Spanned<f64>,
    pub fwhm_nm: Spanned<f64>,
    pub peak_eps_l_per_mg_cm: Spanned<f64>,
}

#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct RawFiber {
    pub name: Spanned<String>,
    #[serde(rename = "type")]
    pub kind: Spanned<String>,
    pub section: Option<Spanned<RawSection>>,
    pub diameter_um: Option<Spanned<f64>>,
    pub seed: Option<Spanned<f64>>,
    pub variant: Option<Spanned<f64>>,
    pub eta: Option<Spanned<f64>>,
    pub beta_deg: Option<Spanned<f64>>,
    pub roughness: Option<Spanned<RawRoughness>>,
    pub dye: Option<Spanned<String>>,
    pub depth_of_shade_percent: Option<Spanned<f64>>,
    pub cuticle: Option<Spanned<RawCuticle>>,
    pub sections: Option<Spanned<f64>>,
    pub sweep: Option<Spanned<RawSweep>>,
    pub symmetry: Option<Spanned<String>>,
}

/// Exactly one of `shape` (a generator, or `ellipse` with `ratio`), `polygon` (CSV) or `mask`
/// (image, with `um_per_px`).
#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct RawSection {
    pub shape: Option<Spanned<String>>,
    pub ratio: Option<Spanned<f64>>,
    pub polygon: Option<Spanned<String>>,
    pub mask: Option<Spanned<String>>,
    pub um_per_px: Option<Spanned<f64>>,
    pub smoothing_passes: Option<Spanned<f64>>,
}

#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct RawRoughness {
    pub ra_nm: Spanned<f64>,
    pub l_nm: Spanned<f64>,
}

#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct RawCuticle {
    pub enabled: Option<Spanned<bool>>,
    pub length_um: Option<Spanned<f64>>,
    pub tilt_deg: Option<Spanned<f64>>,
}
