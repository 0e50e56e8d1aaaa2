//! Writers: every file goes through [`atomic::write`], so an interrupted bake never leaves a
//! half-written file under its final name.

pub mod atomic;
pub mod bkt;
pub mod csv;
pub mod document;
pub mod exr;
pub mod hdf5;
pub mod manifest;
pub mod mci;
pub mod plot;
pub mod preview;
pub mod slice;
pub mod tables;
