//! The biophysical, time-varying skin model of thesis chapter 3.
//!
//! A person (age, gender, Fitzpatrick type, body location, exposure ξ) becomes five layers with
//! thickness, refractive index and spectral μa, μs′ (§3.4), plus the dermo-epidermal junction
//! (Eq. 1) and the surface reflection parameters (§3.4.2). Where the thesis is silent or
//! contradicts itself, the choice made is recorded in `skin/DECISIONS.md`.

pub mod absorption;
pub mod chromophores;
pub mod collagen;
pub mod document;
pub mod layers;
pub mod model;
pub mod params;
pub mod scattering;
pub mod surface;

pub use model::{evaluate, Intermediate, LayerOptics, ModelError, SkinOptics};
pub use params::{
    BodyLocation, Freeze, Gender, HypodermisAbsorption, MelaninInput, ModelKind,
    PheomelaninAbsorption, SkinLayer, SkinParams, SkinType, SkinTypeMelanin,
};

/// Age at which Table 1 and Table 2 give their base values; aging laws run from here (§3.4.1).
pub const REFERENCE_AGE_YEARS: f64 = 30.0;

/// Decades elapsed since the reference age, never negative: the thesis describes atrophy and
/// chromophore decline from the adult base values at 30 onwards, so younger skin keeps them.
pub fn decades_since_reference(age_years: f64) -> f64 {
    ((age_years - REFERENCE_AGE_YEARS) / 10.0).max(0.0)
}

/// Linear interpolation through `(x, y)` knots sorted by x, holding the end values outside.
pub(crate) fn piecewise_linear(knots: &[(f64, f64)], x: f64) -> f64 {
    let (first, last) = (knots[0], knots[knots.len() - 1]);
    if x <= first.0 {
        return first.1;
    }
    if x >= last.0 {
        return last.1;
    }
    let j = knots.partition_point(|k| k.0 <= x);
    let ((x0, y0), (x1, y1)) = (knots[j - 1], knots[j]);
    y0 + (y1 - y0) * (x - x0) / (x1 - x0)
}
