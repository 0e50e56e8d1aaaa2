//! Skin diffusion profiles (thesis §3.5): per entry, the transport engine turns the layer
//! optics into Rd(r, λ) for a pencil beam at normal incidence; colour maps them to linear sRGB
//! profiles; a sum of Gaussians is fitted to each.
//!
//! Entries whose stacks differ only in absorption (at one age, the skin types and ξ levels)
//! share one white simulation per wavelength ([`crate::transport::run_white_sets`]), and the
//! packets of each wavelength are those that meet a noise target at the least work
//! ([`allocate`]).

pub mod allocate;
pub mod rgb;
pub mod simulate;

pub use allocate::NoiseTarget;
pub use rgb::{rgb_profile, RgbProfile};
pub use simulate::{
    plan, simulate, simulate_units, skin_units, GroupPlan, SimOptions, SkinSimulation, SkinUnits,
    SpectralProfile,
};
