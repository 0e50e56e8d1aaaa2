//! Writers: every file goes through [`atomic::write`], so an interrupted bake never leaves a
//! half-written file under its final name.

pub mod atomic;
pub mod csv;
pub mod document;
pub mod mci;
pub mod plot;
