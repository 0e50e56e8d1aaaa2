//! The baker: declarative specs in, lookup tables for physically based rendering out.
//!
//! Modules follow the physics: [`skin`] (thesis ch. 3), [`spectral`] (wavelength grids and
//! measured spectra), [`spec`] (the YAML spec language), [`output`] (atomic writers, plots,
//! MCML input files), [`cli`] (the commands behind the `baker` binary).

pub mod cancel;
pub mod cli;
pub mod export;
pub mod fiber;
pub mod files;
pub mod fit;
pub mod output;
pub mod pipeline;
pub mod profile;
pub mod skin;
pub mod spec;
pub mod spectral;
pub mod stats;
pub mod transport;
