//! The baker: declarative specs in, lookup tables for physically based rendering out.
//!
//! The modules, bottom-up (baker/README.md has the picture and the rules):
//!
//! - ground floor: [`math`] (rng and seeding, quadrature, Fresnel), [`progress`] and
//!   [`cancel`] (how long work reports and stops), [`files`] (bounded reads), [`data`] (the
//!   checksum of the compiled data tables), [`error`] (exit codes), [`suggest`] ("did you
//!   mean …?");
//! - generic machinery: [`output`] (atomic writers, paths inside `--out`, HDF5, `.bkt`, EXR,
//!   PNG) and [`pipeline`] (work units, cache, events, interruption, shards);
//! - physics: [`spectral`] (wavelength grids, measured spectra, colour), [`stats`], [`fit`]
//!   (Gaussian fits, simplex), [`transport`] (layered Monte Carlo, thesis §3.5), [`skin`]
//!   (the skin model, thesis ch. 3), [`fiber`] (cross-sections and the photon tracer, thesis
//!   ch. 5), [`spec`] (the YAML spec language), [`profile`] (skin work units and RGB fits);
//! - products: [`bake`] (the bake of a spec of either kind) and [`export`] (renderer
//!   parameters);
//! - [`cli`]: the commands behind the `baker` binary, a thin layer of flags and printing.

pub mod bake;
pub mod cancel;
pub mod cli;
pub mod data;
pub mod error;
pub mod export;
pub mod fiber;
pub mod files;
pub mod fit;
pub mod math;
pub mod output;
pub mod pipeline;
pub mod profile;
pub mod progress;
pub mod skin;
pub mod spec;
pub mod spectral;
pub mod stats;
pub mod suggest;
pub mod transport;
