//! Writers: every file goes through [`atomic::write`], so an interrupted bake never leaves a
//! half-written file under its final name, and a device or FIFO given as an output stays what
//! it is; every path a bake writes is built by [`paths`], inside `--out`.

pub mod atomic;
pub mod bkt;
pub mod csv;
pub mod exr;
pub mod hdf5;
pub mod manifest;
pub mod mci;
pub mod paths;
pub mod plot;
pub mod slice;
pub mod tables;

/// The file in a spec's output folder that records what produced it (`bake::stamp`).
pub const STAMP_FILE: &str = ".baked";
