//! On-disk formats of the baker and light readers for renderers and tools.
//!
//! This crate has no heavy dependencies (no HDF5, no rayon, no physics): a renderer links it
//! to read what the baker writes. Each format documents its layout in its module.

pub mod bcsdf;
pub mod grid;
pub mod optics;
pub mod profile;
pub mod table;

pub use bcsdf::{Bcsdf, Precision};
pub use grid::AngularGrid;
/// The fiber BCSDF table reader under the name the renderer-facing docs use.
pub type BcsdfTable = Bcsdf;
pub use optics::{
    OpticsDocument, OpticsEntry, OpticsError, OpticsJunction, OpticsLayer, OpticsSurface,
};
pub use profile::{Gaussians, ProfileData, ProfileEntry, ProfileTable};
pub use table::{Array, DType, Data, IndexEntry, TableError, TableFile, TableIndex};
